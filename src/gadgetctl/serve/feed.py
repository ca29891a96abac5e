"""The per-frame consumer of `gadgetctl serve`: it reads what the monitor session gathered
in a frame (every sample of every served device, and the proxies' new values) and hands
it, as VRPN reports, to an :class:`Outlet` (the server that fans them out to clients).

Sample times are the input manager's clock (:func:`gadgetctl.input.clock.now`); VRPN
carries wall-clock time, so the feed adds a fixed offset measured once at start.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator, Sequence
from typing import Any, Protocol

import numpy as np

from gadgetctl.input.clock import now
from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.proxies import Proxy
from gadgetctl.input.samples import FEW_SLOTS, FrameSamples, Sample, SampleBatch
from gadgetctl.serve.catalog import Role, ServedElement, proxy_role, served_positions

_PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)


class Outlet(Protocol):
    """Where the feed puts reports; ``sender`` is a VRPN device name, times are wall-clock
    seconds (Unix epoch)."""

    def tracker(
        self, sender: str, times: np.ndarray, positions: np.ndarray, quaternions: np.ndarray
    ) -> None:
        """``times`` (n,), ``positions`` (n, sensors, 3) in meters, ``quaternions``
        (n, sensors, 4) as x, y, z, w; sensor numbers are the second index."""

    def buttons(
        self, sender: str, changes: Sequence[tuple[float, int, int]], states: np.ndarray
    ) -> None:
        """Button transitions (time, button, 0/1) in order; ``states`` every button's state
        after them (what a client that connects later is told first)."""

    def analog(self, sender: str, times: np.ndarray, values: np.ndarray) -> None:
        """``times`` (n,), ``values`` (n, channels)."""

    def text(self, sender: str, moment: float, level: int, text: str) -> None:
        """One text message; ``level`` is the unit number."""


class BatchOutlet(Outlet, Protocol):
    """An outlet that also takes a whole frame's tracker batches at once."""

    def trackers(self, batches: list[tuple[str, np.ndarray, np.ndarray]], offset: float) -> None:
        """Every (sender, times, matrices) of a frame, as :meth:`Outlet.tracker` takes them
        except that the times are on the input manager's clock: ``offset`` makes them Unix
        time (added once for the whole frame, not per batch)."""


class SharedOutlet(Protocol):
    """An outlet that also takes a frame group's tracker windows from its shared arrays."""

    def tracker_shared(
        self, windows: Any, slots: np.ndarray, senders: np.ndarray, offset: float
    ) -> None:
        """The windows of ``slots`` of ``windows`` (a
        :class:`~gadgetctl.input.samples.SharedWindows`; fresh slots whose arrays hold
        position data only), served as ``senders``; times on the input manager's clock plus
        ``offset``."""


class WindowOutlet(BatchOutlet, Protocol):
    """An outlet that also takes tracker samples as windows of arrays computed ahead."""

    def tracker_windows(
        self, windows: list[tuple[str, np.ndarray, np.ndarray, int, int]], offset: float
    ) -> None:
        """A frame's (sender, times, matrices, start, stop): samples ``start`` .. ``stop - 1``
        of ``times`` (n,) on the input manager's clock and ``matrices`` (n, sensors, 4, 4),
        arrays that later frames cut their windows from too (a waveform device's block): the
        outlet may convert a stretch of them once for several frames. Like
        :meth:`Outlet.tracker`, it ignores what is not (samples, sensors, 4, 4)."""


def wall_clock_offset() -> float:
    """Seconds to add to an input-manager timestamp to get Unix time."""
    return time.time() - now()


def chunk_arrays(frame: FrameSamples) -> Iterator[tuple[np.ndarray, Any]]:
    """(timestamps, values) per chunk of a frame; a single sample gives arrays of one."""
    for chunk in frame.chunks:
        if type(chunk) is Sample:
            yield np.array([chunk.timestamp]), [chunk.values]
        else:
            yield np.asarray(chunk.timestamps, dtype=np.float64), chunk.values


class _ButtonState:
    """The states a Button sender reported last, to turn samples into transitions."""

    __slots__ = ("states",)

    def __init__(self) -> None:
        self.states = np.zeros(0, dtype=np.int8)

    def changes(self, times: np.ndarray, rows: np.ndarray) -> list[tuple[float, int, int]]:
        """Transitions of ``rows`` (n, buttons) of 0/1 against the states so far."""
        if rows.ndim != 2 or not rows.size:
            return []
        units = rows.shape[1]
        previous = self.states
        if len(previous) < units:  # new buttons start released
            previous = np.concatenate([previous, np.zeros(units - len(previous), dtype=np.int8)])
        stacked = np.vstack([previous[None, :units], rows])
        steps = np.nonzero(np.diff(stacked, axis=0))
        result = [(float(times[i]), int(j), int(rows[i, j])) for i, j in zip(*steps, strict=True)]
        previous = previous.copy()
        previous[:units] = rows[-1]
        self.states = previous
        return result


class _GroupPlan:
    """The served devices of one shared group (see :meth:`ServeFeed._group`): their slots,
    sender names, and whether each slot's arrays hold position data only (checked again when
    the arrays change)."""

    def __init__(self, group: Any, picked: list[tuple[int, ServedElement]]) -> None:
        self.group = group
        self.entries = [entry for _, entry in picked]
        self.slots = group.slots[[index for index, _ in picked]]
        if np.array_equal(self.slots, group.windows.every):
            self.slots = group.windows.every  # all of them: read with slices
        self.senders = np.array([entry.vrpn_name for entry in self.entries], dtype=object)
        self.generation = np.full(len(picked), -1, dtype=np.int64)
        self.poses_only = np.zeros(len(picked), dtype=bool)
        self.all_poses = False  # every slot's arrays hold position data only
        #: The group's every slot, in order (its windows' counts then say which are fresh).
        self.whole = self.slots is group.windows.every
        self.slot_list: list[int] = self.slots.tolist()

    def all_bulk(self, windows: Any) -> bool:
        """Whether every slot is fresh with position data only and its arrays were checked,
        asked slot by slot (for a few slots, cheaper than with numpy)."""
        fresh, generation = windows.fresh, windows.generation
        checked, poses_only = self.generation, self.poses_only
        for index, slot in enumerate(self.slot_list):
            if not (fresh[slot] and poses_only[index]) or checked[index] != generation[slot]:
                return False
        return True

    def recheck(self, windows: Any, indices: np.ndarray) -> None:
        for index in indices.tolist():
            slot = int(self.slots[index])
            arrays = windows.arrays[slot]
            self.poses_only[index] = arrays is not None and served_positions(arrays[1]) is not None
            self.generation[index] = windows.generation[slot]
        self.all_poses = np.count_nonzero(self.poses_only) == len(self.poses_only)


class ServeFeed:
    """A :data:`~gadgetctl.monitor.session.FrameConsumer` that serves ``catalog``."""

    def __init__(
        self, catalog: Iterable[ServedElement], outlet: Outlet, *, offset: float | None = None
    ) -> None:
        self.outlet = outlet
        self.offset = wall_clock_offset() if offset is None else offset
        self.devices = [e for e in catalog if e.kind == "device" and e.roles]
        self.proxies = [e for e in catalog if e.kind != "device" and e.roles]
        self._buttons: dict[str, _ButtonState] = {}
        self._batched = callable(getattr(outlet, "trackers", None))
        self._windowed = self._batched and callable(getattr(outlet, "tracker_windows", None))
        self._poses: list[tuple[str, np.ndarray, np.ndarray]] = []  # this frame's tracker batches
        # this frame's tracker windows of arrays computed ahead (see WindowOutlet)
        self._windows: list[tuple[str, np.ndarray, np.ndarray, int, int]] = []
        self._proxy_stamps: dict[str, float | None] = {}
        self._shared = callable(getattr(outlet, "tracker_shared", None))
        # per list of shared groups (GatheredFrames.groups): the devices served from them
        self._plan: tuple[object, list[ServedElement], list[_GroupPlan]] | None = None
        #: Reports handed to the outlet (one per sensor, button change, analog row, text);
        #: tracker windows are counted by the outlet that takes them (its ``messages``).
        self.reports = 0

    def _plan_for(self, groups: Any) -> tuple[list[ServedElement], list[_GroupPlan]]:
        """The served devices read per device, and those read from each shared group."""
        plan = self._plan
        if plan is not None and plan[0] is groups:
            return plan[1], plan[2]
        served = {e.element: e for e in self.devices}
        plans = []
        for group in groups:
            picked = [(i, served.pop(name)) for i, name in enumerate(group.names) if name in served]
            if picked:
                plans.append(_GroupPlan(group, picked))
        own = [e for e in self.devices if e.element in served]
        self._plan = (groups, own, plans)
        return own, plans

    def __call__(self, session: Any, moment: float) -> None:
        gathered = getattr(session, "gathered", None)
        if gathered is None:  # a session without the gathered map: ask per device
            frame_samples = session.frame_samples
            gathered = {e.element: f for e in self.devices if (f := frame_samples(e.element))}
        groups = getattr(gathered, "groups", ()) if self._shared else ()
        entries = self.devices
        if groups:
            entries, plans = self._plan_for(groups)
            for plan in plans:
                self._group(plan, gathered)
        windows = self._windows
        windowed = self._windowed
        position = DeviceKind.POSITION
        for entry in entries:
            frames = gathered.get(entry.element)
            if not frames:
                continue
            if windowed and len(frames) == 1:
                # the usual frame of a device publishing what it computed ahead: one window
                frame = frames.get(position)
                if frame is not None and len(frame.chunks) == 1:
                    chunk = frame.chunks[0]
                    base = chunk.base if type(chunk) is SampleBatch else None
                    if base is not None:
                        windows.append((entry.vrpn_name, *base))
                        continue
            self._device(entry, frames)
        if windows:
            windows, self._windows = self._windows, []
            self.outlet.tracker_windows(windows, self.offset)
        poses, self._poses = self._poses, []
        if poses:
            if self._batched:
                self.outlet.trackers(poses, self.offset)
            else:
                offset = self.offset
                for sender, stamps, matrices in poses:
                    self.outlet.tracker(sender, np.add(stamps, offset, dtype=np.float64), matrices)
        manager = session.manager
        for entry in self.proxies:
            target = manager.aliases.get(entry.element) if entry.kind == "alias" else entry.element
            proxy = manager.proxies.get(target) if target is not None else None
            if proxy is not None:
                self._proxy(entry, proxy)

    # -- devices ------------------------------------------------------------------------

    def _group(self, plan: _GroupPlan, gathered: Any) -> None:
        """The served devices of one shared group: those whose frame is a window of position
        data only, at once (:meth:`SharedOutlet.tracker_shared`); the others one by one."""
        windows = plan.group.windows
        slots = plan.slots
        if len(plan.entries) <= FEW_SLOTS and plan.all_bulk(windows):
            self.outlet.tracker_shared(windows, slots, plan.senders, self.offset)
            return
        taken = windows.select(slots)
        stale = plan.generation != windows.generation[taken]
        if np.count_nonzero(stale):
            plan.recheck(windows, stale.nonzero()[0])
        # (bool arrays counted with count_nonzero: all() and any() cost a few times more)
        whole = plan.whole and plan.all_poses  # the windows' counts tell every slot's frame
        if whole and windows.all_fresh:
            self.outlet.tracker_shared(windows, slots, plan.senders, self.offset)
            return
        bulk = windows.fresh[taken] & plan.poses_only
        served = np.count_nonzero(bulk)
        if served == len(slots):
            self.outlet.tracker_shared(windows, slots, plan.senders, self.offset)
            return
        if served:
            self.outlet.tracker_shared(windows, slots[bulk], plan.senders[bulk], self.offset)
        if whole and windows.none_alone:
            return  # the others' frames are empty
        alone = ~(bulk | windows.emptied[taken])  # empty frames have nothing to serve
        for index in alone.nonzero()[0].tolist():
            entry = plan.entries[index]
            frames = gathered.get(entry.element)
            if frames:
                self._device(entry, frames)

    def _device(self, entry: ServedElement, frames: dict[DeviceKind, FrameSamples]) -> None:
        sender = entry.vrpn_name
        outlet = self.outlet
        offset = self.offset
        for kind, frame in frames.items():
            if kind is DeviceKind.POSITION:
                # kept for the end of the frame (times on the manager's clock): the offset is
                # added and every tracker framed once for all devices
                poses = self._poses
                for chunk in frame.chunks:
                    if self._windowed and type(chunk) is SampleBatch:
                        base = chunk.base
                        if base is not None:  # framed by the outlet, a stretch at a time
                            self._windows.append((sender, *base))
                            continue
                    if type(chunk) is Sample:
                        stamps = np.array([chunk.timestamp])
                        matrices = np.asarray([chunk.values], dtype=np.float64)
                    else:  # a batch's arrays as they are (no copy when already float64)
                        stamps = chunk.timestamps
                        matrices = np.asarray(chunk.values, dtype=np.float64)
                    shape = matrices.shape
                    if len(shape) != 4 or not shape[1]:
                        continue
                    poses.append((sender, stamps, matrices))
                    self.reports += shape[0] * shape[1]
            elif kind is DeviceKind.DIGITAL:
                state = self._buttons.setdefault(sender, _ButtonState())
                changes: list[tuple[float, int, int]] = []
                for stamps, values in chunk_arrays(frame):
                    rows = (np.asarray(values) != 0).astype(np.int8)
                    changes += state.changes(stamps + offset, rows)
                if changes:
                    outlet.buttons(sender, changes, state.states)
                    self.reports += len(changes)
            elif kind is DeviceKind.ANALOG:
                for stamps, values in chunk_arrays(frame):
                    rows = np.asarray(values, dtype=np.float64)
                    if rows.ndim == 2 and rows.shape[1]:
                        outlet.analog(sender, stamps + offset, rows)
                        self.reports += rows.shape[0]
            elif kind is DeviceKind.STRING or kind is DeviceKind.COMMAND:
                for sample in frame:
                    for unit, value in enumerate(sample.values):
                        text = str(value) if kind is DeviceKind.STRING else str(int(value))
                        outlet.text(sender, sample.timestamp + offset, unit, text)
                        self.reports += 1

    # -- proxies and aliases ------------------------------------------------------------

    def _proxy(self, entry: ServedElement, proxy: Proxy) -> None:
        stamp = proxy.timestamp
        if stamp is None or proxy.stupefied or self._proxy_stamps.get(entry.element) == stamp:
            return
        self._proxy_stamps[entry.element] = stamp
        sender = entry.vrpn_name
        moment = stamp + self.offset
        role = proxy_role(proxy)
        outlet = self.outlet
        if role is Role.TRACKER:
            outlet.tracker(
                sender, np.array([moment]), np.asarray(proxy.data, dtype=np.float64)[None, None]
            )
        elif role is Role.BUTTON:
            state = self._buttons.setdefault(sender, _ButtonState())
            pressed = 1 if proxy.data in _PRESSED else 0
            changes = state.changes(np.array([moment]), np.array([[pressed]], dtype=np.int8))
            if not changes:
                return
            outlet.buttons(sender, changes, state.states)
        elif role is Role.ANALOG:
            outlet.analog(sender, np.array([moment]), np.array([[float(proxy.data)]]))
        elif role is Role.TEXT:
            outlet.text(sender, moment, 0, str(proxy.data))
        else:
            return
        self.reports += 1
