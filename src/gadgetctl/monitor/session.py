"""The data side of `gadgetctl monitor` and `gadgetctl replay`: a session runs the embedded
input manager frame by frame and hands out what the views and writers need.

:class:`MonitorSession` configures an :class:`~gadgetctl.input.manager.InputManager`,
resolves the selected names (exact names or glob patterns of devices, proxies and aliases)
and, once per frame, reads *every* sample each watched device delivered since the previous
frame (``SampleStore.frame``): it feeds the running statistics (rates, intervals, jitter,
gaps, dropped samples, faults), counts button presses, keeps a short history of analog values
for sparklines, and writes sample, frame, status and marker records to its sinks
(:class:`~gadgetctl.monitor.recording.Recorder` objects: a recording file or an NDJSON
stream; :mod:`gadgetctl.monitor.sinks` hands the records out). Renderers (the live and
table views of the CLI) ask for a :class:`Snapshot` when they draw, at their own pace; the
session itself never prints.

Nothing here imports rich or typer.
"""

from __future__ import annotations

import fnmatch
import gc
import time
from collections.abc import Callable, Container, Iterable, Iterator, Mapping, Sequence
from typing import Protocol

from gadgetctl.errors import GadgetctlError
from gadgetctl.input.clock import now
from gadgetctl.input.device import DeviceState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager
from gadgetctl.input.proxies import (
    AnalogProxy,
    DigitalProxy,
    ProxyState,
)
from gadgetctl.input.samples import FrameSamples
from gadgetctl.input.status import UNKNOWN_TYPE, ElementKind, ElementStatus
from gadgetctl.jccl.configuration import Configuration
from gadgetctl.monitor.encoding import proxy_value
from gadgetctl.monitor.framerecords import ALIAS, DEVICE, PROXY, FrameRecords
from gadgetctl.monitor.gather import NOTHING
from gadgetctl.monitor.gathering import FrameGatherer
from gadgetctl.monitor.poses import MATRIX
from gadgetctl.monitor.recording import Recorder
from gadgetctl.monitor.records import (
    FrameRecord,
    MarkerRecord,
)
from gadgetctl.monitor.sinks import FRAME, MARKER, SAMPLES, Opener, Sinks
from gadgetctl.monitor.stats import DeviceSnapshot, snapshot_rows, snapshots
from gadgetctl.monitor.tracks import DeviceTrack
from gadgetctl.monitor.views import ElementView, Frame, Snapshot, UnitView
from gadgetctl.perf import collector_paused
from gadgetctl.suggest import did_you_mean

PENDING = "pending"
DEFAULT_HISTORY_SECONDS = 5.0
SINK_WARMUP = 0.5  # seconds a session waits for every device's first sample before its header
#: Work done ahead between frames (InputManager.prepare, serve's rows framed ahead) waits for
#: a later pause when less than this share of a frame period is left before the next frame
#: (0: only when the next frame is already due; skipped work is done by a later pause, or by
#: the frame that needs it).
PREPARE_SLACK = 0.0


class SelectionError(GadgetctlError):
    """A NAME pattern that matches no device, proxy or alias."""


FrameConsumer = Callable[["MonitorSession", float], object]
"""Called once per frame, after the session gathered every watched device's samples, with
the session and the frame's time. The recording writers are one consumer; `gadgetctl serve`
is another. Consumers read :meth:`MonitorSession.frame_samples` and the manager's proxies."""


class ReplaySource(Protocol):
    """What a session needs from a replay feeder (see :mod:`gadgetctl.monitor.replaydevice`)."""

    @property
    def done(self) -> bool: ...

    def drain_markers(self) -> list[MarkerRecord]: ...


# --------------------------------------------------------------------------- the session


#: A run that reaches less than this share of the requested frame rate says so (once),
#: checked after RATE_CHECK_AFTER seconds or at the end of a run of RATE_CHECK_MIN seconds.
RATE_SHORTFALL = 0.9
RATE_CHECK_AFTER = 1.0
RATE_CHECK_MIN = 0.25


#: The values of the kinds of a device class (its kinds() is one tuple per class).
_KIND_VALUES: dict[tuple[DeviceKind, ...], tuple[str, ...]] = {}


def _kind_values(kinds: tuple[DeviceKind, ...]) -> tuple[str, ...]:
    if type(kinds) is not tuple:  # (a driver's own kinds(), whatever it returns)
        return tuple(kind.value for kind in kinds)
    values = _KIND_VALUES.get(kinds)
    if values is None:
        values = _KIND_VALUES[kinds] = tuple(kind.value for kind in kinds)
    return values


#: Devices whose final statistics are computed together (numpy over all their timestamps);
#: the figures of one such part are held while its entries are read.
FINAL_PART = 512

_STUPEFIED, _ACTIVE = ProxyState.STUPEFIED.value, ProxyState.ACTIVE.value


class FinalStats(Mapping[str, dict[str, object]]):
    """:meth:`MonitorSession.final_stats` made one device at a time when read (see
    :meth:`MonitorSession.final_stats_view`), from statistics computed for
    :data:`FINAL_PART` devices at a time."""

    def __init__(self, session: MonitorSession, moment: float) -> None:
        self._session = session
        self._moment = moment
        tracks, device = session.gatherer.tracks, session.manager.device
        self._names = [
            name
            for name in session._selected
            if tracks.get(name) is not None and device(name) is not None
        ]
        self._position = {name: i for i, name in enumerate(self._names)}
        self._part = -1
        self._rows: dict[str, dict[str, object]] = {}

    def __getitem__(self, name: str) -> dict[str, object]:
        position = self._position.get(name)
        entry = None
        if position is not None:
            if position // FINAL_PART != self._part:
                self._read_part(position // FINAL_PART)
            entry = self._session._final_entry(name, self._moment, self._rows.get(name))
        if entry is None:
            raise KeyError(name)
        return entry

    def _read_part(self, part: int) -> None:
        self._rows = {}  # (the previous part's figures go first)
        tracks = self._session.gatherer.tracks
        found = [
            (name, track)
            for name in self._names[part * FINAL_PART : (part + 1) * FINAL_PART]
            if (track := tracks.get(name)) is not None
        ]
        rows = snapshot_rows([track.stats for _, track in found], self._moment)
        self._rows = {name: row for (name, _), row in zip(found, rows, strict=True)}
        self._part = part

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)


class MonitorSession:
    """Runs an input manager for monitoring; see the module documentation.

    ``selectors``: names or glob patterns (``fnmatch``, case-sensitive, then case-insensitive
    when nothing matched); none selects every device, proxy and alias. Sample records are
    written for the selected devices, and for proxies and aliases only when ``selectors``
    name them (one record per frame with new data).
    """

    def __init__(
        self,
        manager: InputManager,
        configuration: Configuration | None = None,
        *,
        selectors: Sequence[str] = (),
        rate: float = 60.0,
        history: float = DEFAULT_HISTORY_SECONDS,
        source: ReplaySource | None = None,
        info: Mapping[str, object] | None = None,
        statistics: bool = True,
    ) -> None:
        if not rate > 0:
            raise ValueError("the frame rate must be positive")
        self.manager = manager
        self.configuration = configuration
        self.selectors = tuple(selectors)
        self.rate = rate
        self.history = max(2, round(history * rate))
        self.source = source
        self.info = dict(info or {})
        self.statistics = (
            statistics  # False: gather samples only (no statistics, presses, histories)
        )
        self.frame = 0
        self.started_at: float | None = None
        #: When :meth:`start` began configuring (no sample of the session is older).
        self.configured_at: float | None = None
        self.frame_timestamp = 0.0
        self.markers: list[MarkerRecord] = []
        self.finished = False
        self._selected: list[str] = []
        #: The watched devices, their tracks and each frame's samples.
        self.gatherer = FrameGatherer(manager, self.history, statistics)
        #: The records of its frames (proxies' own sample records when selectors name them).
        self.records = FrameRecords(manager, self.gatherer, stream_proxies=bool(self.selectors))
        self._sinks = Sinks()
        self._frame_interval = 1.0 / rate
        self._last_frame_at: float | None = None
        #: When the next frame of :meth:`frames` is due (None outside it).
        self.next_frame_due: float | None = None
        #: Frames run by :meth:`frames` and the seconds they took (wall clock).
        self.frames_run = 0
        self.run_seconds = 0.0
        #: (requested, achieved) frame rate, set once when the frames fall short of the rate.
        self.rate_shortfall: tuple[float, float] | None = None
        self._stop = False
        self._consumers: list[FrameConsumer] = []
        self._keyboards: tuple[object, list[str]] | None = None  # (arrangement, names)

    # -- setting up ---------------------------------------------------------------------

    def start(self) -> list[str]:
        """Configure the manager (when a configuration was given) and resolve the selection.
        Raises :class:`SelectionError` when a pattern matches nothing. Returns the names."""
        self.configured_at = now()  # before any device of the session starts
        with collector_paused():  # what is built here lives as long as the session
            # where each element is in the configuration: the order of the names selected
            # (only here: 20,000 names and their places, about 1 MB, need not last the session)
            places: dict[str, int] = {}
            if self.configuration is not None:
                self.manager.configure(self.configuration)
                for index, element in enumerate(self.configuration.elements):
                    places.setdefault(element.full_name, index)
            self._selected = self._resolve(self.selectors, places)
        return list(self._selected)

    def known(self) -> dict[str, str]:
        """Every selectable name and what it is (device, proxy, alias), pending ones included."""
        manager = self.manager
        names: dict[str, str] = {}
        for name in manager.devices:
            names[name] = DEVICE
        for name in manager.proxies:
            names.setdefault(name, PROXY)
        for name in manager.aliases:
            names.setdefault(name, ALIAS)
        for status in self._pending_statuses().values():
            if status.kind in (ElementKind.DEVICE, ElementKind.PROXY, ElementKind.ALIAS):
                names.setdefault(status.name, status.kind.value)
        return names

    def _pending_statuses(self) -> dict[str, ElementStatus]:
        if not self.manager.pending():
            return {}
        return {s.name: s for s in self.manager.statuses() if s.state in (PENDING, UNKNOWN_TYPE)}

    def _resolve(self, selectors: Sequence[str], places: Mapping[str, int]) -> list[str]:
        known = self.known()
        group = {DEVICE: 0, PROXY: 1, ALIAS: 2}

        def order(name: str) -> tuple[int, int, str]:
            return group[known[name]], places.get(name, 1 << 30), name

        if not selectors:
            return sorted(known, key=order)
        chosen: set[str] = set()
        unmatched = []
        for pattern in selectors:
            hits = [n for n in known if n == pattern or fnmatch.fnmatchcase(n, pattern)]
            if not hits:
                lowered = pattern.lower()
                hits = [n for n in known if fnmatch.fnmatchcase(n.lower(), lowered)]
            if not hits:
                unmatched.append(pattern)
            chosen.update(hits)
        if unmatched:
            suggestions = [(p, s) for p in unmatched if (s := did_you_mean(p, known))]
            if len(unmatched) > 1:
                suggestions = [(p, f"{p!r}: {s}") for p, s in suggestions]
            if suggestions:
                hint = "; ".join(s for _, s in suggestions)
            else:
                more = "" if len(known) <= 12 else f" and {len(known) - 12} more"
                hint = f"available: {', '.join(sorted(known, key=order)[:12]) or 'nothing'}{more}"
            quoted = ", ".join(repr(p) for p in unmatched)
            raise SelectionError(f"no device, proxy or alias matches {quoted} ({hint})")
        return sorted(chosen, key=order)

    @property
    def selected(self) -> list[str]:
        return list(self._selected)

    @property
    def watched(self) -> list[str]:
        """The devices whose samples are gathered every frame (the selected ones and those
        the selected proxies and aliases read)."""
        return list(self.gatherer.watch)

    def frame_samples(self, name: str) -> Mapping[DeviceKind, FrameSamples]:
        """Every sample the watched device ``name`` delivered this frame, per kind (empty
        when it delivered nothing or is not watched)."""
        return self.gatherer.gathered.get(name, NOTHING)

    @property
    def gathered(self) -> Mapping[str, Mapping[DeviceKind, FrameSamples]]:
        """This frame's samples of every watched device that delivered any, by device name:
        what :meth:`frame_samples` gives, in one read-only mapping (replaced each frame)."""
        return self.gatherer.gathered

    def add_sink(
        self,
        opener: Opener,
        *,
        per_frame: bool = False,
        pose: str = MATRIX,
    ) -> None:
        """Add a writer: ``opener(header_info)`` makes the :class:`Recorder` once the header is
        known (after the first samples, at most :data:`SINK_WARMUP` seconds in). With
        ``per_frame`` it gets frame records instead of sample records; ``pose`` chooses how
        its positions are written (recordings keep matrices, which replay reads)."""
        if not self._sinks:
            self.add_consumer(MonitorSession._write_frame)
        self._sinks.add(opener, per_frame=per_frame, pose=pose)

    def add_consumer(self, consumer: FrameConsumer) -> None:
        """Call ``consumer(session, moment)`` once per frame, after the frame's samples were
        gathered (see :data:`FrameConsumer`)."""
        self._consumers.append(consumer)

    @property
    def recorders(self) -> list[Recorder]:
        return self._sinks.recorders

    # -- header -------------------------------------------------------------------------

    def header_info(self) -> dict[str, object]:
        """What replay needs: every selected element with its type, kinds, units and links
        (:meth:`FrameRecords.header_elements`), the selection and the frame rate."""
        devices, elements = self.records.header_elements(self._selected)
        return {
            **self.info,
            "devices": devices,
            "elements": elements,
            "selection": list(self.selectors),
            "frame_rate": self.rate,
        }

    # -- running ------------------------------------------------------------------------

    def stop(self) -> None:
        """End :meth:`frames` after the current frame."""
        self._stop = True

    def frames(
        self,
        *,
        duration: float | None = None,
        frames: int | None = None,
        sleep: Callable[[float], object] = time.sleep,
        stop_at_end: bool = True,
    ) -> Iterator[Frame]:
        """Run frames at the session's rate until ``duration`` seconds (wall clock, however
        many frames that is) or ``frames`` frames, :meth:`stop`, or the end of a replay
        (unless ``stop_at_end`` is false: then :attr:`finished` is set and frames go on);
        yields each frame after its data were gathered and written. When the frames fall
        short of the rate, :attr:`rate_shortfall` is set (once)."""
        period = 1.0 / self.rate
        # keep frames free of long full collections (as InputManager.run does); no collection
        # first: it found nothing to free and cost 0.3 s with 10,000 devices, and what is
        # frozen is unfrozen when the frames end
        gc.freeze()
        began = now()
        count = 0
        try:
            start = began  # the pacing origin; moves when the frames fall behind
            self.started_at = began
            while not self._stop:
                if frames is not None and count >= frames:
                    break
                if duration is not None and now() - began >= duration:
                    break
                source_done = self.source is not None and self.source.done
                self.next_frame_due = start + (count + 1) * period
                if count:
                    frame = self.step()
                else:  # the first frame makes what the others reuse (tracks, sinks): kept;
                    # the scheduler does not stand in for its devices while it is made (it
                    # publishes what is due itself, the next frame what came due meanwhile:
                    # with 10,000 devices, a second's passes otherwise)
                    with collector_paused(), self.manager.hold_sampling():
                        frame = self.step()
                    gc.freeze()
                count += 1
                self.frames_run, self.run_seconds = count, now() - began
                yield frame
                if self.has_slack():  # work done ahead, when it does not make the next frame late
                    self.manager.prepare()
                if (
                    source_done and not self.finished
                ):  # the feeder had finished before this frame swapped
                    self.finished = True
                    if stop_at_end:
                        break
                if self.rate_shortfall is None and now() - began >= RATE_CHECK_AFTER:
                    self._check_rate(count, now() - began)
                delay = start + count * period - now()
                if delay > 0:
                    sleep(delay)
                elif delay < -period:  # fell behind: do not try to catch up
                    start = now() - count * period
        finally:
            gc.unfreeze()
            self.next_frame_due = None
            self.frames_run, self.run_seconds = count, now() - began
            if self.rate_shortfall is None and self.run_seconds >= RATE_CHECK_MIN:
                self._check_rate(count, self.run_seconds)

    @property
    def last_look(self) -> float:
        """When the latest frame gathered the devices' samples (now, before the first frame):
        the instant the figures at the end of a run describe. What came after it was never
        read; at a later instant, a device read by frames slower than its samples (10,000
        devices make about one frame a second) looked as if it were slowing down: its window
        rate fell (a 10 Hz device showed 1 Hz) and its age grew while it sampled on."""
        last = self._last_frame_at
        return now() if last is None else last

    def has_slack(self) -> bool:
        """Whether the next frame is due in more than :data:`PREPARE_SLACK` of a frame period
        (or no frames run): time for work done ahead (it waits for a later pause otherwise)."""
        due = self.next_frame_due
        return due is None or due - now() > PREPARE_SLACK / self.rate

    @property
    def achieved_rate(self) -> float:
        """Frames per second of the last :meth:`frames` run (0 before any)."""
        return self.frames_run / self.run_seconds if self.run_seconds > 0 else 0.0

    def _check_rate(self, count: int, elapsed: float) -> None:
        achieved = count / elapsed
        if achieved < RATE_SHORTFALL * self.rate:
            self.rate_shortfall = (self.rate, achieved)

    def step(self) -> Frame:
        """One frame: update the manager, gather every watched device's samples, write."""
        moment = now()
        if self._last_frame_at is not None:
            self._frame_interval += 0.1 * ((moment - self._last_frame_at) - self._frame_interval)
        self._last_frame_at = moment
        if self.started_at is None:
            self.started_at = moment
        manager = self.manager
        arrangement = manager.arrangement  # replaced when devices or proxies come or go
        self.frame = manager.update()
        self.frame_timestamp = moment
        samples = self.gatherer.gather(
            self.frame,
            self._selected,
            renewed=manager.arrangement is not arrangement,
            every=self.statistics or bool(self._sinks),
        )
        if self.source is not None:
            for marker in self.source.drain_markers():
                self._note_marker(marker)
        for consumer in self._consumers:
            consumer(self, moment)
        return Frame(self.frame, moment, moment - self.started_at, samples)

    # -- writing ------------------------------------------------------------------------

    def _write_frame(self, moment: float) -> None:
        # the sinks open (header, then what earlier frames left waiting) before this frame's
        # records, which then go out in parts as they are encoded: the first frame of
        # 10,000 devices is megabytes of text, three copies of it when made whole first
        sinks = self._sinks
        if not sinks.is_open and (
            self._warm() or moment - (self.started_at or moment) >= SINK_WARMUP
        ):
            sinks.open(self.header_info())
        sinks.note_statuses(moment, ((name, *self._status_of(name)) for name in self._selected))
        poses = sinks.poses(per_frame=False)
        if len(poses) == 1 and sinks.is_open:
            for text, count in self.records.sample_parts(self._selected, poses[0]):
                sinks.deliver(SAMPLES, {poses[0]: text}, count)
        elif poses:
            texts: dict[str, str] = {}
            count = 0
            for pose in poses:
                texts[pose], count = self.encode_samples(pose)
            if count:
                sinks.emit(SAMPLES, texts, count)
        poses = sinks.poses(per_frame=True)
        if poses:
            sinks.emit(FRAME, {pose: self.frame_record(pose) for pose in poses}, 0)

    def warm(self) -> bool:
        """Whether every watched running device has delivered a sample."""
        return self._warm()

    def _warm(self) -> bool:
        """Whether every watched running device has delivered something (so the header can
        tell its units)."""
        for name in self.gatherer.watch:
            device = self.manager.device(name)
            if device is None or device.state is not DeviceState.RUNNING:
                continue
            if not any(device.store.latest(kind) is not None for kind in device.store.kinds):
                return False
        return True

    def open_sinks(self) -> None:
        """Open every sink now (normally done after the first samples)."""
        if not self._sinks.is_open:
            self._sinks.open(self.header_info())

    def encode_samples(self, pose: str = MATRIX) -> tuple[str, int]:
        """This frame's sample records of the selected devices (and of proxies and aliases
        named by the selectors), as NDJSON text and count; positions in ``pose``."""
        return self.records.samples(self._selected, pose)

    def frame_record(self, pose: str = MATRIX) -> FrameRecord:
        """What every selected element delivered this frame, with its newest values
        (positions in ``pose``)."""
        return self.records.frame(self._selected, self.frame, self.frame_timestamp, pose)

    def mark(self, name: str | None = None) -> MarkerRecord:
        """Write a marker (named ``marker N`` when no name is given) to every sink."""
        marker = MarkerRecord(name or f"marker {len(self.markers) + 1}", now())
        self._note_marker(marker)
        return marker

    def _note_marker(self, marker: MarkerRecord) -> None:
        self.markers.append(marker)
        if self._sinks:
            self._sinks.emit(MARKER, marker, 0)

    def reset_stats(self) -> None:
        """Forget statistics and press counts (the r key)."""
        self.gatherer.reset()

    def close_sinks(
        self,
        reason: str = "closed",
        *,
        stats: bool = True,
        final: Mapping[str, Mapping[str, object]] | None = None,
    ) -> None:
        """Write the final statistics record (``final``, :meth:`final_stats_view` when not
        given) and the end record of every sink."""
        if self._sinks and not self._sinks.is_open:
            self.open_sinks()
        if not stats:
            final = None
        elif final is None and self._sinks:
            final = self.final_stats_view()
        if isinstance(final, FinalStats) and len(self._sinks) > 1:
            final = dict(final)  # made once for every sink
        self._sinks.close(reason, final, now())

    # -- reading ------------------------------------------------------------------------

    def _status_of(self, name: str) -> tuple[str | None, str, str, str | None]:
        """(element, type, state, reason) of a selected name."""
        manager = self.manager
        device = manager.device(name)
        if device is not None:
            state, reason = device.shown_state()
            return DEVICE, device.element_type, state.value, reason
        proxy = manager.proxies.get(name)
        if proxy is not None:
            reason = proxy.reason  # (read once: a proxy reads its device when read)
            if proxy.device is None or reason is not None:
                return PROXY, proxy.element_type, _STUPEFIED, reason
            return PROXY, proxy.element_type, _ACTIVE, None
        target = manager.aliases.get(name)
        if target is not None:
            proxy = manager.proxies.get(target)
            if proxy is None:
                return ALIAS, "alias", _STUPEFIED, f"its proxy {target!r} is not configured"
            return ALIAS, "alias", proxy.state.value, proxy.reason if proxy.stupefied else None
        status = manager.status(name)
        if status is not None and status.state in (PENDING, UNKNOWN_TYPE):
            return (
                (status.kind.value if status.kind is not None else None),
                status.type,
                status.state,
                status.reason,
            )
        element = manager.element(name)
        return None, element.type if element is not None else "", "removed", "no longer configured"

    def device_stats(self, name: str, moment: float | None = None) -> DeviceSnapshot | None:
        track = self.gatherer.tracks.get(name)
        return None if track is None else track.snapshot(now() if moment is None else moment)

    def final_stats(self) -> dict[str, dict[str, object]]:
        """Per selected device: the fields of :class:`DeviceSnapshot` plus ``samples``
        (sampling instants), ``state``, ``type``, ``kinds`` and ``units``; for a device that
        keeps its source's own timestamps (a ``remote_clock``, e.g. VRPN), ``source_clock``:
        ``offset`` (the least local receive time minus source time: clock offset plus the
        least transport latency), ``latency`` (the mean above that least) and ``samples``."""
        return dict(self.final_stats_view())

    def final_stats_view(self) -> FinalStats:
        """:meth:`final_stats` as a mapping whose entries are made when read, each time, at
        the instant of the latest frame (:attr:`last_look`): a consumer that encodes them one at a time (a stats
        record) never holds them all (10,000 devices' were about 15 MB). Their statistics are
        computed for :data:`FINAL_PART` devices together, at the first read of one of them.
        Read it while the statistics stand still (no frames, the scheduler held)."""
        return FinalStats(self, self.last_look)

    def _final_entry(
        self, name: str, moment: float, figures: Mapping[str, object] | None = None
    ) -> dict[str, object] | None:
        """The :meth:`final_stats` entry of ``name`` at ``moment`` (None: not a device
        with a track), with its statistics' ``figures`` when they were computed (with
        other devices': :func:`~gadgetctl.monitor.stats.snapshot_rows`)."""
        track = self.gatherer.tracks.get(name)
        device = self.manager.device(name)
        if track is None or device is None:
            return None
        entry = dict(track.stats.snapshot(moment).to_dict() if figures is None else figures)
        entry.pop("name", None)
        entry["samples"] = entry["count"]
        entry["state"] = device.state.value
        entry["error"] = device.error
        entry["type"] = device.element_type
        entry["kinds"] = list(_kind_values(device.kinds()))
        entry["units"] = dict(track.units)
        entry["health"] = device.health()
        clock = getattr(device, "remote_clock", None)  # devices that keep their source's times
        if clock is not None and getattr(clock, "count", 0):
            entry["source_clock"] = clock.to_dict()
        return entry

    def final_faults(self) -> dict[str, tuple[int, str, str | None]]:
        """Per selected device: the ``faults``, ``state`` and ``error`` of :meth:`final_stats`,
        without the statistics."""
        result: dict[str, tuple[int, str, str | None]] = {}
        for name in self._selected:
            track = self.gatherer.tracks.get(name)
            device = self.manager.device(name)
            if track is not None and device is not None:
                result[name] = (track.stats.faults, device.state.value, device.error)
        return result

    @property
    def samples_written(self) -> int:
        """Sample records written to the recordings so far."""
        return self._sinks.samples_written

    @property
    def frame_rate(self) -> float:
        return 1.0 / self._frame_interval if self._frame_interval > 0 else 0.0

    def keyboards(self) -> list[str]:
        """Names of keyboard/mouse devices that receive terminal keys (found again only when
        the manager's devices change: a table of 10,000 devices asks once per part)."""
        arrangement = self.manager.arrangement
        found = self._keyboards
        if found is None or found[0] is not arrangement:
            names = [
                name
                for name, device in self.manager.devices.items()
                if DeviceKind.KEYBOARD_MOUSE in device.kinds()
            ]
            found = self._keyboards = (arrangement, names)
        return list(found[1])

    def snapshot(
        self,
        moment: float | None = None,
        *,
        names: Iterable[str] | None = None,
        detail: bool = True,
        states: Container[str] | None = None,
    ) -> Snapshot:
        """Everything a view shows, for the selected elements (or ``names`` of them); without
        ``detail``, their statuses only (no statistics, values or health); with ``states``,
        only the elements in one of those states (a run's problems: the 20,000 views of a
        run of 10,000 devices and proxies that all ran were made to be dropped)."""
        moment = now() if moment is None else moment
        chosen = self._selected if names is None else names
        if states is not None:
            chosen = [name for name in chosen if self._status_of(name)[2] in states]
        if detail:
            chosen = list(chosen)
            self._refresh_stats(chosen, moment)
        views = [self.element_view(name, moment, detail=detail) for name in chosen]
        return Snapshot(
            self.frame,
            self.frame_timestamp,
            moment - (self.started_at or moment),
            self.frame_rate,
            views,
            self.markers[-5:],
            self.keyboards(),
            self._sinks.samples_written,
            self.finished,
        )

    def _refresh_stats(self, names: Iterable[str], moment: float) -> None:
        """Compute together the statistics at ``moment`` of the devices among ``names`` whose
        views would compute them (:meth:`DeviceTrack.snapshot`), one device after another."""
        stale = [
            track
            for name in names
            if (track := self.gatherer.current_track(name)) is not None and track.stale(moment)
        ]
        if len(stale) > 1:
            found = snapshots([track.stats for track in stale], moment)
            for track, snapshot in zip(stale, found, strict=True):
                track.keep_snapshot(snapshot, moment)

    def element_view(
        self, name: str, moment: float | None = None, *, detail: bool = True
    ) -> ElementView:
        """One element's status, statistics and values now (without ``detail``: its status)."""
        moment = now() if moment is None else moment
        manager = self.manager
        element, element_type, state, reason = self._status_of(name)
        view = ElementView(
            name,
            element or PENDING,
            element_type,
            state,
            reason,
            note=manager.vrjuggler_difference(name),
        )
        device = manager.device(name)
        if device is not None and not detail:
            return view
        if device is not None:
            track = self.gatherer.current_track(name)
            if track is not None and track.device is device:
                self._fill_from_track(view, track, moment)
                view.values = track.unit_views()
            view.health = device.health()
            return view
        proxy = manager.proxy(name)
        if proxy is None:
            if element == ALIAS:
                view.target = manager.aliases.get(name)
            return view
        view.target = manager.aliases.get(name) if element == ALIAS else proxy.device_name
        if proxy.stupefied and proxy.device_name:
            device_state = self._status_of(proxy.device_name)[2]
            if device_state not in ("running", "configured", "removed"):
                view.blocked_by = proxy.device_name
        view.unit = proxy.unit if proxy.HAS_UNIT else None
        if not detail:
            return view
        track = self.gatherer.current_track(proxy.device_name)
        live = track is not None and track.device is proxy.device
        if live:
            self._fill_from_track(view, track, moment)
        if not proxy.stupefied:
            value, raw = proxy_value(proxy)
            unit = proxy.unit if proxy.HAS_UNIT else 0
            history = None
            presses = 0
            if live:
                if isinstance(proxy, AnalogProxy) and unit < len(track.analog_history):
                    history = track.analog_history[unit]
                if (
                    isinstance(proxy, DigitalProxy)
                    and track.presses is not None
                    and unit < len(track.presses)
                ):
                    presses = int(track.presses[unit])
            changed = isinstance(proxy, DigitalProxy) and value in (2, 3)
            view.values = [UnitView(proxy.KIND.value, unit, value, raw, changed, presses, history)]
        return view

    @staticmethod
    def _fill_from_track(view: ElementView, track: DeviceTrack, moment: float) -> None:
        view.device = track.name
        view.stats = track.snapshot(moment)
        newest = track.stats.newest_timestamp
        view.age = None if newest is None else max(0.0, moment - newest)
        view.count = track.count
