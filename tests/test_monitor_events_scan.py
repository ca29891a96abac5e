"""The analog change scan gives the same events whatever the frames' sizes: a frame of a few
samples is scanned by a plain loop, a long one a block of samples at a time (runs of noise
at once), and both follow the documented rule: a unit is reported when it moved more than
the dead band from the value last reported."""

from __future__ import annotations

import numpy as np
import pytest

from gadgetctl.monitor.events import ChangeDetector, Thresholds, _DeviceMemory


def _signal(seed: int, count: int = 3000) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    stamps = np.arange(count) / 1000.0
    noise = rng.random(count)  # beyond the band at nearly every sample
    slow = np.sin(np.arange(count) / 150.0)  # beyond it now and then
    quiet = np.where(np.arange(count) % 700 < 650, 0.25, rng.random(count))  # bursts
    return stamps, np.stack([noise, slow, quiet], axis=1)


def _rule(stamps: np.ndarray, values: np.ndarray, band: float) -> list[tuple]:
    found = []
    for unit in range(values.shape[1]):
        last = float(values[0, unit])
        for index in range(1, len(stamps)):
            value = float(values[index, unit])
            if abs(value - last) > band:
                found.append((float(stamps[index]), unit, value))
                last = value
    return sorted(found)


def _scan(stamps: np.ndarray, values: np.ndarray, band: float, frame: int) -> list[tuple]:
    detector = ChangeDetector(Thresholds(dead_band=band))
    memory = _DeviceMemory()
    events: list = []
    for start in range(0, len(stamps), frame):
        part = slice(start, start + frame)
        detector._analog(events, "A", None, memory, stamps[part], values[part])
    assert all(e.raw == e.value for e in events)  # (no range: the raw value is the value)
    return sorted((e.timestamp, e.unit, e.value) for e in events)


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("band", [0.0, 0.02, 0.3])
def test_short_and_long_frames_give_the_rule_s_events(seed, band):
    stamps, values = _signal(seed)
    expected = _rule(stamps, values, band)
    assert len(expected) > 100
    for frame in (1, 17, 64, 65, 1000, 3000):  # loops, blocks, and the limit between
        assert _scan(stamps, values, band, frame) == expected, frame
