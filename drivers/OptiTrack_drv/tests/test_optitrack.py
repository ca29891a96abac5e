"""The OptiTrack driver against its loopback NatNet emulator: units and their order, metres and
quaternion rotations, the upstream defects fixed (markers stored, bodies with zeros kept),
bounded decoding, garbage, disconnection and return, multicast through loopback."""

from __future__ import annotations

import math
import socket
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest
from OptiTrack_drv.emulator import (
    FrameWriter,
    OptiTrackEmulator,
    body_pose,
    encode_frame,
    marker_position,
)
from OptiTrack_drv.standalone import (
    DEFAULT_LIMITS,
    NatNetFormatError,
    NatNetReceiver,
    NatNetUnits,
    decode_frame,
    quaternion_matrix,
)
from OptiTrack_drv.tests.elements import optitrack_element

from gadgetctl.input import DeviceKind
from gadgetctl.input.testing import frames_until, wait_until
from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration, free_udp_port, pending_in, proxy
from gadgetctl.input.testing.fixtures import managers_fixture

pytestmark = pytest.mark.timeout(30)

V20 = (2, 0)

RATE = 200.0


build = managers_fixture(
    "Optitrack_drv",
    name="build",
    ready=True,
    tune={"optitrack": {"multicast_interface": "127.0.0.1"}},  # multicast through loopback
)


def device(name: str, port: int, bodies: list[int], markers: list[int], extra: str = "") -> str:
    """An optitrack element on ``port``; ``extra``: more properties (the NatNet version is
    4.1, the emulator's, unless ``extra`` names one)."""
    if "natnet_version" not in extra:
        extra += "<natnet_version>4.1</natnet_version>"
    return optitrack_element(name, bodies, markers, f"<port>{port}</port>{extra}")


def expected_body(index: int, frame: int = 0, moving: bool = False) -> np.ndarray:
    pose = body_pose(frame, index, moving)
    matrix = np.eye(4)
    matrix[:3, :3] = quaternion_matrix(*pose[3:])
    matrix[:3, 3] = pose[:3]
    return matrix


# -- decoding ----------------------------------------------------------------------------------


def test_quaternion_convention_is_x_y_z_w_right_handed() -> None:
    half = math.sqrt(0.5)
    turn = quaternion_matrix(0.0, 0.0, half, half)  # a quarter turn about +z
    np.testing.assert_allclose(turn @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(quaternion_matrix(0, 0, 0, 2.0), np.eye(3))  # normalised


def test_bodies_with_zero_components_and_markers_are_kept() -> None:
    # upstream dropped body 5 (zeros) and never stored markers
    packet = encode_frame(
        9,
        [(5, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)), (6, (1.0, 0.0, 2.0, 0, 0, 0, 1.0))],
        [(0.1, 0.2, 0.3), (0.4, 0.5, 0.6)],
        [("set", [(1.0, 1.0, 1.0)])],
        version=V20,
    )
    frame = decode_frame(packet, V20)
    assert frame.number == 9 and set(frame.bodies) == {5, 6} and frame.bad_records == 0
    np.testing.assert_allclose(frame.markers, [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]], rtol=1e-6)
    assert set(frame.body_markers) == {500, 501, 600, 601}
    units = NatNetUnits([6, 5, 77], [1000, 1001, 601])
    m = units.update(frame)
    np.testing.assert_allclose(m[0, :3, 3], [1.0, 0.0, 2.0])
    np.testing.assert_allclose(m[1], np.eye(4))  # body 5 at the origin: tracked, identity
    np.testing.assert_allclose(m[2], np.eye(4))  # body 77 never seen
    # marker_index 1000 is marker 0 of marker set 0 (Gadgeteer), not an unidentified marker
    np.testing.assert_allclose(m[3, :3, 3], [1.0, 1.0, 1.0], rtol=1e-6)
    np.testing.assert_allclose(m[4], np.eye(4))  # set 0 has one marker only
    np.testing.assert_allclose(m[5, :3, 3], [1.01, 0.0, 2.0], rtol=1e-6)


@pytest.mark.parametrize(
    "payload",
    [
        struct.pack("<ii", 1, DEFAULT_LIMITS.marker_sets + 1),
        struct.pack("<ii", 1, -1),
        struct.pack("<iii", 1, 0, DEFAULT_LIMITS.markers + 1),
        struct.pack("<iiii", 1, 0, 0, DEFAULT_LIMITS.rigid_bodies + 1),
        struct.pack("<iiii", 1, 0, 0, 1) + struct.pack("<i7fi", 1, 0, 0, 0, 0, 0, 0, 1, 10_000),
        struct.pack("<iiii", 1, 0, 0, 2),  # bodies announced, none present
    ],
)
def test_counts_beyond_the_limits_are_bad_packets(payload: bytes) -> None:
    with pytest.raises(NatNetFormatError):
        decode_frame(struct.pack("<HH", 7, len(payload)) + payload, V20)


def test_a_body_without_a_rotation_is_a_bad_record() -> None:
    packet = encode_frame(
        1,
        [(1, (1.0, 2.0, 3.0, 0, 0, 0, 0)), (2, (1.0, math.nan, 3.0, 0, 0, 0, 1))],
        [],
        version=V20,
    )
    frame = decode_frame(packet, V20)
    assert frame.bodies == {} and frame.bad_records == 2


def test_signalling_nan_coordinates_are_bad_records_without_a_warning() -> None:
    """A float32 signalling NaN (found by ``make fuzz``'s udp.optitrack) in a marker set, an
    unidentified and a labeled marker: bad records, and no numpy RuntimeWarning ("invalid value
    encountered in cast") on stderr."""
    quiet = struct.pack("<f", 1.5)
    packet = encode_frame(
        3,
        [],
        [(1.5, 0.0, 0.0)],
        [("set", [(1.5, 0.0, 0.0)])],
        version=(3, 0),
        labeled=[(7, (1.5, 0.0, 0.0))],
    )
    assert packet.count(quiet) == 3
    packet = packet.replace(quiet, struct.pack("<I", 0x7F800001))  # signalling NaN
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        frame = decode_frame(packet, (3, 0))
    assert frame.bad_records >= 2 and frame.markers.shape == (1, 3)


# -- through the input manager -------------------------------------------------------------------


def test_bodies_then_markers_in_metres_through_proxies(build) -> None:
    port = free_udp_port()
    body = device("OT", port, [2, 1, 3], [1000, 1002])
    for unit, name in enumerate(["B2", "B1", "B3", "M0", "M2"]):
        body += proxy("position", name, "OT", unit)
    manager = build(body)
    with OptiTrackEmulator(port, scenario="idle", rate=RATE, bodies=3, markers=3):
        frames_until(manager, lambda: manager.device("OT").store.total(DeviceKind.POSITION) > 3)
    np.testing.assert_allclose(manager.proxy("B2").matrix, expected_body(1), atol=1e-6)
    np.testing.assert_allclose(manager.proxy("B3").matrix, expected_body(2), atol=1e-6)
    # body id 1 rests at the origin with the identity rotation: kept (upstream dropped it)
    np.testing.assert_allclose(manager.proxy("B1").matrix, np.eye(4), atol=1e-6)
    assert manager.proxy("B1").timestamp is not None
    np.testing.assert_allclose(
        manager.proxy("M2").translation, marker_position(0, 2, False), atol=1e-6
    )  # marker 2 of marker set 0
    np.testing.assert_allclose(manager.proxy("M0").matrix[:3, :3], np.eye(3))
    # a quarter of a turn etc.: body index 2 is turned 30 degrees about z
    turned = manager.proxy("B3").matrix[:3, :3] @ [1, 0, 0]
    np.testing.assert_allclose(
        turned, [math.cos(math.radians(30)), math.sin(math.radians(30)), 0], atol=1e-6
    )


def test_moving_bodies_follow_the_frames(build) -> None:
    port = free_udp_port()
    manager = build(
        device("OT", port, [2], [1000])
        + proxy("position", "B", "OT", 0)
        + proxy("position", "M", "OT", 1)
    )
    with OptiTrackEmulator(port, scenario="motion", rate=RATE, max_frames=40) as emu:
        frames_until(
            manager, lambda: emu.finished.is_set() and manager.device("OT").counters["frames"] >= 40
        )
        frames_until(manager, lambda: manager.device("OT").store.total(DeviceKind.POSITION) >= 40)
    np.testing.assert_allclose(manager.proxy("B").matrix, expected_body(1, 40, True), atol=1e-5)
    np.testing.assert_allclose(
        manager.proxy("M").translation, marker_position(40, 0, True), atol=1e-6
    )
    assert manager.device("OT").counters["missed_frames"] == 0


def test_garbage_is_counted_and_every_frame_is_a_sample(build) -> None:
    port = free_udp_port()
    manager = build(device("OT", port, [1], []) + proxy("position", "B", "OT", 0))
    dev = manager.device("OT")
    with OptiTrackEmulator(port, scenario="garbage", rate=RATE, max_frames=40, seed=2) as emu:
        frames_until(
            manager,
            lambda: (
                emu.finished.is_set()
                and dev.counters["datagrams"] >= 80
                and dev.store.total(DeviceKind.POSITION) >= 40
            ),
        )
        assert manager.status("OT").state == "running" and dev.faults == 0
    # exact counts once sampling stopped: the last datagram (junk) is counted received before
    # it is counted bad, and this thread may read between the two
    manager.shutdown()
    counters = dev.counters
    assert counters["bad_datagrams"] == emu.garbage_sent == 40
    assert counters["frames"] == dev.store.total(DeviceKind.POSITION) == 40


def test_a_silent_server_faults_and_data_returns_within_two_seconds(build) -> None:
    port = free_udp_port()
    manager = build(device("OT", port, [1], []) + proxy("position", "B", "OT", 0), peer_timeout=0.3)
    dev = manager.device("OT")
    with OptiTrackEmulator(port, scenario="disconnect", rate=RATE, disconnect_after=20) as emu:
        frames_until(manager, lambda: emu.finished.is_set() and dev.store.total() >= 20)
        frames_until(manager, lambda: manager.status("OT").state == "faulted")
    assert "NatNet" in manager.status("OT").reason
    with OptiTrackEmulator(port, scenario="motion", rate=RATE, first_frame=500):
        count = dev.store.total()
        resumed = frames_until(manager, lambda: dev.store.total() > count, timeout=4.0)
        assert resumed < 2.0
        frames_until(manager, lambda: manager.status("OT").state == "running")
    assert dev.restarts >= 1


def test_multicast_through_loopback_reaches_the_receiver() -> None:
    receiver = NatNetReceiver(
        0, group="224.0.0.1", interface="127.0.0.1", receive_timeout=0.05, version=(4, 1)
    )
    receiver.open()
    try:
        assert receiver.joined
        with OptiTrackEmulator(receiver.port, scenario="idle", rate=RATE, group="224.0.0.1"):
            frames: list = []
            assert wait_until(
                lambda: bool(frames.extend(receiver.sample_all()) or frames), timeout=5.0
            )
        assert frames[0].bodies[2] == pytest.approx(body_pose(0, 1, False), rel=1e-6)
    finally:
        receiver.close()


def test_unusable_ports_stay_pending_with_a_reason(tmp_path: Path) -> None:
    path = tmp_path / "bad.jconf"
    path.write_text(configuration("Optitrack_drv", device("Huge", 70000, [1], [])))
    reasons = pending_in(path)
    assert reasons["Huge"] == "port 70000 is not a UDP port (0 to 65535)"


def test_doctor_checks_the_port_and_the_multicast_group(tmp_path: Path) -> None:
    import json

    port = free_udp_port()
    path = tmp_path / "doctor.jconf"
    path.write_text(configuration("Optitrack_drv", device("OT", port, [1], [])))
    result = run_gadgetctl("doctor", str(path), "--format", "json", timeout=60)
    report = json.loads(result.stdout)
    checks = {c["target"]: c for d in report["devices"] for c in d["checks"]}
    assert checks[f"{port}/udp"]["status"] == "ok"
    # doctor joins only link-local groups; Motive's is named, not joined
    assert checks["239.255.42.99 (multicast)"]["status"] == "unchecked"


def test_validate_counts_bodies_and_markers_as_units(tmp_path: Path) -> None:

    path = tmp_path / "units.jconf"
    body = (
        device("OT", 1001, [1], [1000])
        + proxy("position", "Ok", "OT", 1)
        + proxy("position", "Beyond", "OT", 2)
    )
    path.write_text(configuration("Optitrack_drv", body))
    result = run_gadgetctl("validate", str(path), timeout=60)
    assert result.returncode == 1
    assert "CFG034" in result.stdout and "'Beyond'" in result.stdout and "'Ok'" not in result.stdout


# -- sessions with the server, versions, undecodable data, frame numbers --------------------------


def test_a_unicast_session_with_an_emulated_motive(build) -> None:
    port = free_udp_port()
    with OptiTrackEmulator(
        port, scenario="motion", rate=RATE, command_port=0, unicast=True, version=(3, 1)
    ) as motive:
        command_port = motive.command_address[1]
        extra = (
            "<connection_type>Unicast</connection_type><server_address>127.0.0.1</server_address>"
            f"<command_port>{command_port}</command_port><natnet_version></natnet_version>"
        )
        manager = build(
            device("OT", port, [2], [1001], extra=extra)
            + proxy("position", "B", "OT", 0)
            + proxy("position", "M", "OT", 1)
        )
        dev = manager.device("OT")
        frames_until(manager, lambda: dev.store.total(DeviceKind.POSITION) >= 30)
        # keep-alives follow the connect request while the session lasts
        frames_until(manager, lambda: motive.keepalives >= 1, timeout=10.0)
        assert motive.connects >= 1 and len(motive.clients) == 1
    counters = dev.counters
    assert counters["server_infos"] >= 1 and counters["bad_datagrams"] == 0
    assert dev._receiver.version == (3, 1)  # from the server's information
    turned = manager.proxy("B").matrix[:3, :3] @ [1, 0, 0]
    assert abs(np.linalg.norm(turned) - 1) < 1e-9 and manager.proxy("B").timestamp is not None
    np.testing.assert_allclose(manager.proxy("M").translation[0], 0.01, atol=1e-6)


def test_a_unicast_receiver_connects_again_after_a_reconnection() -> None:
    with OptiTrackEmulator(
        free_udp_port(), scenario="idle", rate=RATE, command_port=0, unicast=True
    ) as motive:
        receiver = NatNetReceiver(
            0,
            group=None,
            unicast=True,
            command_port=motive.command_address[1],
            receive_timeout=0.02,
        )
        for _session in range(2):  # a restart after a loss is a new session for the server
            before = motive.connects
            receiver.open()
            try:
                assert wait_until(lambda: bool(receiver.sample_all()), 5.0)
            finally:
                receiver.close()
            assert motive.connects > before and receiver.version == (4, 1)
        assert receiver.frames >= 2 and receiver.bad_datagrams == 0


def test_a_device_whose_frames_never_decode_shows_undecodable_with_the_first_error(build) -> None:
    # NatNet 3.0 frames read as 2.0 (the element says so): every one fails; upstream, and
    # gadgetctl before, showed such a device as running
    port = free_udp_port()
    manager = build(
        device("OT", port, [1], [], extra="<natnet_version>2.0</natnet_version>")
        + proxy("position", "B", "OT", 0)
    )
    dev = manager.device("OT")
    with OptiTrackEmulator(port, scenario="motion", rate=RATE, version=(3, 0)):
        frames_until(manager, lambda: manager.status("OT").state == "undecodable")
        status = manager.status("OT")
        assert dev.counters["bad_datagrams"] > 0 and dev.counters["frames"] == 0
    assert "none decoded" in status.reason and "NatNet 2.0 frame:" in status.reason
    assert dev.health()["bad_datagrams"] == dev.health()["datagrams"]
    assert dev.store.total(DeviceKind.POSITION) == 0


def test_hostile_frame_numbers_never_make_absurd_missed_frames() -> None:
    import warnings

    receiver = NatNetReceiver(0, group=None, version=V20)
    numbers = [1, 2, 5, 2**31 - 1, -(2**31), -(2**31) + 3, 77, 77, 3, 3 + 10_000, 2**31 - 7]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for n in numbers:
            frame = receiver.decode(
                encode_frame(n, [(1, (1.0, 2.0, 3.0, 0, 0, 0, 1.0))], [], version=V20)
            )
            assert frame is not None and frame.number == n
    # 2 -> 5: 2 missed; int32 wrap -2**31 -> -2**31+3: 2 missed; 3 -> 10003: 9999 missed
    assert receiver.missed_frames == 2 + 2 + 9_999
    # 2**31-1 -> -2**31 is the int32 wrap, a step of 1; jumps, counted once each:
    # 5 -> 2**31-1, -2**31+3 -> 77, the repeated 77, 77 -> 3 (back), 10003 -> 2**31-7
    assert receiver.frame_jumps == 5


def test_without_an_answer_the_frames_are_reported_undecodable() -> None:
    receiver = NatNetReceiver(
        0, group=None, command_port=free_udp_port(), receive_timeout=0.02, version_timeout=0.2
    )
    receiver.open()
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
            packet = encode_frame(1, [(1, (1.0, 2.0, 3.0, 0, 0, 0, 1.0))], [])

            def judged() -> bool:
                sender.sendto(packet, ("127.0.0.1", receiver.port))
                receiver.sample_all()
                return receiver.undecoded_frames > 0

            assert wait_until(judged, timeout=10.0)
        assert receiver.requests_sent >= 1 and receiver.frames == 0
        why = receiver.undecodable_reason()
        assert why is not None and "did not answer the connect request" in why
        assert receiver.bad_datagrams == receiver.undecoded_frames
    finally:
        receiver.close()


def test_a_configured_version_in_multicast_mode_sends_nothing() -> None:
    receiver = NatNetReceiver(0, group=None, version=(4, 1), receive_timeout=0.02)
    receiver.open()
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
            sender.sendto(FrameWriter("idle", 2, 2).frame(3), ("127.0.0.1", receiver.port))
            frames: list = []
            assert wait_until(lambda: bool(frames.extend(receiver.sample_all()) or frames), 5.0)
        assert receiver.requests_sent == 0 and receiver.server is None
    finally:
        receiver.close()


def test_the_connect_request_asks_for_the_configured_version_or_none() -> None:
    from OptiTrack_drv.natnet import connect_request, keep_alive

    request = connect_request()
    # SDK layout: id 0, 271 payload bytes, a sender block named "Ping", the stream version
    # asked for at payload bytes 265..268, a final NUL
    assert struct.unpack_from("<HH", request) == (0, 271) and len(request) == 4 + 271
    assert request[4:8] == b"Ping" and request[-1] == 0
    assert request[4 + 265 : 4 + 269] == bytes(4)  # none: the server's own setting
    assert connect_request((3, 0))[4 + 265 : 4 + 269] == bytes((3, 0, 0, 0))
    assert keep_alive() == struct.pack("<HH", 10, 0) + b"\0"
