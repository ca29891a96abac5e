"""A frame's samples by device: the sampling instants of one device's frame, and the
mapping a session hands its consumers (:class:`GatheredFrames`), which reads the devices
whose frames are windows of a frame group's shared arrays only when asked."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from types import MappingProxyType
from typing import Any, Protocol

import numpy as np

from gadgetctl.input.device import Input
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import FrameSamples, Sample, SharedWindows

NOTHING: Mapping = MappingProxyType({})


def _chunk_timestamps(frame: FrameSamples) -> np.ndarray:
    parts = []
    singles: list[float] = []
    for chunk in frame.chunks:
        if type(chunk) is Sample:
            singles.append(chunk.timestamp)
        else:
            if singles:
                parts.append(np.asarray(singles, dtype=np.float64))
                singles = []
            parts.append(np.asarray(chunk.timestamps, dtype=np.float64))
    if singles:
        parts.append(np.asarray(singles, dtype=np.float64))
    if len(parts) == 1:
        return parts[0]
    return np.concatenate(parts) if parts else np.empty(0)


def frame_timestamps(frames: Mapping[DeviceKind, FrameSamples]) -> np.ndarray:
    """The distinct sampling instants of one device's frame, over all its kinds, in order."""
    arrays = [_chunk_timestamps(f) for f in frames.values() if f.count]
    if not arrays:
        return np.empty(0)
    if len(arrays) == 1:
        return arrays[0]
    longest = max(arrays, key=len)
    if all(len(a) == len(longest) and a[0] == longest[0] and a[-1] == longest[-1] for a in arrays):
        return longest  # the kinds were sampled together (the usual multi-kind driver)
    return np.unique(np.concatenate(arrays))


def as_rows(values: Any) -> np.ndarray:
    array = np.asarray(values)
    return array.reshape(len(array), -1) if array.ndim != 2 else array


class SharedGroup:
    """The watched devices of one frame group that share windows (see
    :class:`~gadgetctl.input.samples.SharedWindows`): their slots and names, in slot order
    (``slots`` is the windows' ``every`` when they are all of them)."""

    __slots__ = ("names", "slots", "windows")

    def __init__(self, windows: SharedWindows, slots: list[int], names: list[str]) -> None:
        order = sorted(range(len(slots)), key=slots.__getitem__)  # in slot order
        self.windows = windows
        self.slots = np.array([slots[i] for i in order], dtype=np.int64)
        self.names = [names[i] for i in order]
        if np.array_equal(self.slots, windows.every):
            self.slots = windows.every  # all of them: read with slices


class Noted(Protocol):
    """What holds a device's frame made when read (a monitor's track of the device)."""

    @property
    def frames(self) -> Mapping[DeviceKind, FrameSamples]: ...


class GatheredFrames(Mapping[str, Mapping[DeviceKind, FrameSamples]]):
    """A frame's samples by device name (:attr:`MonitorSession.gathered`): those gathered per
    device (``own``: their frames, or what holds a frame made when read), and those of the
    devices whose frame is a window of their group's shared arrays, made per device only
    when asked. ``groups``: the latter, for a consumer that reads the shared arrays of every
    device at once (a slot is in this frame when ``fresh``)."""

    __slots__ = ("_own", "_shared", "groups")

    def __init__(
        self,
        own: dict[str, Mapping[DeviceKind, FrameSamples] | Noted],
        shared: Mapping[str, tuple[SharedWindows, int, Input]] = NOTHING,
        groups: Sequence[SharedGroup] = (),
    ) -> None:
        self._own = own
        self._shared = shared
        self.groups = groups

    def __getitem__(self, name: str) -> Mapping[DeviceKind, FrameSamples]:
        frames = self._own.get(name)
        if frames is not None:
            return frames if isinstance(frames, Mapping) else frames.frames
        entry = self._shared.get(name)
        if entry is not None and entry[0].fresh[entry[1]]:
            return entry[2].store.current
        raise KeyError(name)

    def get(self, name: str, default: Any = None) -> Any:
        try:
            return self[name]
        except KeyError:
            return default

    def __contains__(self, name: object) -> bool:
        return self.get(name) is not None  # type: ignore[arg-type]

    def __iter__(self) -> Iterator[str]:
        yield from self._own
        for name, (windows, slot, _) in self._shared.items():
            if windows.fresh[slot]:
                yield name

    def __len__(self) -> int:
        return len(self._own) + sum(1 for w, slot, _ in self._shared.values() if w.fresh[slot])


class GatherPlan:
    """How a session gathers: the watched devices read per device (``own``), and per frame
    group sharing windows, the watched members (``groups``; ``shared``: each member's
    windows, slot and device, for a session without statistics, which reads them at once).
    Every watched device in order: its name, its track, and where its frames are
    (``places``: -1 for a device read per device, else the index of its frame group's
    shared windows in ``windows`` times :data:`PLACE` plus its slot there). Lists and an
    array rather than a tuple a device: 10,000 of them were a megabyte more."""

    __slots__ = (
        "arrangement",
        "groups",
        "names",
        "own",
        "own_indices",
        "places",
        "serials",
        "shared",
        "slot_indices",
        "tracks",
        "watch",
        "windows",
    )

    def __init__(
        self,
        arrangement: object,
        watch: list[str],
        own: list[str],
        shared: dict[str, tuple[SharedWindows, int, Input]],
        groups: list[SharedGroup],
        names: list[str] | None = None,
        tracks: list[Any] | None = None,
        places: np.ndarray | None = None,
        windows: list[SharedWindows] | None = None,
        own_indices: list[int] | None = None,
    ) -> None:
        self.arrangement, self.watch, self.own, self.shared, self.groups = (
            arrangement,
            watch,
            own,
            shared,
            groups,
        )
        self.names = names if names is not None else []
        self.tracks = tracks if tracks is not None else []
        self.places = places if places is not None else np.empty(0, dtype=np.int64)
        self.windows = windows if windows is not None else [group.windows for group in groups]
        #: The indices (in ``names``) of the devices read per device.
        self.own_indices = (
            own_indices if own_indices is not None else np.flatnonzero(self.places < 0).tolist()
        )
        #: Per shared windows: each slot's index in ``names`` (-1: not watched), and the
        #: serial of the windows' frame gathered last.
        self.slot_indices: list[np.ndarray] = []
        for group, shared_windows in enumerate(self.windows):
            index_of = np.full(len(shared_windows.every), -1, dtype=np.int64)
            mine = np.flatnonzero((self.places >= 0) & (self.places // PLACE == group))
            index_of[self.places[mine] % PLACE] = mine
            self.slot_indices.append(index_of)
        self.serials = [-1] * len(self.windows)


#: A group's index in a :class:`GatherPlan`'s ``places`` is counted in these.
PLACE = 1 << 32


NO_GATHERING = GatheredFrames({})
