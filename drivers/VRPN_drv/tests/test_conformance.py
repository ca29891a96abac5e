"""Conformance: VRPN_drv and its protocol package read bytes that the real VRPN C++ library
sent, not bytes of our own server or emulator.

Source of every fixture: ``conformance/*.bin``, recorded from a server built from VRPN's C++
sources (github.com/vrpn/vrpn, commit 893c7496, wire version 07.38) with its own
``vrpn_Tracker_Server``, ``vrpn_Button_Server``, ``vrpn_Analog_Server``, ``vrpn_Dial`` and
``vrpn_Text_Sender`` classes; ``conformance/README.md`` says how (the program and the raw
client that recorded the bytes are beside them). The values asserted are the script that
server was given, not anything our code produced.
"""

from __future__ import annotations

import socket
import struct
import threading
from pathlib import Path

import numpy as np
import pytest
from VRPN_drv.standalone import Batch, ServerClock, VrpnInput, pose_matrix

from gadgetctl.vrpn import codecs
from gadgetctl.vrpn.endpoint import Endpoint
from gadgetctl.vrpn.wire import COOKIE_SIZE, Message

pytestmark = pytest.mark.timeout(60)

HERE = Path(__file__).parent / "conformance"
POSITIONS = ((0.5, -1.0, 2.0), (0.25, 0.125, -0.75), (-3.5, 4.0, 0.0625))
QUATS = ((0.0, 0.0, 0.0, 1.0), (0.5, 0.5, 0.5, 0.5), (0.0, 0.6, 0.0, 0.8))


def read_stream(name: str) -> tuple[Endpoint, list[Message]]:
    """The captured TCP stream through an :class:`Endpoint`, as the client reads it."""
    data = (HERE / name).read_bytes()
    with socket.create_server(("127.0.0.1", 0)) as listener:
        right = socket.create_connection(listener.getsockname(), timeout=5)
        left, _ = listener.accept()
    endpoint = Endpoint(left)
    endpoint.decode = codecs.decode
    messages: list[Message] = []

    def write() -> None:
        right.sendall(data)
        right.shutdown(socket.SHUT_WR)

    writer = threading.Thread(target=write, daemon=True)
    writer.start()
    left.setblocking(True)
    left.settimeout(5)
    try:
        while True:
            try:
                messages += endpoint.read(2000.0)
            except ConnectionError:  # the capture's end: the peer closed
                break
    finally:
        writer.join(5)
        endpoint.close()
        right.close()
    return endpoint, messages


def datagrams(name: str) -> list[bytes]:
    data = (HERE / name).read_bytes()
    out, pos = [], 0
    while pos < len(data):
        (n,) = struct.unpack_from(">I", data, pos)
        out.append(data[pos + 4 : pos + 4 + n])
        pos += 4 + n
    return out


def test_the_handshake_and_every_device_family_decode() -> None:
    endpoint, messages = read_stream("vrpn0738_tcp.bin")
    assert endpoint.peer_version == "07.38"
    assert endpoint.setup_senders == {
        "VRPN Control",
        "Tracker0",
        "Button0",
        "Analog0",
        "Dial0",
        "Text0",
    }
    assert endpoint.remote_types[4] == codecs.TRACKER_POS_QUAT
    assert endpoint.counters["bad_reports"] == 0 and endpoint.counters["undescribed"] == 0
    poses = [m for m in messages if m.type == codecs.TRACKER_POS_QUAT]
    assert [(m.sec, m.usec) for m in poses] == [(1700000000, 100000)] * 3 + [
        (1700000000, 101000)
    ] * 3
    for m in poses:
        tick = 0 if m.usec == 100000 else 1
        x, y, z = POSITIONS[m.report.sensor]
        assert m.report.position == (x + tick, y, z)
        assert m.report.quat == QUATS[m.report.sensor]
    (velocity, _) = [m.report for m in messages if m.type == codecs.TRACKER_VELOCITY]
    assert velocity == codecs.TrackerVelocity(
        0, pytest.approx((0.1, 0.2, 0.3)), (0.0, 0.0, 0.0, 1.0), 1.0
    )
    changes = [m for m in messages if m.type == codecs.BUTTON_CHANGE]
    assert [m.report for m in changes] == [codecs.ButtonChange(1, 1), codecs.ButtonChange(1, 0)]
    assert {(m.sec, m.usec) for m in changes} == {(0, 0)}  # vrpn_Button_Server sends time 0
    states = [m.report for m in messages if m.type == codecs.BUTTON_STATES]
    assert states and states[0] == codecs.ButtonStates((0, 0, 0, 0))
    (analog,) = [m for m in messages if m.type == codecs.ANALOG_CHANNEL]
    assert analog.report == codecs.AnalogChannels((0.25, -0.5, 1.0))
    assert (analog.sec, analog.usec) == (1700000000, 200000)
    dials = [m.report for m in messages if m.type == codecs.DIAL_UPDATE]
    assert dials == [codecs.DialUpdate(0, 0.05), codecs.DialUpdate(2, -0.125)]
    (text,) = [m for m in messages if m.type == codecs.TEXT_MESSAGE]
    assert len(text.payload) == 1032  # the C++ sends its whole buffer
    assert text.report == codecs.TextReport(1, 3, "capture done")
    assert text.sender == "Text0"


def test_the_element_makes_one_sample_per_tick_with_the_servers_times() -> None:
    _endpoint, messages = read_stream("vrpn0738_tcp.bin")
    device = VrpnInput("Tracker0@127.0.0.1:1", 3, "Button0@127.0.0.1:1", 4, "Dial0@127.0.0.1:1", 3)
    batch = Batch()
    clock = ServerClock()
    device._take(messages, batch, clock)
    assert len(batch.positions) == 2
    (t0, first), (t1, second) = batch.positions
    assert t1 - t0 == pytest.approx(0.001, abs=1e-6)  # the server's interval, not the reads'
    for sensor in range(3):
        x, y, z = POSITIONS[sensor]
        np.testing.assert_allclose(first[sensor], pose_matrix((x, y, z), QUATS[sensor]))
        np.testing.assert_allclose(second[sensor], pose_matrix((x + 1, y, z), QUATS[sensor]))
    assert [values for _, values in batch.digital][-2:] == [(0, 1, 0, 0), (0, 0, 0, 0)]
    # the dial is the analog server here: its updates accumulate in revolutions
    assert [values for _, values in batch.analog] == [(0.05, 0.0, 0.0), (0.05, 0.0, -0.125)]
    assert device.counters["text_messages"] == 0  # Text0 is none of this element's devices


def test_tracker_reports_by_udp_one_datagram_per_tick() -> None:
    endpoint, _ = read_stream("vrpn0738_lob_tcp.bin")
    # the stream's own UDP_DESCRIPTION came first (the server's channel for our reports)
    grams = datagrams("vrpn0738_lob_udp.bin")
    assert len(grams) == 2
    device = VrpnInput("Tracker0@127.0.0.1:1", 3)
    left, right = socket.socketpair()
    with left, right:
        reader = Endpoint(left)
        reader.decode = codecs.decode
        reader.remote_senders.update(endpoint.remote_senders)
        reader.remote_types.update(endpoint.remote_types)
        batch = Batch()
        messages: list[Message] = []
        for gram in grams:  # one poll reads every datagram waiting, as the client does
            found = reader.read_datagram(gram, 2000.0)
            assert len(found) == 4  # three poses and a velocity
            messages += found
        device._take(messages, batch)
    assert [round(t - batch.positions[0][0], 6) for t, _ in batch.positions] == [0.0, 0.001]
    assert reader.counters["bad_datagrams"] == 0


def test_the_cookie_is_the_one_the_reference_shows() -> None:
    data = (HERE / "vrpn0738_tcp.bin").read_bytes()
    assert data[:COOKIE_SIZE] == bytes.fromhex("7672706e3a207665722e2030372e33382020300000000000")
