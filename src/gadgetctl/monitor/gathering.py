"""Gathering a monitor session's frames: each frame, every sample each watched device
delivered since the previous one, noted in the device's track (statistics, presses, analog
histories) and handed out by device name (:class:`~gadgetctl.monitor.gather.GatheredFrames`).

The members of a frame group whose samples are windows of the group's shared arrays are
noted from the arrays at once; those with nothing this frame are not visited (their tracks
catch up with the session's :class:`~gadgetctl.monitor.tracks.FrameClock` when next noted
or read). A :class:`FrameGatherer` knows nothing of sinks, views or encodings.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from gadgetctl.input.clock import now
from gadgetctl.input.device import Input
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager
from gadgetctl.input.samples import FrameSamples, SharedWindows
from gadgetctl.monitor.gather import (
    NO_GATHERING,
    PLACE,
    GatheredFrames,
    GatherPlan,
    Noted,
    SharedGroup,
)
from gadgetctl.monitor.tracks import DeviceTrack, FrameClock

Gathered = dict[str, Mapping[DeviceKind, FrameSamples] | Noted]


class FrameGatherer:
    """The watched devices of a session (the selected ones and those the selected proxies
    and aliases read), their tracks and the clock the tracks share.

    ``history``: frames of analog history a track keeps; without ``statistics``, tracks
    gather samples only (no statistics, presses or histories), and a device whose frames are
    windows of its group's arrays is read from them only when asked."""

    def __init__(self, manager: InputManager, history: int, statistics: bool = True) -> None:
        self.manager = manager
        self.history = history
        self.statistics = statistics
        #: The tracks by device name (a device replaced under the same name gets a new one).
        self.tracks: dict[str, DeviceTrack] = {}
        #: Ticked once a frame, before the frame's tracks are noted.
        self.clock = FrameClock()
        #: The watched device names, in the order their frames are handed out.
        self.watch: list[str] = []
        #: The latest frame's samples by device name (replaced each frame).
        self.gathered: Mapping[str, Mapping[DeviceKind, FrameSamples]] = NO_GATHERING
        self.frame = 0
        self._plan: GatherPlan | None = None
        self._plan_by_name = False
        # what :attr:`watch` was found for: the selection and the manager's arrangement
        self._watch_for: tuple[Sequence[str], object] | None = None

    def watch_names(self, selected: Sequence[str]) -> list[str]:
        """``selected`` plus the proxies and devices they lead to."""
        manager = self.manager
        names = list(selected)
        seen = set(names)
        for name in list(names):
            target = manager.aliases.get(name)
            if target is not None and target not in seen:
                names.append(target)
                seen.add(target)
        for name in list(names):
            proxy = manager.proxies.get(name)
            if proxy is not None and proxy.device_name and proxy.device_name not in seen:
                names.append(proxy.device_name)
                seen.add(proxy.device_name)
        return names

    def watched(self, selected: Sequence[str]) -> list[str]:
        """:meth:`watch_names` of ``selected``: :attr:`watch` when the latest frame found it
        for that selection (the same list) and for what the manager has now."""
        found = self._watch_for
        if found is not None and found[0] is selected and found[1] is self.manager.arrangement:
            return self.watch
        return self.watch_names(selected)

    def gather(
        self, frame: int, selected: Sequence[str], *, renewed: bool, every: bool = True
    ) -> int:
        """Gather manager frame ``frame``: note every watched device's samples in its track
        and hand them out (:attr:`gathered`); returns the samples (sampling instants).
        ``renewed``: devices or proxies came or went since the previous frame (the watched
        names are found again); without ``every``, frame groups' shared windows are handed
        out as they are, read per device only when asked (a session with neither statistics
        nor sinks)."""
        self.frame = frame
        if renewed or not self.watch:
            self.watch = self.watch_names(selected)
            self._watch_for = (selected, self.manager.arrangement)
        gathered: Gathered = {}
        self.clock.tick(now())  # (before the plan: a track made for it starts in this frame)
        plan = self._gather_plan(by_name=not every)
        if every:
            samples = self._gather_every(plan, gathered)
            self.gathered = GatheredFrames(gathered)
            return samples
        samples = self._gather(plan.own, gathered) if plan.own else 0
        for group in plan.groups:
            windows = group.windows
            if group.slots is windows.every:  # every slot's window, as published
                samples += windows.fresh_samples
                if windows.none_alone:
                    continue  # (every other slot empty: none swapped on its own)
                slots, fresh = windows.select(group.slots), windows.fresh
            else:
                slots = windows.select(group.slots)
                fresh = windows.fresh[slots]
                sizes = windows.stops[slots] - windows.starts[slots]
                if fresh.all():
                    samples += int(sizes.sum())
                    continue
                samples += int(sizes[fresh].sum())
            alone = ~(fresh | windows.emptied[slots])  # neither a window nor empty
            if alone.any():
                names = [group.names[i] for i in np.flatnonzero(alone).tolist()]
                samples += self._gather(names, gathered)
        self.gathered = GatheredFrames(gathered, plan.shared, plan.groups)
        return samples

    def track(self, name: str, device: Input) -> DeviceTrack:
        """The track of device ``name``, made for ``device`` when it has none (or one of
        another device of that name)."""
        track = self.tracks.get(name)
        if track is None or track.device is not device:
            track = self.tracks[name] = DeviceTrack(
                name, device, self.history, self.statistics, self.clock
            )
        return track

    def current_track(self, name: str) -> DeviceTrack | None:
        """The track of ``name`` with this frame's samples (without statistics, a device
        gathered from shared windows has its track brought up to date when it is read)."""
        track = self.tracks.get(name)
        if track is not None and track.frame_seen != self.frame and not self.statistics:
            track.update()
            track.frame_seen = self.frame
        return track

    def reset(self) -> None:
        """Forget every track's statistics and press counts."""
        for track in self.tracks.values():
            track.reset()

    # -- gathering ----------------------------------------------------------------------

    def _gather(self, names: Iterable[str], gathered: Gathered) -> int:
        """Update the tracks of ``names`` (watched devices) and put what each delivered this
        frame in ``gathered``; returns the samples (sampling instants)."""
        samples = 0
        device_named = self.manager.devices.get
        frame = self.frame
        for name in names:
            device = device_named(name)
            if device is None:
                continue
            track = self.track(name, device)
            samples += track.update()
            track.frame_seen = frame
            if track.frames:
                gathered[name] = track.frames
        return samples

    def _gather_every(self, plan: GatherPlan, gathered: Gathered) -> int:
        """:meth:`_gather` of every watched device with something this frame, in watch
        order: a device whose frame is a window of its group's shared arrays is noted from the
        arrays (:meth:`DeviceTrack.update_window`), the others per device. The members of a
        frame group with nothing this frame (most, for slow devices) are not visited: their
        tracks catch up with the clock when next noted or read."""
        frame = self.frame
        tracks = plan.tracks
        found: dict[int, Mapping[DeviceKind, FrameSamples] | Noted] = {}
        samples = 0
        for index in plan.own_indices:
            track = tracks[index]
            samples += track.update()
            track.frame_seen = frame
            if track.frames:
                found[index] = track.frames
        for group, windows in enumerate(plan.windows):
            serial = windows.serial
            if serial == plan.serials[group]:
                continue  # it did not publish this frame: nothing new for its devices
            plan.serials[group] = serial
            index_of = plan.slot_indices[group]
            moment = windows.moment
            if windows.fresh_slots:
                if windows.fresh_slots == len(windows.every):
                    slots = windows.every
                else:
                    slots = np.flatnonzero(windows.fresh)
                indices = index_of[slots]
                chosen = indices >= 0
                if not chosen.all():
                    slots, indices = slots[chosen], indices[chosen]
                arrays = windows.arrays
                for slot, index, start, stop in zip(
                    slots.tolist(),
                    indices.tolist(),
                    windows.starts[slots].tolist(),
                    windows.stops[slots].tolist(),
                    strict=True,
                ):
                    track = tracks[index]
                    if track._swapped_at == moment:
                        continue  # noted already (a plan made again within the frame)
                    timestamps, items = arrays[slot]
                    count = track.update_window(timestamps, items, start, stop, moment)
                    samples += count
                    track.frame_seen = frame
                    if count:  # (its frame made when read)
                        found[index] = track
                    elif track.frames:
                        found[index] = track.frames
            if not windows.none_alone:  # swapped on their own this frame
                alone = np.flatnonzero(~(windows.fresh | windows.emptied))
                for index in index_of[alone].tolist():
                    if index < 0:
                        continue
                    track = tracks[index]
                    samples += track.update()
                    track.frame_seen = frame
                    if track.frames:
                        found[index] = track.frames
        names = plan.names
        for index in sorted(found):
            gathered[names[index]] = found[index]
        return samples

    def _gather_plan(self, *, by_name: bool) -> GatherPlan:
        """How :meth:`gather` gathers, made again when the watched names, what the manager
        updates or ``by_name`` change. ``by_name``: the frame groups' members are also
        listed by name and by group (only a session without statistics or sinks reads
        shared windows so: 10,000 devices' entries were a megabyte more)."""
        manager = self.manager
        arrangement = manager.arrangement
        plan = self._plan
        if (
            plan is not None
            and plan.arrangement is arrangement
            and plan.watch is self.watch
            and self._plan_by_name == by_name
        ):
            return plan
        own: list[str] = []
        shared: dict[str, tuple[SharedWindows, int, Input]] = {}
        # per group: its windows, the watched slots and names, and its index
        members: dict[int, tuple[SharedWindows, list[int], list[str], int]] = {}
        names: list[str] = []
        tracks: list[DeviceTrack] = []
        places: list[int] = []
        own_indices: list[int] = []
        for name in self.watch:
            device = manager.devices.get(name)
            if device is None:
                continue
            names.append(name)
            tracks.append(self.track(name, device))
            place = device.store.shared
            if place is None:
                own.append(name)
                own_indices.append(len(places))
                places.append(-1)
                continue
            windows, slot = place
            entry = members.get(id(windows))
            if entry is None:
                entry = members[id(windows)] = (windows, [], [], len(members))
            if by_name:
                shared[name] = (windows, slot, device)
                entry[1].append(slot)
                entry[2].append(name)
            places.append(entry[3] * PLACE + slot)
        groups = [
            SharedGroup(windows, slots, group_names)
            for windows, slots, group_names, _ in (members.values() if by_name else ())
        ]
        self._plan = GatherPlan(
            arrangement,
            self.watch,
            own,
            shared,
            groups,
            names,
            tracks,
            np.array(places, dtype=np.int64),
            [windows for windows, _, _, _ in members.values()],
            own_indices,
        )
        self._plan_by_name = by_name
        return self._plan
