"""What VRPN_drv makes of a server's reports, message by message: each sample keeps its own
VRPN time, a tick split over two reads is one sample, nothing is made before the first
report, the cost of many sensors is bounded, dials read as analog units, text is counted."""

from __future__ import annotations

import numpy as np
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


def _stream_through(bulk: bool, stream: bytes, sensors: int) -> tuple[Batch, VrpnInput]:
    """``stream`` (after the cookie) read by an endpoint, as messages or with the tracker's
    poses left framed in blocks, into a fresh element."""
    import socket

    from gadgetctl.vrpn.endpoint import Endpoint
    from gadgetctl.vrpn.wire import make_cookie

    with socket.create_server(("127.0.0.1", 0)) as listener:
        writer = socket.create_connection(listener.getsockname(), timeout=5)
        reader, _ = listener.accept()
    with writer:
        endpoint = Endpoint(reader)
        endpoint.decode = codecs.decode
        writer.sendall(make_cookie() + stream)
        writer.shutdown(socket.SHUT_WR)
        reader.setblocking(True)
        device = VrpnInput(f"Tracker0@{HOST}", sensors)
        batch, clock = Batch(), ServerClock()
        pairs = frozenset({("Tracker0", codecs.TRACKER_POS_QUAT)})
        try:
            while True:
                if bulk:
                    messages, blocks = endpoint.read_bulk(2000.0, pairs)
                else:
                    messages, blocks = endpoint.read(2000.0), []
                device._take(messages, batch, clock)
                for block in blocks:
                    device._take_block(block, batch, clock)
        except ConnectionError:
            pass
        finally:
            endpoint.close()
    device._end_tick(batch)
    return batch, device


def test_a_whole_read_unpacked_at_once_makes_the_same_samples() -> None:
    from gadgetctl.vrpn.wire import pack_description, pack_message

    stream = pack_description(-1, 0, "Tracker0") + pack_description(-1, 1, "Button0")
    stream += pack_description(-2, 0, codecs.TRACKER_POS_QUAT)
    stream += pack_description(-2, 1, codecs.BUTTON_CHANGE)
    quats = [(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 0.0), (1.0, 2.0, 3.0, 4.0), (0.0, 0.6, 0.0, 0.8)]
    for tick in range(40):
        stamp = 1700000000 + tick * 0.001
        for sensor in (0, 1, 2, 5) if tick % 7 else (2, 0):  # some ticks incomplete
            payload = codecs.encode_pose(sensor, (tick, sensor, -1.5), quats[(tick + sensor) % 4])
            stream += pack_message(0, 0, payload, stamp)
        if tick % 5 == 0:
            stream += pack_message(1, 1, codecs.encode_button_change(1, tick % 2), stamp)
    one_by_one, device_a = _stream_through(False, stream, 3)
    at_once, device_b = _stream_through(True, stream, 3)
    assert len(at_once.positions) == len(one_by_one.positions) > 30
    for (ta, va), (tb, vb) in zip(one_by_one.positions, at_once.positions, strict=True):
        assert ta == pytest.approx(tb, abs=1e-6)
        np.testing.assert_allclose(va, vb, atol=1e-12)
    assert at_once.digital == one_by_one.digital
    assert device_a.counters["beyond_count"] == device_b.counters["beyond_count"] > 0


def test_sample_times_never_go_back() -> None:
    device = VrpnInput(f"Tracker0@{HOST}", 1)
    clock = ServerClock()
    first, second = Batch(), Batch()
    device._take([pose(0, 100, 0, 150.5)], first, clock)  # 0.5 s of latency at first
    device._take([pose(0, 100, 1000, 150.002)], second, clock)  # then almost none
    (t0, _), (t1, _) = first.positions[0], second.positions[0]
    assert t0 == pytest.approx(150.5) and t1 >= t0
