"""The statistics of many devices computed together (gadgetctl.monitor.stats.snapshot_rows,
on gadgetctl.monitor.batchstats) are each device's own, bit for bit, whatever devices it is
computed with; they agree with plain arithmetic; and reading them changes nothing."""

from __future__ import annotations

import json
import math
import struct

import numpy as np
import pytest

from gadgetctl.monitor.stats import DeviceStats, snapshot_rows, snapshots

pytestmark = pytest.mark.timeout(120)


def _bits(value: object) -> object:
    """A figure with its float's exact bits (so 0.1 + 0.2 and 0.3 differ, and -0.0 and 0.0)."""
    if isinstance(value, float):
        return (type(value), struct.pack("<d", value))
    return (type(value), value)


def _exact(row: dict[str, object]) -> dict[str, object]:
    return {name: _bits(value) for name, value in row.items()}


def _copy(stats: DeviceStats) -> DeviceStats:
    """A device fed the same (to read one with snapshot, the other together)."""
    twin = DeviceStats(stats.name, window=stats.window, history=stats.history)
    for name in DeviceStats.__slots__:
        value = getattr(stats, name)
        if isinstance(value, np.ndarray):
            value = value if not value.flags.writeable else value.copy()
        elif hasattr(value, "tobytes"):  # array.array
            value = type(value)(value.typecode, value)
        setattr(twin, name, value)
    return twin


def _varied(rng: np.random.Generator) -> list[DeviceStats]:
    """Devices with every kind of history: none, one sample, a few, gaps, drops and faults,
    rates from 1 Hz to 2 kHz, rings below and at their history (wrapped or not), timestamps
    consolidated or still pending, frames timed or not."""
    devices: list[DeviceStats] = []
    devices.append(DeviceStats("never"))
    framed = DeviceStats("frames only")
    framed.end_frame(10.0)
    framed.end_frame(10.5)
    devices.append(framed)
    one = DeviceStats("one")
    one.add_timestamp(5.0)
    devices.append(one)
    two_equal = DeviceStats("two at once")
    two_equal.add_timestamps([7.0, 7.0])
    devices.append(two_equal)
    for i in range(160):
        history = int(rng.choice([2, 3, 8, 16, 50, 4096]))
        window = float(rng.choice([0.05, 0.25, 1.0, 3.0]))
        stats = DeviceStats(f"d{i}", window=window, history=history)
        rate = float(rng.choice([1, 10, 60, 90, 250, 1000, 2000]))
        seconds = float(rng.uniform(0.0, 4.0))
        n = int(rate * seconds) + int(rng.integers(0, 3))
        jitter = rng.normal(0, 0.1 / rate, n) if rng.random() < 0.6 else np.zeros(n)
        times = 1000.0 + i + np.arange(n) / rate + jitter
        times = np.maximum.accumulate(times)  # (non-decreasing, as a device gives them)
        if n > 4 and rng.random() < 0.4:  # a gap
            times[n // 2 :] += float(rng.uniform(0.05, 2.0))
        position = 0
        while position < n:
            size = int(rng.integers(1, 40))
            chunk = times[position : position + size]
            if rng.random() < 0.3:
                for t in chunk.tolist():
                    stats.add_timestamp(t)
            else:
                stats.add_timestamps(chunk if rng.random() < 0.5 else chunk.tolist())
            position += size
            if rng.random() < 0.5:
                stats.end_frame(float(chunk[-1]) + 0.001 if rng.random() < 0.8 else None)
            if rng.random() < 0.2:  # a snapshot now and then consolidates what came
                stats.snapshot()
        if rng.random() < 0.3:
            stats.add_dropped(int(rng.integers(1, 50)))
        if rng.random() < 0.2:
            stats.add_fault(int(rng.integers(1, 3)))
        devices.append(stats)
    return devices


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("late", [None, 0.0, 0.3, 5.0])
def test_a_device_s_figures_are_the_same_alone_and_among_others_bit_for_bit(seed, late):
    devices = _varied(np.random.default_rng(seed))
    twins = [_copy(stats) for stats in devices]
    newest = max(s.newest_timestamp for s in devices if s.newest_timestamp is not None)
    now = None if late is None else newest + late
    expected = [_exact(stats.snapshot(now).to_dict()) for stats in twins]
    rows = snapshot_rows(devices, now)
    assert [_exact(row) for row in rows] == expected
    shuffled = list(np.random.default_rng(seed).permutation(len(devices)))
    again = snapshot_rows([devices[i] for i in shuffled], now)
    assert [_exact(row) for row in again] == [expected[i] for i in shuffled]
    # and as JSON text, the way a stats record writes them
    assert json.dumps(rows) == json.dumps([s.snapshot(now).to_dict() for s in twins])


@pytest.mark.parametrize("seed", [1, 2])
def test_the_figures_are_those_of_plain_arithmetic(seed):
    """Each device's figures against numpy and Python on its own timestamps (not the code
    under test): nearest-rank percentiles, mean and standard deviation, window rate."""
    devices = _varied(np.random.default_rng(seed))
    newest = max(s.newest_timestamp for s in devices if s.newest_timestamp is not None)
    now = newest + 0.3
    for stats, row in zip(devices, snapshot_rows(devices, now), strict=True):
        recent = _copy(stats).recent_timestamps()
        intervals = np.diff(recent)
        if not len(intervals):
            assert row["p50_interval"] is row["p99_interval"] is row["jitter"] is None
            continue
        ordered = sorted(intervals.tolist())
        n = len(ordered)
        assert row["p50_interval"] == ordered[max(0, math.ceil(0.5 * n) - 1)]
        assert row["p99_interval"] == ordered[max(0, math.ceil(0.99 * n) - 1)]
        assert row["jitter"] == pytest.approx(float(np.std(intervals)), rel=1e-9, abs=1e-15)
        end = max(now, stats.newest_timestamp)
        inside = recent[recent > end - stats.window]
        rate = (len(inside) - 1) / (end - inside[0]) if len(inside) >= 2 else 0.0
        assert row["window_rate"] == pytest.approx(rate, rel=1e-12)


def test_the_varied_devices_cover_what_the_batch_tells_apart():
    devices = _varied(np.random.default_rng(1))
    snaps = [s.snapshot() for s in devices]
    assert any(s.count == 0 for s in snaps) and any(s.count == 1 for s in snaps)
    intervals = [s.count - 1 for s in snaps if s.count > 1]
    assert min(intervals) < 8 and max(intervals) > 4096  # rings short and wrapped
    assert any(s.jitter for s in snaps) and any(s.jitter == 0.0 for s in snaps)
    assert any(s.window_rate == 0.0 and s.count > 2 for s in snaps)
    assert any(s.dropped for s in snaps) and any(s.faults for s in snaps)
    assert any(s.window_samples_per_frame is None and s.frames for s in snaps)


def test_reading_them_together_changes_nothing_and_feeding_goes_on():
    devices = _varied(np.random.default_rng(4))
    first = [_exact(row) for row in snapshot_rows(devices, 2000.0)]
    assert [_exact(row) for row in snapshot_rows(devices, 2000.0)] == first
    for stats in devices:  # the pending timestamps are not held by a view: they grow
        stats.add_timestamp(3000.0)
        stats.add_timestamps([3000.5, 3001.0])
    after = snapshot_rows(devices)
    assert [row["count"] for row in after] == [s.count for s in devices]
    assert all(row["newest_timestamp"] == 3001.0 for row in after)
    assert [_exact(row) for row in after] == [_exact(s.snapshot().to_dict()) for s in devices]


def test_rows_have_the_snapshot_s_fields_in_order():
    from dataclasses import fields

    from gadgetctl.monitor.stats import DeviceSnapshot

    (row,) = snapshot_rows([DeviceStats("x")])
    assert list(row) == [f.name for f in fields(DeviceSnapshot)]


def test_snapshots_are_device_snapshots():
    devices = _varied(np.random.default_rng(5))[:20]
    assert snapshots(devices, 1500.0) == [s.snapshot(1500.0) for s in devices]
    assert snapshots([]) == [] and snapshot_rows([]) == []


def test_known_figures_of_a_few_devices():
    fast, slow, empty = DeviceStats("fast"), DeviceStats("slow"), DeviceStats("empty")
    fast.add_timestamps([0.0, 0.01, 0.02, 0.04])
    slow.add_timestamps([0.0, 0.5])
    rows = snapshot_rows([fast, slow, empty], 0.5)
    assert rows[0]["p50_interval"] == pytest.approx(0.01)
    assert rows[0]["p99_interval"] == pytest.approx(0.02)
    assert rows[0]["max_gap"] == pytest.approx(0.02)
    assert rows[0]["window_rate"] == pytest.approx(3 / 0.5)
    assert rows[0]["age"] == pytest.approx(0.46)
    assert rows[1]["jitter"] == 0.0 and rows[1]["window_rate"] == 2.0  # 1 interval in 0.5 s
    assert rows[2]["p50_interval"] is None and rows[2]["max_gap"] is None
    assert rows[2]["age"] is None and rows[2]["window_rate"] == 0.0
    assert not math.isnan(rows[0]["jitter"])


@pytest.mark.parametrize("count", [0, 1, 127, 128, 129, 300])
def test_a_stats_record_encoded_by_batches_of_devices_is_encode_record_s_text(count):
    """encode_stats_parts encodes STATS_BATCH devices to one encoder call; joined, the parts
    are the record encode_record writes, whatever mappings the entries are."""
    from types import MappingProxyType

    from gadgetctl.monitor.records import (
        STATS_BATCH,
        StatsRecord,
        encode_record,
        encode_stats_parts,
    )

    assert STATS_BATCH == 128
    devices = {
        f'W"{i}\u00e9': (MappingProxyType if i % 3 else dict)(
            {"count": i, "jitter": i / 7 if i % 2 else None, "units": {"position": 1}}
        )
        for i in range(count)
    }
    record = StatsRecord(3.25, devices)
    parts = list(encode_stats_parts(record, size=2_000))
    assert "".join(parts) == encode_record(
        StatsRecord(3.25, {name: dict(values) for name, values in devices.items()})
    )
    assert all(parts) and (count < 300 or len(parts) >= 3)  # parts of a few batches
