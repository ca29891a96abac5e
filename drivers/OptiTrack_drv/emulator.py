"""An OptiTrack NatNet server emulated on loopback: the sender's side of NatNet frames.

Knows nothing of gadgetctl's input manager (the command line comes from the shared emulator
scaffolding, :mod:`gadgetctl.emulation`). Frames go as UDP datagrams to ``127.0.0.1:port``
(or, with ``group``, to that multicast group through the loopback interface only); never to
another host, never broadcast.

Scenarios: ``idle`` (bodies and markers at rest), ``motion`` (they move and turn),
``buttons`` (OptiTrack has no buttons: bodies and markers drop out of frames in turn and come
back, as untracked objects do), ``garbage`` (``motion``, and after every frame a datagram a
receiver must count as bad: junk, a cut-off frame, counts beyond NatNet's limits) and
``disconnect`` (``motion`` for ``disconnect_after`` frames, then the sender closes).

Rigid body ``i`` has NatNet id ``i + 1``; unidentified marker ``k`` is marker id ``1000 + k``.

Run ``python emulator.py --help`` (or ``gadgetctl emulate OptiTrack_drv``) for the command line.
"""

from __future__ import annotations

import math
import random
import struct
import sys

from gadgetctl.emulation import emulator_parser, run
from gadgetctl.emulation.network import STANDARD_SCENARIOS, UdpFrameSender, ended

SCENARIOS = STANDARD_SCENARIOS
NAT_FRAMEOFDATA = 7


# -- the scenario's data (pure functions, so tests can compute what to expect) ----------------


def body_pose(frame: int, index: int, moving: bool) -> tuple[float, ...]:
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


def marker_position(frame: int, index: int, moving: bool) -> tuple[float, float, float]:
    """x, y, z (metres) of unidentified marker ``index``."""
    t = frame if moving else 0
    return (0.01 * index, 1.0 + 0.05 * math.cos(0.05 * t), 0.5 - 0.001 * index)


def visible(frame: int, index: int, scenario: str) -> bool:
    """Whether object ``index`` is in frame ``frame`` (``buttons``: each drops out in turn)."""
    return scenario != "buttons" or (frame // 10) % 4 != index % 4


def encode_frame(
    number: int,
    bodies: list[tuple[int, tuple[float, ...]]],
    markers: list[tuple[float, float, float]],
    marker_sets: list[tuple[str, list[tuple[float, float, float]]]] = (),  # type: ignore[assignment]
    body_markers: int = 0,
) -> bytes:
    """A NatNet frame-of-data packet (the 1.x/2.0 layout)."""
    parts = [struct.pack("<ii", number, len(marker_sets))]
    for name, points in marker_sets:
        parts.append(name.encode() + b"\0" + struct.pack("<i", len(points)))
        parts.extend(struct.pack("<3f", *p) for p in points)
    parts.append(struct.pack("<i", len(markers)))
    parts.append(b"".join(struct.pack("<3f", *m) for m in markers))
    parts.append(struct.pack("<i", len(bodies)))
    for ident, pose in bodies:
        parts.append(struct.pack("<i7fi", ident, *pose, body_markers))
        for k in range(body_markers):
            parts.append(struct.pack("<3f", pose[0] + 0.01 * k, pose[1], pose[2]))
        parts.append(b"".join(struct.pack("<i", 100 * ident + k) for k in range(body_markers)))
        parts.append(b"".join(struct.pack("<f", 0.012) for _ in range(body_markers)))
        parts.append(struct.pack("<f", 0.0005))
    payload = b"".join(parts)
    return struct.pack("<HH", NAT_FRAMEOFDATA, len(payload)) + payload


class FrameWriter:
    """The frames of one scenario."""

    def __init__(self, scenario: str, bodies: int, markers: int) -> None:
        self.scenario = scenario
        self.bodies = bodies
        self.markers = markers

    @property
    def moving(self) -> bool:
        return self.scenario not in ("idle", "buttons")

    def frame(self, n: int) -> bytes:
        bodies = [
            (i + 1, body_pose(n, i, self.moving))
            for i in range(self.bodies)
            if visible(n, i, self.scenario)
        ]
        markers = [marker_position(n, k, self.moving) for k in range(self.markers)]
        return encode_frame(n, bodies, markers, [("all", markers[:3])], body_markers=2)


# -- the emulator ----------------------------------------------------------------------------


class OptiTrackEmulator(UdpFrameSender):
    """Sends NatNet frames to ``127.0.0.1:port`` (or multicast ``group`` via loopback) at
    ``rate`` frames per second. ``frames_sent`` counts the valid frames, ``garbage_sent`` the
    bad datagrams of the garbage scenario. With ``max_frames`` it stops sending after that
    many frames (and sets ``finished``)."""

    NAME = "natnet"

    def __init__(
        self,
        port: int = 1001,
        *,
        scenario: str = "motion",
        rate: float = 100.0,
        bodies: int = 2,
        markers: int = 2,
        disconnect_after: int = 10,
        max_frames: int | None = None,
        first_frame: int = 1,
        group: str | None = None,
        seed: int = 0,
    ) -> None:
        if bodies < 0 or markers < 0:
            raise ValueError("the counts must not be negative")
        super().__init__(
            port,
            scenario=scenario,
            rate=rate,
            disconnect_after=disconnect_after,
            max_frames=max_frames,
            first_frame=first_frame,
            group=group,
        )
        self.writer = FrameWriter(scenario, bodies, markers)
        self.frames_sent = 0
        self.garbage_sent = 0
        self._rng = random.Random(seed)

    def send_frame(self, n: int) -> None:
        self.send_raw(self.writer.frame(n))
        self.frames_sent += 1
        if self.scenario == "garbage":
            self.send_raw(self._garbage(n))
            self.garbage_sent += 1

    def _garbage(self, n: int) -> bytes:
        """A datagram a receiver must count as bad."""
        kind = n % 4
        good = self.writer.frame(n)
        if kind == 0:  # junk whose header is no NatNet message
            return struct.pack("<HH", 0x7A7A, 0) + self._rng.randbytes(self._rng.randint(0, 60))
        if kind == 1:  # a frame cut short (its header announces more than comes)
            return good[: len(good) // 2]
        if kind == 2:  # a rigid-body count far beyond NatNet's limit
            payload = struct.pack("<iii", n, 0, 0) + struct.pack("<i", 1_000_000)
            return struct.pack("<HH", NAT_FRAMEOFDATA, len(payload)) + payload
        payload = struct.pack("<ii", n, -5)  # a negative marker-set count
        return struct.pack("<HH", NAT_FRAMEOFDATA, len(payload)) + payload


def main(argv: list[str] | None = None) -> int:
    """Command line: send frames until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "OptiTrack_drv.emulator",
        "Emulate an OptiTrack NatNet server on loopback UDP.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="frames per second (default 100)",
    )
    parser.add_argument(
        "--port", type=int, default=1001, help="UDP port on 127.0.0.1 to send to (default 1001)"
    )
    parser.add_argument("--bodies", type=int, default=2, help="rigid bodies, ids 1.. (default 2)")
    parser.add_argument(
        "--markers", type=int, default=2, help="unidentified markers, ids 1000.. (default 2)"
    )
    parser.add_argument(
        "--group", help="send to this multicast group through loopback instead of unicast"
    )
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
            disconnect_after=args.disconnect_after,
            group=args.group,
            seed=args.seed,
        )
    except ValueError as exc:
        parser.error(str(exc))

    def announce() -> None:
        print(
            f"OptiTrack emulator ({args.scenario}, {args.rate:g} Hz) sending to {emulator.address}"
        )
        print(f"Point the optitrack element at it: <port>{args.port}</port>")
        print("Press Ctrl-C to stop.", flush=True)

    return run(emulator, duration=args.duration, announce=announce, check=ended(emulator))


if __name__ == "__main__":
    sys.exit(main())
