"""A SpaceMouse or SpaceBall puck on a pseudo-terminal, independent of gadgetctl's input manager
(it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

The emulator answers the start-up commands (version, mode, sensitivity, null radius, zero;
``@`` reset and the SpaceBall settings) and, once the mode is set, plays a scenario:

``idle``        nothing moves, nothing is sent
``motion``      the six axes follow slow sine waves (analog records); every eighth record
                a button press or release
``buttons``     buttons 1..12 are pressed and released in turn (button records)
``garbage``     motion and buttons with junk lines, overlong runs and broken records between
``disconnect``  ``disconnect_after`` records of motion, then the line is hung up
"""

from __future__ import annotations

import math
import os
import struct
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

# The emulator keeps its own copy of the wire format so that a mistake in the driver cannot be
# mirrored here and go unnoticed by the tests.
MODELS = ("SpaceMouse", "SpaceMouse Plus XT", "SpaceBall 2003B", "SpaceBall 4000 FLX")
SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-spaceball"
VERSION_MOUSE = b"v  MAGELLAN  Version 6.70  3Dconnexion GmbH 05/11/04"
VERSION_BALL = (
    b"@1 Spaceball alive and well after a reset.",
    b"@2 Firmware version 4.10 created on 10-Oct-2002",
)
#: Axis values of the first motion record: bytes that a SpaceBall must escape.
ESCAPE_AXES = (0x000D, 0x0011, 0x0013, 0x005E, 0x0D0D, -0x0D0D)
AMPLITUDE = {
    "SpaceMouse": 450,
    "SpaceMouse Plus XT": 450,
    "SpaceBall 2003B": 1800,
    "SpaceBall 4000 FLX": 1800,
}


def is_mouse(model: str) -> bool:
    return model.startswith("SpaceMouse")


def nibble(value: int) -> int:
    ones = bin(value).count("1")
    return (0x30 if ones % 2 == 0 else 0x40) | value


def encode_axes(model: str, axes: tuple[int, ...], timer: int = 0) -> bytes:
    """An analog record, CR included."""
    if is_mouse(model):
        body = b"".join(bytes(nibble((a + 32768) >> s & 0xF) for s in (12, 8, 4, 0)) for a in axes)
        return b"d" + body + b"\r"
    wire = list(axes)
    wire[2], wire[5] = -wire[2], -wire[5]  # the ball's z and roll point the other way
    body = struct.pack(">H6h", timer & 0xFFFF, *(max(-32768, min(32767, a)) for a in wire))
    return b"D" + escape(model, body) + b"\r"


def encode_buttons(model: str, buttons: tuple[int, ...], left_handed: bool = False) -> bytes:
    """A button record (buttons 1..12 as 0/1), CR included."""
    bits = sum(1 << k for k, b in enumerate(buttons) if b)
    if is_mouse(model):
        return b"k" + bytes(nibble(bits >> s & 0xF) for s in (0, 4, 8)) + b"\r"
    if model == "SpaceBall 2003B":
        body = bytes([0x40 | (bits >> 4 & 0x1F), 0x40 | (bits & 0x0F)])
        return b"K" + escape(model, body) + b"\r"
    first = 0x40 | (bits >> 7 & 0x1F) | (0x20 if left_handed else 0)
    second = 0x40 | (bits & 0x3F) | (bits >> 6 & 1) << 7
    return b"." + escape(model, bytes([first, second])) + b"\r"


def escape(model: str, body: bytes) -> bytes:
    """A SpaceBall's record body as it goes on the wire: CR, XON, XOFF as ``^M``, ``^Q``,
    ``^S`` and ``^`` as ``^^`` (every SpaceBall does it: VRPN ``vrpn_Spaceball.C`` and VR
    Juggler's ``puck_device.cpp`` unescape for each model, the 2003B included)."""
    if is_mouse(model):
        return body
    out = bytearray()
    for c in body:
        if c == 0x5E:
            out += b"^^"
        elif c in (0x0D, 0x11, 0x13):
            out += bytes([0x5E, c | 0x40])
        else:
            out.append(c)
    return bytes(out)


def motion_axes(model: str, step: int) -> tuple[int, ...]:
    if step == 0 and not is_mouse(model):
        return ESCAPE_AXES
    amp = AMPLITUDE[model]
    return tuple(round(amp * math.sin(step / 10 + axis)) for axis in range(6))


def button_pattern(step: int) -> tuple[int, ...]:
    """Button (step // 2) % 12 + 1 pressed on even steps, everything released on odd ones."""
    held = (step // 2) % 12 if step % 2 == 0 else -1
    return tuple(int(k == held) for k in range(12))


def garbage(model: str, step: int) -> bytes:
    """Junk between the good records: every kind of bad record in turn."""
    kind = step % 5
    if kind == 0:
        return b"hello?\r"  # a line no dialect has
    if kind == 1:
        return (b"d" if is_mouse(model) else b"D") * 200 + b"\r"  # an overlong run, then a CR
    if kind == 2:
        return b"d0000\r" if is_mouse(model) else b"D\x01\x02\r"  # a record cut short
    if kind == 3:
        return b"k\x01\x02\x03\r" if is_mouse(model) else b".\x00\x00\r"  # impossible bytes
    return b"\xff\xfe\x00\x0d"


class SpaceBallEmulator(PtyDeviceEmulator):
    """The puck's side of the line on a pty pair.

    ``rate`` is records per second; ``sent`` lists every good record sent as
    ``("axes", values)`` or ``("buttons", values)``; ``commands`` every command line received.
    """

    DEVICE = "SpaceBall"
    CATCH_UP = 0.05  # catch up at most a few records, never a burst after a stall

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 30.0,
        *,
        model: str = "SpaceMouse",
        disconnect_after: int = 5,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        if model not in MODELS:
            raise ValueError(f"unknown model {model!r}; choose from {', '.join(MODELS)}")
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link, drain=0.5
        )
        self.model = model
        self.sent: list[tuple[str, tuple[int, ...]]] = []
        self._line = bytearray()
        self._step = 0

    def on_bytes(self, data: bytes) -> None:
        self._line += data
        while b"\r" in self._line:
            line, _, rest = bytes(self._line).partition(b"\r")
            self._line = bytearray(rest)
            if line:
                self.commands.append(line)
                self._answer(line)

    def _answer(self, line: bytes) -> None:
        code = line[:1]
        if is_mouse(self.model):
            if line == b"vQ":
                self.write(VERSION_MOUSE + b"\r")
            elif code in (b"m", b"c", b"q", b"n", b"z", b"b"):
                self.write(line + b"\r")  # the puck echoes its settings
                if code in (b"m", b"c"):
                    self.begin_sending()
            else:
                self.write(b"eA" + bytes([nibble(line[0] >> 4), nibble(line[0] & 0xF)]) + b"\r")
            return
        if code == b"@":
            self.write(VERSION_BALL[0] + b"\r" + VERSION_BALL[1] + b"\r")
        elif code == b"M":
            self.begin_sending()

    def emit(self) -> None:
        step = self._step
        if self.scenario == "idle":
            return
        if self.scenario == "disconnect" and step >= self.disconnect_after:
            self.hang_up_once_read()  # a pty drops unread input on hang-up
            return
        self._step += 1
        tapping = self.scenario in ("motion", "garbage") and step % 8 == 7
        if self.scenario == "buttons" or tapping or (self.scenario == "garbage" and step % 3 == 2):
            buttons = button_pattern(step)
            if self.model == "SpaceBall 2003B":
                buttons = (*buttons[:9], 0, 0, 0)  # eight buttons and the pick button
            record = encode_buttons(self.model, buttons)
            self.sent.append(("buttons", buttons))
        else:
            axes = motion_axes(self.model, step)
            record = encode_axes(self.model, axes, timer=step)
            self.sent.append(("axes", axes))
        junk = garbage(self.model, step) if self.scenario == "garbage" else b""
        self.write(junk + record)


def main(argv: list[str] | None = None) -> int:
    parser = pty_parser(
        "SpaceBall_drv.emulator",
        "Emulate a 3Dconnexion SpaceMouse or SpaceBall on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=30.0,
        rate_help="records per second (9600 baud carries about 33 SpaceMouse motion records/s)",
        disconnect_after=5,
    )
    parser.add_argument("--model", choices=MODELS, default="SpaceMouse", help="puck dialect")
    args = parser.parse_args(argv)
    emulator = SpaceBallEmulator(
        args.scenario,
        args.rate,
        model=args.model,
        disconnect_after=args.disconnect_after,
        link=args.port or None,
    )
    return run_pty(emulator, title=args.model, element="puck_device", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
