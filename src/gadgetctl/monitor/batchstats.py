"""The figures of :meth:`DeviceStats.snapshot <gadgetctl.monitor.stats.DeviceStats.snapshot>`
for many devices at once: their recent timestamps gathered in one array and reduced by
segment with numpy, rather than a dozen numpy calls for each device (the final statistics
of 10,000 devices, and a table of them, were mostly those calls).

The numbers are the same, bit for bit: percentiles are picked from the same intervals, a
mean is summed in the order numpy sums a device's intervals (eight running sums joined
pairwise, up to 128 of them; numpy's own sum beyond), and the jitter's sum of squares is
numpy's dot of each device's deviations, as :meth:`DeviceStats.snapshot` computes them.
Nothing is consolidated: the statistics read stay as they were.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from gadgetctl.monitor.stats import DeviceSnapshot, DeviceStats

__all__ = ["snapshot_rows", "snapshots"]

#: Values numpy sums with eight running sums (it splits longer runs in halves first).
_PAIRWISE_BLOCK = 128


def snapshots(devices: Sequence[DeviceStats], now: float | None = None) -> list[DeviceSnapshot]:
    """``[stats.snapshot(now) for stats in devices]``, computed together."""
    return [DeviceSnapshot(**row) for row in snapshot_rows(devices, now)]


def snapshot_rows(
    devices: Sequence[DeviceStats], now: float | None = None
) -> list[dict[str, object]]:
    """``[stats.snapshot(now).to_dict() for stats in devices]``, computed together."""
    count = len(devices)
    if not count:
        return []
    stamps, lengths, unseen, gaps = _gather(devices)
    starts = np.cumsum(lengths) - lengths
    intervals_of = np.maximum(lengths - 1, 0)

    # each device's intervals, one after the other (none across two devices)
    steps = stamps[1:] - stamps[:-1]
    keep = np.ones(len(steps), dtype=bool)
    heads = starts[(lengths > 0) & (starts > 0)]
    keep[heads - 1] = False
    intervals = steps[keep]
    firsts = np.cumsum(intervals_of) - intervals_of  # where each device's intervals begin
    has = intervals_of > 0
    owner = np.repeat(np.arange(count), intervals_of)

    p50 = np.zeros(count)
    p99 = np.zeros(count)
    jitter = np.zeros(count)
    if len(intervals):
        ordered = intervals[np.lexsort((intervals, owner))]
        n = intervals_of.astype(np.float64)
        for p, into in ((50, p50), (99, p99)):
            ranks = np.maximum(0, np.ceil(p / 100.0 * n).astype(np.int64) - 1)
            into[has] = ordered[(firsts + ranks)[has]]
        totals = _sums(intervals, firsts, intervals_of)
        means = totals[has] / intervals_of[has]
        deviations = intervals - np.repeat(means, intervals_of[has])
        begins, ends = firsts.tolist(), (firsts + intervals_of).tolist()
        for i in np.flatnonzero(has).tolist():
            mine = deviations[begins[i] : ends[i]]
            jitter[i] = math.sqrt(float(np.dot(mine, mine)) / (ends[i] - begins[i]))

    # the largest of the intervals not yet in a device's largest gap (its newest ones)
    fresh_gap = np.zeros(count)
    with_fresh = np.flatnonzero(unseen > 0)
    if len(with_fresh):
        ends = firsts[with_fresh] + intervals_of[with_fresh]
        found = _reduce(np.maximum, intervals, ends - unseen[with_fresh], ends)
        fresh_gap[with_fresh] = found

    # the window rate: the timestamps in the window ending at the newest (or ``now``)
    newest = np.array([s.newest_timestamp or 0.0 for s in devices], dtype=np.float64)
    window = np.array([s.window for s in devices], dtype=np.float64)
    end = newest if now is None else np.maximum(now, newest)
    rate = np.zeros(count)
    several = lengths >= 2
    if several.any():
        inside = stamps > np.repeat(end - window, lengths)
        at = starts[several]
        ends = at + lengths[several]
        within = _reduce(np.add, inside.astype(np.int64), at, ends)
        position = np.where(inside, np.arange(len(stamps)), len(stamps))
        first = _reduce(np.minimum, position, at, ends)
        within_all = np.zeros(count, dtype=np.int64)
        within_all[several] = within
        first_all = np.zeros(count, dtype=np.int64)
        first_all[several] = np.minimum(first, len(stamps) - 1)
        span = end - stamps[first_all]
        counted = (within_all >= 2) & (span > 0)
        rate[counted] = (within_all[counted] - 1) / span[counted]

    rows: list[dict[str, object]] = []
    for stats, gap, fresh, known, middle, high, spread, rated, newer in zip(
        devices,
        gaps,
        unseen.tolist(),
        has.tolist(),
        p50.tolist(),
        p99.tolist(),
        jitter.tolist(),
        rate.tolist(),
        fresh_gap.tolist(),
        strict=True,
    ):
        if fresh and (gap is None or newer > gap):
            gap = newer
        newest_timestamp = stats.newest_timestamp
        # (DeviceSnapshot's fields, in order: a test holds them to it)
        rows.append(
            {
                "name": stats.name,
                "count": stats.count,
                "first_timestamp": stats.first_timestamp,
                "newest_timestamp": newest_timestamp,
                "mean_rate": stats.mean_rate,
                "window_rate": rated,
                "p50_interval": middle if known else None,
                "p99_interval": high if known else None,
                "max_gap": gap,
                "jitter": spread if known else None,
                "dropped": stats.dropped,
                "faults": stats.faults,
                "age": None if now is None or newest_timestamp is None else now - newest_timestamp,
                "frames": stats.frames,
                "samples_per_frame": stats.samples_per_frame,
                "mean_samples_per_frame": stats.mean_samples_per_frame,
                "window_samples_per_frame": stats.window_samples_per_frame(now),
            }
        )
    return rows


def _gather(
    devices: Sequence[DeviceStats],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[float | None]]:
    """The devices' recent timestamps one after the other, how many each has, how many of
    its newest intervals are not in its largest gap yet, and that gap."""
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
    return (
        stamps,
        np.array(lengths, dtype=np.int64),
        np.array(unseen, dtype=np.int64),
        gaps,
    )


def _reduce(
    ufunc: np.ufunc, values: np.ndarray, begins: np.ndarray, ends: np.ndarray
) -> np.ndarray:
    """``ufunc.reduce(values[begin:end])`` for each (begin, end), in order and not empty."""
    bounds = np.empty(2 * len(begins), dtype=np.int64)
    bounds[0::2] = begins
    bounds[1::2] = ends
    if bounds[-1] == len(values):  # (the last one runs to the end)
        bounds = bounds[:-1]
    return ufunc.reduceat(values, bounds)[0::2]


def _sums(values: np.ndarray, firsts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Each segment's ``values[first : first + count].sum()``, added up as numpy adds them:
    up to :data:`_PAIRWISE_BLOCK` values, eight running sums (one value at a time below
    eight) joined pairwise, then the rest one at a time; computed for all the segments of
    one length together. Longer segments are summed by numpy one by one."""
    totals = np.zeros(len(counts))
    for length in np.unique(counts).tolist():
        rows = np.flatnonzero(counts == length)
        if length == 0:
            continue
        if length > _PAIRWISE_BLOCK:
            for i in rows.tolist():
                first = int(firsts[i])
                totals[i] = values[first : first + length].sum()
            continue
        block = values[firsts[rows][:, None] + np.arange(length)]
        totals[rows] = 0.0 + _pairwise(block)
    return totals


def _pairwise(block: np.ndarray) -> np.ndarray:
    """numpy's sum of each row of ``block`` (at most :data:`_PAIRWISE_BLOCK` columns)."""
    length = block.shape[1]
    if length < 8:
        total = np.zeros(len(block))
        for column in range(length):
            total = total + block[:, column]
        return total
    sums = [block[:, j] for j in range(8)]
    whole = length - length % 8
    for start in range(8, whole, 8):
        sums = [sums[j] + block[:, start + j] for j in range(8)]
    total = ((sums[0] + sums[1]) + (sums[2] + sums[3])) + (
        (sums[4] + sums[5]) + (sums[6] + sums[7])
    )
    for column in range(whole, length):
        total = total + block[:, column]
    return total
