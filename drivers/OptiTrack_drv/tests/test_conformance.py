"""OptiTrack conformance: the driver against bytes that do not come from our emulator.

Two independent sources:

* Real Motive traffic: ``captures/motive-2.1-natnet-3.0.pcapng`` (Motive 2.1, NatNet 3.0; see
  ``captures/README.md`` for its source, mje-nz/python_natnet, BSD 3-Clause), checked against
  the numbers NaturalPoint's own SampleClient printed for the same session.
* Frames packed here by :class:`SdkPacker`, written from the NatNet SDK's sample decoders
  field by field (not from the driver nor from our emulator): ``PacketClient.cpp`` ``Unpack()``
  of NatNet SDK 3.0 (as ported in b4be1/packet-client-linux, PacketClient.cpp) for NatNet
  1.x to 3.x, and ``NatNetClient.py`` of the NatNet 4.1 SDK's PythonClient (as in
  lunarring/optitrack_python, optitrack_python/NatNetClient.py: ``__unpack_mocap_data`` and
  the ``__unpack_*`` functions it calls, ``__unpack_data_size`` for the 4.1 byte counts,
  ``__unpack_server_info`` for the server information) for 4.x.

The acceptance test sends such frames of NatNet 2.0, 2.5, 2.7, 3.0, 3.1, 4.0 and 4.1, with
several rigid bodies, marker sets, labeled markers and a skeleton, over real multicast on the
loopback interface to Motive's default group and port, to an ``optitrack`` element that sets
no property at all; a stand-in server answers the driver's connect request on Motive's
command port with the SDK's server information. Nothing leaves the host: the sender's
multicast interface is 127.0.0.1 and its TTL 0. Tests on Motive's fixed ports take turns with
every other test on fixed addresses (the quick-start lock).
"""

from __future__ import annotations

import math
import socket
import struct
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from OptiTrack_drv.natnet import NatNetFormatError, decode_frame, decode_server_info
from OptiTrack_drv.standalone import NatNetReceiver, quaternion_matrix
from OptiTrack_drv.tests.elements import optitrack_element

from gadgetctl.input import DeviceKind
from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.configs import fixed_addresses, proxy
from gadgetctl.input.testing.fixtures import managers_fixture

pytestmark = pytest.mark.timeout(60)

CAPTURE = Path(__file__).parent / "captures" / "motive-2.1-natnet-3.0.pcapng"
MOTIVE_GROUP, DATA_PORT, COMMAND_PORT = "239.255.42.99", 1511, 1510
VERSIONS = [(2, 0), (2, 5), (2, 7), (3, 0), (3, 1), (4, 0), (4, 1)]


# -- the real capture ---------------------------------------------------------------------------


def capture_datagrams() -> list[tuple[str, int, str, int, bytes]]:
    """(source, source port, destination, destination port, payload) of every UDP datagram
    of the capture (pcapng enhanced packet blocks, Ethernet, IPv4)."""
    data = CAPTURE.read_bytes()
    found, offset = [], 0
    while offset < len(data):
        kind, length = struct.unpack_from("<II", data, offset)
        if kind == 6:  # enhanced packet block
            caplen = struct.unpack_from("<I", data, offset + 20)[0]
            packet = data[offset + 28 : offset + 28 + caplen]
            ip = packet[14:]
            if ip[0] >> 4 == 4 and ip[9] == 17:
                header = (ip[0] & 15) * 4
                sport, dport, size = struct.unpack_from("!HHH", ip, header)
                found.append(
                    (
                        socket.inet_ntoa(ip[12:16]),
                        sport,
                        socket.inet_ntoa(ip[16:20]),
                        dport,
                        bytes(ip[header + 8 : header + size]),
                    )
                )
        offset += length
    return found


def test_every_frame_of_real_motive_traffic_decodes_as_the_sdk_printed_it() -> None:
    datagrams = capture_datagrams()
    infos = [d[4] for d in datagrams if d[4][:2] == b"\x01\x00"]
    info = decode_server_info(infos[0])
    assert (info.application, info.natnet_version) == ("Motive", (3, 0, 0, 0))
    assert (info.data_port, info.multicast, info.multicast_group) == (1511, True, MOTIVE_GROUP)

    receiver = NatNetReceiver(0, group=None)  # the version comes from the server's reply
    frames = []
    for source, sport, _dest, _dport, payload in datagrams:
        frames.extend(receiver.handle(payload, (source, sport)))
    # the old 1.x/2.0 reader decoded 0 of these 518 frames ("rigid body marker count
    # 973541338 is outside 0..20"); every datagram is now a frame or a counted message
    assert receiver.version == (3, 0)
    assert receiver.frames == len(frames) == 518
    assert receiver.bad_datagrams == 0 and receiver.missed_frames == 0
    assert receiver.other_messages + receiver.server_infos + 518 == len(datagrams)

    first = frames[0]  # SampleClient: FrameID 162734, body 2, 5 other, 6 labeled markers
    assert first.number == 162734
    assert list(first.bodies) == [2]
    np.testing.assert_allclose(
        first.bodies[2], (0.17, 1.45, -0.73, -0.05, 0.51, 0.04, -0.86), atol=0.005
    )
    np.testing.assert_allclose(
        first.markers,
        [
            (0.13, 1.51, -0.89),
            (0.21, 1.48, -0.71),
            (-0.05, 1.43, -0.83),
            (0.18, 1.44, -0.65),
            (0.32, 1.41, -0.75),
        ],
        atol=0.005,
    )
    # labeled marker ids: model id << 16 | marker id
    assert sorted(first.labeled_markers) == [50007, *((2 << 16) | k for k in range(1, 6))]
    np.testing.assert_allclose(first.labeled_markers[50007], (0.17, 1.51, -0.84), atol=0.005)
    assert [f.number for f in frames] == list(range(162734, 162734 + 518))


def test_real_frames_read_as_another_version_are_never_counted_as_good() -> None:
    payloads = [d[4] for d in capture_datagrams() if d[4][:2] == b"\x07\x00"]
    for version in [(1, 0), (2, 0), (2, 5), (2, 6), (2, 9), (2, 11), (4, 1)]:
        receiver = NatNetReceiver(0, group=None, version=version)
        for payload in payloads:
            receiver.handle(payload)
        assert receiver.frames == 0 and receiver.bad_datagrams == len(payloads), version
        assert receiver.first_error


# -- frames packed from the SDK's layout --------------------------------------------------------


class SdkPacker:
    """Packs a NatNet frame of data field by field in the order and under the version
    conditions of the SDK's sample decoders (see the module)."""

    def __init__(self, major: int, minor: int) -> None:
        self.major, self.minor = major, minor
        self.out = bytearray()

    def at_least(self, major: int, minor: int) -> bool:
        return (self.major, self.minor) >= (major, minor)

    def put(self, fmt: str, *values: object) -> None:
        self.out += struct.pack("<" + fmt, *values)

    def count(self, n: int, section: bytes) -> None:
        """A count; from 4.1 the section's size in bytes follows it (``__unpack_data_size``)."""
        self.put("i", n)
        if self.at_least(4, 1):
            self.put("i", len(section))
        self.out += section

    def rigid_body(self, ident: int, pose: tuple[float, ...], markers: int = 0) -> bytes:
        inner = SdkPacker(self.major, self.minor)
        inner.put("i", ident)
        inner.put("3f", *pose[:3])
        inner.put("4f", *pose[3:])
        if self.major < 3:  # "Before NatNet 3.0, marker data was here"
            inner.put("i", markers)
            for k in range(markers):
                inner.put("3f", pose[0] + k, pose[1], pose[2])
            if self.major >= 2:
                for k in range(markers):
                    inner.put("i", 100 * ident + k)
                for _ in range(markers):
                    inner.put("f", 0.02)
        if self.major >= 2:
            inner.put("f", 0.0003)  # mean marker error
        if self.at_least(2, 6):
            inner.put("h", 0x01)  # tracking valid
        return bytes(inner.out)

    def frame(self, number: int, scene: Scene) -> bytes:
        self.put("i", number)
        sets = b"".join(
            name.encode()
            + b"\0"
            + struct.pack("<i", len(pts))
            + b"".join(struct.pack("<3f", *p) for p in pts)
            for name, pts in scene.marker_sets
        )
        self.count(len(scene.marker_sets), sets)
        self.count(len(scene.other), b"".join(struct.pack("<3f", *p) for p in scene.other))
        bodies = b"".join(self.rigid_body(i, p, markers=2) for i, p in scene.bodies)
        self.count(len(scene.bodies), bodies)
        if self.at_least(2, 1):
            skeleton = struct.pack("<ii", scene.skeleton_id, len(scene.bones))
            skeleton += b"".join(self.rigid_body(i, p) for i, p in scene.bones)
            self.count(1, skeleton)
        if self.at_least(4, 1):  # assets ("Motive 3.1/NatNet 4.1 and greater"): one
            asset = struct.pack("<ii", 40, 1) + struct.pack("<i3f4ffh", 41, *(0.0,) * 6, 1, 0, 1)
            asset += struct.pack("<i", 1) + struct.pack("<i3ffhf", 42, 0, 0, 0, 0.01, 0, 0)
            self.count(1, asset)
        if self.at_least(2, 3):
            labeled = bytearray()
            for ident, xyz in scene.labeled:
                labeled += struct.pack("<i3ff", ident, *xyz, 0.015)
                if self.at_least(2, 6):
                    labeled += struct.pack("<h", 0x02)  # point-cloud solved
                if self.major >= 3:
                    labeled += struct.pack("<f", 0.0004)  # residual
            self.count(len(scene.labeled), bytes(labeled))
        if self.at_least(2, 9):  # force plates: one, 1 channel of 2 samples
            self.count(1, struct.pack("<iii2f", 5, 1, 2, 10.0, 11.0))
        if self.at_least(2, 11):  # devices: one, 2 channels of 1 sample
            self.count(1, struct.pack("<iii1fi1f", 6, 2, 1, 0.5, 1, 0.25))
        if self.major < 3:
            self.put("f", 0.002)  # software latency (removed in 3.0)
        self.put("II", 0, 0)  # timecode, subframe
        if self.at_least(2, 7):
            self.put("d", number / 120)
        else:
            self.put("f", number / 120)
        if self.major >= 3:
            self.put("3Q", 11, 12, 13)  # camera mid-exposure, data received, transmit
        if self.major >= 4:
            self.put("II", 1, 2)  # precision timestamp, seconds and fraction
        self.put("h", 0)  # frame parameters
        return struct.pack("<HH", 7, len(self.out)) + bytes(self.out)


def server_information(major: int, minor: int) -> bytes:
    """``sSender_Server`` (PacketClient.cpp): the name (256 bytes), the application version,
    the NatNet version, the clock frequency, data port, multicast flag and group."""
    body = b"Motive".ljust(256, b"\0") + bytes((3, 1, 0, 0)) + bytes((major, minor, 0, 0))
    body += struct.pack("<QH?", 10_000_000, DATA_PORT, True) + socket.inet_aton(MOTIVE_GROUP)
    return struct.pack("<HH", 1, len(body)) + body


class Scene:
    """What one frame holds; poses depend on the frame number so motion is visible."""

    def __init__(self, number: int) -> None:
        turn = math.radians(number % 360)
        self.bodies = [
            (3, (0.5, 1.2, -0.3, 0.0, math.sin(turn / 2), 0.0, math.cos(turn / 2))),
            (7, (-1.0, 0.0, 2.25, math.sin(0.3), 0.0, 0.0, math.cos(0.3))),
            (12, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)),  # at the origin: still a body
        ]
        self.skeleton_id = 4
        self.bones = [((4 << 16) | b, (0.1 * b, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)) for b in (1, 2)]
        self.marker_sets = [
            ("Wand", [(0.25, 1.5, 0.75), (0.3, 1.55, 0.7), (0.2, 1.45, 0.8)]),
            ("all", [(0.25, 1.5, 0.75)]),
        ]
        self.other = [(2.0, 0.1, 0.2)]
        self.labeled = [((3 << 16) | 1, (0.5, 1.25, -0.25)), (77, (9.0, 8.0, 7.0))]


def expected_matrix(pose: tuple[float, ...]) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = quaternion_matrix(*pose[3:])
    m[:3, 3] = pose[:3]
    return m


EVERY_LAYOUT = sorted({(1, 0), (2, 1), (2, 3), (2, 6), (2, 9), (2, 11), *VERSIONS})


@pytest.mark.parametrize("version", EVERY_LAYOUT, ids=[f"{a}.{b}" for a, b in EVERY_LAYOUT])
def test_sdk_layout_frames_decode_to_the_right_ids_and_poses(version) -> None:
    scene = Scene(30)
    frame = decode_frame(SdkPacker(*version).frame(30, scene), version)
    assert frame.number == 30 and frame.bad_records == 0
    assert sorted(frame.bodies) == [3, 7, 12]
    for ident, pose in scene.bodies:
        np.testing.assert_allclose(frame.bodies[ident], pose, atol=1e-6)
    assert [name for name, _ in frame.marker_sets] == ["Wand", "all"]
    np.testing.assert_allclose(frame.marker_sets[0][1], scene.marker_sets[0][1], atol=1e-6)
    np.testing.assert_allclose(frame.markers, scene.other, atol=1e-6)
    if version >= (2, 1):  # skeletons exist from NatNet 2.1
        assert list(frame.skeletons) == [4]
        assert sorted(frame.skeletons[4]) == [(4 << 16) | 1, (4 << 16) | 2]
        np.testing.assert_allclose(frame.skeletons[4][(4 << 16) | 2], scene.bones[1][1], atol=1e-6)
    else:
        assert frame.skeletons == {}
    if version >= (2, 3):
        assert sorted(frame.labeled_markers) == [77, (3 << 16) | 1]
        np.testing.assert_allclose(frame.labeled_markers[77], (9.0, 8.0, 7.0), atol=1e-6)
    if (2, 0) <= version < (3, 0):  # rigid-body marker lists with their ids
        np.testing.assert_allclose(frame.body_markers[301], (1.5, 1.2, -0.3), atol=1e-6)


@pytest.mark.parametrize("version", VERSIONS, ids=[f"{a}.{b}" for a, b in VERSIONS])
def test_a_frame_read_as_another_version_is_bad_or_the_same(version) -> None:
    """Never garbage: read with the wrong layout, a frame is refused, or (where the layouts
    agree up to the end of what the driver uses) decodes to the same bodies."""
    scene = Scene(5)
    packet = SdkPacker(*version).frame(5, scene)
    for other in [(1, 0), *VERSIONS, (2, 6), (2, 9), (2, 11)]:
        if other == version:
            continue
        try:
            frame = decode_frame(packet, other)
        except NatNetFormatError:
            continue
        assert frame.bodies.keys() == {3, 7, 12}, (version, other)
        for ident, pose in scene.bodies:
            np.testing.assert_allclose(frame.bodies[ident], pose, atol=1e-6)


# -- over multicast at Motive's defaults ----------------------------------------------------------


class StandIn:
    """A stand-in Motive on loopback: answers connect requests on 127.0.0.1:1510 with
    ``info`` and multicasts ``frame(n)`` to 239.255.42.99:1511 through 127.0.0.1 (TTL 0) every
    ``interval`` seconds, for n = 1, 2, ... while ``frame`` returns bytes."""

    def __init__(self, info: bytes, frame: Callable[[int], bytes | None], interval: float):
        self.info, self.frame, self.interval = info, frame, interval
        self.connects = 0
        self.sent = 0
        self.stop = threading.Event()
        self.command = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.command.bind(("127.0.0.1", COMMAND_PORT))
        self.command.settimeout(0.05)
        self.data = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.data.setsockopt(
            socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1")
        )
        self.data.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
        self.data.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        self.data.bind(("127.0.0.1", 0))
        self.threads = [
            threading.Thread(target=self._answer, daemon=True),
            threading.Thread(target=self._send, daemon=True),
        ]

    def __enter__(self) -> StandIn:
        for thread in self.threads:
            thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        for thread in self.threads:
            thread.join(5)
        self.command.close()
        self.data.close()

    def _answer(self) -> None:
        while not self.stop.is_set():
            try:
                request, peer = self.command.recvfrom(2048)
            except TimeoutError:
                continue
            if request[:2] == b"\x00\x00":  # NAT_CONNECT
                self.connects += 1
                self.command.sendto(self.info, peer)

    def _send(self) -> None:
        n = 0
        while not self.stop.wait(self.interval):
            n += 1
            packet = self.frame(n)
            if packet is None:
                return
            self.data.sendto(packet, (MOTIVE_GROUP, DATA_PORT))
            self.sent += 1


build = managers_fixture("Optitrack_drv", name="build", ready=True)  # no tuning at all


def settled_counters(device, timeout: float = 10.0) -> dict[str, int]:
    """The device's counters once its receiver has taken every datagram sent (three equal
    reads in a row): counters read while it works may be caught between two of them."""
    deadline = time.monotonic() + timeout
    seen = [device.counters]
    while len(seen) < 3 or any(c != seen[-1] for c in seen[-3:]):
        assert time.monotonic() < deadline, "the receiver's counters never settled"
        time.sleep(0.05)  # the pace of the reads; the condition is the three equal reads
        seen.append(device.counters)
    return seen[-1]


@pytest.mark.parametrize("version", VERSIONS, ids=[f"{a}.{b}" for a, b in VERSIONS])
def test_sdk_frames_over_multicast_at_motive_defaults_with_no_option_given(build, version):
    bone = (4 << 16) | 2
    units = ["B3", "B7", "B12", "Bone", "M1000", "M1002", "L77"]
    body = optitrack_element("OT", [3, 7, 12, bone], [1000, 1002, 77])  # no property
    for unit, name in enumerate(units):
        body += proxy("position", name, "OT", unit)
    with fixed_addresses():
        manager = build(body)
        device = manager.device("OT")
        last = {}

        def frame(n: int) -> bytes:
            last["n"] = n
            return SdkPacker(*version).frame(n, Scene(n))

        with StandIn(server_information(*version), frame, 0.005) as motive:
            frames_until(manager, lambda: device.store.total(DeviceKind.POSITION) >= 20)
            number = last["n"]
        counters = settled_counters(device)
        assert motive.connects >= 1 and counters["server_infos"] >= 1
        # bad only if frames overflowed the hold while waiting for the reply (a slow machine)
        assert counters["bad_datagrams"] == counters["undecoded_frames"]
        assert counters["frames"] >= 20
    # the proxies hold the pose of the newest frame read (a recent one: motion is visible)
    read = manager.proxy("B3").matrix
    candidates = [Scene(n).bodies[0][1] for n in range(1, number + 1)]
    assert any(np.allclose(read, expected_matrix(p), atol=1e-5) for p in candidates)
    scene = Scene(1)
    np.testing.assert_allclose(
        manager.proxy("B7").matrix, expected_matrix(scene.bodies[1][1]), atol=1e-5
    )
    np.testing.assert_allclose(manager.proxy("B12").matrix, np.eye(4), atol=1e-6)
    assert manager.proxy("B12").timestamp is not None  # at the origin, but tracked
    bone_pose = expected_matrix(scene.bones[1][1]) if version >= (2, 1) else np.eye(4)
    np.testing.assert_allclose(manager.proxy("Bone").matrix, bone_pose, atol=1e-5)
    # marker_index 1000 + k: marker k of marker set 0 (Gadgeteer's reading)
    np.testing.assert_allclose(manager.proxy("M1000").translation, (0.25, 1.5, 0.75), atol=1e-6)
    np.testing.assert_allclose(manager.proxy("M1002").translation, (0.2, 1.45, 0.8), atol=1e-6)
    if version >= (2, 3):  # below 1000: a labeled marker's id
        np.testing.assert_allclose(manager.proxy("L77").translation, (9.0, 8.0, 7.0), atol=1e-6)
    else:
        np.testing.assert_allclose(manager.proxy("L77").matrix, np.eye(4))


def test_real_motive_frames_over_multicast_at_motive_defaults(build) -> None:
    datagrams = capture_datagrams()
    frames = [d[4] for d in datagrams if d[4][:2] == b"\x07\x00"]
    info = next(d[4] for d in datagrams if d[4][:2] == b"\x01\x00")
    body = optitrack_element("OT", [2], []) + proxy("position", "Body", "OT", 0)
    with fixed_addresses():
        manager = build(body)
        device = manager.device("OT")
        with StandIn(info, lambda n: frames[n - 1] if n <= len(frames) else None, 1 / 240):
            frames_until(
                manager,
                lambda: (
                    device.counters["frames"]
                    + device.counters["undecoded_frames"]
                    + device.counters["kernel_dropped"]
                    >= len(frames)
                ),
                timeout=30,
            )
        counters = settled_counters(device)
    assert counters["bad_datagrams"] == counters["undecoded_frames"] and counters["frames"] > 0
    assert counters["frames"] + counters["undecoded_frames"] + counters["kernel_dropped"] == 518
    # every decoded frame is a sample; once all are in the store, a frame makes the newest
    # one current
    frames_until(manager, lambda: device.store.total(DeviceKind.POSITION) >= counters["frames"])
    manager.update()
    poses = [decode_frame(f, (3, 0)).bodies[2] for f in frames]
    read = manager.proxy("Body").matrix
    if counters["kernel_dropped"] == 0:  # the last frame arrived: it is the pose shown
        np.testing.assert_allclose(read, expected_matrix(poses[-1]), atol=1e-5)
    else:
        assert any(np.allclose(read, expected_matrix(p), atol=1e-5) for p in poses)
