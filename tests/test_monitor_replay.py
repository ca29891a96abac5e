"""Replay timing with an injected clock: speed, loop, mapping and batching."""

from __future__ import annotations

import itertools
import math
import time

import pytest

from gadgetctl.monitor.records import EndRecord, FrameRecord, MarkerRecord, SampleRecord
from gadgetctl.monitor.replay import ReplaySchedule

pytestmark = pytest.mark.timeout(30)


class FakeClock:
    """A clock that only moves when slept on; remembers every sleep."""

    def __init__(self, now: float = 500.0) -> None:
        self.now = now
        self.sleeps: list[float] = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        assert seconds > 0
        self.sleeps.append(seconds)
        self.now += seconds


STAMPS = [100.0, 100.5, 101.0, 103.0]


def recording():
    return [SampleRecord("Wand", "analog", 0, t, i / 4, i) for i, t in enumerate(STAMPS)]


def replay(records, clock, **kwargs):
    """(clock time at release, record) for every record the schedule hands out."""
    schedule = ReplaySchedule(records, clock=clock, sleep=clock.sleep, tolerance=0.0, **kwargs)
    return schedule, [(clock.now, r) for r in schedule]


@pytest.mark.parametrize("speed", [1.0, 10.0, 0.5])
def test_records_are_released_at_their_time(speed):
    clock = FakeClock()
    _, out = replay(recording(), clock, speed=speed)
    expected = [500.0 + (t - 100.0) / speed for t in STAMPS]
    assert [when for when, _ in out] == pytest.approx(expected)
    assert [r.timestamp for _, r in out] == pytest.approx(expected)  # rebased on the clock
    assert [r.value for _, r in out] == [0, 0.25, 0.5, 0.75]
    assert sum(clock.sleeps) == pytest.approx(3.0 / speed)


@pytest.mark.parametrize("speed", [0, math.inf])
def test_as_fast_as_possible_never_sleeps(speed):
    clock = FakeClock()
    _, out = replay(recording(), clock, speed=speed)
    assert clock.sleeps == [] and len(out) == 4
    assert [r.timestamp for _, r in out] == pytest.approx([500.0 + t - 100.0 for t in STAMPS])


def test_loop_keeps_timestamps_increasing():
    clock = FakeClock()
    schedule, out = replay(recording(), clock, speed=2.0, loop=True, max_loops=3)
    assert schedule.period == pytest.approx(3.5)  # 3 s long + the median step of 0.5 s
    stamps = [r.timestamp for _, r in out]
    assert len(stamps) == 12
    assert all(b > a for a, b in itertools.pairwise(stamps))
    expected = [500.0 + (t - 100.0 + k * 3.5) / 2.0 for k in range(3) for t in STAMPS]
    assert stamps == pytest.approx(expected)
    assert [when for when, _ in out] == pytest.approx(expected)


def test_unbounded_loop_runs_until_the_consumer_stops():
    clock = FakeClock()
    schedule = ReplaySchedule(recording(), speed=0, loop=True, clock=clock, sleep=clock.sleep)
    taken = []
    for record in schedule:
        taken.append(record)
        if len(taken) == 41:
            break
    assert [r.value for r in taken[-5:]] == [0.0, 0.25, 0.5, 0.75, 0.0]  # 10 passes and one


def test_without_rebase_the_recorded_times_are_kept_plus_the_loop_offset():
    clock = FakeClock()
    _, out = replay(recording(), clock, loop=True, max_loops=2, rebase=False)
    assert [r.timestamp for _, r in out] == pytest.approx(STAMPS + [t + 3.5 for t in STAMPS])


def test_mapping_renames_devices_and_reports_unknown_names():
    records = [*recording(), SampleRecord("Head", "position", 0, 100.2, [[1.0]], [[1.0]])]
    clock = FakeClock()
    schedule, out = replay(records, clock, mapping={"Wand": "Wand2", "Glove": "G"})
    assert {r.device for _, r in out} == {"Wand2", "Head"}
    assert schedule.devices == ("Head", "Wand2")
    assert schedule.unused_mapping == ("Glove",)
    assert schedule.mapping_warnings == ("'Glove' does not occur in the recording",)
    merged = ReplaySchedule(records, mapping={"Wand": "Head"})
    assert merged.mapping_warnings == ("'Head' and 'Wand' all become 'Head'",)


def test_markers_are_replayed_and_other_records_are_not():
    records = [
        *recording(),
        MarkerRecord("poke", 100.75),
        FrameRecord(1, 100.2),
        EndRecord(104.0, "closed", 4, 1, 1),
    ]
    clock = FakeClock()
    _, out = replay(records, clock)
    kinds = [type(r).__name__ for _, r in out]
    assert kinds == ["SampleRecord"] * 2 + ["MarkerRecord"] + ["SampleRecord"] * 2
    assert out[2] == (pytest.approx(500.75), MarkerRecord("poke", pytest.approx(500.75)))


def test_records_out_of_order_are_sorted():
    clock = FakeClock()
    _, out = replay(list(reversed(recording())), clock)
    assert [r.value for _, r in out] == [0, 0.25, 0.5, 0.75]


def test_tolerance_releases_close_records_together():
    records = [
        SampleRecord(f"d{i % 3}", "digital", 0, 10.0 + i * 0.0001, i % 2, i % 2) for i in range(300)
    ]
    clock = FakeClock()
    schedule = ReplaySchedule(records, clock=clock, sleep=clock.sleep, tolerance=0.001)
    released = [(clock.now, batch) for batch in schedule.batches()]
    assert sum(len(b.records) for _, b in released) == 300
    assert len(clock.sleeps) < 40 and len(released) < 60  # instead of 299 sleeps
    for when, batch in released:  # nothing is released more than the tolerance early
        assert all(r.timestamp <= when + 0.001 + 1e-9 for r in batch.records)
        assert batch.due == batch.records[0].timestamp


def test_real_clock_at_speed_10():
    records = [SampleRecord("A", "analog", 0, i * 0.05, 0.0, 0) for i in range(11)]  # 0.5 s
    start = time.monotonic()
    out = list(ReplaySchedule(records, speed=10.0))
    elapsed = time.monotonic() - start
    assert len(out) == 11
    assert 0.045 <= elapsed < 1.0
    assert out[-1].timestamp - out[0].timestamp == pytest.approx(0.05)


def test_empty_recordings_and_invalid_speeds():
    assert list(ReplaySchedule([], loop=True)) == []
    for speed in (-1.0, math.nan):
        with pytest.raises(ValueError, match="speed"):
            ReplaySchedule(recording(), speed=speed)
    with pytest.raises(ValueError, match="max_loops"):
        ReplaySchedule(recording(), loop=True, max_loops=0)
    single = ReplaySchedule([SampleRecord("A", "analog", 0, 5.0, 0.0, 0)], loop=True)
    assert single.duration == 0.0 and single.period == 1.0


# -- pauses (issue 24 item 11) -------------------------------------------------------------


@pytest.mark.parametrize(
    ("stamps", "speed"),
    [
        ([0.5, 1e308], 1.0),  # gave NaN timestamps (an internal error)
        ([0.5, 1.0, 1e9 + 1.0, 1e9 + 1.5], 1.0),  # slept 1e9 s
        ([0.0, 1.7e9, 1.7e9 + 0.5], 2.0),  # a VRPN log whose first time is 0
        ([-1e308, 1e308], 0.5),  # a step beyond any float
    ],
)
def test_a_long_pause_is_shortened_to_the_longest_wait(stamps, speed):
    from gadgetctl.monitor.replay import MAX_PAUSE

    clock = FakeClock()
    records = [SampleRecord("W", "analog", 0, t, 0.5, 1) for t in stamps]
    schedule, out = replay(records, clock, speed=speed, loop=True, max_loops=2)
    assert schedule.pauses_shortened == 1 and schedule.longest_pause >= 1e9
    assert max(clock.sleeps) <= MAX_PAUSE + 1e-9  # replay seconds, whatever the speed
    assert len(out) == 2 * len(stamps)
    released = [r.timestamp for _, r in out]
    assert all(math.isfinite(t) for t in released) and released == sorted(released)
    assert clock.now - 500.0 <= 3 * MAX_PAUSE + 2.0  # two passes and the step between


def test_pauses_up_to_the_longest_wait_keep_their_length():
    from gadgetctl.monitor.replay import MAX_PAUSE

    clock = FakeClock()
    stamps = [0.0, MAX_PAUSE * 3, MAX_PAUSE * 3 + 1.0]  # 30 s recorded: 10 s at speed 3
    schedule, out = replay(
        [SampleRecord("W", "analog", 0, t, 0.5, 1) for t in stamps], clock, speed=3.0
    )
    assert schedule.pauses_shortened == 0
    assert [when for when, _ in out] == pytest.approx([500.0, 510.0, 500.0 + 31 / 3])
