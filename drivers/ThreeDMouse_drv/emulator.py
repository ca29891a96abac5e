"""A Logitech 3D mouse / head tracker on a pseudo-terminal, independent of gadgetctl's input
manager (it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

It answers the two-byte commands ``*D``, ``*R``, ``*\\x05`` (diagnostics: ``0xBF 0x3F``),
``*H``, ``*h``, ``*G`` and ``*d`` (one 16-byte report, at most ``rate`` a second).
Scenarios:

``idle``        the mouse holds still, no button pressed
``motion``      it circles and turns about all three axes
``buttons``     still; left, middle and right buttons press in turn
``garbage``     motion, with junk and broken reports before the reports
``disconnect``  ``disconnect_after`` reports, then hang-up
"""

from __future__ import annotations

import math
import os
import random
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-3dmouse"
BUTTONS = (0x04, 0x02, 0x01)  # left, middle, right

#: Junk put before reports by the ``garbage`` scenario, in turn.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    b"\x13\x37\x00\x7e",  # 7-bit bytes outside any report
    b"\x80\x01\x02\x03",  # a report cut short by the next one
    b"\x80" + b"\x00" * 9 + b"\x7f\x7f" + b"\x00" * 4,  # an angle beyond a turn
    b"\xff\xfe\x90",  # flag bytes only
)

Sample = tuple[tuple[int, int, int], tuple[int, int, int], int]


def encode_report(
    position: tuple[int, int, int], angles: tuple[int, int, int], flags: int = 0
) -> bytes:
    """A report: position in thousandths of an inch, angles in fortieths of a degree."""
    out = bytearray([0x80 | (flags & 0x7F)])
    for value in position:
        raw = value & ((1 << 21) - 1)  # 21-bit two's complement
        out += bytes((raw >> 14 & 0x7F, raw >> 7 & 0x7F, raw & 0x7F))
    for value in angles:
        out += bytes((value >> 7 & 0x7F, value & 0x7F))
    return bytes(out)


def state(scenario: str, step: int) -> Sample:
    """Position (1/1000 inch), angles (1/40 degree) and flag bits at a step."""
    if scenario in ("motion", "garbage"):
        t = step / 25.0
        position = (
            round(4000 * math.cos(t)),
            round(-3000 + 4000 * math.sin(t)),
            round(12000 + 1500 * math.sin(2 * t)),
        )
        angles = (step * 40 % 14400, (step * 80 + 3600) % 14400, (7200 + step * 120) % 14400)
        return position, angles, 0
    flags = BUTTONS[step // 3 % 3] if scenario == "buttons" and step % 6 < 3 else 0
    return (1500, -2500, 9000), (40 * 30, 40 * 45, 40 * 60), flags


class ThreeDMouseEmulator(PtyDeviceEmulator):
    """The mouse side on a pty pair. ``sent`` records each valid report as ``(position in
    1/1000 inch, angles in 1/40 degree, flag bits)``."""

    DEVICE = "3D-mouse"

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 100.0,
        *,
        disconnect_after: int = 20,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
        diagnostic: bytes = b"\xbf\x3f",
        seed: int = 7,
    ) -> None:
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link
        )
        self.diagnostic = diagnostic
        self.sent: list[Sample] = []
        self._rng = random.Random(seed)
        self._pending: int | None = None

    def on_byte(self, value: int) -> None:
        if self._pending is None:
            if value == ord("*"):
                self._pending = value
            return
        self._pending = None
        self.commands.append(b"*" + bytes([value]))
        if value == 0x05:
            self.write(self.diagnostic)
        elif value == ord("d"):
            self.begin_sending()

    def emit(self) -> None:
        """Answer the poll waiting with one report."""
        count = len(self.sent)
        if self.scenario == "disconnect" and count >= self.disconnect_after:
            self.hang_up_once_read()  # the poll stays waiting until the line is hung up
            return
        self.streaming.clear()
        sample = state(self.scenario, count)
        junk = b""
        if self.scenario == "garbage":
            junk = GARBAGE_CHUNKS[count % len(GARBAGE_CHUNKS)]
            junk += bytes(self._rng.randrange(0x00, 0x80) for _ in range(count % 3))
        self.sent.append(sample)
        self.write(junk + encode_report(*sample))


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = pty_parser(
        "ThreeDMouse_drv.emulator",
        "Emulate a Logitech 3D mouse / head tracker on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=100.0,
        rate_help="reports per second at most",
        disconnect_after=20,
        disconnect_help="reports before hang-up",
    )
    args = parser.parse_args(argv)
    emulator = ThreeDMouseEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )
    return run_pty(emulator, title="3D mouse", element="three_d_mouse", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
