"""What a monitor session keeps about one device between frames (:class:`DeviceTrack`):
its running statistics, button presses, analog histories and the values a view shows."""

from __future__ import annotations

from array import array
from collections import deque
from collections.abc import Iterable, Mapping
from types import MappingProxyType

import numpy as np

from gadgetctl.input.clock import now
from gadgetctl.input.device import Input
from gadgetctl.input.devicetypes import Analog
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import NO_CURRENT, FrameSamples, Sample
from gadgetctl.monitor.encoding import plain_value
from gadgetctl.monitor.gather import as_rows, frame_timestamps
from gadgetctl.monitor.stats import DEFAULT_WINDOW, DeviceSnapshot, DeviceStats
from gadgetctl.monitor.views import UnitView

#: A track's analog histories while it has none (shared).
_NO_HISTORY: tuple[()] = ()

_ANALOG, _DIGITAL = DeviceKind.ANALOG, DeviceKind.DIGITAL
#: A track's frames are its store's current frame, made when read (:attr:`DeviceTrack.frames`).
_FROM_STORE: Mapping[DeviceKind, FrameSamples] = MappingProxyType({})

#: Tracks' units (:attr:`DeviceTrack.units`), one read-only mapping for each content.
_UNITS: dict[tuple[tuple[str, int], ...], Mapping[str, int]] = {}
_NO_UNITS: Mapping[str, int] = MappingProxyType({})
#: At most this many distinct units are shared (then each track has its own).
_UNITS_MOST = 1024


def _units_with(units: Mapping[str, int], value: str, width: int) -> Mapping[str, int]:
    """``units`` with ``width`` units of the kind ``value`` (read-only, shared)."""
    grown = dict(units)
    grown[value] = width
    key = tuple(grown.items())
    found = _UNITS.get(key)
    if found is None:
        found = MappingProxyType(grown)
        if len(_UNITS) < _UNITS_MOST:
            _UNITS[key] = found
    return found


STATS_REFRESH = 0.25  # seconds between recomputations of interval percentiles and jitter
#: A frame clock keeps the times of the frames of this many seconds (at least two): enough
#: for a statistics window (:data:`~gadgetctl.monitor.stats.DEFAULT_WINDOW`) and the frame
#: before it.
CLOCK_KEEPS = 2 * DEFAULT_WINDOW


class FrameClock:
    """The frames a session's tracks note, shared by them: how many so far (``ticks``) and
    the times of the recent ones. A track that had nothing in some frames (most of them, for
    a slow device of a frame group) is not visited then: it catches up with the clock when
    it is next noted or read, as if it had noted each of those frames empty."""

    __slots__ = ("_first", "_times", "ticks")

    def __init__(self) -> None:
        self.ticks = 0
        self._times = array("d")
        self._first = 1  # the tick whose time is _times[0]

    def tick(self, at: float) -> int:
        """A new frame, ending at ``at``; returns its number (1 for the first)."""
        self.ticks += 1
        times = self._times
        times.append(at)
        if len(times) > 64 and times[32] < at - CLOCK_KEEPS:  # dropped in batches
            old = 32
            while old + 2 < len(times) and times[old + 1] < at - CLOCK_KEEPS:
                old += 1
            del times[:old]
            self._first += old
        return self.ticks

    @property
    def now(self) -> float:
        """The time of the latest frame."""
        return self._times[-1]

    def times(self, after: int, upto: int) -> array:
        """The times of frames ``after + 1`` .. ``upto`` that the clock still keeps."""
        first = self._first
        return self._times[max(0, after + 1 - first) : max(0, upto + 1 - first)]


class DeviceTrack:
    """What a session keeps about one device between frames."""

    # one per watched device: slotted
    __slots__ = (
        "_analog_history",
        "_changed",
        "_clock",
        "_count",
        "_counted",
        "_digital_state",
        "_dropped_seen",
        "_faults_seen",
        "_frames",
        "_items_seen",
        "_noted",
        "_own_clock",
        "_presses",
        "_snapshot",
        "_snapshot_at",
        "_stats",
        "_swapped_at",
        "device",
        "frame_seen",
        "history_length",
        "name",
        "statistics",
        "units",
    )

    def __init__(
        self,
        name: str,
        device: Input,
        history: int,
        statistics: bool = True,
        clock: FrameClock | None = None,
    ) -> None:
        """``clock``: the session's, ticked once a frame before its tracks are noted; without
        one, each :meth:`update` or :meth:`update_window` is a frame of the track's own."""
        self.name = name
        self.device = device
        self.statistics = statistics
        self._stats = DeviceStats(name)
        self.history_length = history
        self._own_clock = clock is None
        self._clock = FrameClock() if clock is None else clock
        # the clock's frame noted last (those after it, up to the clock's, are owed: empty)
        self._noted = self._clock.ticks if clock is None else self._clock.ticks - 1
        self._frames: Mapping[DeviceKind, FrameSamples] = NO_CURRENT  # (shared, read-only)
        self._count = 0
        self.frame_seen = -1  # the manager frame whose samples ``frames`` holds
        # the most units seen of each kind (by value), in the order the kinds came: one
        # read-only mapping for every track that saw the same (a dict each was 1.8 MB for
        # 10,000 devices)
        self.units: Mapping[str, int] = _NO_UNITS
        self._dropped_seen = self._dropped_now()
        # a device is new to its manager, and the session started it: a fault before the first
        # frame (while it started) is one of this run's too
        self._faults_seen = 0
        self._counted = True  # the dropped samples and faults looked at since the last note
        self._digital_state: np.ndarray | None = None
        self._presses: np.ndarray | None = None
        self._changed: np.ndarray | None = None
        # one history per analog unit, made at its first value (most devices have none)
        self._analog_history: list[deque[float]] | tuple[()] = _NO_HISTORY
        self._snapshot: DeviceSnapshot | None = None
        self._snapshot_at = -1.0
        self._swapped_at: float | None = None
        self._items_seen: object = None  # the shared arrays whose units were noted last

    # -- read: brought up to date with the clock first ------------------------------------

    @property
    def stats(self) -> DeviceStats:
        self.catch_up()
        return self._stats

    @property
    def count(self) -> int:
        """The samples (sampling instants) of the frame noted last."""
        self.catch_up()
        return self._count

    @property
    def presses(self) -> np.ndarray | None:
        self.catch_up()
        return self._presses

    @property
    def changed(self) -> np.ndarray | None:
        """Per button, whether it changed in the frame noted last."""
        self.catch_up()
        return self._changed

    @property
    def digital_state(self) -> np.ndarray | None:
        return self._digital_state

    @property
    def analog_history(self) -> list[deque[float]] | tuple[()]:
        """One value per frame of each analog unit, the newest last."""
        self.catch_up()
        return self._analog_history

    def catch_up(self, upto: int | None = None) -> None:
        """Note the frames after the one noted last, up to the clock's (or ``upto``), as
        frames without samples: what noting each of them would have done."""
        clock = self._clock
        upto = clock.ticks if upto is None else upto
        owed = upto - self._noted
        if owed <= 0:
            if not self._counted and self.statistics:  # (a frame noted from windows)
                self._note_counters()
            return
        self._noted = upto
        self._frames = NO_CURRENT
        self._count = 0
        if not self.statistics:
            return
        self._stats.end_frames(owed, clock.times(upto - owed, upto))
        self._note_counters()
        changed = self._changed
        if changed is not None and changed.any():
            changed[:] = False
        self._hold_analog(owed)

    def _hold_analog(self, frames: int) -> None:
        """The analog histories of ``frames`` frames without samples (the newest value held)."""
        for history in self._analog_history:
            if history:
                history.extend([history[-1]] * min(frames, self.history_length))

    def reset(self) -> None:
        self.catch_up()
        self._stats.reset()
        if self._presses is not None:
            self._presses[:] = 0
        self._snapshot = None
        self._dropped_seen = self._dropped_now()
        self._faults_seen = self.device.faults

    def _dropped_now(self) -> int:
        """Samples dropped by the store (the most of any kind) plus what the transport lost
        before the driver read it (kernel receive-buffer overflows)."""
        return self.device.store.most_dropped() + self.device.transport_dropped()

    def _begin_frame(self) -> int:
        """Before noting a frame (with a clock of the track's own, a new one): returns how
        many frames before it are owed (empty; :meth:`_note` notes them first)."""
        clock = self._clock
        if self._own_clock:
            clock.tick(now())
        owed = clock.ticks - 1 - self._noted
        if owed > 0 and not self.statistics:
            self.catch_up(clock.ticks - 1)
        self._noted = clock.ticks
        return owed

    def update(self) -> int:
        owed = self._begin_frame()
        device = self.device
        store = device.store
        swapped_at = store.swapped_at
        fresh = swapped_at != self._swapped_at  # a failed update_data leaves the old frame
        self._swapped_at = swapped_at
        # the kinds with samples this frame, as the swap found them (a read-only mapping)
        self._frames = frames = store.current if fresh else NO_CURRENT
        if not self.statistics:  # gathering only (serve): no rates, presses or histories
            if not frames:
                self._count = 0
            elif len(frames) == 1:
                self._count = next(iter(frames.values())).count
            else:
                self._count = max(f.count for f in frames.values())
            return self._count
        units = [
            (kind, len(newest.values))
            for kind, samples in frames.items()
            if (newest := samples.newest) is not None
        ]
        stamps = frame_timestamps(frames) if frames else ()
        return self._note(frames.get(_DIGITAL), stamps, units, owed, _ANALOG in frames)

    def update_window(
        self,
        timestamps: np.ndarray,
        items: tuple[tuple[DeviceKind, np.ndarray], ...],
        start: int,
        stop: int,
        moment: float,
    ) -> int:
        """:meth:`update` of a device whose frame is a window of its frame group's shared
        arrays (:class:`~gadgetctl.input.samples.SharedWindows`): samples ``start`` ..
        ``stop - 1`` of ``timestamps`` and of each kind's values ``items``, swapped at
        ``moment`` (``stop == start``: a frame with nothing new). Its sampling instants are
        that window of ``timestamps`` and its units the arrays' second dimension, read without
        making the store's frame (:attr:`frames` is made when read, but for buttons)."""
        owed = self._begin_frame()
        self._swapped_at = moment
        if stop == start or not items:  # (no kinds: no sampling instants either)
            self._frames = NO_CURRENT if stop == start else self.device.store.current
            if not self.statistics:
                self._count = 0
                return 0
            return self._note(None, (), (), owed, False if stop == start else None)
        self._frames = _FROM_STORE
        if not self.statistics:
            self._count = stop - start
            return self._count
        digital = None
        analog = False
        for kind, _ in items:
            if kind is _DIGITAL:  # (presses are counted over every sample of the frame)
                digital = self.device.store.current.get(_DIGITAL)
            elif kind is _ANALOG:
                analog = True
        stamps = timestamps[start:stop]
        if items is self._items_seen:  # (their units are noted already)
            return self._note(digital, stamps, (), owed, analog, counters=False)
        self._items_seen = items
        units = [(kind, values.shape[1]) for kind, values in items]
        return self._note(digital, stamps, units, owed, analog, counters=False)

    @property
    def frames(self) -> Mapping[DeviceKind, FrameSamples]:
        """The samples of each kind that had any in the frame noted last (read-only, shared);
        read within that frame (before the manager's next update), as every consumer of a
        frame reads it: a frame noted from shared windows is its store's frame, made when
        first read. A track not noted in the clock's latest frame had nothing in it."""
        if self._noted != self._clock.ticks:
            return NO_CURRENT
        frames = self._frames
        return self.device.store.current if frames is _FROM_STORE else frames

    @frames.setter
    def frames(self, frames: Mapping[DeviceKind, FrameSamples]) -> None:
        self._frames = frames

    def _note(
        self,
        digital: FrameSamples | None,
        stamps: np.ndarray | tuple[()],
        units: Iterable[tuple[DeviceKind, int]],
        owed: int = 0,
        analog: bool | None = None,
        counters: bool = True,
    ) -> int:
        """Statistics, presses and histories of a frame: its button samples (``digital``),
        its sampling instants ``stamps`` and the units of each kind with samples; the
        ``owed`` frames before it, empty, first. ``analog``: whether the frame has analog
        samples (None: not known); ``counters``: whether to look at the dropped samples and
        faults now."""
        stats = self._stats
        clock = self._clock
        first = not stats.frames  # (what came before this track is read once, from the store)
        if owed > 0:
            ticks = clock.ticks
            stats.end_frames(owed, clock.times(ticks - 1 - owed, ticks - 1))
        count = len(stamps)
        if count:
            stats.add_timestamps(stamps)
        self._count = count
        stats.end_frame(clock.now)
        if counters:
            self._note_counters()
        else:
            self._counted = False
        if digital is not None:
            self._scan_digital(digital)
        elif self._changed is not None and self._changed.any():
            self._changed[:] = False
        store = self.device.store
        if _ANALOG in store.kinds:
            if analog is False and not first:  # nothing new: the newest held
                self._hold_analog(owed + 1)
            else:
                self._note_analog(store.latest(_ANALOG), owed)
        known = self.units
        for kind, width in units:
            value = kind._value_  # (kind.value: the enum's descriptor, a call per read)
            if known.get(value, -1) < width:  # a kind not seen yet, or more units of it
                known = _units_with(known, value, width)
        self.units = known
        return count

    def _note_counters(self) -> None:
        """The samples dropped and the faults since they were noted last (a frame noted
        from shared windows brings neither: they are looked at when the track is read or
        next noted otherwise)."""
        self._counted = True
        dropped = self._dropped_now()
        if dropped != self._dropped_seen:
            self._stats.add_dropped(max(0, dropped - self._dropped_seen))
            self._dropped_seen = dropped
        faults = self.device.faults
        if faults != self._faults_seen:
            self._stats.add_fault(max(0, faults - self._faults_seen))
            self._faults_seen = faults

    def _scan_digital(self, frame: FrameSamples) -> None:
        try:
            parts = [
                np.asarray([chunk.values]) if type(chunk) is Sample else as_rows(chunk.values)
                for chunk in frame.chunks
            ]
            rows = (np.concatenate(parts) if len(parts) > 1 else parts[0]) != 0
        except ValueError:  # units changed within the frame: look at the newest sample only
            newest = frame.newest
            rows = (
                np.asarray([newest.values]) != 0 if newest is not None else np.zeros((0, 0), bool)
            )
        if not rows.size:
            return
        units = rows.shape[1]
        previous = self._digital_state
        if previous is None or len(previous) != units:
            previous = rows[0]
            presses = np.zeros(units, dtype=np.int64)
            if self._presses is not None:
                presses[: min(units, len(self._presses))] = self._presses[:units]
            self._presses = presses
        stacked = np.vstack((previous[None, :], rows)).astype(np.int8)
        steps = np.diff(stacked, axis=0)
        self._presses += (steps > 0).sum(axis=0)
        self._changed = (steps != 0).any(axis=0)
        self._digital_state = rows[-1].copy()

    def _note_analog(self, newest: Sample | None, owed: int = 0) -> None:
        """One more value of each analog unit (``owed`` frames before: the newest then)."""
        histories = self._analog_history
        if owed > 0:
            self._hold_analog(owed)
        if newest is None:
            return
        values = newest.values
        if type(histories) is tuple:
            histories = self._analog_history = []
        while len(histories) < len(values):
            histories.append(deque(maxlen=self.history_length))
        device = self.device
        normalize = device.normalize if isinstance(device, Analog) else float
        for unit, raw in enumerate(values):
            histories[unit].append(normalize(float(raw)))

    def snapshot(self, moment: float) -> DeviceSnapshot:
        if self.stale(moment):
            self.keep_snapshot(self.stats.snapshot(moment), moment)
        return self._snapshot  # type: ignore[return-value]

    def stale(self, moment: float) -> bool:
        """Whether :meth:`snapshot` at ``moment`` computes the figures again."""
        return self._snapshot is None or moment - self._snapshot_at >= STATS_REFRESH

    def keep_snapshot(self, snapshot: DeviceSnapshot, moment: float) -> None:
        """The figures :meth:`snapshot` at ``moment`` computes (computed with other devices')."""
        self._snapshot = snapshot
        self._snapshot_at = moment

    # -- values -------------------------------------------------------------------------

    def unit_views(self) -> list[UnitView]:
        self.catch_up()
        device = self.device
        store = device.store
        views: list[UnitView] = []
        for kind, latest in store.newest():
            values = latest.values
            if kind is not DeviceKind.POSITION and kind is not DeviceKind.GLOVE:
                tolist = getattr(values, "tolist", None)  # Python numbers at once, not numpy
                if tolist is not None:  # scalars one by one (a tenth of a table of 10,000 devices)
                    values = tolist()
            if kind is DeviceKind.ANALOG:
                for unit, raw in enumerate(values):
                    raw = float(raw)
                    value = device.normalize(raw) if isinstance(device, Analog) else raw
                    history = (
                        self._analog_history[unit] if unit < len(self._analog_history) else None
                    )
                    views.append(UnitView(kind.value, unit, value, raw, history=history))
            elif kind is DeviceKind.DIGITAL:
                for unit, state in enumerate(values):
                    changed = (
                        bool(self._changed[unit])
                        if self._changed is not None and unit < len(self._changed)
                        else False
                    )
                    presses = (
                        int(self._presses[unit])
                        if self._presses is not None and unit < len(self._presses)
                        else 0
                    )
                    views.append(
                        UnitView(kind.value, unit, int(state), changed=changed, presses=presses)
                    )
            elif kind is DeviceKind.KEYBOARD_MOUSE:
                held = getattr(device, "held", frozenset())
                views.append(UnitView(kind.value, 0, sorted(k.name for k in held)))
            else:
                name = kind.value
                for unit, value in enumerate(values):
                    views.append(UnitView(name, unit, plain_value(kind, value)))
        return views
