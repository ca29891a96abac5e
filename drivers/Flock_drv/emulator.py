"""An Ascension Flock of Birds on a pseudo-terminal, independent of gadgetctl's input manager
(it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

A byte-level state machine: it keeps a pending FBB address prefix, answers ``O`` (examine:
status, revision 3.67, scaling, error codes, model, addressing mode, master address, system
status), takes ``P`` (group mode, auto-configuration), ``L`` (hemisphere), the output formats
``Y`` (PosAngles) and ``]`` (PosQuaternion), the report rates ``Q R S T``, ``B`` (one frame),
``@`` (stream) and ``?`` (stop). In group mode (``master`` not 0) the birds are at addresses
1..``birds``, after an extended range controller at address 1 when ``extended_range``.
Scenarios:

``idle``        every bird holds still
``motion``      the birds circle the transmitter and turn
``buttons``     (a Flock has no buttons) still poses that jump a quarter turn every 20 frames
``garbage``     motion, with junk and broken records between the records
``disconnect``  ``disconnect_after`` frames, then hang-up
"""

from __future__ import annotations

import math
import os
import struct
import sys
import time

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

#: Seconds after the last write before the line counts as drained: the kernel moves what the
#: master wrote to the slave's input queue a moment later, and only then does FIONREAD count it.
QUIET = 0.1
SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-flock"
MODEL = b"6DFOB     "
# The emulator keeps its own copy of the wire layout, so a mistake in the driver is not
# mirrored here unnoticed.
FORMAT_WORDS = {ord("Y"): 6, ord("]"): 7}
ARGUMENTS = {ord("L"): 2, ord("A"): 1, ord("0"): 1}

#: Junk put between frames by the ``garbage`` scenario, in turn.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    b"\x13\x37\x00\x7e",  # bytes without a phasing bit
    b"\x81\x01\x02",  # a record cut short (the next phasing bit comes too early)
    b"\x85" + b"\x00" * 13 + b"\x7f",  # a framed record from an address no bird has
    b"\x80" + b"\x00" * 13 + b"\x01",  # a framed record with a zero quaternion
    b"\xff\xfe\xfd",  # a run of phasing bits
)

Sample = tuple[int, tuple[float, float, float], tuple[float, float, float]]


def encode_word(value: float) -> bytes:
    """A number in [-1, 1) as a 14-bit word: low byte first, 7 bits each."""
    raw = max(-32768, min(32767, round(value * 32768))) & 0xFFFF
    return bytes(((raw >> 2) & 0x7F, (raw >> 9) & 0x7F))


def euler_quaternion(azimuth: float, elevation: float, roll: float) -> tuple[float, ...]:
    """(w, x, y, z) of the rotation Rz(azimuth) Ry(elevation) Rx(roll), degrees."""
    hz, hy, hx = (math.radians(a) / 2 for a in (azimuth, elevation, roll))
    cz, sz, cy, sy, cx, sx = (
        math.cos(hz),
        math.sin(hz),
        math.cos(hy),
        math.sin(hy),
        math.cos(hx),
        math.sin(hx),
    )
    return (
        cz * cy * cx + sz * sy * sx,
        cz * cy * sx - sz * sy * cx,
        cz * sy * cx + sz * cy * sx,
        sz * cy * cx - cz * sy * sx,
    )


def encode_record(
    fmt: int,
    position_feet: tuple[float, float, float],
    angles: tuple[float, float, float],
    scale_feet: float,
    address: int | None = None,
) -> bytes:
    """One sensor record (with its address byte in group mode, ``address`` not None)."""
    words = [v / scale_feet for v in position_feet]
    if fmt == ord("Y"):
        words += [a / 180.0 for a in angles]
    else:
        # the quaternion of the sensor's orientation, as the manual's Shepperd extraction
        # from its MATRIX output gives it (no conjugate)
        words += list(euler_quaternion(*angles))
    data = bytearray(b"".join(encode_word(v) for v in words))
    data[0] |= 0x80  # the phasing bit
    if address is not None:
        data.append(address)
    return bytes(data)


def pose(scenario: str, bird: int, step: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Position (feet) and azimuth, elevation, roll (degrees) of bird ``bird`` (0-based)."""
    base = (1.0 + 0.5 * bird, -0.5 * bird, 0.8)
    if scenario == "buttons":
        return base, (90.0 * (step // 20 % 4) - 180.0, 10.0, -20.0)
    if scenario not in ("motion", "garbage"):
        return base, (20.0 * (bird + 1), -10.0, 5.0)
    t = step / 40.0 + bird
    return (
        (base[0] + 0.5 * math.cos(t), base[1] + 0.5 * math.sin(t), base[2] + 0.2 * math.sin(2 * t)),
        ((step * 2.0) % 360.0 - 180.0, 40.0 * math.sin(t), 60.0 * math.cos(t)),
    )


class FlockEmulator(PtyDeviceEmulator):
    """The flock side on a pty pair. ``address`` is the slave's path once started; ``link``
    optionally a symlink to it. ``sent`` records each valid record as ``(bird, position in
    feet, angles)``, bird counted from 0 in address order."""

    DEVICE = "Flock"
    SETTLE = QUIET

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 144.0,
        *,
        birds: int = 2,
        master: int = 1,
        extended_range: bool = False,
        scale_inches: int = 36,
        disconnect_after: int = 40,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        if master == 0 and (birds != 1 or extended_range):
            raise ValueError("a standalone bird (master 0) is one bird with its own transmitter")
        # A streaming device's last frame may still be in the line: stop() lets the reader
        # drain it (at most ``linger`` seconds) before the pty goes away with it.
        super().__init__(
            scenario,
            rate,
            disconnect_after=disconnect_after,
            linger=linger,
            link=link,
            drain=linger,
        )
        self.master = master
        self.birds = birds
        self.extended_range = extended_range
        self.scale_feet = 12.0 if extended_range else scale_inches / 12.0
        self.scale_inches = scale_inches
        first = 2 if extended_range else 1
        #: FBB address of each bird with a sensor (0 for a standalone bird)
        self.bird_addresses = [0] if master == 0 else list(range(first, first + birds))
        self.formats: dict[int, int] = {}
        self.hemispheres: dict[int, bytes] = {}
        self.group = False
        self.auto_configured = 0
        self.report_rate = "Q"
        #: (FBB address of the prefix before it or None, command) for every command
        self.addressed: list[tuple[int | None, bytes]] = []
        self.sent: list[Sample] = []
        self.frames = 0
        self._prefix: int | None = None
        self._pending: bytearray = bytearray()
        self._needed = 0
        self._points = 0

    def draining(self) -> bool:
        return not self.all_read()

    def sending(self) -> bool:
        return self.streaming.is_set() or self._points > 0

    # -- device behaviour -----------------------------------------------------------------------

    def on_byte(self, value: int) -> None:
        if self._needed:
            self._pending.append(value)
            self._needed -= 1
            if not self._needed:
                self._on_command(bytes(self._pending))
                self._pending.clear()
            return
        if value >= 0xF0:
            self._prefix = value - 0xF0
            return
        if 0xE0 <= value < 0xF0:
            self._prefix = value - 0xE0 + 16
            return
        if value == 0xA0:
            self._pending, self._needed = bytearray(b"\xa0"), 1
            return
        needed = ARGUMENTS.get(value, 0)
        if value == ord("O"):
            needed = 1
        elif value == ord("P"):
            needed = 2  # every change value used here carries one data byte
        if needed:
            self._pending, self._needed = bytearray((value,)), needed
            return
        self._on_command(bytes((value,)))

    def _on_command(self, command: bytes) -> None:
        if command[0] == 0xA0:
            self._prefix = command[1]
            return
        self.commands.append(command)
        target = self._prefix
        self._prefix = None
        self.addressed.append((target, command))
        op = command[0]
        if op == ord("O"):
            self.write(self._examine(command[1], target))
        elif op == ord("P"):
            if command[1] == 0x23:
                self.group = bool(command[2])
            elif command[1] == 0x32:
                self.auto_configured = command[2]
        elif op == ord("L"):
            for address in self._targets(target):
                self.hemispheres[address] = command[1:3]
        elif op in FORMAT_WORDS:
            for address in self._targets(target):
                self.formats[address] = op
        elif chr(op) in "QRST":
            self.report_rate = chr(op)
        elif op == ord("@"):
            self.begin_sending()
        elif op == ord("?"):
            self.streaming.clear()
        elif op == ord("B"):
            self._points += 1
            now = time.monotonic()
            self._next_due = min(self._next_due, now) if self.streaming.is_set() else now

    def _targets(self, target: int | None) -> list[int]:
        return self.bird_addresses if target is None else [target]

    def _examine(self, param: int, target: int | None) -> bytes:
        standalone = self.master == 0
        if param == 0x00:
            master = target in (None, self.master)
            return struct.pack("<H", 0x4000 | 0x1000 | (0x8000 if master else 0))
        if param == 0x01:
            return bytes((3, 67))
        if param == 0x03:
            # a word, low byte first (Ascension's EXAMINE VALUE): 0 36 inches, 1 72 inches
            return bytes((0 if self.scale_inches == 36 else 1, 0))
        if param == 0x0A:
            return b"\x00"
        if param == 0x0F:
            return MODEL
        if param == 0x10:
            return b"\x00\x00"
        if param == 0x13:
            return b"\x00"
        if param == 0x15:
            return bytes((0 if standalone else self.master,))
        if param == 0x24:
            status = bytearray(14)
            if self.extended_range:
                status[0] = 0x80 | 0x40 | 0x10 | 0x01  # the extended range controller
            for address in self.bird_addresses:
                transmitter = 0x01 if address == 1 else 0x00
                status[address - 1] = 0x80 | 0x40 | 0x20 | transmitter
            return bytes(status)
        return b"\x00"

    def emit(self) -> None:
        """One frame: a record of every bird."""
        if self._points and not self.streaming.is_set():
            self._points -= 1
        else:
            self._points = 0
        if self.scenario == "disconnect" and self.frames >= self.disconnect_after:
            self.hang_up_once_read()
            return
        step = self.frames
        self.frames += 1
        group = self.master != 0 and self.group
        out = bytearray()
        for bird, address in enumerate(self.bird_addresses):
            position, angles = pose(self.scenario, bird, step)
            if self.scenario == "garbage":
                out += GARBAGE_CHUNKS[(step + bird) % len(GARBAGE_CHUNKS)]
            fmt = self.formats.get(address, ord("Y"))  # PosAngles at power-up
            out += encode_record(fmt, position, angles, self.scale_feet, address if group else None)
            self.sent.append((bird, position, angles))
        self.write(bytes(out))


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = pty_parser(
        "Flock_drv.emulator",
        "Emulate an Ascension Flock of Birds on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=144.0,
        rate_help="frames (one record per bird) per second",
        disconnect_after=40,
        disconnect_help="frames before hang-up",
    )
    parser.add_argument("--birds", type=int, default=2, help="birds with a sensor (default 2)")
    parser.add_argument("--standalone", action="store_true", help="one bird, no FBB (master 0)")
    parser.add_argument(
        "--extended-range",
        action="store_true",
        help="an extended range transmitter controller at address 1",
    )
    args = parser.parse_args(argv)
    emulator = FlockEmulator(
        args.scenario,
        args.rate,
        birds=1 if args.standalone else args.birds,
        master=0 if args.standalone else 1,
        extended_range=args.extended_range,
        disconnect_after=args.disconnect_after,
        link=args.port or None,
    )
    return run_pty(
        emulator,
        title="Flock of Birds",
        element="flock",
        duration=args.duration,
        detail=f"{len(emulator.bird_addresses)} birds",
    )


if __name__ == "__main__":
    sys.exit(main())
