"""The NatNet packets of NaturalPoint's OptiTrack servers (Tracking Tools, Arena, Motive): the
frame of data (message 7) of every NatNet version from 1.x to 4.1, the server information
(message 1, the reply to a connect request) and the requests a client sends (connect, keep-
alive). Pure functions on bytes, bounded by :class:`NatNetLimits`; no sockets here.

Layouts as the NatNet SDK's sample clients read them (``PacketClient.cpp`` of SDK 2.x/3.x and
``NatNetClient.py`` of the 4.1 SDK's PythonClient). All little-endian. A frame of data is

* u16 message id (7), u16 payload bytes, i32 frame number;
* marker sets: i32 count, then per set a NUL-terminated name, i32 marker count, x y z float32
  each;
* unidentified ("other") markers: i32 count, x y z float32 each;
* rigid bodies: i32 count, then per body i32 id, x y z, qx qy qz qw (float32); before 3.0 an
  i32 marker count and that many x y z, from 2.0 that many i32 marker ids and float32 sizes;
  from 2.0 a float32 mean error; from 2.6 an i16 parameter field (bit 0: tracked);
* skeletons (from 2.1): i32 count, per skeleton i32 id and a rigid-body list as above (bones);
* assets (from 4.1): i32 count, per asset i32 id, i32 body count, bodies of i32 id, x y z,
  qx qy qz qw, float32 error, i16 params; i32 marker count, markers of i32 id, x y z, float32
  size, i16 params, float32 residual;
* labeled markers (from 2.3): i32 count, per marker i32 id, x y z, float32 size, from 2.6 an
  i16 parameter field, from 3.0 a float32 residual;
* force plates (from 2.9) and devices (from 2.11): i32 count, per item i32 id, i32 channel
  count, per channel i32 sample count and that many float32;
* the suffix: before 3.0 a float32 latency; u32 timecode and sub-frame; the timestamp (float32,
  float64 from 2.7); from 3.0 three u64 clock stamps; from 4.x a u32 pair (precision time);
  i16 frame parameters.

From 4.1 every count of a section (marker sets, other markers, rigid bodies, skeletons, assets,
labeled markers, force plates, devices) is followed by an i32 byte count of the section.

Positions are metres. A count beyond :class:`NatNetLimits`, a section that does not fit the
packet, or (from 2.7, where the suffix is known) a frame whose end does not match the version
makes the whole packet bad: :class:`NatNetFormatError`, never a partial frame.
"""

from __future__ import annotations

import math
import re
import struct
from dataclasses import dataclass, field

import numpy as np

NAT_CONNECT = 0
NAT_SERVERINFO = 1
NAT_REQUEST = 2
NAT_RESPONSE = 3
NAT_REQUEST_MODELDEF = 4
NAT_MODELDEF = 5
NAT_REQUEST_FRAMEOFDATA = 6
NAT_FRAMEOFDATA = 7
NAT_MESSAGESTRING = 8
NAT_DISCONNECT = 9
NAT_KEEPALIVE = 10
NAT_UNRECOGNIZED_REQUEST = 100
#: NatNet 3 additions: disconnect by timeout, echo request and response (clock sync), discovery.
NAT_NEWER = (11, 12, 13, 14)
#: NatNet messages a client may see that are not frames: counted, not decoded.
OTHER_MESSAGES = frozenset(
    {
        NAT_CONNECT,
        NAT_REQUEST,
        NAT_RESPONSE,
        NAT_REQUEST_MODELDEF,
        NAT_MODELDEF,
        NAT_REQUEST_FRAMEOFDATA,
        NAT_MESSAGESTRING,
        NAT_DISCONNECT,
        NAT_KEEPALIVE,
        NAT_UNRECOGNIZED_REQUEST,
        *NAT_NEWER,
    }
)

Version = tuple[int, int]
#: The oldest and newest layouts read. 4.x after 4.1 is read with the 4.1 layout.
OLDEST_VERSION: Version = (1, 0)
NEWEST_VERSION: Version = (4, 1)
#: Bytes a suffix may carry beyond the documented fields (an end-of-data tag, the 4.x
#: precision time) before the frame is taken to be of another version.
SUFFIX_SLACK = 16

_HEADER = struct.Struct("<HH")
_I32 = struct.Struct("<i")
_POSE = struct.Struct("<i7f")
_F32 = struct.Struct("<f")
_I16 = struct.Struct("<h")
_ASSET_BODY = struct.Struct("<i7ffh")
_ASSET_MARKER = struct.Struct("<i3ffhf")


def _float64(values: np.ndarray) -> np.ndarray:
    """float32 coordinates as float64; a signalling NaN from the wire becomes a quiet one
    (counted as a bad record by the caller), not a RuntimeWarning on stderr."""
    with np.errstate(invalid="ignore"):
        return values.astype(np.float64)


@dataclass(frozen=True)
class NatNetLimits:
    """Most of each thing one packet may hold. A count beyond one makes the packet bad (a
    NatNet datagram is at most 65,535 bytes, so every count is bounded by its bytes too)."""

    marker_sets: int = 1000
    markers: int = 1000  # markers of a set, unidentified markers (the SDK's cap since 2.6)
    rigid_bodies: int = 1000
    body_markers: int = 20  # markers of one rigid body (the SDK's cap since 2.7)
    skeletons: int = 100
    bones: int = 200  # rigid bodies of one skeleton or asset
    assets: int = 100
    labeled_markers: int = 5000
    force_plates: int = 64  # force plates, or devices
    channels: int = 64
    channel_samples: int = 1000
    name_length: int = 256


DEFAULT_LIMITS = NatNetLimits()


class NatNetFormatError(ValueError):
    """A packet that is not a well-formed NatNet message within the limits."""


def parse_version(text: str) -> Version:
    """``"3.0"``, ``"2.10"`` or ``"4.1.0.0"`` as (major, minor); raises ValueError."""
    match = re.fullmatch(r"\s*(\d{1,3})\.(\d{1,3})(?:\.\d{1,3}){0,2}\s*", text)
    if not match:
        raise ValueError(f"{text.strip()!r} is not a NatNet version such as 3.0 or 4.1")
    version = (int(match[1]), int(match[2]))
    if not version >= OLDEST_VERSION or version[0] > NEWEST_VERSION[0]:
        raise ValueError(
            f"NatNet {version[0]}.{version[1]} is not read (1.0 to 4.1; later 4.x as 4.1)"
        )
    return version


def version_text(version: Version) -> str:
    return f"{version[0]}.{version[1]}"


@dataclass
class NatNetFrame:
    """One decoded frame. ``bodies``: tracked rigid bodies, id -> (x, y, z, qx, qy, qz, qw);
    ``markers``: the unidentified ("other") markers (n, 3); ``marker_sets``: (name, (n, 3))
    in packet order; ``labeled_markers`` (2.3+) and ``body_markers`` (before 3.0): NatNet
    marker id -> (x, y, z); ``skeletons``: skeleton id -> {bone id -> pose}; ``untracked``:
    bodies the server flagged as not tracked in this frame (2.6+), left out of ``bodies``."""

    number: int
    bodies: dict[int, tuple[float, ...]]
    markers: np.ndarray
    body_markers: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    bad_records: int = 0
    marker_sets: list[tuple[str, np.ndarray]] = field(default_factory=list)
    labeled_markers: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    skeletons: dict[int, dict[int, tuple[float, ...]]] = field(default_factory=dict)
    untracked: int = 0
    version: Version = NEWEST_VERSION


@dataclass(frozen=True)
class ServerInfo:
    """What a server says of itself (message 1): its application, that application's
    version, the NatNet version it streams and (NatNet 3+) its data port and multicast."""

    application: str
    application_version: tuple[int, int, int, int]
    natnet_version: tuple[int, int, int, int]
    data_port: int | None = None
    multicast: bool | None = None
    multicast_group: str | None = None

    @property
    def version(self) -> Version:
        return (self.natnet_version[0], self.natnet_version[1])


class _Reader:
    __slots__ = ("byte_counts", "data", "end", "offset")

    def __init__(self, data: bytes, offset: int, end: int, byte_counts: bool) -> None:
        self.data = data
        self.offset = offset
        self.end = end
        self.byte_counts = byte_counts

    def take(self, size: int) -> int:
        start = self.offset
        if size < 0 or start + size > self.end:
            raise NatNetFormatError(f"packet ends inside a field at byte {start}")
        self.offset = start + size
        return start

    def i32(self) -> int:
        return _I32.unpack_from(self.data, self.take(4))[0]

    def count(self, limit: int, what: str, *, section: bool = False) -> int:
        value = self.i32()
        if not 0 <= value <= limit:
            raise NatNetFormatError(f"{what} count {value} is outside 0..{limit}")
        if section and self.byte_counts:
            size = self.i32()
            if not 0 <= size <= self.end - self.offset:
                raise NatNetFormatError(
                    f"{what} section of {size} bytes announced, "
                    f"{self.end - self.offset} left in the packet"
                )
        return value

    def name(self, limit: int) -> str:
        end = self.data.find(b"\0", self.offset, min(self.end, self.offset + limit))
        if end < 0:
            raise NatNetFormatError(f"name without its end at byte {self.offset}")
        text = self.data[self.offset : end].decode("utf-8", "replace")
        self.offset = end + 1
        return text

    def points(self, n: int) -> np.ndarray:
        start = self.take(12 * n)
        return np.frombuffer(self.data, dtype="<f4", count=3 * n, offset=start).reshape(n, 3)


def message_id(data: bytes) -> int | None:
    """The message id of a packet, or None when it is too short to have one."""
    return _HEADER.unpack_from(data)[0] if len(data) >= 4 else None


def _payload_end(data: bytes, expected: int) -> int:
    if len(data) < 4:
        raise NatNetFormatError("packet shorter than its header")
    ident, size = _HEADER.unpack_from(data)
    if ident != expected:
        raise NatNetFormatError(f"message id {ident} where {expected} was expected")
    if size > len(data) - 4:
        raise NatNetFormatError(f"payload of {size} bytes announced, {len(data) - 4} received")
    return 4 + size


def _at_least(version: Version, major: int, minor: int) -> bool:
    return version >= (major, minor)


def _pose_is_usable(pose: tuple[float, ...]) -> bool:
    return all(map(math.isfinite, pose)) and any(pose[3:])


class _FrameDecoder:
    """One frame's decoding for one version."""

    def __init__(self, version: Version, limits: NatNetLimits) -> None:
        self.version = version
        self.limits = limits
        self.markers_in_bodies = version < (3, 0)
        self.marker_ids = version >= (2, 0)
        self.mean_error = version >= (2, 0)
        self.params = version >= (2, 6)

    def body(self, reader: _Reader, frame: NatNetFrame, into: dict[int, tuple[float, ...]]):
        ident, *pose = _POSE.unpack_from(reader.data, reader.take(_POSE.size))
        positions = ids = None
        if self.markers_in_bodies:
            n = reader.count(self.limits.body_markers, "rigid body marker")
            positions = reader.points(n)
            if self.marker_ids:
                start = reader.take(4 * n)
                ids = np.frombuffer(reader.data, dtype="<i4", count=n, offset=start)
                reader.take(4 * n)  # marker sizes
        if self.mean_error:
            reader.take(4)
        tracked = True
        if self.params:
            (params,) = _I16.unpack_from(reader.data, reader.take(2))
            tracked = bool(params & 0x01)
        if not tracked:
            frame.untracked += 1
            return
        if not _pose_is_usable(tuple(pose)):
            frame.bad_records += 1
            return
        into[ident] = tuple(pose)
        if positions is not None and ids is not None:
            for k in range(len(ids)):
                xyz = positions[k]
                if np.isfinite(xyz).all():
                    frame.body_markers[int(ids[k])] = (
                        float(xyz[0]),
                        float(xyz[1]),
                        float(xyz[2]),
                    )

    def decode(self, data: bytes) -> NatNetFrame:
        version, limits = self.version, self.limits
        reader = _Reader(data, 4, _payload_end(data, NAT_FRAMEOFDATA), version >= (4, 1))
        number = reader.i32()
        frame = NatNetFrame(number, {}, np.empty((0, 3)), version=version)
        for _ in range(reader.count(limits.marker_sets, "marker set", section=True)):
            name = reader.name(limits.name_length)
            points = reader.points(reader.count(limits.markers, "marker"))
            frame.marker_sets.append((name, _float64(points)))
        n_other = reader.count(limits.markers, "unidentified marker", section=True)
        markers = _float64(reader.points(n_other))
        finite = np.isfinite(markers).all(axis=1)
        if not finite.all():
            frame.bad_records += int((~finite).sum())
            markers[~finite] = np.nan  # left out when stored
        frame.markers = markers
        for _ in range(reader.count(limits.rigid_bodies, "rigid body", section=True)):
            self.body(reader, frame, frame.bodies)
        if version >= (2, 1):
            for _ in range(reader.count(limits.skeletons, "skeleton", section=True)):
                ident = reader.i32()
                bones: dict[int, tuple[float, ...]] = {}
                for _ in range(reader.count(limits.bones, "skeleton bone")):
                    self.body(reader, frame, bones)
                frame.skeletons[ident] = bones
        if version >= (4, 1):
            for _ in range(reader.count(limits.assets, "asset", section=True)):
                reader.take(4)  # asset id
                reader.take(_ASSET_BODY.size * reader.count(limits.bones, "asset body"))
                reader.take(_ASSET_MARKER.size * reader.count(limits.markers, "asset marker"))
        if version >= (2, 3):
            size = 20 + (2 if version >= (2, 6) else 0) + (4 if version >= (3, 0) else 0)
            n = reader.count(limits.labeled_markers, "labeled marker", section=True)
            records = np.frombuffer(
                data,
                dtype=np.dtype(
                    {
                        "names": ["id", "xyz"],
                        "formats": ["<i4", ("<f4", 3)],
                        "offsets": [0, 4],
                        "itemsize": size,
                    }
                ),
                count=n,
                offset=reader.take(size * n),
            )
            xyz = _float64(records["xyz"])
            finite = np.isfinite(xyz).all(axis=1)
            frame.bad_records += int(n - finite.sum())
            frame.labeled_markers.update(
                zip(records["id"][finite].tolist(), map(tuple, xyz[finite].tolist()), strict=True)
            )
        if version >= (2, 9):
            self.channels(reader, "force plate")
        if version >= (2, 11):
            self.channels(reader, "device")
        self.suffix(reader)
        return frame

    def channels(self, reader: _Reader, what: str) -> None:
        limits = self.limits
        for _ in range(reader.count(limits.force_plates, what, section=True)):
            reader.take(4)  # id
            for _ in range(reader.count(limits.channels, f"{what} channel")):
                reader.take(4 * reader.count(limits.channel_samples, f"{what} sample"))

    def suffix(self, reader: _Reader) -> None:
        """From 2.7 the suffix is known: it must be there, and little may follow it."""
        version = self.version
        if version < (2, 7):
            return
        need = 4 + 8 + 8 + 2 if version < (3, 0) else 8 + 8 + 24 + 2
        left = reader.end - reader.offset
        if left < need:
            raise NatNetFormatError(
                f"frame ends {need - left} bytes short of its NatNet {version_text(version)} "
                "suffix (is the NatNet version right?)"
            )
        if left > need + SUFFIX_SLACK:
            raise NatNetFormatError(
                f"{left - need} bytes after the end of a NatNet {version_text(version)} frame "
                "(is the NatNet version right?)"
            )


def decode_frame(
    data: bytes, version: Version = (2, 5), limits: NatNetLimits = DEFAULT_LIMITS
) -> NatNetFrame:
    """Decode a frame-of-data packet of NatNet ``version``; raises
    :class:`NatNetFormatError` on anything else."""
    if version > NEWEST_VERSION:
        version = NEWEST_VERSION
    return _FrameDecoder(version, limits).decode(data)


def decode_server_info(data: bytes) -> ServerInfo:
    """The server information a server sends in reply to a connect request."""
    end = _payload_end(data, NAT_SERVERINFO)
    if end < 4 + 264:
        raise NatNetFormatError(f"server information of {end - 4} bytes (at least 264)")
    name = data[4 : 4 + 256].split(b"\0", 1)[0].decode("utf-8", "replace")
    app = tuple(data[260:264])
    natnet = tuple(data[264:268])
    if natnet[0] == 0 or (natnet[0], natnet[1]) < OLDEST_VERSION:
        raise NatNetFormatError(f"server information names NatNet {natnet[0]}.{natnet[1]}")
    extra = {}
    if end >= 268 + 8 + 2 + 1 + 4:
        (port,) = struct.unpack_from("<H", data, 276)
        extra = {
            "data_port": port,
            "multicast": bool(data[278]),
            "multicast_group": ".".join(str(b) for b in data[279:283]),
        }
    return ServerInfo(name, app, natnet, **extra)  # type: ignore[arg-type]


def connect_request(version: Version | None = None) -> bytes:
    """A connect request (message 0), laid out as the SDK's Python client sends it: a sender
    block named "Ping", then the NatNet stream version asked for. With no ``version`` it asks
    for none (zeros), leaving the stream as the server is set up (the SDK sample always
    asks for 4.1); the reply names the version. A server that cannot change its stream
    ignores the request's version."""
    major, minor = version or (0, 0)
    body = bytearray(270)
    body[0:4] = b"Ping"
    body[265:269] = bytes((major, minor, 0, 0))
    body += b"\0"
    return _HEADER.pack(NAT_CONNECT, len(body)) + bytes(body)


def keep_alive() -> bytes:
    """A keep-alive (message 10), which a unicast client sends to stay subscribed."""
    return _HEADER.pack(NAT_KEEPALIVE, 0) + b"\0"
