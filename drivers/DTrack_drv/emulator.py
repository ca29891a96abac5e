"""A DTrack tracker emulated on loopback: the sender's side of the DTrack ASCII protocol.

Knows nothing of gadgetctl's input manager (the command line comes from the shared emulator
scaffolding, :mod:`gadgetctl.emulation`). Frames go as UDP datagrams to ``127.0.0.1:port`` only (never to
another host, never broadcast). Each frame holds ``fr``, ``ts``, ``6dcal``, the Flysticks
(``6df2``, or the old ``6df``), the standard bodies (``6d``), single markers (``3d``) and
gloves (``glcal``/``gl``), with locations in millimetres and rotations sent column by column.

Scenarios: ``idle`` (everything at rest), ``motion`` (poses, markers and joystick move; body 1
is left out of every fourth frame, as DTrack leaves out untracked bodies), ``buttons`` (the
Flystick buttons are pressed and released one after the other, beyond the eighth too),
``garbage`` (``motion``, and after every frame a datagram that is binary junk, a cut-off line
or text without a DTrack tag; every fourth frame also carries one malformed line) and
``disconnect`` (``motion`` for ``disconnect_after`` frames, then the sender closes).

With a ``command_port`` the emulator also listens for the remote commands (``dtrack 10 3``,
``dtrack 31``, ``dtrack 32``, ``dtrack 10 0``, ``dtrack 33 n``) and records them; with
``wait_for_start`` it only sends between ``dtrack 31`` and ``dtrack 32`` (or n frames after
``dtrack 33 n``), like a real tracker.

Run ``python emulator.py --help`` (or ``gadgetctl emulate DTrack_drv``) for the command line.
"""

from __future__ import annotations

import math
import random
import select
import socket
import sys
import time
from collections.abc import Sequence

import numpy as np

from gadgetctl.emulation import emulator_parser, run
from gadgetctl.emulation.command import ended
from gadgetctl.emulation.network import LOOPBACK, STANDARD_SCENARIOS, Peers, UdpFrameSender
from gadgetctl.transport.udp import bind_named

SCENARIOS = STANDARD_SCENARIOS
FLYSTICK_FORMATS = ("6df2", "6df")
FINGERS = 3


# -- the scenario's data (pure functions, so tests can compute what to expect) ----------------


def euler_rotation(eta: float, theta: float, phi: float) -> np.ndarray:
    """Rx(eta) @ Ry(theta) @ Rz(phi), angles in degrees.

    The angle convention only fills the unused angle fields of ``6d``/``6df`` lines; receivers
    (Gadgeteer's and ours) read the 9 matrix values.
    """
    a, b, c = (math.radians(v) for v in (eta, theta, phi))
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return rx @ ry @ rz


def object_angles(frame: int, index: int, moving: bool) -> tuple[float, float, float]:
    """Euler angles (degrees) of 6DOF object ``index`` (bodies 0.., gloves 50.., Flysticks 100..)."""
    t = frame if moving else 0
    return (
        (10.0 + 5.0 * index + 2.0 * t) % 360.0,
        20.0 - 0.3 * index,
        (30.0 + 7.0 * index + 3.0 * t) % 360.0,
    )


def object_location(frame: int, index: int, moving: bool) -> tuple[float, float, float]:
    """Location (mm) of 6DOF object ``index``."""
    t = frame if moving else 0
    return (
        round(100.0 * (index % 100 + 1) + 50.0 * math.sin(0.1 * t), 3),
        round(-200.0 + 30.0 * math.cos(0.1 * t), 3),
        round(1000.0 + 10.0 * index + 5.0 * t % 100, 3),
    )


def body_visible(frame: int, index: int, scenario: str) -> bool:
    """Whether body ``index`` is in frame ``frame`` (body 1 drops out every fourth frame)."""
    return not (scenario in ("motion", "garbage", "disconnect") and index == 1 and frame % 4 == 3)


def flystick_buttons(frame: int, n_buttons: int, scenario: str) -> tuple[int, ...]:
    """Buttons (0/1) of every Flystick: in ``buttons``, button (frame // 2) % n is pressed on
    even frames and everything is released on odd frames."""
    pressed = [0] * n_buttons
    if scenario == "buttons" and n_buttons and frame % 2 == 0:
        pressed[(frame // 2) % n_buttons] = 1
    return tuple(pressed)


def flystick_joystick(frame: int, scenario: str) -> tuple[float, float]:
    """The two joystick values of every Flystick (horizontal, vertical)."""
    if scenario in ("idle", "buttons"):
        return (0.0, 0.0)
    return (round(math.sin(0.2 * frame), 3), round(math.cos(0.2 * frame), 3))


def marker_location(frame: int, index: int, moving: bool) -> tuple[float, float, float]:
    """Location (mm) of marker ``index`` (ids start at 1)."""
    t = frame if moving else 0
    return (
        round(-100.0 * index, 3),
        round(50.0 + t % 50, 3),
        round(300.0 + 20.0 * math.sin(0.3 * t), 3),
    )


# -- formatting ------------------------------------------------------------------------------


def _block(values: Sequence[float | int], digits: int = 3) -> str:
    """A bracketed block: integers as they are, floats with ``digits`` decimals."""
    return (
        "[" + " ".join(f"{v:.{digits}f}" if isinstance(v, float) else str(v) for v in values) + "]"
    )


def rotation_block(rotation: np.ndarray) -> str:
    """The 9 rotation values column by column: b[i + 3j] = R[i][j]."""
    return _block([float(v) for v in np.asarray(rotation).flatten(order="F")], digits=6)


class FrameWriter:
    """Formats the frames of a scenario."""

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 60.0,
        bodies: int = 2,
        flysticks: int = 1,
        flystick_buttons: int = 10,
        flystick_format: str = "6df2",
        markers: int = 2,
        gloves: int = 1,
    ) -> None:
        if flystick_format not in FLYSTICK_FORMATS:
            raise ValueError(f"flystick_format must be one of {FLYSTICK_FORMATS}")
        self.scenario = scenario
        self.rate = rate
        self.bodies = bodies
        self.flysticks = flysticks
        self.n_buttons = 8 if flystick_format == "6df" else flystick_buttons
        self.flystick_format = flystick_format
        self.markers = markers
        self.gloves = gloves

    @property
    def moving(self) -> bool:
        return self.scenario not in ("idle", "buttons")

    def frame(self, n: int) -> str:
        """Frame number ``n`` as datagram text."""
        lines = [f"fr {n}", f"ts {36000.0 + n / self.rate:.6f}"]
        old = self.flysticks if self.flystick_format == "6df" else 0
        lines.append(f"6dcal {self.bodies + old}")
        if self.flysticks:
            lines.append(self.flystick_line(n))
        lines.append(self.body_line(n))
        if self.markers:
            lines.append(self.marker_line(n))
        if self.gloves:
            lines += [f"glcal {self.gloves}", self.glove_line(n)]
        return "".join(line + "\r\n" for line in lines)

    def _pose(self, n: int, index: int, with_angles: bool) -> str:
        loc = object_location(n, index, self.moving)
        angles = object_angles(n, index, self.moving)
        middle = list(loc) + (list(angles) if with_angles else [])
        return _block([float(v) for v in middle]) + rotation_block(euler_rotation(*angles))

    def body_line(self, n: int) -> str:
        shown = [i for i in range(self.bodies) if body_visible(n, i, self.scenario)]
        parts = [f"6d {len(shown)}"]
        parts += [_block([i, 1.0]) + self._pose(n, i, True) for i in shown]
        return " ".join(parts)

    def flystick_line(self, n: int) -> str:
        buttons = flystick_buttons(n, self.n_buttons, self.scenario)
        x, y = flystick_joystick(n, self.scenario)
        if self.flystick_format == "6df":
            # Old format: 8-bit mask; the hat bits 0x10..0x80 give the joystick direction.
            mask = sum(b << j for j, b in enumerate(buttons))
            mask |= (0x20 if x < -0.5 else 0x80 if x > 0.5 else 0) | (
                0x10 if y < -0.5 else 0x40 if y > 0.5 else 0
            )
            parts = [f"6df {self.flysticks}"]
            parts += [
                _block([i, 1.0, mask]) + self._pose(n, 100 + i, True) for i in range(self.flysticks)
            ]
            return " ".join(parts)
        fields = [0] * -(-self.n_buttons // 32)
        for j, b in enumerate(buttons):
            fields[j // 32] |= b << (j % 32)
        parts = [f"6df2 {self.flysticks} {self.flysticks}"]
        for i in range(self.flysticks):
            parts.append(
                _block([i, 1.0, self.n_buttons, 2])
                + self._pose(n, 100 + i, False)
                + _block([*fields, float(x), float(y)])
            )
        return " ".join(parts)

    def marker_line(self, n: int) -> str:
        parts = [f"3d {self.markers}"]
        parts += [
            _block([i, 1.0]) + _block([float(v) for v in marker_location(n, i, self.moving)])
            for i in range(1, self.markers + 1)
        ]
        return " ".join(parts)

    def glove_line(self, n: int) -> str:
        parts = [f"gl {self.gloves}"]
        for g in range(self.gloves):
            text = _block([g, 1.0, (g + 1) % 2, FINGERS]) + self._pose(n, 50 + g, False)
            for f in range(FINGERS):
                text += _block([30.0 * f, 80.0, -10.0]) + rotation_block(np.eye(3))
                text += _block([8.0, 20.0 + f, 15.0 + f, 25.0, 12.0 + f, 30.0])
            parts.append(text)
        return " ".join(parts)


# -- the emulator ----------------------------------------------------------------------------


class DTrackEmulator(UdpFrameSender):
    """Sends DTrack frames to ``127.0.0.1:port`` at ``rate`` frames per second.

    ``address`` is where the frames go (the receiver's ``receive_port``). With ``command_port``
    (0 = chosen by the OS, see ``command_address``) remote commands are received and kept in
    ``commands`` (and, as received, in ``raw_commands``). ``frames_sent`` lists the numbers of the valid frames sent; ``garbage_sent``
    and ``bad_lines_sent`` count what the garbage scenario added. With ``max_frames`` the
    emulator stops sending after that many frames (and sets ``finished``) but keeps its socket.
    """

    NAME = "dtrack"

    def __init__(
        self,
        port: int = 5000,
        *,
        scenario: str = "motion",
        rate: float = 60.0,
        bodies: int = 2,
        flysticks: int = 1,
        flystick_buttons: int = 10,
        flystick_format: str = "6df2",
        markers: int = 2,
        gloves: int = 1,
        disconnect_after: int = 10,
        max_frames: int | None = None,
        command_port: int | None = None,
        wait_for_start: bool = False,
        first_frame: int = 1,
        seed: int = 0,
    ) -> None:
        super().__init__(
            port,
            scenario=scenario,
            rate=rate,
            disconnect_after=disconnect_after,
            max_frames=max_frames,
            first_frame=first_frame,
        )
        self.writer = FrameWriter(
            scenario, rate, bodies, flysticks, flystick_buttons, flystick_format, markers, gloves
        )
        self.command_port = command_port
        self.wait_for_start = wait_for_start and command_port is not None
        self.commands: list[str] = []
        self.raw_commands: list[bytes] = []
        self.frames_sent: list[int] = []
        self.garbage_sent = 0
        self.bad_lines_sent = 0
        self._rng = random.Random(seed)
        self._command_sock: socket.socket | None = None
        self._peers = Peers(self.console)
        self._sending = not self.wait_for_start
        self._frames_to_send: int | None = None  # set by "dtrack 33 n"

    @property
    def command_address(self) -> str | None:
        """Where remote commands are received (``server_name``:``command_port``), if anywhere."""
        if self._command_sock is None:
            return None
        return f"{LOOPBACK}:{self._command_sock.getsockname()[1]}"

    # -- life cycle -------------------------------------------------------------------------

    def open(self) -> None:
        if self.command_port is not None:
            self._command_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            bind_named(self._command_sock, LOOPBACK, self.command_port)

    def close(self) -> None:
        if self._command_sock is not None:
            self._command_sock.close()
        self._command_sock = None

    def services(self) -> list:
        return [] if self._command_sock is None else [(self._listen, "dtrack-commands")]

    def wait_for_command(self, command: str, timeout: float = 1.0) -> bool:
        """Wait until ``command`` has been received."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self._lock:
                if command in self.commands:
                    return True
            time.sleep(0.001)
        return False

    # -- threads ------------------------------------------------------------------------------

    def may_send(self) -> bool:
        with self._lock:
            if not self._sending:
                return False
            if self._frames_to_send is not None:
                if self._frames_to_send <= 0:
                    self._sending, self._frames_to_send = False, None
                    return False
                self._frames_to_send -= 1
            return True

    def send_frame(self, n: int) -> None:
        text = self.writer.frame(n)
        if self.scenario == "garbage" and n % 4 == 3:
            text += "3d 2 [1 1.000][10.000 20\r\n"  # a malformed line inside a valid frame
            self.bad_lines_sent += 1
        self.frames_sent.append(n)  # logged first, so a fast reader never gets ahead of the log
        self.send_raw(text)
        if self.scenario == "garbage":
            self.garbage_sent += 1
            self.send_raw(self._garbage(n))

    def _garbage(self, n: int) -> bytes:
        """A datagram that holds no valid DTrack line."""
        kind = n % 3
        if kind == 0:  # binary junk, with at least one byte that is not ASCII
            return bytes([0xFF]) + self._rng.randbytes(self._rng.randint(0, 63))
        if kind == 1:  # a body line cut off inside a block
            line = self.writer.body_line(n + 1)
            if line.count("[") < 2:
                line = "6d 1 [0 1.000][100.000 200.000 300.000]"
            cut = line.index("[", line.index("[") + 1) + 4
            return line[:cut].encode("ascii")
        return b"hello dtrack\r\nthis is not a frame\r\n"

    def _listen(self) -> None:
        sock = self._command_sock
        assert sock is not None
        try:
            while not self._stop.is_set():
                ready, _, _ = select.select([sock], [], [], 0.01)
                if not ready:
                    continue
                data, peer = sock.recvfrom(4096)
                self._peers.heard(peer, "first command")
                with self._lock:
                    self.raw_commands.append(data)
                self._command(data.decode("ascii", "replace").strip("\0 \r\n"))
        except OSError as exc:
            if not self._stop.is_set():
                self.error = exc

    def _command(self, command: str) -> None:
        with self._lock:
            self.commands.append(command)
            words = command.split()
            if words == ["dtrack", "31"]:
                self._sending, self._frames_to_send = True, None
            elif words == ["dtrack", "32"]:
                self._sending = False
            elif len(words) == 3 and words[:2] == ["dtrack", "33"] and words[2].isdigit():
                self._sending, self._frames_to_send = True, int(words[2])


def main(argv: list[str] | None = None) -> int:
    """Command line: send frames until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "DTrack_drv.emulator",
        "Emulate an A.R.T. DTrack tracker on loopback UDP.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=60.0,
        rate_help="frames per second (default 60)",
    )
    parser.add_argument(
        "--port", type=int, default=5000, help="UDP port on 127.0.0.1 to send to (default 5000)"
    )
    parser.add_argument("--bodies", type=int, default=2, help="standard bodies (default 2)")
    parser.add_argument("--flysticks", type=int, default=1, help="Flysticks (default 1)")
    parser.add_argument(
        "--buttons", type=int, default=10, help="buttons per 6df2 Flystick (default 10)"
    )
    parser.add_argument(
        "--format", choices=FLYSTICK_FORMATS, default="6df2", help="Flystick line format"
    )
    parser.add_argument(
        "--command-port", type=int, help="listen for remote commands on this port (0 = any)"
    )
    parser.add_argument("--wait-for-start", action="store_true", help="send only after 'dtrack 31'")
    parser.add_argument("--disconnect-after", type=int, default=10, metavar="N")
    parser.add_argument("--seed", type=int, default=0, help="seed of the garbage scenario")
    args = parser.parse_args(argv)
    if args.rate <= 0 or min(args.bodies, args.flysticks, args.buttons) < 0:
        parser.error("--rate must be positive and the counts not negative")
    try:
        emulator = DTrackEmulator(
            args.port,
            scenario=args.scenario,
            rate=args.rate,
            bodies=args.bodies,
            flysticks=args.flysticks,
            flystick_buttons=args.buttons,
            flystick_format=args.format,
            disconnect_after=args.disconnect_after,
            command_port=args.command_port,
            wait_for_start=args.wait_for_start,
            seed=args.seed,
        )
    except ValueError as exc:
        parser.error(str(exc))

    def announce() -> None:
        print(f"DTrack emulator ({args.scenario}, {args.rate:g} Hz) sending to {emulator.address}")
        print(f"Point the dtrack element at it: <receive_port>{args.port}</receive_port>")
        if emulator.command_address is not None:
            host, cport = emulator.command_address.rsplit(":", 1)
            print(
                f"Remote commands: <server_name>{host}</server_name> <command_port>{cport}</command_port>"
            )
        print("Press Ctrl-C to stop.", flush=True)

    return run(emulator, duration=args.duration, announce=announce, check=ended(emulator))


if __name__ == "__main__":
    sys.exit(main())
