"""A Polhemus Fastrak on a pseudo-terminal, independent of gadgetctl's input manager (it uses
only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

It answers ``c``/``C`` (continuous off/on), ``f``/``F`` (binary/ASCII), ``u``/``U``
(centimetres/inches), ``O<st>,<list>\\r`` (only ``2,11,16,1`` is spoken), ``H<st>,x,y,z\\r``,
``e<st>,<0|1>\\r``, ``l1\\r`` (station status) and ``S`` (status record). With continuous
output on, it streams ``rate`` binary records per second, the active stations (1 and 2, a
stylus on station 1) in turn, as the tracker multiplexes them. Scenarios:

``idle``        the stations hold still, stylus released
``motion``      station 1 circles and turns about z, station 2 tilts
``buttons``     still poses; the stylus presses and releases
``garbage``     motion, with junk and broken records before the records
``disconnect``  ``disconnect_after`` records, then hang-up
"""

from __future__ import annotations

import math
import os
import random
import struct
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

OUTPUT_LIST = "2,11,16,1"
SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-fastrak"
VERSION = "3.0GC "
SYSTEM_ID = "Fastrak gadgetctl emulator"

#: Junk put before records by the ``garbage`` scenario, in turn.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    b"\x13\x37\x00\x7e\xff",  # bytes outside any record
    b"01 " + b"\x00" * 12,  # a record cut short
    b"05 " + struct.pack("<7f", 0, 0, 0, 1, 0, 0, 0) + b" 0\r\n",  # station 5: no such station
    b"01 " + struct.pack("<7f", math.inf, 0, 0, 1, 0, 0, 0) + b" 0\r\n",  # infinite position
    b"01 " + struct.pack("<7f", 0, 0, 0, 2, 0, 0, 0) + b" 0\r\n",  # not a unit quaternion
    b"01 " + struct.pack("<7f", 0, 0, 0, 1, 0, 0, 0) + b" 7\r\n",  # a stylus byte not 0/1
    b"0000\r\n\r\n",  # a run of heads
)

Sample = tuple[int, tuple[float, float, float], tuple[float, float, float, float], int]


def encode_record(
    station: int,
    position: tuple[float, float, float],
    quaternion: tuple[float, float, float, float],
    stylus: int = 0,
) -> bytes:
    """A binary record of station 1..4 (position in the tracker's unit, quaternion w,x,y,z)."""
    return (
        b"0"
        + str(station).encode("ascii")
        + b" "
        + struct.pack("<7f", *position, *quaternion)
        + b" "
        + (b"1" if stylus else b"0")
        + b"\r\n"
    )


def about(axis: tuple[float, float, float], degrees: float) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z) of a rotation about a unit axis."""
    half = math.radians(degrees) / 2
    s = math.sin(half)
    return (math.cos(half), axis[0] * s, axis[1] * s, axis[2] * s)


def pose(
    scenario: str, station: int, step: int
) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """Position (inches) and quaternion of a station at a step."""
    base = (10.0 * station, 5.0, -8.0)
    if scenario not in ("motion", "garbage"):
        return base, about((0.0, 0.0, 1.0), 30.0 * station)
    t = step / 40.0
    if station == 1:
        return (base[0] + 6 * math.cos(t), base[1] + 6 * math.sin(t), base[2]), about(
            (0, 0, 1), step * 2.0 % 360
        )
    return (base[0], base[1], base[2] + 2 * math.sin(t)), about((1.0, 0.0, 0.0), 40 * math.sin(t))


def stylus(scenario: str, station: int, step: int) -> int:
    return int(scenario == "buttons" and station == 1 and step // 4 % 2 == 1)


class FastrakEmulator(PtyDeviceEmulator):
    """The tracker side on a pty pair. ``rate`` is records per second (all stations together).
    ``sent`` records each valid record as ``(station, position in the unit set, quaternion,
    stylus)``."""

    DEVICE = "Fastrak"
    BURST = 16  # several records when the loop fell behind, so the rate holds on a busy machine
    CATCH_UP = math.inf

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 120.0,
        *,
        disconnect_after: int = 20,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
        active: tuple[int, ...] = (1, 2),
        seed: int = 7,
    ) -> None:
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link
        )
        self.active = tuple(sorted(active))
        self.binary = False
        self.centimetres = False
        self.output_lists: dict[int, str] = {}
        self.hemispheres: dict[int, str] = {}
        self.stylus_modes: dict[int, str] = {}
        self.sent: list[Sample] = []
        self._rng = random.Random(seed)
        self._line = bytearray()

    @property
    def continuous(self) -> bool:
        return self.streaming.is_set()

    # -- device behaviour ---------------------------------------------------------------

    def on_byte(self, value: int) -> None:
        if self._line:
            if value == ord("\r"):
                self._on_line(bytes(self._line))
                self._line.clear()
            elif len(self._line) < 64:
                self._line.append(value)
            else:
                self._line.clear()
            return
        char = chr(value)
        if char in "OHel":
            self._line.append(value)
            return
        self.commands.append(bytes([value]))
        if char == "c":
            self.streaming.clear()
        elif char == "C" and self.binary:
            self.begin_sending()
        elif char in "fF":
            self.binary = char == "f"
        elif char in "uU":
            self.centimetres = char == "u"
        elif char == "S":
            flags = int(self.binary) | int(self.centimetres) << 1 | int(self.continuous) << 3
            text = f"21S{flags:03X}000      {VERSION:6.6}{SYSTEM_ID:<32.32}".encode("ascii")
            self.write(text + b"\r\n")

    def _on_line(self, line: bytes) -> None:
        self.commands.append(line)
        text = line.decode("ascii", "replace")
        head, rest = text[:1], text[1:]
        station, _, value = rest.partition(",")
        if head == "l" and rest == "1":
            flags = "".join("1" if s in self.active else "0" for s in range(1, 5))
            self.write(f"21l{flags}\r\n".encode("ascii"))
        elif head == "O" and station.isdigit():
            self.output_lists[int(station)] = value
        elif head == "H" and station.isdigit():
            self.hemispheres[int(station)] = value
        elif head == "e" and station.isdigit():
            self.stylus_modes[int(station)] = value

    def emit(self) -> None:
        count = len(self.sent)
        if self.scenario == "disconnect" and count >= self.disconnect_after:
            self.hang_up_once_read()
            return
        if not self.active:
            return
        station = self.active[count % len(self.active)]
        if self.output_lists.get(station, OUTPUT_LIST) != OUTPUT_LIST:
            return
        step = count // len(self.active)
        (x, y, z), quaternion = pose(self.scenario, station, step)
        scale = 2.54 if self.centimetres else 1.0
        position = (x * scale, y * scale, z * scale)
        button = stylus(self.scenario, station, step)
        junk = b""
        if self.scenario == "garbage":
            junk = GARBAGE_CHUNKS[count % len(GARBAGE_CHUNKS)]
            junk += bytes(self._rng.randrange(0x31, 0x100) for _ in range(count % 3))
        self.sent.append((station, position, quaternion, button))
        self.write(junk + encode_record(station, position, quaternion, button))


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = pty_parser(
        "Fastrak_drv.emulator",
        "Emulate a Polhemus Fastrak tracker on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=120.0,
        rate_help="records per second, all stations together",
        disconnect_after=20,
    )
    args = parser.parse_args(argv)
    emulator = FastrakEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )
    return run_pty(emulator, title="Fastrak", element="fastrak", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
