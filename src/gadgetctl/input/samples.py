"""Timestamped samples and the thread-safe buffers devices fill and frames swap.

A sample holds one value per unit (a button, an axis, a sensor) and the time it was taken.
The sampling side appends samples, one at a time or as a :class:`SampleBatch` (consecutive
samples added together, e.g. computed with numpy); the frame side calls
:meth:`SampleStore.swap` once per frame. After a swap, :meth:`SampleStore.frame` holds every
sample that arrived since the previous swap (monitors and recorders read them all) and
:meth:`SampleStore.latest` the newest sample ever received (proxies read it; it stays
latched when a frame brings nothing new).

At most ``cap`` samples per kind are kept between two swaps; older ones are dropped and
counted, so a stalled frame loop costs memory for one frame at most.

Devices updated together (a frame group) may share one :class:`SharedWindows`: in the usual
frame each device's samples are one window of arrays it computed ahead, and the group writes
every device's window bounds into the shared arrays at once instead of swapping each store.
A store then makes its frame from its slot when it is first read or written (so proxies,
recorders and statistics see exactly what a swap would have given them), and consumers of
every device (the monitor session, `serve`) read the shared arrays without touching the
stores.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Iterable, Iterator, Mapping, Sequence
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from gadgetctl.input.clock import now
from gadgetctl.input.kinds import DeviceKind

DEFAULT_CAP = 5000


class Sample(NamedTuple):
    """One sample: ``values[unit]`` is the datum of each unit."""

    timestamp: float
    values: Any


class SampleBatch:
    """Consecutive samples of one kind: ``timestamps`` has shape (n,), ``values`` (n, units, ...).

    A batch may also be a window ``[start, stop)`` of larger arrays (see
    :meth:`SampleStore.add_slices`), sliced only when read; while it waits for the next
    swap, a following window of the same arrays extends it instead of adding a chunk.
    """

    __slots__ = ("_base_timestamps", "_base_values", "_timestamps", "_values", "start", "stop")

    def __init__(self, timestamps: Any, values: Any) -> None:
        if len(timestamps) != len(values):
            raise ValueError(f"{len(timestamps)} timestamps for {len(values)} samples")
        self._timestamps, self._values = timestamps, values
        self._base_timestamps = self._base_values = None
        self.start, self.stop = 0, len(timestamps)

    @classmethod
    def window(cls, timestamps: Any, values: Any, start: int, stop: int) -> SampleBatch:
        """Samples ``start`` .. ``stop - 1`` of ``timestamps`` and ``values``, not yet sliced."""
        batch = cls.__new__(cls)
        batch._base_timestamps, batch._base_values = timestamps, values
        batch._timestamps = batch._values = None
        batch.start, batch.stop = start, stop
        return batch

    def extends(self, values: Any, start: int) -> bool:
        """Whether ``values[start:...]`` continues this (still unsliced) window."""
        return self._base_values is values and self._timestamps is None and self.stop == start

    # a window's slices are made when read, not kept: a frame of 10,000 devices kept 5 MB
    # of them until the next one

    @property
    def timestamps(self) -> Any:
        if self._timestamps is None:
            return self._base_timestamps[self.start : self.stop]
        return self._timestamps

    @property
    def values(self) -> Any:
        if self._values is None:
            return self._base_values[self.start : self.stop]
        return self._values

    @property
    def base(self) -> tuple[Any, Any, int, int] | None:
        """For a window (:meth:`window`): ``(timestamps, values, start, stop)``, the arrays it
        is cut from and its bounds; None for a batch of arrays of its own. A consumer that
        converts every sample (VRPN framing) can convert a stretch of the arrays once and cut
        this and later windows from the result."""
        if self._base_values is None:
            return None
        return self._base_timestamps, self._base_values, self.start, self.stop

    def __len__(self) -> int:
        return self.stop - self.start

    def row(self, index: int) -> Sample:
        if index < 0:
            index += self.stop - self.start
        if self._base_values is not None:  # read the window's arrays without slicing them
            return Sample(
                float(self._base_timestamps[self.start + index]),
                self._base_values[self.start + index],
            )
        return Sample(float(self._timestamps[index]), self._values[index])

    def tail(self, count: int) -> SampleBatch:
        """The last ``count`` samples."""
        first = len(self) - count
        return SampleBatch(self.timestamps[first:], self.values[first:])

    def __iter__(self) -> Iterator[Sample]:
        for index in range(len(self)):
            yield self.row(index)


Chunk = Sample | SampleBatch


class FrameSamples:
    """The samples of one kind that arrived between two frames, oldest first."""

    __slots__ = ("chunks", "count")

    def __init__(self, chunks: Iterable[Chunk] = (), count: int | None = None) -> None:
        self.chunks = tuple(chunks) if not isinstance(chunks, (tuple, deque)) else chunks
        self.count = (
            count
            if count is not None
            else sum(1 if isinstance(c, Sample) else len(c) for c in self.chunks)
        )

    def __len__(self) -> int:
        return self.count

    def __bool__(self) -> bool:
        return self.count > 0

    def __iter__(self) -> Iterator[Sample]:
        for chunk in self.chunks:
            if isinstance(chunk, Sample):
                yield chunk
            else:
                yield from chunk

    @property
    def newest(self) -> Sample | None:
        if not self.count:
            return None
        last = self.chunks[-1]
        return last if type(last) is Sample else last.row(-1)

    def column(self, unit: int) -> list[Any]:
        """The values of one unit, oldest first (samples without that unit are skipped)."""
        result: list[Any] = []
        for chunk in self.chunks:
            if isinstance(chunk, Sample):
                if unit < len(chunk.values):
                    result.append(chunk.values[unit])
            elif len(chunk.values) and unit < len(chunk.values[0]):
                result.extend(
                    chunk.values[:, unit]
                    if hasattr(chunk.values, "shape")
                    else [row[unit] for row in chunk.values]
                )
        return result

    def timestamps(self) -> list[float]:
        """Every timestamp, oldest first."""
        result: list[float] = []
        for chunk in self.chunks:
            if isinstance(chunk, Sample):
                result.append(chunk.timestamp)
            else:
                result.extend(float(t) for t in chunk.timestamps)
        return result


EMPTY_FRAME = FrameSamples((), 0)


def _window_frame(timestamps: Any, values: Any, start: int, stop: int) -> FrameSamples:
    """A frame of one :meth:`SampleBatch.window` (made field by field: a device swaps one
    such frame per kind every frame)."""
    batch = _new(SampleBatch)
    batch._base_timestamps, batch._base_values = timestamps, values
    batch._timestamps = batch._values = None
    batch.start, batch.stop = start, stop
    frame = _new(FrameSamples)
    frame.chunks, frame.count = (batch,), stop - start
    return frame


_new = object.__new__


#: Up to this many slots, the writer and readers of :class:`SharedWindows` go slot by slot
#: with Python numbers: numpy's fixed cost per call (a few dozen calls a frame) is most of the
#: frame of a small group, e.g. one 1 kHz tracker served over VRPN.
FEW_SLOTS = 16


class SharedWindows:
    """The frames of a frame group's devices whose usual frame is one window of arrays they
    computed ahead, side by side (one slot per device).

    Each group frame (:meth:`publish`) increments ``serial``; a slot marked ``fresh`` then has
    as its current frame samples ``starts[slot]`` .. ``stops[slot] - 1`` of
    ``arrays[slot]`` (``(timestamps, ((kind, values), ...))``), swapped at ``moment``; the
    frame of a slot that is not fresh is empty when ``emptied`` (the store swaps with nothing
    new), else in its store as usual. ``delivered`` counts each
    slot's samples published this way (the stores' totals). A group changes a slot's
    ``arrays`` only after its store took its pending window (:meth:`SampleStore.sync`).
    """

    def __init__(self, stores: Sequence[SampleStore]) -> None:
        count = len(stores)
        self.serial = 0
        self.moment = 0.0
        self.fresh = np.zeros(count, dtype=bool)
        self.emptied = np.zeros(count, dtype=bool)  # swapped with nothing new
        self.window_serial = np.zeros(count, dtype=np.int64)  # when its window was published
        self.starts = np.zeros(count, dtype=np.int64)
        self.stops = np.zeros(count, dtype=np.int64)
        self.delivered = np.zeros(count, dtype=np.int64)
        #: Per slot, how many times its arrays were replaced (a consumer that converted a
        #: stretch of them knows it from this number).
        self.generation = np.zeros(count, dtype=np.int64)
        self.arrays: list[tuple[Any, tuple[tuple[DeviceKind, Any], ...]] | None] = [None] * count
        #: Per slot, the arrays its windows will be cut from next, when known ahead (a
        #: consumer may convert some of them between frames), and how many times they were set.
        self.upcoming: list[tuple[Any, tuple[tuple[DeviceKind, Any], ...]] | None] = [None] * count
        self.upcoming_generation = np.zeros(count, dtype=np.int64)
        #: Incremented whenever some slot's upcoming arrays are set (a reader that saw this
        #: number has seen every slot's).
        self.upcoming_serial = 0
        #: Of the last :meth:`publish`: how many slots are fresh, and their samples in all, and
        #: how many were emptied (a reader of every slot knows from these numbers, without
        #: numpy, whether some slot's frame is in its store this time).
        self.fresh_slots = 0
        self.fresh_samples = 0
        self.emptied_slots = 0
        self.stores = tuple(stores)
        #: Every slot in order: a reader that passes this very array for its slots means all
        #: of them (``select`` turns it into a slice, no gathering copy).
        self.every = np.arange(count, dtype=np.int64)
        for slot, store in enumerate(self.stores):
            store.share(self, slot)

    def publish(
        self,
        moment: float,
        slots: np.ndarray,
        starts: np.ndarray,
        stops: np.ndarray,
        empty: np.ndarray | None = None,
    ) -> None:
        """A group frame at ``moment``: ``slots`` get the windows ``starts`` .. ``stops``
        (each at least one sample, within the slot's arrays); the slots ``empty`` swap with
        nothing new (their newest sample stays); every other slot is not fresh (its device
        swapped its own store this frame, before this call)."""
        self.serial += 1
        self.moment = moment
        fresh = self.fresh
        slots = self.select(slots)
        if type(slots) is slice:
            fresh[:] = True
            self.fresh_slots = len(fresh)
        else:
            fresh[:] = False
            fresh[slots] = True
            self.fresh_slots = len(slots)
        self.emptied[:] = False
        if empty is not None:
            self.emptied[empty] = True
            self.emptied_slots = len(empty)
        else:
            self.emptied_slots = 0
        self.starts[slots] = starts
        self.stops[slots] = stops
        self.window_serial[slots] = self.serial
        sizes = stops - starts
        self.delivered[slots] += sizes
        # (a ufunc's reduce: ndarray.sum() goes through a Python function of numpy's)
        self.fresh_samples = int(np.add.reduce(sizes))

    def publish_few(
        self, moment: float, windows: Sequence[tuple[int, int, int]], empty: Sequence[int] = ()
    ) -> None:
        """:meth:`publish` for a few slots (:data:`FEW_SLOTS`), each window given as
        ``(slot, start, stop)`` with Python numbers, element by element."""
        self.serial += 1
        self.moment = moment
        fresh, emptied = self.fresh, self.emptied
        fresh[:] = False
        emptied[:] = False
        for slot in empty:
            emptied[slot] = True
        serial, samples = self.serial, 0
        starts, stops, window_serial, delivered = (
            self.starts,
            self.stops,
            self.window_serial,
            self.delivered,
        )
        for slot, start, stop in windows:
            fresh[slot] = True
            starts[slot], stops[slot], window_serial[slot] = start, stop, serial
            delivered[slot] += stop - start
            samples += stop - start
        self.fresh_slots = len(windows)
        self.fresh_samples = samples
        self.emptied_slots = len(empty)

    @property
    def all_fresh(self) -> bool:
        """Whether the last :meth:`publish` gave every slot a window."""
        return self.fresh_slots == len(self.every)

    @property
    def none_alone(self) -> bool:
        """Whether the last :meth:`publish` gave every slot a window or an empty frame (no
        slot's frame is in its store alone)."""
        return self.fresh_slots + self.emptied_slots == len(self.every)

    def select(self, slots: np.ndarray) -> np.ndarray | slice:
        """``slots`` as an index of the per-slot arrays: a slice when it is :attr:`every`."""
        return slice(None) if slots is self.every else slots

    def set_arrays(
        self, slot: int, timestamps: Any, items: tuple[tuple[DeviceKind, Any], ...]
    ) -> None:
        """The arrays slot ``slot``'s windows are cut from from now on (its store has taken
        its pending window)."""
        current = self.arrays[slot]
        if current is None or current[0] is not timestamps or current[1] is not items:
            self.arrays[slot] = (timestamps, items)
            self.generation[slot] += 1
            upcoming = self.upcoming[slot]
            if upcoming is not None and upcoming[0] is timestamps:
                self.upcoming[slot] = None

    def set_upcoming(
        self, slot: int, timestamps: Any, items: tuple[tuple[DeviceKind, Any], ...]
    ) -> None:
        """The arrays slot ``slot``'s windows will be cut from after its current ones."""
        self.upcoming[slot] = (timestamps, items)
        self.upcoming_generation[slot] += 1
        self.upcoming_serial += 1


#: A channel's chunks while none waits. Waiting chunks are a list (a frame has one or a
#: few): a deque costs 600 bytes even empty, 6 KB a device of six kinds, 60 MB for 10,000,
#: and a new one at every swap; a list is dropped from the front only when over the cap.
_NO_CHUNKS: tuple[Chunk, ...] = ()


class _Channel:
    """The buffers of one kind of data."""

    __slots__ = ("count", "dropped", "frame", "latest", "ready", "total")

    def __init__(self) -> None:
        self.ready: list[Chunk] | tuple[Chunk, ...] = _NO_CHUNKS
        self.count = 0
        self.total = 0
        self.dropped = 0
        self.frame = EMPTY_FRAME
        self.latest: Sample | None = None

    def waiting(self) -> list[Chunk]:
        """The chunks waiting for the next swap, to append to."""
        ready = self.ready
        if type(ready) is tuple:
            ready = self.ready = []
        return ready  # type: ignore[return-value]

    def trim(self, cap: int) -> None:
        excess = self.count - cap
        ready = self.ready
        whole = 0  # chunks dropped whole, taken off the front at once
        while excess > 0:
            first = ready[whole]
            size = 1 if isinstance(first, Sample) else len(first)
            if size <= excess:
                whole += 1
                excess -= size
                self.dropped += size
            else:
                ready[whole] = first.tail(size - excess)
                self.dropped += excess
                excess = 0
        del ready[:whole]
        self.count = min(self.count, cap)


#: The channel a declared kind reads as before its first sample (never added to).
_UNUSED = _Channel()

#: The tuples of declared kinds, one for each set (10,000 devices alike share one).
_KINDS: dict[tuple[DeviceKind, ...], tuple[DeviceKind, ...]] = {}


#: _declared's answers by the id of a tuple given: (that tuple, the shared tuple). Each
#: device class gives its one tuple of kinds (Input.kinds), for each of 10,000 devices.
_KINDS_GIVEN: dict[int, tuple[tuple, tuple[DeviceKind, ...]]] = {}


def _declared(kinds: Iterable[DeviceKind]) -> tuple[DeviceKind, ...]:
    """The shared tuple of ``kinds`` (see :data:`_KINDS`)."""
    given = _KINDS_GIVEN.get(id(kinds)) if type(kinds) is tuple else None
    if given is not None and given[0] is kinds:
        return given[1]  # (the entry keeps the tuple given: its id is its own)
    # (a member is taken as it is: DeviceKind(member) costs more than the channel)
    declared = tuple(k if type(k) is DeviceKind else DeviceKind(k) for k in kinds)
    shared = _KINDS.setdefault(declared, declared)
    if type(kinds) is tuple and len(_KINDS_GIVEN) < 256:
        _KINDS_GIVEN[id(kinds)] = (kinds, shared)
    return shared


#: A store's current frame before its first swap, and any frame without samples (read-only,
#: as every current frame is; shared by every store and track that has no samples).
NO_CURRENT: Mapping[DeviceKind, FrameSamples] = MappingProxyType({})


class SampleStore:
    """The sample buffers of one device, one per kind it provides, behind one lock."""

    # one per device: slotted (an instance dict was 160 bytes, 1.6 MB for 10,000 devices)
    __slots__ = (
        "_applied",
        "_channels",
        "_current",
        "_delivered",
        "_kinds",
        "_lock",
        "_shared",
        "_slot",
        "_swapped_at",
        "_swaps",
        "_synced",
        "_waiting",
        "cap",
    )

    def __init__(self, kinds: Iterable[DeviceKind], cap: int = DEFAULT_CAP) -> None:
        if cap < 1:
            raise ValueError("the sample cap must be at least 1")
        self.cap = cap
        self._lock = threading.Lock()
        self._kinds = _declared(kinds)  # one tuple per set of kinds
        # a kind's channel is made when its first sample comes: a waveform device with one
        # position path declares six kinds and fills one (five channels and a larger dict,
        # 5 MB for 10,000 devices); a kind without one reads as _UNUSED
        self._channels: dict[DeviceKind, _Channel] = {}
        self._swapped_at: float | None = None
        self._swaps = 0  # frames made current so far (see changes())
        self._waiting = False  # samples were added since the last swap
        self._current: Mapping[DeviceKind, FrameSamples] = NO_CURRENT
        # a frame group's shared windows this store takes its usual frames from (see
        # SharedWindows), its slot there, the serial taken last and the samples counted
        self._shared: SharedWindows | None = None
        self._slot = 0
        self._synced = 0
        self._delivered = 0
        self._applied = 0  # the serial of the last shared window made current

    @property
    def swapped_at(self) -> float | None:
        """When the current frame's samples were taken over."""
        if self._shared is not None and self._shared.serial != self._synced:
            self.sync()
        return self._swapped_at

    def changes(self) -> tuple[int, int]:
        """A value that changes whenever the current frame may have been replaced (what
        :meth:`latest` returns may then differ): a reader that saw it knows whether to read
        again. Read without taking shared windows in: a frame group's frame that brought this
        store no window of its own changes nothing."""
        shared = self._shared
        return (self._swaps, 0 if shared is None else int(shared.window_serial[self._slot]))

    @property
    def current(self) -> Mapping[DeviceKind, FrameSamples]:
        """The current frame's samples of each kind that has any (read-only; replaced, never
        changed, by each swap): what a consumer of every sample reads without asking per kind."""
        if self._shared is not None and self._shared.serial != self._synced:
            self.sync()
        return self._current

    # -- shared windows ---------------------------------------------------------------

    @property
    def shared(self) -> tuple[SharedWindows, int] | None:
        """The shared windows this store takes its usual frames from, and its slot there."""
        return None if self._shared is None else (self._shared, self._slot)

    def share(self, shared: SharedWindows | None, slot: int = 0) -> None:
        """Take usual frames from ``shared`` at ``slot`` from now on (None: no longer); what
        the previous one left pending is taken first."""
        self.sync()
        with self._lock:
            self._swaps += 1  # (changes(): another serial from now on)
            self._shared, self._slot = shared, slot
            self._synced = shared.serial if shared is not None else 0
            self._delivered = int(shared.delivered[slot]) if shared is not None else 0
            self._applied = int(shared.window_serial[slot]) if shared is not None else 0

    def sync(self) -> None:
        """Make the shared windows' latest frame of this store's slot current (when fresh)
        and count the samples published there; a no-op when nothing is pending."""
        shared = self._shared
        if shared is None or shared.serial == self._synced:
            return
        with self._lock:
            serial = shared.serial
            if serial == self._synced:
                return
            self._synced = serial
            slot = self._slot
            delivered = int(shared.delivered[slot])
            counted, self._delivered = delivered - self._delivered, delivered
            fresh = shared.fresh[slot]
            if not fresh and not shared.emptied[slot]:
                return
            timestamps, items = shared.arrays[slot]
            if counted:
                writable = self._writable
                for kind, _ in items:
                    writable(kind).total += counted
            window = int(shared.window_serial[slot])
            if fresh or window > self._applied:  # a window not made current yet comes first
                self._applied = window
                self._window_frames(
                    timestamps, items, int(shared.starts[slot]), int(shared.stops[slot])
                )
            if not fresh:  # then the empty frame of this serial
                self._make_current(self._take())
            self._swapped_at = shared.moment

    @property
    def kinds(self) -> tuple[DeviceKind, ...]:
        return self._kinds

    def _channel(self, kind: DeviceKind) -> _Channel:
        """The channel of ``kind`` to read (:data:`_UNUSED` when none has come yet)."""
        channel = self._channels.get(kind)
        if channel is not None:
            return channel
        if kind in self._kinds:
            return _UNUSED
        raise KeyError(f"this device provides no {kind} data")

    def _writable(self, kind: DeviceKind) -> _Channel:
        """The channel of ``kind`` to add to, made on the first sample of the kind."""
        channel = self._channels.get(kind)
        if channel is None:
            kinds = self._kinds
            if kind not in kinds:
                raise KeyError(f"this device provides no {kind} data")
            kind = kinds[kinds.index(kind)]  # the member, also when given by value
            channel = self._channels[kind] = _Channel()
        return channel

    @property
    def channels_made(self) -> tuple[DeviceKind, ...]:
        """The kinds whose channel was made (that had a sample), in the order they came."""
        return tuple(self._channels)

    # -- sampling side ----------------------------------------------------------------

    def add(self, kind: DeviceKind, timestamp: float, values: Any) -> None:
        """Append one sample."""
        channel = self._writable(kind)
        if self._shared is not None:
            self.sync()
        with self._lock:
            self._waiting = True
            channel.waiting().append(Sample(timestamp, values))
            channel.count += 1
            channel.total += 1
            if channel.count > self.cap:
                channel.trim(self.cap)

    def add_batch(self, kind: DeviceKind, timestamps: Any, values: Any) -> None:
        """Append consecutive samples of one kind."""
        self.add_batches(timestamps, {kind: values})

    def add_batches(
        self, timestamps: Any, values: Mapping[DeviceKind, Any] | Iterable[tuple[DeviceKind, Any]]
    ) -> None:
        """Append consecutive samples of several kinds taken at the same times, under one lock.
        ``values``: kind -> array of shape (samples, units, ...), as a mapping or pairs."""
        size = len(timestamps)
        if not size:
            return
        pairs = values.items() if isinstance(values, dict) else values
        writable = self._writable
        chunks = [(writable(kind), SampleBatch(timestamps, data)) for kind, data in pairs]
        cap = self.cap
        if self._shared is not None:
            self.sync()
        with self._lock:
            self._waiting = True
            for channel, batch in chunks:
                channel.waiting().append(batch)
                channel.count += size
                channel.total += size
                if channel.count > cap:
                    channel.trim(cap)

    def add_slices(
        self, timestamps: Any, values: Iterable[tuple[DeviceKind, Any]], start: int, stop: int
    ) -> None:
        """Append samples ``start`` .. ``stop - 1`` of arrays computed ahead (``timestamps``
        and, per kind, ``values`` of shape (n, units, ...)) without slicing them now."""
        if stop > start:
            if self._shared is not None:
                self.sync()
            with self._lock:
                self._add_slices(timestamps, values, start, stop)

    def _add_slices(
        self, timestamps: Any, values: Iterable[tuple[DeviceKind, Any]], start: int, stop: int
    ) -> None:
        size = stop - start
        channels = self._channels
        cap = self.cap
        self._waiting = True
        for kind, data in values:
            channel = channels.get(kind) or self._writable(kind)
            ready = channel.ready
            last = ready[-1] if ready else None
            if type(last) is SampleBatch and last.extends(data, start):
                last.stop = stop
            else:
                channel.waiting().append(SampleBatch.window(timestamps, data, start, stop))
            channel.count += size
            channel.total += size
            if channel.count > cap:
                channel.trim(cap)

    # -- frame side -------------------------------------------------------------------

    def swap(self, moment: float | None = None) -> None:
        """Make everything added since the previous swap the current frame's samples;
        ``moment``: the swap's time when the caller has it."""
        if self._shared is not None:
            self.sync()
        self._swapped_at = now() if moment is None else moment
        with self._lock:
            taken = self._take()
        self._make_current(taken)

    def add_slices_and_swap(
        self,
        timestamps: Any,
        values: Iterable[tuple[DeviceKind, Any]],
        start: int,
        stop: int,
        moment: float | None = None,
    ) -> None:
        """:meth:`add_slices` then :meth:`swap`, under one lock (a device publishing samples
        computed ahead at the frame); ``moment``: the swap's time when the caller has it.

        When nothing else waits (the usual frame of a device that publishes only here), each
        kind's frame is its one window, made without the general bookkeeping."""
        if self._shared is not None:
            self.sync()
        self._swapped_at = now() if moment is None else moment
        size = stop - start
        with self._lock:
            if not self._waiting and 0 < size <= self.cap:
                channels = self._channels
                for kind, _ in values:
                    (channels.get(kind) or self._writable(kind)).total += size
                self._window_frames(timestamps, values, start, stop)
                return
            if size > 0:
                self._add_slices(timestamps, values, start, stop)
            taken = self._take()
        self._make_current(taken)

    def _window_frames(
        self, timestamps: Any, values: Iterable[tuple[DeviceKind, Any]], start: int, stop: int
    ) -> None:
        """Make each kind's window ``start`` .. ``stop - 1`` the current frame (nothing else
        waits; the caller holds the lock and counted the samples)."""
        current = {}
        channels = self._channels
        for kind, data in values:
            channel = channels.get(kind) or self._writable(kind)
            channel.frame = current[kind] = _window_frame(timestamps, data, start, stop)
            channel.latest = None  # the frame's newest, computed when asked
        for kind in self._current:  # kinds that had samples and have none now
            if kind not in current:
                channel = channels[kind]
                if channel.latest is None:  # keep the newest latched
                    channel.latest = channel.frame.newest
                channel.frame = EMPTY_FRAME
        self._current = current
        self._swaps += 1

    def _take(self) -> list[tuple[DeviceKind, _Channel, list[Chunk], int]]:
        self._waiting = False
        taken: list[tuple[DeviceKind, _Channel, list[Chunk], int]] = []
        for kind, channel in self._channels.items():
            if channel.count:
                taken.append((kind, channel, channel.ready, channel.count))
                channel.ready = _NO_CHUNKS
                channel.count = 0
            elif channel.frame.count:
                if channel.latest is None:
                    channel.latest = channel.frame.newest  # keep it latched
                channel.frame = EMPTY_FRAME
        return taken

    def _make_current(self, taken: list[tuple[DeviceKind, _Channel, list[Chunk], int]]) -> None:
        current = {}
        for kind, channel, chunks, count in taken:
            channel.frame = current[kind] = FrameSamples(chunks, count)
            channel.latest = None  # the frame's newest, computed when asked
        self._current = current
        self._swaps += 1

    def frame(self, kind: DeviceKind) -> FrameSamples:
        if self._shared is not None:
            self.sync()
        return self._channel(kind).frame

    def latest(self, kind: DeviceKind) -> Sample | None:
        """The newest sample ever received (it stays when a frame brings nothing new)."""
        shared = self._shared
        if shared is not None and shared.serial != self._synced:
            slot = self._slot
            # its window of the latest frame, or one not taken yet (the slot had nothing
            # since, or an empty frame): read without making the frame
            if shared.fresh[slot] or shared.window_serial[slot] > self._applied:
                timestamps, items = shared.arrays[slot]
                for found, values in items:
                    if found is kind:  # the last of its window
                        last = int(shared.stops[slot]) - 1
                        return Sample(float(timestamps[last]), values[last])
                # a kind the window has not: its newest is as it was (the frame would latch it)
                channel = self._channel(kind)
                frame = channel.frame
                return frame.newest if frame.count else channel.latest
            self.sync()
        channel = self._channel(kind)
        # the current frame's newest is made when asked, not kept (a sample and a view of its
        # values for each kind of 10,000 devices were 5 MB); a swap to an empty frame latches it
        frame = channel.frame
        return frame.newest if frame.count else channel.latest

    def width(self, kind: DeviceKind) -> int | None:
        """How many units the newest sample of ``kind`` has (None before the first), read
        without making that sample when it is in a shared window not taken in yet."""
        shared = self._shared
        if shared is not None and shared.serial != self._synced:
            slot = self._slot
            if shared.fresh[slot] or shared.window_serial[slot] > self._applied:
                for found, values in shared.arrays[slot][1]:
                    if found is kind:
                        return values.shape[1]
        newest = self.latest(kind)
        return None if newest is None else len(newest.values)

    def newest(self) -> list[tuple[DeviceKind, Sample]]:
        """:meth:`latest` of each declared kind that has had a sample, in declared order
        (the kinds that never had one are not asked: a waveform device declares six and
        fills one)."""
        shared = self._shared
        window: tuple[DeviceKind, ...] | list[DeviceKind] = ()
        if shared is not None and shared.serial != self._synced:
            slot = self._slot
            if shared.fresh[slot] or shared.window_serial[slot] > self._applied:
                window = [kind for kind, _ in shared.arrays[slot][1]]  # (not taken in yet)
        channels = self._channels
        found = []
        for kind in self._kinds:
            if kind in channels or kind in window:
                sample = self.latest(kind)
                if sample is not None:
                    found.append((kind, sample))
        return found

    def total(self, kind: DeviceKind | None = None) -> int:
        """Samples added so far (dropped ones included)."""
        if self._shared is not None:
            self.sync()
        if kind is not None:
            return self._channel(kind).total
        return sum(c.total for c in self._channels.values())

    def dropped(self, kind: DeviceKind | None = None) -> int:
        """Samples dropped because more than ``cap`` arrived between two swaps."""
        if kind is not None:
            return self._channel(kind).dropped
        return sum(c.dropped for c in self._channels.values())

    def most_dropped(self) -> int:
        """The most samples :meth:`dropped` of any one kind (0 without kinds): one call a
        frame for each of 10,000 devices, not one per kind."""
        most = 0
        for channel in self._channels.values():
            if channel.dropped > most:
                most = channel.dropped
        return most
