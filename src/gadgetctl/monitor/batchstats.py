"""The figures of device statistics, computed for many devices at once: their recent
timestamps one after the other in one array, reduced by segment with numpy (a device's
figures are the same alone or with others: each segment is reduced on its own).

:class:`~gadgetctl.monitor.stats.DeviceStats` gathers its timestamps for it; this module
knows only arrays.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Figures", "figures"]


class Figures(NamedTuple):
    """Per device (one entry each): whether it has an interval, the nearest-rank 50th and
    99th percentile intervals, the jitter (population standard deviation of the intervals),
    the largest of its newest ``unseen`` intervals, and the window rate."""

    known: np.ndarray
    p50: np.ndarray
    p99: np.ndarray
    jitter: np.ndarray
    fresh_gap: np.ndarray
    rate: np.ndarray


def figures(
    stamps: np.ndarray,
    lengths: np.ndarray,
    unseen: np.ndarray,
    newest: np.ndarray,
    window: np.ndarray,
    now: float | None,
) -> Figures:
    """The :class:`Figures` of devices whose recent timestamps are ``stamps`` one device after
    another (``lengths`` each, oldest first); ``unseen``: how many of each device's newest
    intervals are to be searched for a gap; ``newest``: each device's newest timestamp (0 for
    none); ``window``: each device's window in seconds, ending at ``now`` or its newest."""
    count = len(lengths)
    starts = np.cumsum(lengths) - lengths
    intervals_of = np.maximum(lengths - 1, 0)

    # each device's intervals, one after the other (none across two devices)
    steps = stamps[1:] - stamps[:-1]
    keep = np.ones(len(steps), dtype=bool)
    heads = starts[(lengths > 0) & (starts > 0)]
    keep[heads - 1] = False
    intervals = steps[keep]
    firsts = np.cumsum(intervals_of) - intervals_of  # where each device's intervals begin
    known = intervals_of > 0

    p50 = np.zeros(count)
    p99 = np.zeros(count)
    jitter = np.zeros(count)
    if len(intervals):
        owner = np.repeat(np.arange(count), intervals_of)
        ordered = intervals[np.lexsort((intervals, owner))]
        n = intervals_of.astype(np.float64)
        for p, into in ((50, p50), (99, p99)):
            ranks = np.maximum(0, np.ceil(p / 100.0 * n).astype(np.int64) - 1)
            into[known] = ordered[(firsts + ranks)[known]]
        begins, ends, sizes = firsts[known], (firsts + intervals_of)[known], n[known]
        means = _reduce(np.add, intervals, begins, ends) / sizes
        deviations = intervals - np.repeat(means, intervals_of[known])
        jitter[known] = np.sqrt(_reduce(np.add, deviations * deviations, begins, ends) / sizes)

    # the largest of each device's newest ``unseen`` intervals
    fresh_gap = np.zeros(count)
    with_fresh = np.flatnonzero(unseen > 0)
    if len(with_fresh):
        ends = firsts[with_fresh] + intervals_of[with_fresh]
        fresh_gap[with_fresh] = _reduce(np.maximum, intervals, ends - unseen[with_fresh], ends)

    # the window rate: the timestamps in the window ending at the newest (or ``now``)
    end = newest if now is None else np.maximum(now, newest)
    rate = np.zeros(count)
    several = lengths >= 2
    if several.any():
        inside = stamps > np.repeat(end - window, lengths)
        at = starts[several]
        ends = at + lengths[several]
        within = np.zeros(count, dtype=np.int64)
        within[several] = _reduce(np.add, inside.astype(np.int64), at, ends)
        position = np.where(inside, np.arange(len(stamps)), len(stamps))
        first = np.zeros(count, dtype=np.int64)
        first[several] = np.minimum(_reduce(np.minimum, position, at, ends), len(stamps) - 1)
        span = end - stamps[first]
        counted = (within >= 2) & (span > 0)
        rate[counted] = (within[counted] - 1) / span[counted]
    return Figures(known, p50, p99, jitter, fresh_gap, rate)


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
