"""Sparklines: fixed width, bucket means, NaN-safe, constant series in the middle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gadgetctl.monitor.sparkline import BARS, GAP, MID, sparkline


def test_a_ramp_uses_every_bar_in_order():
    assert sparkline(range(8), 8) == BARS
    line = sparkline(np.linspace(0, 1, 1000), 40)
    assert len(line) == 40 and line[0] == BARS[0] and line[-1] == BARS[-1]
    assert list(line) == sorted(line)


def test_buckets_are_averaged():
    # 4 buckets of 2: means 0, 0, 7, 7 -> low, low, high, high
    assert sparkline([0, 0, 0, 0, 0, 14, 14, 0], 4) == BARS[0] * 2 + BARS[-1] * 2


def test_short_series_are_stretched_to_the_width():
    assert sparkline([0, 1], 6) == BARS[0] * 3 + BARS[-1] * 3


def test_constant_series_are_mid_bars():
    assert sparkline([0.1] * 1000, 30) == MID * 30
    assert sparkline([5], 3) == MID * 3


def test_nan_inf_and_none_are_left_out():
    line = sparkline([0.0, math.nan, None, 7.0, math.inf, -math.inf], 6)
    assert line == BARS[0] + GAP * 2 + BARS[-1] + GAP * 2
    assert sparkline([1, math.nan] * 50, 10) == MID * 10  # every bucket has a finite value
    assert sparkline([math.nan] * 5, 4) == GAP * 4
    assert sparkline([], 5) == GAP * 5


def test_explicit_scale():
    assert sparkline([0.5], 2, lo=0.0, hi=1.0) in (BARS[3] * 2, BARS[4] * 2)
    assert sparkline([2.0, -1.0], 2, lo=0.0, hi=1.0) == BARS[-1] + BARS[0]


def test_width_must_be_positive():
    with pytest.raises(ValueError):
        sparkline([1, 2], 0)
