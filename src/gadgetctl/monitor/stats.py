"""Running per-device sample statistics for the live monitor.

Feed each device the timestamps of its updates (one per sampling instant, whatever the
number of units), in non-decreasing order, in batches. Adding is a list append; the numpy
work happens once per snapshot (or when ``history`` timestamps are pending), so 100 devices
at 1 kHz cost little. Counts, mean rate and the largest gap cover the whole run; interval
percentiles and jitter cover the ``history`` most recent intervals; the window rate and the
window samples per frame cover the last ``window`` seconds (the live view and the table show
these two side by side, so they must describe the same stretch of time).

:func:`summarize_recording` (in :mod:`gadgetctl.monitor.summary`) summarizes a finished
recording.
"""

from __future__ import annotations

from array import array
from bisect import bisect_right
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, fields
from itertools import chain, repeat

import numpy as np

from gadgetctl.monitor.batchstats import figures
from gadgetctl.monitor.summary import summarize_recording

__all__ = [
    "DeviceSnapshot",
    "DeviceStats",
    "MonitorStats",
    "snapshot_rows",
    "snapshots",
    "summarize_recording",
]

DEFAULT_WINDOW = 1.0
DEFAULT_HISTORY = 4096
#: Timestamps a device's ring holds before it first grows (doubling up to its history): a
#: 10 Hz device of a short run gives a handful (64 cost 10,000 devices 4 MB more).
INITIAL_RING = 16
#: Every device's ring before its first timestamps are consolidated (read-only, shared).
_NO_RING = np.empty(0, dtype=np.float64)
_NO_RING.flags.writeable = False


@dataclass(frozen=True, slots=True)
class DeviceSnapshot:
    """Statistics of one device at one moment; times in seconds, rates in Hz.

    ``None`` means "not known yet" (e.g. percentiles before the second sample).
    """

    name: str
    count: int
    first_timestamp: float | None
    newest_timestamp: float | None
    mean_rate: float
    window_rate: float
    p50_interval: float | None
    p99_interval: float | None
    max_gap: float | None
    jitter: float | None
    dropped: int
    faults: int
    age: float | None
    frames: int
    samples_per_frame: int | None
    mean_samples_per_frame: float | None
    window_samples_per_frame: float | None = None

    def to_dict(self) -> dict[str, object]:
        # every field is a number, a name or None: no deep copy (asdict) needed
        return {name: getattr(self, name) for name in _SNAPSHOT_FIELDS}


_SNAPSHOT_FIELDS = tuple(f.name for f in fields(DeviceSnapshot))


class DeviceStats:
    """Running statistics of one device's sample timestamps."""

    # one per watched device: slotted
    __slots__ = (
        "_frame_ends",
        "_frame_samples",
        "_frame_start_count",
        "_last",
        "_max_gap",
        "_pending",
        "_ring",
        "_ring_len",
        "_ring_pos",
        "count",
        "dropped",
        "faults",
        "first_timestamp",
        "frames",
        "history",
        "name",
        "newest_timestamp",
        "samples_per_frame",
        "window",
    )

    def __init__(
        self, name: str, *, window: float = DEFAULT_WINDOW, history: int = DEFAULT_HISTORY
    ) -> None:
        if window <= 0:
            raise ValueError("window must be positive")
        if history < 2:
            raise ValueError("history must hold at least 2 timestamps")
        self.name = name
        self.window = window
        self.history = history
        # the first timestamps consolidated, grown as more come, up to
        # ``history``: a 10 Hz device of a short run holds a few, not 4096 (32 KB for each
        # of 10,000 devices); none before then (a ring of 16 for each of 10,000 devices was
        # 2 MB held through a whole run whose statistics are read only at its end)
        self._ring = _NO_RING
        self.reset()

    def reset(self) -> None:
        """Forget everything, counters included."""
        self.count = 0
        self.first_timestamp: float | None = None
        self.newest_timestamp: float | None = None
        self.dropped = 0
        self.faults = 0
        self.frames = 0
        self.samples_per_frame: int | None = None
        self._frame_start_count = 0
        self._frame_samples = 0
        # time, count, time, count ... of recent frame ends, as doubles (a list of (time,
        # count) tuples held 80 bytes a frame, 2 MB for 10,000 devices after three frames;
        # a deque is 600 bytes even empty); a window holds tens of frames, dropped from the
        # front at once
        self._frame_ends = array("d")
        # doubles, not a list of Python floats (32 bytes each, 8 here)
        self._pending = array("d")
        self._ring_len = 0
        self._ring_pos = 0
        self._last: float | None = None
        self._max_gap: float | None = None

    # ---------------------------------------------------------------- feeding

    def add_timestamp(self, timestamp: float) -> None:
        """One update at ``timestamp``."""
        self._pending.append(float(timestamp))
        self.count += 1
        if self.first_timestamp is None:
            self.first_timestamp = float(timestamp)
        self.newest_timestamp = float(timestamp)
        if len(self._pending) >= self.history:
            self._consolidate()

    def add_timestamps(self, timestamps: Sequence[float] | np.ndarray) -> None:
        """A batch of updates (a list, tuple or numpy array of timestamps)."""
        n = len(timestamps)
        if n == 0:
            return
        if n == 1:  # (a frame's one sample: the usual case of a slow device)
            self.add_timestamp(timestamps[0])
            return
        if isinstance(timestamps, np.ndarray):
            self._pending.frombytes(timestamps.astype(np.float64, copy=False).ravel().tobytes())
        else:
            self._pending.extend(timestamps)
        self.count += n
        if self.first_timestamp is None:
            self.first_timestamp = float(timestamps[0])
        self.newest_timestamp = float(timestamps[-1])
        if len(self._pending) >= self.history:
            self._consolidate()

    def add_dropped(self, count: int = 1) -> None:
        """Samples the caller knows were lost (e.g. buffer overflow)."""
        self.dropped += count

    def add_fault(self, count: int = 1) -> None:
        """Device faults (read errors, reconnects) reported by the caller."""
        self.faults += count

    def end_frame(self, at: float | None = None) -> None:
        """A frame boundary: the samples added since the previous one belong to this frame.
        ``at`` (the timestamps' clock) places it in time, for the window figures."""
        self.samples_per_frame = self.count - self._frame_start_count
        self._frame_start_count = self.count
        self._frame_samples += self.samples_per_frame
        self.frames += 1
        if at is not None:
            ends = self._frame_ends
            ends.append(float(at))
            ends.append(self.count)  # (exact as a double below 2**53)
            old = 0  # keep one frame before the window
            while 2 * old + 2 < len(ends) and ends[2 * old + 2] <= at - self.window:
                old += 1
            if old:
                del ends[: 2 * old]

    def end_frames(self, count: int, times: Sequence[float]) -> None:
        """``count`` frame boundaries with no samples added between them (:meth:`end_frame`
        that many times), the last ``len(times)`` of them placed at ``times`` (older ones
        need not be: only their number counts)."""
        if count <= 0:
            return
        delta = self.count - self._frame_start_count  # (samples added before the first)
        self._frame_start_count = self.count
        self._frame_samples += delta
        self.samples_per_frame = delta if count == 1 else 0
        self.frames += count
        if not times:
            return
        ends = self._frame_ends
        at = times[-1]
        # only those in the window and the one before it are kept (see end_frame)
        first = max(0, bisect_right(times, at - self.window) - 1)
        ends.extend(chain.from_iterable(zip(times[first:], repeat(float(self.count)))))
        old = 0  # keep one frame before the window
        while 2 * old + 2 < len(ends) and ends[2 * old + 2] <= at - self.window:
            old += 1
        if old:
            del ends[: 2 * old]

    # ---------------------------------------------------------------- numpy side

    def _consolidate(self) -> None:
        if not self._pending:
            return
        batch = np.array(self._pending, dtype=np.float64)
        del self._pending[:]
        # np.diff's numbers by slicing (np.diff itself cost more than its arithmetic)
        if self._last is not None:
            intervals = np.concatenate(((batch[0] - self._last,), batch[1:] - batch[:-1]))
        else:
            intervals = batch[1:] - batch[:-1]
        if intervals.size:
            largest = float(intervals.max())
            if self._max_gap is None or largest > self._max_gap:
                self._max_gap = largest
        self._last = float(batch[-1])
        cap = self.history
        if len(batch) >= cap:
            if len(self._ring) < cap:
                self._ring = np.empty(cap, dtype=np.float64)
            self._ring[:] = batch[-cap:]
            self._ring_pos, self._ring_len = 0, cap
            return
        size = len(self._ring)
        if not size:  # the first timestamps: the batch itself is the ring (no copy of it)
            self._ring, self._ring_len = batch, len(batch)
            self._ring_pos = len(batch)  # (below ``history``: it does not wrap)
            return
        if size < cap and self._ring_len + len(batch) > size:
            # below ``history`` the ring never wraps: its timestamps are [0, ring_len)
            grown = np.empty(
                min(cap, max(INITIAL_RING, 2 * size, self._ring_len + len(batch))), np.float64
            )
            grown[: self._ring_len] = self._ring[: self._ring_len]
            self._ring = grown
        end = self._ring_pos + len(batch)
        if end <= cap:
            self._ring[self._ring_pos : end] = batch
        else:
            split = cap - self._ring_pos
            self._ring[self._ring_pos :] = batch[:split]
            self._ring[: end - cap] = batch[split:]
        self._ring_pos = end % cap
        self._ring_len = min(cap, self._ring_len + len(batch))

    def recent_timestamps(self) -> np.ndarray:
        """The ``history`` newest timestamps, oldest first (a copy)."""
        recent = self._recent()
        return recent.copy() if recent.base is self._ring else recent

    def _recent(self) -> np.ndarray:
        """:meth:`recent_timestamps`, a view of the ring when it did not wrap (not a copy:
        for the figures computed from it, not to be kept)."""
        self._consolidate()
        if self._ring_len < self.history:
            return self._ring[: self._ring_len]
        return np.concatenate((self._ring[self._ring_pos :], self._ring[: self._ring_pos]))

    def recent_parts(self) -> tuple[tuple[np.ndarray, ...], int, float | None]:
        """What :func:`gadgetctl.monitor.batchstats.snapshot_rows` needs of this device,
        without consolidating: the :meth:`recent_timestamps` in pieces, oldest first (views:
        read them before more timestamps come); how many of the newest intervals are not in
        the largest gap yet (those of the timestamps not consolidated, the one before the
        first of them included when there was an earlier one); and that largest gap."""
        pending = self._pending
        if len(pending) >= self.history:  # (not left so by adding; consolidated as before)
            self._consolidate()
        fresh = len(pending)
        ring_len = self._ring_len
        if ring_len < self.history:
            parts: tuple[np.ndarray, ...] = (self._ring[:ring_len],) if ring_len else ()
        else:
            pos = self._ring_pos
            parts = (self._ring[pos:], self._ring[:pos]) if pos else (self._ring,)
        if fresh:
            parts += (np.frombuffer(pending, dtype=np.float64),)
            if ring_len + fresh > self.history:
                parts = (np.concatenate(parts)[-self.history :],)
        unseen = fresh if self._last is not None else max(0, fresh - 1)
        return parts, unseen, self._max_gap

    # ---------------------------------------------------------------- figures

    @property
    def mean_samples_per_frame(self) -> float | None:
        """Samples per frame over the run (None before the first frame)."""
        return self._frame_samples / self.frames if self.frames else None

    @property
    def mean_rate(self) -> float:
        """Updates per second from the first to the newest timestamp."""
        if self.count < 2 or self.newest_timestamp is None or self.first_timestamp is None:
            return 0.0
        span = self.newest_timestamp - self.first_timestamp
        return (self.count - 1) / span if span > 0 else 0.0

    @property
    def max_gap(self) -> float | None:
        """The longest interval between two consecutive updates over the run."""
        self._consolidate()
        return self._max_gap

    def window_rate(self, now: float | None = None) -> float:
        """Updates per second over the last ``window`` seconds before ``now``.

        Without ``now`` the window ends at the newest timestamp; with it, a device that
        went silent decays towards 0 Hz.
        """
        return self.snapshot(now).window_rate

    def window_samples_per_frame(self, now: float | None = None) -> float | None:
        """Samples per frame over the frames that ended in the last ``window`` seconds before
        ``now`` (the window of :meth:`window_rate`); 0 when frames went on without samples,
        None without timed frames in it."""
        ends = self._frame_ends  # time, count, time, count ...
        if not ends:
            return None
        end = ends[-2] if now is None else max(now, ends[-2])
        start = end - self.window
        count = len(ends) // 2
        first = 0  # the first frame end inside the window (ends are pruned to about one before it)
        while first < count and ends[2 * first] <= start:
            first += 1
        frames = count - first
        if frames == 0:
            return None
        last = int(ends[-1])
        if first == 0:  # no frame end before the window: count from the first one in it
            return (last - int(ends[1])) / (frames - 1) if frames > 1 else None
        return (last - int(ends[2 * first - 1])) / frames

    def interval_stats(self) -> tuple[float | None, float | None, float | None]:
        """(p50, p99, jitter) of the recent intervals: nearest-rank percentiles and the
        population standard deviation, in seconds."""
        snap = self.snapshot()
        return snap.p50_interval, snap.p99_interval, snap.jitter

    def age(self, now: float) -> float | None:
        """Seconds since the newest update (None before the first)."""
        return None if self.newest_timestamp is None else now - self.newest_timestamp

    def snapshot(self, now: float | None = None) -> DeviceSnapshot:
        """All figures at once; ``now`` (same clock as the timestamps) enables age and decay.
        (:func:`snapshots` computes those of many devices together.)"""
        return DeviceSnapshot(**snapshot_rows((self,), now)[0])


def snapshots(devices: Sequence[DeviceStats], now: float | None = None) -> list[DeviceSnapshot]:
    """``[stats.snapshot(now) for stats in devices]``, computed together."""
    return [DeviceSnapshot(*values) for values in _snapshot_values(devices, now)]


def snapshot_rows(
    devices: Sequence[DeviceStats], now: float | None = None
) -> list[dict[str, object]]:
    """``[stats.snapshot(now).to_dict() for stats in devices]``, computed together with
    :func:`~gadgetctl.monitor.batchstats.figures` (numpy over all their timestamps, not a
    dozen numpy calls for each device: 10,000 devices' final statistics were mostly those
    calls). Nothing is consolidated: reading changes nothing."""
    return [
        dict(zip(_SNAPSHOT_FIELDS, values, strict=True))
        for values in _snapshot_values(devices, now)
    ]


def _snapshot_values(devices: Sequence[DeviceStats], now: float | None) -> list[tuple]:
    """The fields of each device's :class:`DeviceSnapshot`, in their order (snapshots are
    made of them without a dict and keywords for each)."""
    if not devices:
        return []
    pieces: list[np.ndarray] = []
    lengths: list[int] = []
    unseen: list[int] = []
    gaps: list[float | None] = []
    for stats in devices:
        parts, fresh, gap = stats.recent_parts()
        lengths.append(sum(map(len, parts)))
        pieces.extend(parts)
        unseen.append(fresh)
        gaps.append(gap)
    # (a copy: the pieces view the devices' pending timestamps, which must stay free to grow)
    stamps = np.concatenate(pieces) if pieces else np.empty(0, dtype=np.float64)
    found = figures(
        stamps,
        np.array(lengths, dtype=np.int64),
        np.array(unseen, dtype=np.int64),
        np.array([s.newest_timestamp or 0.0 for s in devices], dtype=np.float64),
        np.array([s.window for s in devices], dtype=np.float64),
        now,
    )
    rows: list[tuple] = []
    for stats, gap, fresh, known, middle, high, spread, rated, newer in zip(
        devices,
        gaps,
        unseen,
        found.known.tolist(),
        found.p50.tolist(),
        found.p99.tolist(),
        found.jitter.tolist(),
        found.rate.tolist(),
        found.fresh_gap.tolist(),
        strict=True,
    ):
        if fresh and (gap is None or newer > gap):
            gap = newer
        newest_timestamp = stats.newest_timestamp
        rows.append(  # DeviceSnapshot's fields, in order
            (
                stats.name,
                stats.count,
                stats.first_timestamp,
                newest_timestamp,
                stats.mean_rate,
                rated,  # window_rate
                middle if known else None,  # p50_interval
                high if known else None,  # p99_interval
                gap,  # max_gap
                spread if known else None,  # jitter
                stats.dropped,
                stats.faults,
                None if now is None or newest_timestamp is None else now - newest_timestamp,  # age
                stats.frames,
                stats.samples_per_frame,
                stats.mean_samples_per_frame,
                stats.window_samples_per_frame(now),
            )
        )
    return rows


class MonitorStats:
    """:class:`DeviceStats` for every device and proxy name, created on first use."""

    def __init__(self, *, window: float = DEFAULT_WINDOW, history: int = DEFAULT_HISTORY) -> None:
        self.window = window
        self.history = history
        self._devices: dict[str, DeviceStats] = {}

    def device(self, name: str) -> DeviceStats:
        stats = self._devices.get(name)
        if stats is None:
            stats = self._devices[name] = DeviceStats(
                name, window=self.window, history=self.history
            )
        return stats

    def add_timestamps(self, name: str, timestamps: Sequence[float] | np.ndarray) -> None:
        self.device(name).add_timestamps(timestamps)

    def add_timestamp(self, name: str, timestamp: float) -> None:
        self.device(name).add_timestamp(timestamp)

    def add_dropped(self, name: str, count: int = 1) -> None:
        self.device(name).add_dropped(count)

    def add_fault(self, name: str, count: int = 1) -> None:
        self.device(name).add_fault(count)

    def end_frame(self, names: Iterable[str] | None = None, at: float | None = None) -> None:
        """A frame boundary for every device (or the ``names`` given), at ``at``."""
        for stats in self._devices.values() if names is None else map(self.device, names):
            stats.end_frame(at)

    def snapshot(self, now: float | None = None) -> dict[str, DeviceSnapshot]:
        return dict(zip(self._devices, snapshots(list(self._devices.values()), now), strict=True))

    def reset(self) -> None:
        """Reset every device's statistics (devices stay known)."""
        for stats in self._devices.values():
            stats.reset()

    def __contains__(self, name: object) -> bool:
        return name in self._devices

    def __iter__(self) -> Iterator[str]:
        return iter(self._devices)

    def __len__(self) -> int:
        return len(self._devices)
