"""What VRPN_drv makes of a server's reports, message by message: each sample keeps its own
VRPN time, a tick split over two reads is one sample, nothing is made before the first
report, the cost of many sensors is bounded, dials read as analog units, text is counted."""

from __future__ import annotations

import pytest
from VRPN_drv.standalone import (
    POSE_BYTES,
    POSE_READ_BYTES,
    Batch,
    ServerClock,
    VrpnInput,
    pose_matrix,
)

from gadgetctl.vrpn import codecs
from gadgetctl.vrpn.wire import Message

pytestmark = pytest.mark.timeout(60)

HOST = "127.0.0.1:1"  # never connected: the tests feed messages to the element directly


def pose(sensor: int, sec: int, usec: int, received: float, x: float = 0.0) -> Message:
    report = codecs.TrackerPose(sensor, (x, float(sensor), 0.0), (0.0, 0.0, 0.0, 1.0))
    payload = codecs.encode_pose(sensor, report.position, report.quat)
    return Message(4, 1, sec, usec, payload, "Tracker0", codecs.TRACKER_POS_QUAT, received, report)


def message(type_name: str, report: object, sec: int, usec: int, received: float) -> Message:
    return Message(9, 2, sec, usec, b"", "Dev0", type_name, received, report)


def test_each_sample_keeps_its_own_message_time() -> None:
    device = VrpnInput(f"Tracker0@{HOST}", 1)
    batch = Batch()
    # three ticks 1 ms apart (server time) arrive in one read, at one receive time
    device._take([pose(0, 1000, 1000 * i, received=5000.0) for i in range(3)], batch)
    device._end_tick(batch)
    times = [t for t, _ in batch.positions]
    assert times[1] - times[0] == pytest.approx(0.001, abs=1e-9)
    assert times[2] - times[1] == pytest.approx(0.001, abs=1e-9)
    assert max(times) <= 5000.0  # never later than the arrival


def test_the_server_clock_maps_onto_the_local_clock() -> None:
    clock = ServerClock()

    def seen(sent: float, received: float) -> float:
        clock.observe(sent, received)
        return clock.local(sent, received)

    assert seen(100.0, 150.25) == pytest.approx(150.25)
    # less latency later: the mapping follows the smallest difference
    assert seen(101.0, 151.0) == pytest.approx(151.0)
    assert seen(102.0, 152.5) == pytest.approx(152.0)
    # no time given (a C++ vrpn_Button_Server sends 0): the receive time
    assert seen(0.0, 153.0) == 153.0
    # the server's clock stepped back by an hour: re-anchored, not an hour in the past
    assert seen(102.0 - 3600, 154.0) == pytest.approx(154.0)


def test_a_tick_split_over_two_reads_is_one_sample() -> None:
    device = VrpnInput(f"Tracker0@{HOST}", 3)
    first, second = Batch(), Batch()
    device._take([pose(0, 7, 0, 10.0, x=1.0), pose(1, 7, 0, 10.0, x=1.0)], first)
    device._take(
        [pose(2, 7, 0, 10.001, x=1.0)] + [pose(s, 7, 1000, 10.001, x=2.0) for s in range(3)],
        second,
    )
    assert first.positions == []  # the tick is not whole yet: nothing half-updated is shown
    assert len(second.positions) == 2
    for (_, values), x in zip(second.positions, (1.0, 2.0), strict=True):
        assert [float(values[s][0, 3]) for s in range(3)] == [x, x, x]


def test_nothing_before_the_first_report() -> None:
    device = VrpnInput(f"Tracker0@{HOST}", 2, f"Button0@{HOST}", 2, f"Analog0@{HOST}", 2)
    batch = Batch()
    device._take([], batch)
    assert not batch


def test_many_sensors_do_not_grow_what_a_read_makes() -> None:
    # a first report for sensor 1023, then small poses of sensor 0, each its own tick
    device = VrpnInput(f"Tracker0@{HOST}", 1024)
    batch = Batch()
    messages = [pose(1023, 1, 0, 2.0)] + [pose(0, 1, 1 + i, 2.0, x=i) for i in range(600)]
    device._take(messages, batch)
    device._end_tick(batch)
    held = sum(values.nbytes for _, values in batch.positions)
    assert held <= POSE_READ_BYTES
    assert len(batch.positions) == POSE_READ_BYTES // (POSE_BYTES * 1024)
    assert device.counters["merged_ticks"] == 601 - len(batch.positions)
    # the last sample is the newest state: nothing is lost but intermediate ticks
    newest = batch.positions[-1][1]
    assert float(newest[0][0, 3]) == 599.0 and float(newest[1023][1, 3]) == 1023.0


def test_dials_are_analog_units_and_text_is_counted() -> None:
    device = VrpnInput(analog=f"Dev0@{HOST}", analog_count=3)
    batch = Batch()
    device._take(
        [
            message(codecs.DIAL_UPDATE, codecs.DialUpdate(0, 0.05), 1, 0, 2.0),
            message(codecs.DIAL_UPDATE, codecs.DialUpdate(2, -0.125), 1, 0, 2.0),
            message(codecs.DIAL_UPDATE, codecs.DialUpdate(0, 0.05), 1, 1, 2.0),
            message(codecs.DIAL_UPDATE, codecs.DialUpdate(7, 1.0), 1, 2, 2.0),
            message(codecs.TEXT_MESSAGE, codecs.TextReport(1, 3, "hello"), 1, 3, 2.0),
        ],
        batch,
    )
    assert [values for _, values in batch.analog] == [
        (0.05, 0.0, 0.0),
        (0.05, 0.0, -0.125),
        (0.1, 0.0, -0.125),
    ]
    assert device.counters["beyond_count"] == 1
    assert device.counters["text_messages"] == 1
    assert device.texts[-1][1:] == ("Dev0", 1, 3, "hello")


def test_pose_matrix_is_the_identity_for_no_rotation() -> None:
    assert (
        pose_matrix((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)) == pose_matrix((0, 0, 0), (0, 0, 0, 2))
    ).all()
