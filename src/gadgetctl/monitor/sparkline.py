"""Values to a fixed-width unicode sparkline ("▁▂▃▄▅▆▇█"), resampled by bucket mean."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

BARS = "▁▂▃▄▅▆▇█"
MID = BARS[len(BARS) // 2 - 1]
GAP = " "


def _bucket_means(data: np.ndarray, width: int) -> np.ndarray:
    n = len(data)
    finite = np.isfinite(data)
    if n < width:  # stretch: each column shows the value under it
        picked = data[(np.arange(width) * n) // width]
        return np.where(np.isfinite(picked), picked, np.nan)
    edges = (np.arange(width) * n) // width
    sums = np.add.reduceat(np.where(finite, data, 0.0), edges)
    counts = np.add.reduceat(finite.astype(np.int64), edges)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)


def sparkline(
    values: Iterable[float | None] | np.ndarray,
    width: int = 40,
    *,
    lo: float | None = None,
    hi: float | None = None,
) -> str:
    """``width`` bars for ``values``: each bar is the mean of its bucket of values.

    NaN, infinite and None values are left out of the means; a bucket without any finite
    value is a space. The scale runs from ``lo`` to ``hi`` (by default the smallest and
    largest bucket mean); a constant series is drawn as a row of middle bars.
    """
    if width < 1:
        raise ValueError("width must be at least 1")
    data = np.asarray(values if isinstance(values, np.ndarray) else list(values), dtype=np.float64)
    data = data.ravel()
    if data.size == 0:
        return GAP * width
    means = _bucket_means(data, width)
    present = np.isfinite(means)
    if not present.any():
        return GAP * width
    low = float(np.min(means[present])) if lo is None else float(lo)
    high = float(np.max(means[present])) if hi is None else float(hi)
    span = high - low
    if not span > 1e-12 * max(1.0, abs(high), abs(low)):
        return "".join(MID if p else GAP for p in present)
    levels = np.clip(
        np.rint((np.where(present, means, low) - low) / span * (len(BARS) - 1)), 0, len(BARS) - 1
    ).astype(np.int64)
    return "".join(
        BARS[level] if p else GAP
        for level, p in zip(levels.tolist(), present.tolist(), strict=True)
    )
