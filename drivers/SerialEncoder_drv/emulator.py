"""Two US Digital encoders on an SEI bus behind a pseudo-terminal, independent of gadgetctl's
input manager (it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

Encoder 1 is a table's tilt (degrees) and encoder 2 its height (inches). Each read-position
command (``0x10 | address``) is answered with the command byte and the position as a
big-endian float; other addresses stay silent, as an empty bus address does.

``idle``        the table stands still (tilt 0, height 30 in)
``motion``      the table tilts (±30 degrees) and rises and falls (20..40 in)
``buttons``     the table steps between three preset positions (encoders have no buttons)
``garbage``     motion, with junk before replies, corrupt positions and unasked bytes
``disconnect``  ``disconnect_after`` answers, then the line is hung up
"""

from __future__ import annotations

import math
import os
import struct
import sys
import time

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

# The emulator keeps its own copy of the wire format so that a mistake in the driver cannot be
# mirrored here and go unnoticed by the tests.
SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-encoder"
TILT, HEIGHT = 1, 2
PRESETS = ((0.0, 30.0), (15.0, 36.0), (-20.0, 24.5))
#: Junk of the ``garbage`` scenario: never the command bytes 0x11 / 0x12 themselves.
JUNK = (b"\x00\x7f", b"\xff" * 7, b"\x13\x10\x20")
NAN = b"\x7f\xc0\x00\x00"


def encode_reply(address: int, value: float) -> bytes:
    return bytes([0x10 | address]) + struct.pack(">f", value)


def table_position(scenario: str, step: int) -> tuple[float, float]:
    """(tilt degrees, height inches) of a step, as float32 values."""
    if scenario == "idle":
        tilt, height = 0.0, 30.0
    elif scenario == "buttons":
        tilt, height = PRESETS[step // 5 % len(PRESETS)]
    else:
        tilt, height = 30.0 * math.sin(step / 15), 30.0 + 10.0 * math.sin(step / 23)
    as_f32 = struct.Struct(">f")
    return tuple(as_f32.unpack(as_f32.pack(v))[0] for v in (tilt, height))  # type: ignore[return-value]


class SerialEncoderEmulator(PtyDeviceEmulator):
    """The encoders' side of the bus on a pty pair. ``rate`` caps answers per second;
    ``sent`` lists every good answer as ``(address, position)``."""

    DEVICE = "Encoder"
    READ_SIZE = 256

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 500.0,
        *,
        disconnect_after: int = 10,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        super().__init__(scenario, rate, disconnect_after=disconnect_after, link=link)
        self.sent: list[tuple[int, float]] = []
        self.commands: list[int] = []  # type: ignore[assignment]
        self._step = 0
        self._answers = 0

    def sending(self) -> bool:
        return False  # nothing is sent unasked: answers go out as the commands come

    def on_byte(self, value: int) -> None:
        """A command: answered at once (at most ``rate`` answers a second)."""
        self.commands.append(value)
        self.streaming.set()  # a driver is there
        if value & 0xF0 != 0x10 or (value & 0x0F) not in (TILT, HEIGHT):
            return  # nobody at that address
        if self.scenario == "disconnect" and self._answers >= self.disconnect_after:
            self.hang_up()
            return
        wait = self._next_due - time.monotonic()
        if wait > 0:
            self._stop.wait(wait)
        self._next_due = max(self._next_due, time.monotonic() - 0.05) + 1.0 / self.rate
        address = value & 0x0F
        scenario = "motion" if self.scenario in ("garbage", "disconnect") else self.scenario
        tilt, height = table_position(scenario, self._step)
        if address == HEIGHT:
            self._step += 1
        position = tilt if address == TILT else height
        self._answers += 1
        n = self._answers
        if self.scenario == "garbage" and n % 4 == 0:
            self.write(bytes([value]) + NAN)  # a corrupt position: not in ``sent``
            return
        junk = JUNK[n % len(JUNK)] if self.scenario == "garbage" and n % 4 == 1 else b""
        self.sent.append((address, position))
        self.write(junk + encode_reply(address, position))
        if self.scenario == "garbage" and n % 4 == 2:
            self.write(b"\x00\x01")  # unasked bytes after an answer


def main(argv: list[str] | None = None) -> int:
    parser = pty_parser(
        "SerialEncoder_drv.emulator",
        "Emulate two US Digital encoders (a table's tilt and height) on an SEI bus over a "
        "pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=500.0,
        rate_help="answers per second at most",
        disconnect_after=10,
        disconnect_help="answers before hang-up",
    )
    args = parser.parse_args(argv)
    emulator = SerialEncoderEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )
    return run_pty(emulator, title="SEI encoder", element="serial_encoder", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
