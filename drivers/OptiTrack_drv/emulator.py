"""An OptiTrack NatNet server (Motive) emulated on loopback: the sender's side of NatNet.

Knows nothing of gadgetctl's input manager (the command line comes from the shared emulator
scaffolding, :mod:`gadgetctl.emulation`). Frames go as UDP datagrams to ``127.0.0.1:port``,
or to a multicast group through the loopback interface only (TTL 0), never to another host.
The command line's defaults are Motive's: multicast to 239.255.42.99, data port 1511, command
port 1510, NatNet 4.1.

Frames are written in the layout of the NatNet ``version`` chosen (1.0 to 4.1): marker sets,
unidentified markers, rigid bodies (marker lists before 3.0, tracking parameters from 2.6),
skeletons (2.1+), assets (4.1), labeled markers (2.3+), force plates (2.9+), devices (2.11+),
the version's suffix, and from 4.1 the byte count after each count.

With a ``command_port`` the emulator is an emulated Motive: it answers a connect request
(message 0) with its server information (message 1, naming the NatNet version), counts
keep-alives, and in ``unicast`` mode sends frames only to the clients that connected (from
its command socket, as Motive does), none before.

Scenarios: ``idle`` (bodies and markers at rest), ``motion`` (they move and turn),
``buttons`` (OptiTrack has no buttons: bodies drop out in turn and come back, flagged as
untracked from NatNet 2.6, left out before), ``garbage`` (``motion``, and after every frame a
datagram a receiver must count as bad) and ``disconnect`` (``motion`` for
``disconnect_after`` frames, then the sender closes).

Rigid body ``i`` has NatNet id ``i + 1``; marker ``k`` is marker k of marker set 0 (and of
the unidentified markers), labeled marker id ``LABELED_ID + k``; skeleton ``s`` has id
``s + 1`` and bones ``(s + 1) << 16 | (b + 1)``.

Run ``python emulator.py --help`` (or ``gadgetctl emulate OptiTrack_drv``) for the command line.
"""

from __future__ import annotations

import math
import random
import select
import socket
import struct
import sys
import threading

from gadgetctl.emulation import emulator_parser, run
from gadgetctl.emulation.command import ended
from gadgetctl.emulation.network import LOOPBACK, STANDARD_SCENARIOS, UdpFrameSender
from gadgetctl.transport.udp import bind_named

SCENARIOS = STANDARD_SCENARIOS
NAT_CONNECT = 0
NAT_SERVERINFO = 1
NAT_FRAMEOFDATA = 7
NAT_KEEPALIVE = 10
MOTIVE_GROUP = "239.255.42.99"
MOTIVE_DATA_PORT = 1511
MOTIVE_COMMAND_PORT = 1510
NEWEST = (4, 1)
LABELED_ID = 500
BONES = 3

Pose = tuple[float, float, float, float, float, float, float]


# -- the scenario's data (pure functions, so tests can compute what to expect) ----------------


def body_pose(frame: int, index: int, moving: bool) -> Pose:
    """x, y, z (metres) and qx, qy, qz, qw of rigid body ``index`` (a turn about z).

    Body 0 rests exactly at the origin with the identity rotation when not moving (upstream
    dropped such a body: every zero component counted as 'not tracked')."""
    t = frame if moving else 0
    if index == 0 and not moving:
        return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
    angle = math.radians(15.0 * index + 2.0 * t)
    return (
        0.25 * index + 0.1 * math.sin(0.05 * t),
        1.5,
        -0.5 + 0.01 * index,
        0.0,
        0.0,
        math.sin(angle / 2),
        math.cos(angle / 2),
    )


def bone_pose(frame: int, skeleton: int, bone: int, moving: bool) -> Pose:
    """The pose of bone ``bone`` of skeleton ``skeleton`` (a turn about x)."""
    t = frame if moving else 0
    angle = math.radians(10.0 * (bone + 1) + 3.0 * t)
    return (
        -1.0 - skeleton,
        0.9 + 0.3 * bone,
        0.2 * math.cos(0.04 * t),
        math.sin(angle / 2),
        0.0,
        0.0,
        math.cos(angle / 2),
    )


def marker_position(frame: int, index: int, moving: bool) -> tuple[float, float, float]:
    """x, y, z (metres) of marker ``index``."""
    t = frame if moving else 0
    return (0.01 * index, 1.0 + 0.05 * math.cos(0.05 * t), 0.5 - 0.001 * index)


def visible(frame: int, index: int, scenario: str) -> bool:
    """Whether object ``index`` is tracked in frame ``frame`` (``buttons``: in turn not)."""
    return scenario != "buttons" or (frame // 10) % 4 != index % 4


# -- the encoder --------------------------------------------------------------------------------


def _body(ident: int, pose: Pose, version: tuple[int, int], tracked: bool = True) -> bytes:
    out = [struct.pack("<i7f", ident, *pose)]
    if version < (3, 0):
        count = 2
        out.append(struct.pack("<i", count))
        out += [struct.pack("<3f", pose[0] + 0.01 * k, pose[1], pose[2]) for k in range(count)]
        if version >= (2, 0):
            out += [struct.pack("<i", 100 * ident + k) for k in range(count)]
            out += [struct.pack("<f", 0.012)] * count
    if version >= (2, 0):
        out.append(struct.pack("<f", 0.0005))
    if version >= (2, 6):
        out.append(struct.pack("<h", 1 if tracked else 0))
    return b"".join(out)


def _section(version: tuple[int, int], count: int, items: list[bytes]) -> bytes:
    """A count, from 4.1 the section's byte count, then the items."""
    body = b"".join(items)
    if version >= (4, 1):
        return struct.pack("<ii", count, len(body)) + body
    return struct.pack("<i", count) + body


def encode_frame(
    number: int,
    bodies: list[tuple[int, Pose]],
    markers: list[tuple[float, float, float]],
    marker_sets: list[tuple[str, list[tuple[float, float, float]]]] = (),  # type: ignore[assignment]
    *,
    version: tuple[int, int] = NEWEST,
    untracked: list[int] = (),  # type: ignore[assignment]
    labeled: list[tuple[int, tuple[float, float, float]]] = (),  # type: ignore[assignment]
    skeletons: list[tuple[int, list[tuple[int, Pose]]]] = (),  # type: ignore[assignment]
    extras: bool = True,
) -> bytes:
    """A NatNet frame-of-data packet of ``version``. ``untracked``: body ids sent as not
    tracked (2.6+). ``extras``: an asset, a force plate and a device where the version has
    them (decoders must step over them)."""
    v = version
    parts = [struct.pack("<i", number)]
    parts.append(
        _section(
            v,
            len(marker_sets),
            [
                name.encode() + b"\0" + struct.pack("<i", len(pts)) + _points(pts)
                for name, pts in marker_sets
            ],
        )
    )
    parts.append(_section(v, len(markers), [_points(markers)]))
    items = [_body(i, p, v) for i, p in bodies]
    if v >= (2, 6):
        items += [_body(i, (0.0,) * 7, v, tracked=False) for i in untracked]  # type: ignore[arg-type]
    parts.append(_section(v, len(items), items))
    if v >= (2, 1):
        parts.append(
            _section(
                v,
                len(skeletons),
                [
                    struct.pack("<ii", sid, len(bones)) + b"".join(_body(b, p, v) for b, p in bones)
                    for sid, bones in skeletons
                ],
            )
        )
    if v >= (4, 1):
        assets = []
        if extras:
            assets.append(
                struct.pack("<ii", 7, 1)
                + struct.pack("<i7ffh", 70, 0, 0, 0, 0, 0, 0, 1, 0.0, 1)
                + struct.pack("<i", 1)
                + struct.pack("<i3ffhf", 71, 0.1, 0.2, 0.3, 0.01, 0, 0.0)
            )
        parts.append(_section(v, len(assets), assets))
    if v >= (2, 3):
        items = []
        for ident, xyz in labeled:
            item = struct.pack("<i3ff", ident, *xyz, 0.014)
            if v >= (2, 6):
                item += struct.pack("<h", 0x04)
            if v >= (3, 0):
                item += struct.pack("<f", 0.0002)
            items.append(item)
        parts.append(_section(v, len(items), items))
    for since in ((2, 9), (2, 11)):
        if v >= since:
            items = []
            if extras:  # one plate or device: 2 channels of 3 samples
                channel = struct.pack("<i3f", 3, 1.0, 2.0, 3.0)
                items.append(struct.pack("<ii", 1, 2) + channel * 2)
            parts.append(_section(v, len(items), items))
    parts.append(_suffix(number, v))
    payload = b"".join(parts)
    return struct.pack("<HH", NAT_FRAMEOFDATA, len(payload)) + payload


def _points(points) -> bytes:
    return b"".join(struct.pack("<3f", *p) for p in points)


def _suffix(number: int, v: tuple[int, int]) -> bytes:
    out = []
    if v < (3, 0):
        out.append(struct.pack("<f", 0.004))  # latency
    out.append(struct.pack("<II", 0x01020304, 0))  # timecode, subframe
    stamp = number / 120.0
    out.append(struct.pack("<d", stamp) if v >= (2, 7) else struct.pack("<f", stamp))
    if v >= (3, 0):
        out.append(struct.pack("<3Q", 1000 * number, 1000 * number + 3, 1000 * number + 5))
    if v >= (4, 0):
        out.append(struct.pack("<II", number // 120, number % 120))  # precision time
    out.append(struct.pack("<h", 0))  # frame parameters
    out.append(struct.pack("<i", 0))  # end of data
    return b"".join(out)


def server_info(
    version: tuple[int, int], data_port: int, multicast: bool, group: str = MOTIVE_GROUP
) -> bytes:
    """The server information (message 1) Motive sends in reply to a connect request."""
    application = (3, 1, 0, 0) if version >= (4, 0) else (2, 0, 0, 0)
    body = b"Motive".ljust(256, b"\0") + bytes(application) + bytes((*version, 0, 0))
    body += struct.pack("<QH?", 1_000_000_000, data_port, multicast)
    body += socket.inet_aton(group)
    return struct.pack("<HH", NAT_SERVERINFO, len(body)) + body


class FrameWriter:
    """The frames of one scenario."""

    def __init__(
        self,
        scenario: str,
        bodies: int,
        markers: int,
        *,
        version: tuple[int, int] = NEWEST,
        skeletons: int = 1,
    ) -> None:
        self.scenario = scenario
        self.bodies = bodies
        self.markers = markers
        self.version = version
        self.skeletons = skeletons

    @property
    def moving(self) -> bool:
        return self.scenario not in ("idle", "buttons")

    def frame(self, n: int) -> bytes:
        moving = self.moving
        shown = [i for i in range(self.bodies) if visible(n, i, self.scenario)]
        hidden = [i + 1 for i in range(self.bodies) if i not in shown]
        markers = [marker_position(n, k, moving) for k in range(self.markers)]
        return encode_frame(
            n,
            [(i + 1, body_pose(n, i, moving)) for i in shown],
            markers,
            [("Rigid Body 1", markers), ("all", markers)],
            version=self.version,
            untracked=hidden,
            labeled=[(LABELED_ID + k, m) for k, m in enumerate(markers)],
            skeletons=[
                (
                    s + 1,
                    [((s + 1) << 16 | (b + 1), bone_pose(n, s, b, moving)) for b in range(BONES)],
                )
                for s in range(self.skeletons)
            ],
        )


# -- the emulator ----------------------------------------------------------------------------


class OptiTrackEmulator(UdpFrameSender):
    """Sends NatNet frames to ``127.0.0.1:port`` (or multicast ``group`` via loopback) at
    ``rate`` frames per second. ``frames_sent`` counts the valid frames, ``garbage_sent`` the
    bad datagrams of the garbage scenario. With ``max_frames`` it stops sending after that
    many frames (and sets ``finished``). With ``command_port`` (0: chosen by the OS) it
    answers connect requests (``connects``, ``keepalives`` count what came); ``unicast``
    sends frames only to the clients that connected."""

    NAME = "natnet"

    def __init__(
        self,
        port: int = MOTIVE_DATA_PORT,
        *,
        scenario: str = "motion",
        rate: float = 100.0,
        bodies: int = 2,
        markers: int = 2,
        skeletons: int = 1,
        version: tuple[int, int] = NEWEST,
        disconnect_after: int = 10,
        max_frames: int | None = None,
        first_frame: int = 1,
        group: str | None = None,
        command_port: int | None = None,
        unicast: bool = False,
        seed: int = 0,
    ) -> None:
        if bodies < 0 or markers < 0 or skeletons < 0:
            raise ValueError("the counts must not be negative")
        if not (1, 0) <= version <= NEWEST:
            raise ValueError("the NatNet version must be 1.0 to 4.1")
        if unicast and command_port is None:
            raise ValueError("unicast needs a command port (clients connect there)")
        super().__init__(
            port,
            scenario=scenario,
            rate=rate,
            disconnect_after=disconnect_after,
            max_frames=max_frames,
            first_frame=first_frame,
            group=None if unicast else group,
        )
        self.writer = FrameWriter(scenario, bodies, markers, version=version, skeletons=skeletons)
        self.version = version
        self.command_port = command_port
        self.unicast = unicast
        self.frames_sent = 0
        self.garbage_sent = 0
        self.connects = 0
        self.keepalives = 0
        self.clients: list[tuple[str, int]] = []
        self._command_sock: socket.socket | None = None
        self._clients_lock = threading.Lock()
        self._rng = random.Random(seed)

    @property
    def command_address(self) -> tuple[str, int] | None:
        """Where connect requests are answered, once started."""
        if self._command_sock is None:
            return None
        return (LOOPBACK, self._command_sock.getsockname()[1])

    # -- life cycle -------------------------------------------------------------------------

    def open(self) -> None:
        if self.command_port is not None:
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                bind_named(sock, LOOPBACK, self.command_port)
            except OSError:
                sock.close()
                raise
            self._command_sock = sock

    def close(self) -> None:
        if self._command_sock is not None:
            self._command_sock.close()
        self._command_sock = None

    def services(self) -> list:
        return [] if self._command_sock is None else [(self._listen, "natnet-commands")]

    def _listen(self) -> None:
        sock = self._command_sock
        assert sock is not None
        while not self._stop.is_set():
            ready, _, _ = select.select([sock], [], [], 0.05)
            if not ready:
                continue
            try:
                data, peer = sock.recvfrom(65_535)
            except OSError:
                return
            if len(data) < 4:
                continue
            ident = struct.unpack_from("<H", data)[0]
            if ident == NAT_CONNECT:
                with self._clients_lock:
                    self.connects += 1
                    if peer not in self.clients:
                        self.clients.append(peer)
                self.console.client_connected(f"{peer[0]}:{peer[1]} (connect request)")
                reply = server_info(
                    self.version, self.port, not self.unicast, self.group or MOTIVE_GROUP
                )
                sock.sendto(reply, peer)
            elif ident == NAT_KEEPALIVE:
                with self._clients_lock:
                    self.keepalives += 1

    # -- sending ------------------------------------------------------------------------------

    def may_send(self) -> bool:
        if not self.unicast:
            return True
        with self._clients_lock:
            return bool(self.clients)

    def send_raw(self, data: bytes | str) -> None:
        if not self.unicast:
            super().send_raw(data)
            return
        payload = data.encode("ascii") if isinstance(data, str) else data
        sock = self._command_sock
        if sock is None:
            raise RuntimeError("the emulator is not running")
        with self._clients_lock:
            clients = list(self.clients)
        for client in clients:
            sock.sendto(payload, client)

    def send_frame(self, n: int) -> None:
        self.send_raw(self.writer.frame(n))
        self.frames_sent += 1
        if self.scenario == "garbage":
            self.send_raw(self._garbage(n))
            self.garbage_sent += 1

    def _garbage(self, n: int) -> bytes:
        """A datagram a receiver must count as bad, whatever the version."""
        kind = n % 4
        good = self.writer.frame(n)
        if kind == 0:  # junk whose header is no NatNet message
            return struct.pack("<HH", 0x7A7A, 0) + self._rng.randbytes(self._rng.randint(0, 60))
        if kind == 1:  # a frame cut short (its header announces more than comes)
            return good[: len(good) // 2]
        if kind == 2:  # a rigid-body count far beyond NatNet's limit
            empty = (0, 0, 0, 0) if self.version >= (4, 1) else (0, 0)  # no markers
            payload = struct.pack("<6i" if len(empty) == 4 else "<4i", n, *empty, 1_000_000)
            return struct.pack("<HH", NAT_FRAMEOFDATA, len(payload)) + payload
        payload = struct.pack("<ii", n, -5)  # a negative marker-set count
        return struct.pack("<HH", NAT_FRAMEOFDATA, len(payload)) + payload


def _version(text: str) -> tuple[int, int]:
    try:
        major, minor = (int(part) for part in text.split("."))
    except ValueError:
        raise ValueError(f"{text!r} is not a NatNet version such as 3.0") from None
    return (major, minor)


def main(argv: list[str] | None = None) -> int:
    """Command line: send frames until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "OptiTrack_drv.emulator",
        "Emulate an OptiTrack NatNet server (Motive) on loopback UDP.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="frames per second (default 100)",
    )
    parser.add_argument(
        "--port",
        type=int,
        default=MOTIVE_DATA_PORT,
        help=f"data port the frames go to (default Motive's {MOTIVE_DATA_PORT})",
    )
    parser.add_argument(
        "--group",
        default=MOTIVE_GROUP,
        help=f"multicast group, sent through loopback (default {MOTIVE_GROUP}); "
        "empty: unicast to 127.0.0.1",
    )
    parser.add_argument(
        "--command-port",
        type=int,
        default=MOTIVE_COMMAND_PORT,
        help="UDP port on 127.0.0.1 where connect requests are answered "
        f"(default {MOTIVE_COMMAND_PORT}; 0: chosen by the system)",
    )
    parser.add_argument(
        "--unicast",
        action="store_true",
        help="send frames only to the clients that connected (Motive's unicast mode)",
    )
    parser.add_argument(
        "--natnet-version", default="4.1", metavar="X.Y", help="NatNet version, 1.0 to 4.1"
    )
    parser.add_argument("--bodies", type=int, default=2, help="rigid bodies, ids 1.. (default 2)")
    parser.add_argument(
        "--markers", type=int, default=2, help="markers of marker set 0 (default 2)"
    )
    parser.add_argument("--skeletons", type=int, default=1, help="skeletons (default 1)")
    parser.add_argument("--disconnect-after", type=int, default=10, metavar="N")
    parser.add_argument("--seed", type=int, default=0, help="seed of the garbage scenario")
    args = parser.parse_args(argv)
    try:
        emulator = OptiTrackEmulator(
            args.port,
            scenario=args.scenario,
            rate=args.rate,
            bodies=args.bodies,
            markers=args.markers,
            skeletons=args.skeletons,
            version=_version(args.natnet_version),
            disconnect_after=args.disconnect_after,
            group=args.group or None,
            command_port=args.command_port,
            unicast=args.unicast,
            seed=args.seed,
        )
    except ValueError as exc:
        parser.error(str(exc))

    def announce() -> None:
        where = "connected clients (unicast)" if args.unicast else emulator.address
        print(
            f"OptiTrack emulator ({args.scenario}, NatNet {args.natnet_version}, "
            f"{args.rate:g} Hz) sending to {where}"
        )
        command = emulator.command_address
        if command is not None:
            print(f"Answering connect requests on {command[0]}:{command[1]}")
        if args.unicast:
            print("Point the optitrack element at it: <connection_type>Unicast</connection_type>")
        else:
            print(f"Point the optitrack element at it: <port>{args.port}</port>")
        print("Press Ctrl-C to stop.", flush=True)

    return run(emulator, duration=args.duration, announce=announce, check=ended(emulator))


if __name__ == "__main__":
    sys.exit(main())
