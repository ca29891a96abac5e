"""The NatNet protocol of NaturalPoint's OptiTrack servers (Tracking Tools, Arena, Motive): the
frame-of-data packet, decoded with bounds, and a UDP receiver. Knows nothing of gadgetctl's
input manager.

A frame-of-data packet (little-endian, the NatNet 1.x/2.0 layout Gadgeteer reads):

* u16 message id (7 = frame of data), u16 payload bytes;
* i32 frame number, i32 marker-set count; per set a NUL-terminated name, i32 marker count and
  that many x, y, z float32 (the sets are skipped);
* i32 count of unidentified ("other") markers and their x, y, z float32;
* i32 rigid-body count; per body i32 id, float32 x, y, z, qx, qy, qz, qw, i32 marker count,
  that many x, y, z, then that many i32 marker ids, that many float32 sizes, float32 mean
  error. Newer servers append more (skeletons, latency, timecode), which is ignored.

Positions are metres. Counts beyond NatNet's own limits (:class:`NatNetLimits`, the SDK's
``MAX_*`` constants) make the packet a bad datagram: counted, skipped, never a resize. A body
with a non-finite number or an all-zero quaternion is a bad record: counted and skipped.

Upstream fixes (Gadgeteer's ``OptiTrackStandalone``): a body is kept when some of its
components are zero (upstream dropped any body with a zero in x, y, z or the quaternion, so a
body on an axis or at the origin vanished); unidentified markers are decoded and reported
(upstream skipped them and never stored a marker).
"""

from __future__ import annotations

import math
import select
import socket
import struct
import time
from dataclasses import dataclass, field

import numpy as np

from gadgetctl.transport.udp import DropCountingReceiver

NAT_FRAMEOFDATA = 7
#: The other NatNet message ids (ping, ping response, requests, replies, message string,
#: unrecognised request): such packets are counted, not decoded.
OTHER_MESSAGES = frozenset({0, 1, 2, 3, 4, 5, 6, 8, 100})
DEFAULT_PORT = 1001
DEFAULT_GROUP = "224.0.0.1"
#: Unidentified markers are numbered from here, in the order of the packet (marker_index 1000
#: is the first); smaller marker_index values name rigid-body markers by their NatNet id.
FIRST_MARKER_ID = 1000
MAX_DATAGRAM = 65_535

_HEADER = struct.Struct("<HH")
_I32 = struct.Struct("<i")
_BODY = struct.Struct("<i7fi")


@dataclass(frozen=True)
class NatNetLimits:
    """Most of each thing a packet may hold (NatNet SDK limits)."""

    marker_sets: int = 1000
    markers: int = 200  # markers of a set, or unidentified markers
    rigid_bodies: int = 1000
    body_markers: int = 20
    name_length: int = 256


DEFAULT_LIMITS = NatNetLimits()


class NatNetFormatError(ValueError):
    """A packet that is not a well-formed NatNet frame within the limits."""


class NatNetDisconnected(ConnectionError):
    """No NatNet frame arrived for longer than the receiver's peer timeout."""


@dataclass
class NatNetFrame:
    """One decoded frame: ``bodies`` id -> (x, y, z, qx, qy, qz, qw); ``markers`` the
    unidentified markers (n, 3); ``body_markers`` NatNet marker id -> (x, y, z)."""

    number: int
    bodies: dict[int, tuple[float, ...]]
    markers: np.ndarray
    body_markers: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    bad_records: int = 0


class _Reader:
    __slots__ = ("data", "offset")

    def __init__(self, data: bytes, offset: int) -> None:
        self.data = data
        self.offset = offset

    def take(self, size: int) -> int:
        start = self.offset
        if start + size > len(self.data):
            raise NatNetFormatError(f"packet ends inside a field at byte {start}")
        self.offset = start + size
        return start

    def count(self, limit: int, what: str) -> int:
        (value,) = _I32.unpack_from(self.data, self.take(4))
        if not 0 <= value <= limit:
            raise NatNetFormatError(f"{what} count {value} is outside 0..{limit}")
        return value

    def floats(self, n: int) -> np.ndarray:
        start = self.take(4 * n)
        return np.frombuffer(self.data, dtype="<f4", count=n, offset=start)


def message_id(data: bytes) -> int | None:
    """The message id of a packet, or None when it is too short to have one."""
    return _HEADER.unpack_from(data)[0] if len(data) >= 4 else None


def decode_frame(data: bytes, limits: NatNetLimits = DEFAULT_LIMITS) -> NatNetFrame:
    """Decode a frame-of-data packet; raises :class:`NatNetFormatError` on anything else."""
    if len(data) < 4:
        raise NatNetFormatError("packet shorter than its header")
    ident, size = _HEADER.unpack_from(data)
    if ident != NAT_FRAMEOFDATA:
        raise NatNetFormatError(f"message id {ident} is not a frame of data")
    if size > len(data) - 4:
        raise NatNetFormatError(f"payload of {size} bytes announced, {len(data) - 4} received")
    reader = _Reader(data[: 4 + size], 4)
    (number,) = _I32.unpack_from(reader.data, reader.take(4))
    for _ in range(reader.count(limits.marker_sets, "marker set")):
        end = reader.data.find(b"\0", reader.offset, reader.offset + limits.name_length)
        if end < 0:
            raise NatNetFormatError("marker set name without its end")
        reader.offset = end + 1
        reader.take(12 * reader.count(limits.markers, "marker"))
    n_markers = reader.count(limits.markers, "unidentified marker")
    markers = reader.floats(3 * n_markers).astype(np.float64).reshape(n_markers, 3)
    bad = 0
    finite = np.isfinite(markers).all(axis=1)
    if not finite.all():
        bad += int((~finite).sum())
        markers = markers.copy()
        markers[~finite] = np.nan  # left out when stored
    bodies: dict[int, tuple[float, ...]] = {}
    body_markers: dict[int, tuple[float, float, float]] = {}
    for _ in range(reader.count(limits.rigid_bodies, "rigid body")):
        ident_, *pose, count = _BODY.unpack_from(reader.data, reader.take(_BODY.size))
        if not 0 <= count <= limits.body_markers:
            raise NatNetFormatError(
                f"rigid body marker count {count} is outside 0..{limits.body_markers}"
            )
        positions = reader.floats(3 * count)
        ids = np.frombuffer(reader.data, dtype="<i4", count=count, offset=reader.take(4 * count))
        reader.take(4 * count + 4)  # marker sizes, mean error
        # Upstream fix: zeros are valid coordinates; only a pose that cannot be one is bad.
        if not all(map(math.isfinite, pose)) or not any(pose[3:]):
            bad += 1
            continue
        bodies[ident_] = tuple(pose)
        for k in range(count):
            xyz = positions[3 * k : 3 * k + 3]
            if np.isfinite(xyz).all():
                body_markers[int(ids[k])] = (float(xyz[0]), float(xyz[1]), float(xyz[2]))
    return NatNetFrame(number, bodies, markers, body_markers, bad)


def quaternion_matrix(qx: float, qy: float, qz: float, qw: float) -> np.ndarray:
    """The 3x3 rotation of a (normalised) quaternion, NatNet's x, y, z, w order."""
    norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    x, y, z, w = qx / norm, qy / norm, qz / norm, qw / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


class NatNetUnits:
    """The position units of an ``optitrack`` device: its rigid bodies (by NatNet id), then
    its markers (by marker id), in configuration order. Each unit keeps its last pose while
    its body or marker is missing from frames (identity until first seen)."""

    def __init__(self, body_ids: list[int], marker_ids: list[int]) -> None:
        self.body_ids = list(body_ids)
        self.marker_ids = list(marker_ids)
        self.matrices = np.tile(np.eye(4), (len(body_ids) + len(marker_ids), 1, 1))
        self._body_unit = {}
        for unit, ident in enumerate(self.body_ids):
            self._body_unit.setdefault(ident, []).append(unit)
        first = len(self.body_ids)
        self._marker_unit = {}
        for k, ident in enumerate(self.marker_ids):
            self._marker_unit.setdefault(ident, []).append(first + k)

    def update(self, frame: NatNetFrame) -> np.ndarray:
        """Apply ``frame``; returns the matrices of every unit (a view: copy to keep)."""
        for ident, units in self._body_unit.items():
            pose = frame.bodies.get(ident)
            if pose is None:
                continue
            rotation = quaternion_matrix(*pose[3:])
            for unit in units:
                self.matrices[unit, :3, :3] = rotation
                self.matrices[unit, :3, 3] = pose[:3]
        markers = frame.markers
        for ident, units in self._marker_unit.items():
            if ident >= FIRST_MARKER_ID:
                index = ident - FIRST_MARKER_ID
                if index >= len(markers) or not np.isfinite(markers[index]).all():
                    continue
                xyz = markers[index]
            else:
                found = frame.body_markers.get(ident)
                if found is None:
                    continue
                xyz = found
            for unit in units:
                self.matrices[unit, :3, 3] = xyz
        return self.matrices


class NatNetReceiver:
    """Receives NatNet frames on UDP ``port`` (0: chosen by the OS), joining multicast
    ``group`` on ``interface`` when a group is given (a failed join is counted in
    ``join_failures``; unicast still arrives). Counters: ``datagrams``, ``frames``,
    ``bad_datagrams`` (malformed or beyond the limits), ``bad_records``, ``other_messages``
    (NatNet messages that are not frames), ``missed_frames`` (gaps in the frame number),
    ``kernel_dropped``."""

    def __init__(
        self,
        port: int = DEFAULT_PORT,
        *,
        group: str | None = DEFAULT_GROUP,
        interface: str = "0.0.0.0",
        receive_timeout: float = 0.1,
        peer_timeout: float = 2.0,
        receive_buffer: int = 4 * 1024 * 1024,
        limits: NatNetLimits = DEFAULT_LIMITS,
    ) -> None:
        self.requested_port = port
        self.group = group
        self.interface = interface
        self.receive_timeout = receive_timeout
        self.peer_timeout = peer_timeout
        self.receive_buffer = receive_buffer
        self.limits = limits
        self.datagrams = 0
        self.frames = 0
        self.bad_datagrams = 0
        self.bad_records = 0
        self.other_messages = 0
        self.missed_frames = 0
        self.join_failures = 0
        self.joined = False
        self._drops = DropCountingReceiver()
        self._sock: socket.socket | None = None
        self._last_number: int | None = None
        self._last_data = time.monotonic()

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    @property
    def port(self) -> int:
        if self._sock is None:
            return self.requested_port
        return self._sock.getsockname()[1]

    @property
    def kernel_dropped(self) -> int:
        self._drops.refresh()
        return self._drops.dropped

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, self.receive_buffer)
            sock.bind(("", self.requested_port))
        except OSError:
            sock.close()
            raise
        self.joined = False
        if self.group:
            request = socket.inet_aton(self.group) + socket.inet_aton(self.interface)
            try:
                sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, request)
                self.joined = True
            except OSError:
                self.join_failures += 1
        sock.setblocking(False)
        self._sock = sock
        self._drops.attach(sock)
        self._last_data = time.monotonic()

    def close(self) -> None:
        if self._sock is not None:
            self._drops.detach()
            self._sock.close()
            self._sock = None

    def sample_all(self, limit: int = 100) -> list[NatNetFrame]:
        """The frames that arrive within ``receive_timeout`` (at most ``limit``); raises
        :class:`NatNetDisconnected` after ``peer_timeout`` seconds without a datagram."""
        sock = self._sock
        if sock is None:
            raise NatNetDisconnected("the receiver is closed")
        frames: list[NatNetFrame] = []
        ready, _, _ = select.select([sock], [], [], self.receive_timeout)
        while ready and len(frames) < limit:
            try:
                data = self._drops.receive(MAX_DATAGRAM)
            except BlockingIOError:
                break
            self._last_data = time.monotonic()
            self.datagrams += 1
            frame = self.decode(data)
            if frame is not None:
                frames.append(frame)
        if not frames and time.monotonic() - self._last_data > self.peer_timeout:
            raise NatNetDisconnected(
                f"no NatNet data on UDP port {self.port} for {self.peer_timeout:g} s"
            )
        return frames

    def decode(self, data: bytes) -> NatNetFrame | None:
        """Decode one datagram and count it; None unless it is a good frame."""
        ident = message_id(data)
        if ident in OTHER_MESSAGES and _HEADER.unpack_from(data)[1] == len(data) - 4:
            self.other_messages += 1
            return None
        try:
            frame = decode_frame(data, self.limits)
        except NatNetFormatError:
            self.bad_datagrams += 1
            return None
        self.frames += 1
        self.bad_records += frame.bad_records
        if self._last_number is not None and frame.number > self._last_number + 1:
            self.missed_frames += frame.number - self._last_number - 1
        self._last_number = frame.number
        return frame
