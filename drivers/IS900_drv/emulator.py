"""An InterSense IS-900 on a pseudo-terminal, independent of gadgetctl's input manager (it
uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

It answers ``c``/``C`` (polled/continuous), ``MS`` (system record), ``f``/``F`` (binary/
ASCII), ``U``/``u`` (inches/centimetres), ``S`` (status record), ``l<st>,<0|1>`` (station
off/on), ``O<st>,<list>`` (output list; only ``2,4,40,22,23,1`` is spoken) and ``P`` (one
binary record per station that is on, at most ``rate`` polls answered per second).
Stations 1 and 2 (indices 0 and 1) are on at power-up: a wand with four buttons and a
two-axis joystick, and a head tracker. Scenarios:

``idle``        both stations hold still, no button pressed
``motion``      the wand circles, the head turns; no buttons
``buttons``     still poses; wand buttons press in turn, the joystick sweeps
``garbage``     motion, with junk and broken records before the records
``disconnect``  ``disconnect_after`` polls answered, then hang-up
"""

from __future__ import annotations

import math
import os
import random
import struct
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

# The emulator keeps its own copy of the wire layout, so a mistake in the driver is not
# mirrored here unnoticed.
STATION_CHARS = "123456789abcdefghijklmnopqrstuv"
OUTPUT_LIST = "2,4,40,22,23,1"
SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-is900"
PRODUCT_IS900 = "9"
FIRMWARE = "4.26  IS-900 gadgetctl emulator"

#: Junk put before records by the ``garbage`` scenario, in turn.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    b"\x13\x37\x00\x7e\xff",  # bytes outside any record
    b"0" + b"1" + b" " + b"\x00" * 10,  # a record cut short (no CR LF where it should be)
    b"0z " + b"\x00" * 28 + b"\r\n",  # a station no tracker has
    b"01 " + struct.pack("<3f", math.nan, 0.0, 0.0) + b"\x00" * 16 + b"\r\n",  # NaN position
    b"01 " + b"\x00" * 12 + struct.pack("<3f", 9999.0, 0.0, 0.0) + b"\x00" * 4 + b"\r\n",  # angle
    b"000000\r\n\r\n",  # a run of heads
)

Sample = tuple[int, tuple[float, float, float], tuple[float, float, float], int, tuple[int, int]]


def encode_record(
    station: int,
    position: tuple[float, float, float],
    euler: tuple[float, float, float],
    buttons: int = 0,
    analog: tuple[int, int] = (127, 127),
    tracking: int = 0,
) -> bytes:
    """A binary data record of station index ``station`` (position in the tracker's unit)."""
    return (
        b"0"
        + STATION_CHARS[station].encode("ascii")
        + b" "
        + struct.pack("<6fBBBB", *position, *euler, tracking, buttons & 0xFF, *analog)
        + b"\r\n"
    )


def pose(
    scenario: str, station: int, step: int
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Position (inches) and azimuth, elevation, roll (degrees) of a station at a step."""
    base = ((12.0, -6.0, 40.0), (0.0, 0.0, 66.0))[station % 2]
    if scenario not in ("motion", "garbage"):
        return base, (10.0 * (station + 1), -5.0, 2.5)
    t = step / 50.0
    x, y, z = base
    return (
        (x + 10.0 * math.cos(t), y + 10.0 * math.sin(t), z + 2.0 * math.sin(2 * t)),
        ((step * 3.0) % 360.0 - 180.0, 30.0 * math.sin(t), 15.0 * math.cos(t)),
    )


def controls(scenario: str, station: int, step: int) -> tuple[int, tuple[int, int]]:
    """Buttons (bit k = button k) and the two joystick bytes of a station at a step."""
    if scenario != "buttons" or station != 0:
        return 0, (127, 127)
    return 1 << (step // 5 % 4) if step % 10 < 5 else 0, (step * 7 % 256, 255 - step * 3 % 256)


class IS900Emulator(PtyDeviceEmulator):
    """The tracker side on a pty pair. ``address`` is the slave's path once started; ``link``
    optionally a symlink to it. ``sent`` records each valid record as ``(station, position in
    inches or centimetres, euler, buttons, analog)``. ``units`` is ``"inches"`` or
    ``"centimetres"`` at power-up."""

    DEVICE = "IS-900"

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 180.0,
        *,
        disconnect_after: int = 20,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
        units: str = "inches",
        stations_on: tuple[int, ...] = (0, 1),
        seed: int = 7,
    ) -> None:
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link
        )
        self.centimetres = units == "centimetres"
        self.binary = False
        self.continuous = True
        self.stations_on = set(stations_on)
        self.output_lists: dict[int, str] = {}
        self.sent: list[Sample] = []
        self.polls_answered = 0
        self._rng = random.Random(seed)
        self._line = bytearray()

    # -- device behaviour ---------------------------------------------------------------

    def on_byte(self, value: int) -> None:
        if self._line:  # a command that ends with CR LF
            self._line.append(value)
            if self._line.endswith(b"\r\n"):
                self._on_line(bytes(self._line[:-2]))
                self._line.clear()
            elif len(self._line) > 64:
                self._line.clear()
            return
        char = chr(value)
        if char in "OlM":
            self._line.append(value)
            return
        self.commands.append(bytes([value]))
        if char == "c":
            self.continuous = False
        elif char == "C":
            self.continuous = True
        elif char in "fF":
            self.binary = char == "f"
        elif char in "uU":
            self.centimetres = char == "u"
        elif char == "S":
            flags = int(self.binary) | int(self.centimetres) << 1 | int(self.continuous) << 3
            self.write(f"21S{flags:03X}000      {FIRMWARE:<38.38}\r\n".encode("ascii"))
        elif char == "P" and self.binary:
            self.begin_sending()  # polls asked while one is pending are answered once

    def _on_line(self, line: bytes) -> None:
        self.commands.append(line)
        text = line.decode("ascii", "replace")
        if text == "MS":
            self.write(f"31S{PRODUCT_IS900}IS-900 SimTracker\r\n".encode("ascii"))
        elif text.startswith("l") and text[2:] in (",0", ",1") and text[1] in STATION_CHARS:
            station = STATION_CHARS.index(text[1])
            (self.stations_on.add if text[3] == "1" else self.stations_on.discard)(station)
        elif text.startswith("O") and text[1:2] in tuple(STATION_CHARS) and text[2:3] == ",":
            self.output_lists[STATION_CHARS.index(text[1])] = text[3:]

    def emit(self) -> None:
        """Answer the poll waiting."""
        if self.scenario == "disconnect" and self.polls_answered >= self.disconnect_after:
            self.hang_up_once_read()  # the poll stays waiting until the line is hung up
            return
        self.streaming.clear()
        step = self.polls_answered
        self.polls_answered += 1
        scale = 2.54 if self.centimetres else 1.0
        out = bytearray()
        for station in sorted(self.stations_on):
            if self.output_lists.get(station, OUTPUT_LIST) != OUTPUT_LIST:
                continue  # a list this emulator does not speak
            (x, y, z), euler = pose(self.scenario, station, step)
            position = (x * scale, y * scale, z * scale)
            buttons, analog = controls(self.scenario, station, step)
            if self.scenario == "garbage":
                out += GARBAGE_CHUNKS[(step + station) % len(GARBAGE_CHUNKS)]
                out += bytes(self._rng.randrange(0x31, 0x100) for _ in range(step % 3))
            out += encode_record(station, position, euler, buttons, analog)
            self.sent.append((station, position, euler, buttons, analog))
        self.write(bytes(out))


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = pty_parser(
        "IS900_drv.emulator",
        "Emulate an InterSense IS-900 tracker on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=180.0,
        rate_help="polls answered per second at most",
        disconnect_after=20,
        disconnect_help="polls before hang-up",
    )
    parser.add_argument("--units", choices=("inches", "centimetres"), default="inches")
    args = parser.parse_args(argv)
    emulator = IS900Emulator(
        args.scenario,
        args.rate,
        disconnect_after=args.disconnect_after,
        link=args.port or None,
        units=args.units,
    )
    return run_pty(emulator, title="IS-900", element="intersense", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
