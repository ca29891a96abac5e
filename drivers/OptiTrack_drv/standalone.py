"""A NatNet client for NaturalPoint's OptiTrack servers (Tracking Tools, Arena, Motive): the
UDP receiver, its sessions with the server (connect request, server information, keep-alive)
and the position units it fills. The packet layouts are in :mod:`.natnet`. Knows nothing of
gadgetctl's input manager.

Where and how (Motive's defaults): frames are multicast to group 239.255.42.99, data port
1511; the server takes requests on command port 1510. The receiver binds the data port, joins
the group (on every interface unless one is named, so a server on this host, streaming on
loopback, reaches it too) and reads every NatNet message arriving there.

* The NatNet version decides the frame layout. It is the one configured, else the one the
  server names in its server information (message 1), its reply to a connect request
  (message 0) sent to the command port: of the configured server, or else of the host the
  first frame came from. Frames that arrive before the reply are held (at most
  ``receiver_limits.pending_frames``), then decoded; without a reply within
  ``version_timeout`` they are ``undecoded_frames`` and bad datagrams, and the requests go on.
* Unicast: the receiver sends the connect request to the server's command port from its data
  socket (so the frames reach it whether the server answers the requester or the data
  port), repeats it until the server answers, then sends a keep-alive every
  ``keepalive_interval`` seconds.

Every datagram read is counted once in the :class:`DatagramLedger` (``ledger``), as
decoded (a frame, the server information, another NatNet message) or bad with its reason;
the ledger also keeps the kernel's drops and says when the receiver is undecodable (data
arrives, none decodes), with the first error. Counters: ``datagrams``, ``frames``,
``bad_datagrams`` (not NatNet, malformed, beyond the limits, or not of the version),
``bad_records`` (a body or marker whose numbers cannot be a
pose), ``other_messages``, ``server_infos``, ``requests_sent``, ``undecoded_frames``,
``untracked_bodies`` (bodies the server flagged as not tracked), ``missed_frames`` (gaps in
the frame numbers of at most ``MAX_FRAME_GAP``), ``frame_jumps`` (a frame number that goes
back, repeats or leaps further: a restarted server or a hostile one, never counted as
missed), ``join_failures``, ``kernel_dropped``. ``first_error`` keeps the first reason a
datagram was bad.

Upstream fixes (Gadgeteer's ``OptiTrackStandalone``): every NatNet version is read, not only
the 1.x/2.0 layout; a body with zeros among its components is kept (upstream dropped it);
markers are stored (upstream never stored one).
"""

from __future__ import annotations

import collections
import math
import select
import socket
import struct
import time
from dataclasses import dataclass

import numpy as np

from gadgetctl.transport.udp import DatagramLedger, LedgeredReceiver, bind_udp

from .natnet import (
    DEFAULT_LIMITS as FRAME_LIMITS,
)
from .natnet import (
    NAT_FRAMEOFDATA,
    NAT_SERVERINFO,
    OTHER_MESSAGES,
    NatNetFormatError,
    NatNetFrame,
    NatNetLimits,
    ServerInfo,
    Version,
    connect_request,
    decode_frame,
    decode_server_info,
    keep_alive,
    message_id,
    version_text,
)

__all__ = [
    "COMMAND_PORT",
    "DATA_PORT",
    "DEFAULT_LIMITS",
    "MULTICAST_GROUP",
    "NatNetDisconnected",
    "NatNetFormatError",
    "NatNetFrame",
    "NatNetReceiver",
    "NatNetUndecodable",
    "NatNetUnits",
    "ReceiverLimits",
    "decode_frame",
    "quaternion_matrix",
]

#: Motive's defaults.
MULTICAST_GROUP = "239.255.42.99"
DATA_PORT = 1511
COMMAND_PORT = 1510
#: marker_index 1000 is the first marker of marker set 0, 1001 the second... (Gadgeteer's
#: MARKER_INDEX_OFFSET); smaller values are NatNet marker ids (labeled markers, and before
#: NatNet 3.0 the markers of rigid bodies).
FIRST_MARKER_ID = 1000
#: The largest forward step of the frame number counted as missed frames (about 28 s at
#: Motive's 360 Hz); a larger step, a step back or a repeat is a ``frame_jumps`` event.
MAX_FRAME_GAP = 10_000
MAX_DATAGRAM = 65_535

DEFAULT_LIMITS = FRAME_LIMITS


@dataclass(frozen=True)
class ReceiverLimits:
    """What the receiver holds at most: frames waiting for the server's NatNet version."""

    pending_frames: int = 256


class NatNetDisconnected(ConnectionError):
    """No NatNet datagram arrived for longer than the receiver's peer timeout."""


class NatNetUndecodable(ConnectionError):
    """NatNet datagrams arrive but none decodes (the first error says why)."""


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
    """The position units of an ``optitrack`` device: its rigid bodies (by NatNet id; an id
    no rigid body of the frame has is looked up among the skeleton bones, by the id the
    server gives the bone), then its markers (``marker_index`` 1000 + k: marker k of marker
    set 0, as Gadgeteer reads it; below 1000: a NatNet marker id), in configuration order.
    Each unit keeps its last pose while its body or marker is missing from frames (identity
    until first seen)."""

    def __init__(self, body_ids: list[int], marker_ids: list[int]) -> None:
        self.body_ids = list(body_ids)
        self.marker_ids = list(marker_ids)
        self.matrices = np.tile(np.eye(4), (len(body_ids) + len(marker_ids), 1, 1))
        self._body_unit: dict[int, list[int]] = {}
        for unit, ident in enumerate(self.body_ids):
            self._body_unit.setdefault(ident, []).append(unit)
        first = len(self.body_ids)
        self._marker_unit: dict[int, list[int]] = {}
        for k, ident in enumerate(self.marker_ids):
            self._marker_unit.setdefault(ident, []).append(first + k)

    def update(self, frame: NatNetFrame) -> np.ndarray:
        """Apply ``frame``; returns the matrices of every unit (a view: copy to keep)."""
        for ident, units in self._body_unit.items():
            pose = frame.bodies.get(ident)
            if pose is None:
                pose = next((b[ident] for b in frame.skeletons.values() if ident in b), None)
                if pose is None:
                    continue
            rotation = quaternion_matrix(*pose[3:])
            for unit in units:
                self.matrices[unit, :3, :3] = rotation
                self.matrices[unit, :3, 3] = pose[:3]
        first_set = frame.marker_sets[0][1] if frame.marker_sets else None
        for ident, units in self._marker_unit.items():
            if ident >= FIRST_MARKER_ID:
                index = ident - FIRST_MARKER_ID
                if first_set is None or index >= len(first_set):
                    continue
                xyz = first_set[index]
                if not np.isfinite(xyz).all():
                    continue
            else:
                found = frame.labeled_markers.get(ident) or frame.body_markers.get(ident)
                if found is None:
                    continue
                xyz = found
            for unit in units:
                self.matrices[unit, :3, 3] = xyz
        return self.matrices


class NatNetReceiver(LedgeredReceiver):
    """Receives NatNet messages on UDP ``port`` (0: chosen by the OS).

    ``group``: the multicast group joined (None or "": none), on ``interface`` ("0.0.0.0":
    every interface). ``unicast``: ask ``server`` (default 127.0.0.1) for the stream. ``version``:
    the NatNet version of the frames (None: from the server). See the module for the rest."""

    def __init__(
        self,
        port: int = DATA_PORT,
        *,
        group: str | None = MULTICAST_GROUP,
        interface: str = "0.0.0.0",
        unicast: bool = False,
        server: str | None = None,
        command_port: int = COMMAND_PORT,
        version: Version | None = None,
        receive_timeout: float = 0.1,
        peer_timeout: float = 2.0,
        version_timeout: float = 2.0,
        request_interval: float = 0.5,
        keepalive_interval: float = 1.0,
        receive_buffer: int = 4 * 1024 * 1024,
        limits: NatNetLimits = DEFAULT_LIMITS,
        receiver_limits: ReceiverLimits = ReceiverLimits(),
    ) -> None:
        self.requested_port = port
        self.group = group or None
        self.interface = interface
        self.unicast = unicast
        self.server = server or ("127.0.0.1" if unicast else None)
        self.command_port = command_port
        self.configured_version = version
        self.version = version
        self.receive_timeout = receive_timeout
        self.peer_timeout = peer_timeout
        self.version_timeout = version_timeout
        self.request_interval = request_interval
        self.keepalive_interval = keepalive_interval
        self.receive_buffer = receive_buffer
        self.limits = limits
        self.receiver_limits = receiver_limits
        self.server_info: ServerInfo | None = None
        #: Every datagram read, counted once as decoded or bad; the kernel's drops.
        self.ledger = DatagramLedger()
        self.frames = 0
        self.bad_records = 0
        self.other_messages = 0
        self.server_infos = 0
        self.requests_sent = 0
        self.undecoded_frames = 0
        self.untracked_bodies = 0
        self.missed_frames = 0
        self.frame_jumps = 0
        self.join_failures = 0
        self.joined = False
        self.first_error: str | None = None
        self._sock: socket.socket | None = None
        self._last_number: int | None = None
        self._last_data = time.monotonic()
        self._pending: collections.deque[bytes] = collections.deque()
        self._pending_since: float | None = None
        self._last_request = -math.inf
        self._last_keepalive = -math.inf

    # -- the socket -----------------------------------------------------------------------

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    @property
    def port(self) -> int:
        if self._sock is None:
            return self.requested_port
        return self._sock.getsockname()[1]

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, self.receive_buffer)
            if self.group:  # several clients of one host share the multicast port (as the SDK)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            bind_udp(sock, "", self.requested_port)
        except OSError:
            sock.close()
            raise
        self.joined = False
        if self.group:
            if _join(sock, self.group, self.interface):
                self.joined = True
            else:
                self.join_failures += 1
        sock.setblocking(False)
        self._sock = sock
        self.ledger.attach(sock)
        moment = time.monotonic()
        self._last_data = moment
        self.server_info = None  # a new session: unicast connects again (a version stays)
        self._last_request = self._last_keepalive = -math.inf
        self._maintain(moment)

    def close(self) -> None:
        if self._sock is not None:
            self.ledger.detach()
            self._sock.close()
            self._sock = None

    def _send(self, data: bytes) -> None:
        if self._sock is None or self.server is None:
            return
        try:
            self._sock.sendto(data, (self.server, self.command_port))
        except OSError as err:  # an unreachable server is a silent one: the peer timeout says it
            self._note_error(f"cannot send to {self.server}:{self.command_port}: {err}")
            return
        self.requests_sent += 1

    def _maintain(self, moment: float) -> None:
        """Send what is due: the connect request until the server answers (unicast, or while
        the version is unknown), then (unicast) the keep-alives."""
        wants_info = self.unicast or self.version is None
        if wants_info and self.server_info is None and self.server is not None:
            if moment - self._last_request >= self.request_interval:
                self._last_request = moment
                self._send(connect_request(self.configured_version))
        elif self.unicast and moment - self._last_keepalive >= self.keepalive_interval:
            self._last_keepalive = moment
            self._send(keep_alive())

    # -- reading --------------------------------------------------------------------------

    def sample_all(self, limit: int = 100) -> list[NatNetFrame]:
        """The frames that arrive within ``receive_timeout`` (at most ``limit``); raises
        :class:`NatNetDisconnected` after ``peer_timeout`` seconds without a datagram. Data
        that arrives but does not decode is the ledger's to report (:meth:`undecodable_reason`)."""
        sock = self._sock
        if sock is None:
            raise NatNetDisconnected("the receiver is closed")
        frames: list[NatNetFrame] = []
        ready, _, _ = select.select([sock], [], [], self.receive_timeout)
        while ready and len(frames) < limit:
            try:
                data, address = self.ledger.receive_from(MAX_DATAGRAM)
            except BlockingIOError:
                break
            self._last_data = time.monotonic()
            frames.extend(self.handle(data, address))
        moment = time.monotonic()
        self._maintain(moment)
        self._check_pending(moment)
        if not frames and moment - self._last_data > self.peer_timeout:
            raise NatNetDisconnected(
                f"no NatNet data on UDP port {self.port} for {self.peer_timeout:g} s"
            )
        return frames

    def undecodable_reason(self) -> str | None:
        """Why nothing decodes while datagrams arrive (the ledger's verdict, with the first
        error of the bad run); None when the receiver decodes what it gets."""
        return self.ledger.undecodable()

    def handle(self, data: bytes, address: tuple[str, int] | None = None) -> list[NatNetFrame]:
        """Count one datagram and act on it; the frames it yields (several when it is the
        server information that frees held frames)."""
        ident = message_id(data)
        size_ok = ident is not None and struct.unpack_from("<H", data, 2)[0] <= len(data) - 4
        if ident == NAT_FRAMEOFDATA and self.version is None:
            if self.server is None and address is not None:
                self.server = address[0]  # the frames' sender answers requests
                self._maintain(time.monotonic())
            if self._pending_since is None:
                self._pending_since = time.monotonic()
            if len(self._pending) >= self.receiver_limits.pending_frames:
                self._pending.popleft()
                self.undecoded_frames += 1
                self.ledger.bad("more frames than are held while the NatNet version is unknown")
            self._pending.append(data)
            return []
        if ident == NAT_FRAMEOFDATA:
            frame = self.decode(data)
            return [] if frame is None else [frame]
        if ident == NAT_SERVERINFO and size_ok:
            try:
                info = decode_server_info(data)
            except NatNetFormatError as err:
                self._bad(str(err))
                return []
            self.ledger.decoded()
            return self._use(info)
        if ident in OTHER_MESSAGES and size_ok:
            self.other_messages += 1
            self.ledger.decoded()
            return []
        self._bad(
            "datagram shorter than a NatNet header"
            if ident is None
            else f"message id {ident} is no NatNet message"
            if ident not in OTHER_MESSAGES and ident != NAT_SERVERINFO
            else f"message {ident} announces more bytes than it has"
        )
        return []

    def _use(self, info: ServerInfo) -> list[NatNetFrame]:
        self.server_infos += 1
        self.server_info = info
        if self.configured_version is None:
            self.version = info.version
        held, self._pending = list(self._pending), collections.deque()
        self._pending_since = None
        frames = []
        for data in held:
            frame = self.decode(data)
            if frame is not None:
                frames.append(frame)
        return frames

    def _check_pending(self, moment: float) -> None:
        """Frames held longer than ``version_timeout`` for want of a NatNet version are bad
        (``undecoded_frames``); the connect requests go on, so a late answer still helps."""
        if self._pending_since is None or moment - self._pending_since < self.version_timeout:
            return
        held = len(self._pending)
        self.undecoded_frames += held
        self._pending.clear()
        self._pending_since = None
        where = f"{self.server}:{self.command_port}" if self.server else "the server"
        reason = (
            f"NatNet version unknown: {where} did not answer the connect request within "
            f"{self.version_timeout:g} s (set natnet_version)"
        )
        self._note_error(reason)
        self.ledger.bad(reason, held)

    def decode(self, data: bytes) -> NatNetFrame | None:
        """Decode one frame-of-data datagram with the current version (2.5 while none is
        known) and count it; None unless it is a good frame."""
        try:
            frame = decode_frame(data, self.version or (2, 5), self.limits)
        except NatNetFormatError as err:
            version = version_text(self.version or (2, 5))
            self._bad(f"NatNet {version} frame: {err}")
            return None
        self.frames += 1
        self.ledger.decoded()
        self.bad_records += frame.bad_records
        self.untracked_bodies += frame.untracked
        self._count_gap(frame.number)
        return frame

    def _count_gap(self, number: int) -> None:
        """Gaps in the (int32, wrapping) frame numbers: a step of 2..MAX_FRAME_GAP counts
        the frames between as missed; anything else is a jump, counted once."""
        last = self._last_number
        self._last_number = number
        if last is None:
            return
        step = (number - last) & 0xFFFF_FFFF
        if step == 1:
            return
        if 1 < step <= MAX_FRAME_GAP:
            self.missed_frames += step - 1
        else:
            self.frame_jumps += 1

    def _bad(self, reason: str) -> None:
        self.ledger.bad(reason)
        self._note_error(reason)

    def _note_error(self, reason: str) -> None:
        if self.first_error is None:
            self.first_error = reason


def _join(sock: socket.socket, group: str, interface: str) -> bool:
    """Join ``group`` on ``interface``, or ("0.0.0.0") on every interface that takes it
    (Linux's ip_mreqn by interface index; elsewhere the system's default interface)."""
    address = socket.inet_aton(group)
    if interface not in ("", "0.0.0.0"):
        try:
            request = address + socket.inet_aton(interface)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, request)
        except OSError:
            return False
        return True
    joined = False
    try:
        indexes = [index for index, _name in socket.if_nameindex()]
    except (OSError, AttributeError):
        indexes = []
    for index in indexes:
        request = address + socket.inet_aton("0.0.0.0") + struct.pack("@i", index)
        try:
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, request)
        except OSError:
            continue  # an interface without IPv4 multicast
        joined = True
    if not joined:
        try:
            request = address + socket.inet_aton("0.0.0.0")
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, request)
        except OSError:
            return False
        joined = True
    return joined
