"""Running statistics on known timestamp series, and summaries of written recordings."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gadgetctl.monitor.recording import Recorder
from gadgetctl.monitor.records import SampleRecord
from gadgetctl.monitor.sparkline import BARS, MID
from gadgetctl.monitor.stats import DeviceStats, MonitorStats, summarize_recording

pytestmark = pytest.mark.timeout(60)

MS = 1e-3


def regular(rate, seconds, start=100.0):
    return start + np.arange(int(rate * seconds)) / rate


def fed(stats, timestamps, batch):
    for i in range(0, len(timestamps), batch):
        stats.add_timestamps(timestamps[i : i + batch])
    return stats


def test_regular_1khz_series():
    stats = fed(DeviceStats("Wand"), regular(1000, 5), 10)
    snap = stats.snapshot()
    assert snap.count == 5000
    assert snap.mean_rate == pytest.approx(1000, rel=1e-3)
    assert snap.window_rate == pytest.approx(1000, rel=1e-3)
    assert snap.p50_interval == pytest.approx(MS, rel=1e-6)
    assert snap.p99_interval == pytest.approx(MS, rel=1e-6)
    assert snap.max_gap == pytest.approx(MS, rel=1e-6)
    assert snap.jitter < 1e-9
    assert (snap.dropped, snap.faults, snap.frames, snap.age) == (0, 0, 0, None)


@pytest.mark.parametrize("feed", ["one batch", "batches of 7", "lists", "singles"])
def test_feeding_style_does_not_change_the_figures(feed):
    rng = np.random.default_rng(3)
    stamps = 10.0 + np.cumsum(rng.uniform(0.5, 1.5, 9000) * MS)
    stats = DeviceStats("x")
    if feed == "one batch":
        stats.add_timestamps(stamps)
    elif feed == "batches of 7":
        fed(stats, stamps, 7)
    elif feed == "lists":
        fed(stats, stamps.tolist(), 100)
    else:
        for t in stamps.tolist():
            stats.add_timestamp(t)
    intervals = np.diff(stamps)
    recent = intervals[-(stats.history - 1) :]
    p50, p99, jitter = stats.interval_stats()
    assert stats.count == 9000
    assert stats.max_gap == intervals.max()
    assert p50 == np.percentile(recent, 50, method="inverted_cdf")
    assert p99 == np.percentile(recent, 99, method="inverted_cdf")
    assert jitter == pytest.approx(recent.std(), rel=1e-9)
    assert stats.mean_rate == pytest.approx(8999 / (stamps[-1] - stamps[0]), rel=1e-12)


def series_with_outliers(slow):
    """1001 timestamps: 1000 intervals of 1 ms, of which ``slow`` (spread out) are 5 ms."""
    intervals = np.full(1000, MS)
    intervals[np.linspace(50, 950, slow).astype(int)] = 5 * MS
    return 50.0 + np.concatenate(([0.0], np.cumsum(intervals)))


def test_percentiles_are_nearest_rank():
    stats = DeviceStats("x")
    stats.add_timestamps(series_with_outliers(10))  # 99% of intervals are 1 ms
    p50, p99, _ = stats.interval_stats()
    assert p50 == pytest.approx(MS) and p99 == pytest.approx(MS)
    stats = DeviceStats("x")
    stats.add_timestamps(series_with_outliers(20))  # 2% are 5 ms
    p50, p99, _ = stats.interval_stats()
    assert p50 == pytest.approx(MS) and p99 == pytest.approx(5 * MS)


def test_jitter_is_the_population_stdev_of_intervals():
    stats = DeviceStats("x")
    stats.add_timestamps(series_with_outliers(10))
    # mean 1.04 ms; variance (990 * 0.04^2 + 10 * 3.96^2) / 1000 = 0.1584 ms^2
    assert stats.interval_stats()[2] == pytest.approx(math.sqrt(0.1584) * MS, rel=1e-6)
    assert stats.max_gap == pytest.approx(5 * MS)


def test_a_gap_shows_in_max_gap_age_and_the_decaying_window_rate():
    before = regular(100, 2, start=0.0)
    after = regular(100, 1, start=2.5)  # 0.51 s without samples
    stats = DeviceStats("x")
    stats.add_timestamps(before)
    stats.add_timestamps(after)
    assert stats.max_gap == pytest.approx(0.51)
    assert stats.window_rate() == pytest.approx(100, rel=1e-3)
    newest = after[-1]
    assert stats.age(newest + 0.25) == pytest.approx(0.25)
    # window (2.995, 3.995]: the 50 samples from 3.00 to 3.49, then silence
    assert stats.window_rate(newest + 0.505) == pytest.approx(49 / 0.995, rel=1e-9)
    assert stats.window_rate(newest + 1.5) == 0.0
    assert stats.snapshot(newest + 0.25).age == pytest.approx(0.25)


def test_window_rate_follows_a_rate_change_and_mean_rate_the_run():
    stats = DeviceStats("x")
    stats.add_timestamps(regular(500, 2, start=0.0))
    stats.add_timestamps(regular(1000, 2, start=2.0))
    assert stats.window_rate() == pytest.approx(1000, rel=1e-3)
    assert stats.mean_rate == pytest.approx((3000 - 1) / (4.0 - MS), rel=1e-3)


def test_history_bounds_the_recent_figures_not_the_run_figures():
    stats = DeviceStats("x", history=1000)
    stats.add_timestamps(regular(500, 10, start=0.0))  # 2 ms intervals
    fed(stats, regular(1000, 3, start=10.0), 50)  # then 1 ms
    p50, p99, jitter = stats.interval_stats()
    assert p50 == pytest.approx(MS) and p99 == pytest.approx(MS) and jitter < 1e-9
    assert stats.max_gap == pytest.approx(2 * MS)
    assert len(stats.recent_timestamps()) == 1000
    assert stats.count == 8000


def test_counters_frames_and_reset():
    stats = DeviceStats("x")
    stats.add_dropped(3)
    stats.add_fault()
    stats.add_fault(2)
    stats.add_timestamps(regular(1000, 0.016))
    stats.end_frame()
    stats.add_timestamps(regular(1000, 0.017, start=200.0))
    stats.end_frame()
    stats.end_frame()
    snap = stats.snapshot()
    assert (snap.dropped, snap.faults, snap.frames) == (3, 3, 3)
    assert snap.samples_per_frame == 0
    assert snap.mean_samples_per_frame == pytest.approx(33 / 3)
    stats.reset()
    snap = stats.snapshot()
    assert (snap.count, snap.dropped, snap.faults, snap.frames, snap.max_gap) == (0, 0, 0, 0, None)
    assert (snap.mean_rate, snap.window_rate, snap.p50_interval, snap.jitter) == (
        0.0,
        0.0,
        None,
        None,
    )


def test_empty_and_single_sample_devices():
    stats = DeviceStats("x")
    assert stats.snapshot(5.0).age is None
    stats.add_timestamp(1.0)
    snap = stats.snapshot(2.0)
    assert (snap.count, snap.mean_rate, snap.window_rate, snap.p50_interval) == (1, 0.0, 0.0, None)
    assert snap.age == 1.0 and snap.first_timestamp == snap.newest_timestamp == 1.0


def test_monitor_stats_keeps_one_entry_per_device():
    monitor = MonitorStats(window=0.5)
    for d in range(100):
        monitor.add_timestamps(f"dev{d}", regular(1000, 0.1, start=d))
    monitor.add_timestamp("dev0", 1000.0)
    monitor.add_dropped("dev1", 2)
    monitor.add_fault("dev2")
    monitor.end_frame()
    snaps = monitor.snapshot()
    assert len(monitor) == 100 and "dev5" in monitor and next(iter(monitor)) == "dev0"
    assert snaps["dev1"].dropped == 2 and snaps["dev2"].faults == 1
    assert snaps["dev3"].samples_per_frame == 100 and snaps["dev0"].samples_per_frame == 101
    json.dumps({name: s.to_dict() for name, s in snaps.items()})
    monitor.reset()
    assert monitor.snapshot()["dev3"].count == 0


def test_invalid_parameters():
    with pytest.raises(ValueError):
        DeviceStats("x", window=0)
    with pytest.raises(ValueError):
        DeviceStats("x", history=1)


# --------------------------------------------------------------------------- summaries


def position(x):
    return [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, 1.5], [0.0, 0.0, 1.0, -x / 2], [0.0, 0.0, 0.0, 1.0]]


def write_session(path, close=True):
    stamps = [1000.0 + i * 0.01 for i in range(100)] + [1001.2 + i * 0.01 for i in range(100)]
    records = []
    for i, t in enumerate(stamps):
        records.append(SampleRecord("Wand", "analog", 0, t, i / 199, i * 4))
        records.append(SampleRecord("Wand", "analog", 1, t, 0.25, 64))
        records.append(SampleRecord("Wand", "digital", 0, t, 1, 1))
    for i in range(50):
        records.append(
            SampleRecord("Head", "position", 0, 1000.0 + i * 0.02, position(i / 49), None)
        )
    glove = [[0.1 * f + 0.2 * j for j in range(4)] for f in range(6)]
    records.append(SampleRecord("Glove", "glove", 0, 1000.5, glove, glove))
    records.append(SampleRecord("Voice", "string", 0, 1000.7, "hello", "hello"))
    records.append(SampleRecord("Voice", "string", 0, 1000.8, "bye", "bye"))
    recorder = Recorder(path, {"config": "demo.jconf"})
    recorder.write_samples(records)
    recorder.write_marker("poke", 1000.5)
    recorder.close()
    if not close:  # as if the process died: no end record
        lines = path.read_bytes().splitlines(keepends=True)
        path.write_bytes(b"".join(lines[:-1]))
    return records


def test_summarize_recording(tmp_path):
    path = tmp_path / "session.ndjson"
    write_session(path)
    summary = summarize_recording(path, width=20)
    assert summary.samples == 653 and summary.end_reason == "closed"
    assert summary.info == {"config": "demo.jconf"}
    assert summary.duration == pytest.approx(2.19)
    assert [m.name for m in summary.markers] == ["poke"]
    devices = {d.name: d for d in summary.devices}
    assert list(devices) == ["Glove", "Head", "Voice", "Wand"]

    wand = devices["Wand"]
    assert (wand.samples, wand.updates, wand.kinds) == (600, 200, ("analog", "digital"))
    assert wand.duration == pytest.approx(2.19)
    assert wand.mean_rate == pytest.approx(199 / 2.19)
    assert wand.median_interval == pytest.approx(0.01)
    assert wand.gaps.count == 1 and wand.gaps.largest == pytest.approx(0.21)
    assert wand.gaps.threshold == pytest.approx(0.03)
    units = {(u.kind, u.unit): u for u in wand.units}
    ramp, flat, button = units["analog", 0], units["analog", 1], units["digital", 0]
    assert (ramp.minimum, ramp.maximum, ramp.samples) == (0.0, 1.0, 200)
    assert (
        ramp.sparkline[0] == BARS[0]
        and ramp.sparkline[-1] == BARS[-1]
        and len(ramp.sparkline) == 20
    )
    assert (flat.minimum, flat.maximum) == (0.25, 0.25) and flat.sparkline == MID * 20
    assert (button.minimum, button.maximum) == (1.0, 1.0)

    head = devices["Head"].units[0]
    assert head.translation_min == pytest.approx((0.0, 1.5, -0.5))
    assert head.translation_max == pytest.approx((1.0, 1.5, 0.0))
    assert head.minimum is None and head.sparkline is None
    assert set(head.sparklines) == {"x", "y", "z"} and all(
        len(line) == 20 for line in head.sparklines.values()
    )
    assert devices["Head"].gaps.count == 0 and devices["Head"].mean_rate == pytest.approx(50)

    glove = devices["Glove"].units[0]
    assert (glove.minimum, glove.maximum) == pytest.approx((0.0, 1.1))
    voice = devices["Voice"]
    assert voice.units[0].sparkline is None and voice.units[0].samples == 2
    as_json = json.loads(json.dumps(summary.to_dict()))
    assert as_json["devices"][3]["gaps"]["count"] == 1
    assert as_json["markers"][0]["offset"] == pytest.approx(0.5)


def test_summary_of_an_interrupted_recording(tmp_path):
    path = tmp_path / "killed.ndjson"
    write_session(path, close=False)
    with open(path, "a") as f:
        f.write('{"v":1,"type":"sample","device":"Wand","ki')
    summary = summarize_recording(path)
    assert summary.end_reason is None and summary.samples == 653
    assert [p.severity for p in summary.problems] == ["warning"]


def test_summary_of_odd_values(tmp_path):
    path = tmp_path / "odd.ndjson"
    with Recorder(path) as recorder:
        recorder.write_samples(
            [
                SampleRecord("A", "analog", 0, 1.0, math.nan, 0),
                SampleRecord("A", "analog", 0, 2.0, "oops", 0),
                SampleRecord("P", "position", 0, 1.0, "not a matrix", None),
                SampleRecord("P", "position", 0, 2.0, list(range(16)), None),
                SampleRecord("H", "hat", 0, 1.0, 4, 4),
            ]
        )
    summary = summarize_recording(path)
    devices = {d.name: d for d in summary.devices}
    analog = devices["A"].units[0]
    assert analog.minimum is None and analog.sparkline.strip() == ""
    assert devices["P"].units[0].translation_min == (3.0, 7.0, 11.0)
    hat = devices["H"]
    assert hat.units[0].minimum == 4 and hat.mean_rate == 0.0 and hat.median_interval is None


def test_a_device_s_timestamp_ring_grows_with_what_it_was_given():
    """Issue 27: every device held 4096 timestamps (32 KB) from the start, 320 MB for 10,000
    devices whose short run gave each a handful; the ring now grows to ``history``, and the
    figures are those of the newest ``history`` timestamps at every size on the way."""
    rng = np.random.default_rng(7)
    stats = DeviceStats("d", history=300)
    few = DeviceStats("few")
    few.add_timestamps([0.0, 0.1, 0.2])
    few.snapshot(0.3)
    assert few._ring.nbytes <= 64 * 8
    fed: list[float] = []
    t = 0.0
    for size in (2, 5, 30, 2, 70, 150, 1, 400, 3, 299, 7):
        batch = (t + np.cumsum(rng.uniform(0.001, 0.02, size))).tolist()
        t = batch[-1]
        stats.add_timestamps(batch)
        fed += batch
        assert stats.recent_timestamps().tolist() == fed[-300:]
        intervals = np.diff(fed[-300:])
        p50, p99, jitter = stats.interval_stats()
        ordered = np.sort(intervals)
        assert p50 == ordered[math.ceil(0.5 * len(ordered)) - 1]
        assert p99 == ordered[math.ceil(0.99 * len(ordered)) - 1]
        assert jitter == pytest.approx(float(np.std(intervals)))
        assert stats.max_gap == max(np.diff(fed))
    assert len(stats._ring) == 300


def test_timestamps_of_every_form_wait_as_doubles_and_come_out_in_order():
    stats = DeviceStats("d", history=8)
    stats.add_timestamp(1)
    stats.add_timestamps([2, 2.5])  # ints and floats
    stats.add_timestamps(np.array([3.25, 4.0], dtype=np.float32))
    stats.add_timestamps(np.array([5.0, 6.0]))
    assert stats._pending.typecode == "d" and stats._pending.itemsize == 8
    assert stats.recent_timestamps().tolist() == [1.0, 2.0, 2.5, 3.25, 4.0, 5.0, 6.0]
    assert len(stats._pending) == 0 and stats.count == 7
    stats.add_timestamps(np.arange(7.0, 12.0))  # past ``history``: consolidated as it comes
    assert stats.recent_timestamps().tolist() == [4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0]
    assert stats.max_gap == 1.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_frames_without_samples_ended_at_once_are_those_ended_one_by_one(seed):
    # a track that was not visited in some frames ends them at once when next noted or
    # read (end_frames): the figures are those of ending each of them in turn
    rng = np.random.default_rng(seed)
    one, many = DeviceStats("one"), DeviceStats("many")
    at, stamp = 100.0, 100.0
    for _ in range(40):
        idle = int(rng.integers(0, 200))  # frames without samples (some beyond the window)
        times = [at + (i + 1) / 60 for i in range(idle)]
        for t in times:
            one.end_frame(t)
        # the clock keeps the times of the last 2 s (and one before), or all of them
        kept = sum(1 for t in times if t > times[-1] - 2.0) + 1 if rng.random() < 0.5 else idle
        many.end_frames(idle, times[max(0, len(times) - kept) :])
        if times:
            moment = times[-1]
            assert many.window_samples_per_frame(moment) == one.window_samples_per_frame(moment)
            assert list(many._frame_ends) == list(one._frame_ends)  # (the same frames kept)
        at += idle / 60 + 1 / 60
        stamps = np.sort(stamp + rng.random(int(rng.integers(1, 4))) * 0.01)
        stamp = float(stamps[-1]) + 0.01
        for stats in (one, many):
            stats.add_timestamps(stamps)
            stats.end_frame(at)
        assert many.frames == one.frames and many.samples_per_frame == one.samples_per_frame
        assert many.mean_samples_per_frame == one.mean_samples_per_frame
        for moment in (at, at + 0.4):
            assert many.window_samples_per_frame(moment) == one.window_samples_per_frame(moment)
    assert list(many._frame_ends) == list(one._frame_ends)
