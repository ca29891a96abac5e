"""5DT DataGlove (the serial "Data Glove 5") protocol, independent of gadgetctl's input manager
(it uses only :mod:`gadgetctl.transport.serialline`).

The glove streams 10-byte packets at the configured speed (38400 baud by default), 8 data
bits: ``0x80``, then thumb, index, middle, ring and pinky flexure (0..255), pitch and roll
(0..255 over 0..180 degrees), a checksum (the XOR of those seven bytes) and the capability
byte (0 a right glove, 6 a left one). The host sends nothing.

A packet whose checksum or capability byte is wrong is not a packet: the decoder looks for
the next ``0x80`` after its header, and every byte it passes over is counted in
``skipped_bytes``; each run of such bytes between two good packets is one bad record, so
junk costs one count per run, never a fault, and the buffer never holds more than a packet.
"""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

HEADER = 0x80
PACKET_SIZE = 10
DATA_BYTES = 7
RIGHT, LEFT = 0, 6
CAPABILITIES = (RIGHT, LEFT)
FINGERS = ("thumb", "index", "middle", "ring", "pinky")
#: Gestures the C++ driver numbers from the index..pinky flexures (0.5 for the index, middle
#: and ring fingers, 0.35 for the pinky); 16 is "none of them".
NO_GESTURE = 16


class DataGloveError(Exception):
    """Base class of the driver's errors."""


class DataGloveDisconnected(DataGloveError, SerialLineLost):
    """The serial line is gone; reopen to recover."""


def checksum(data: bytes) -> int:
    value = 0
    for byte in data:
        value ^= byte
    return value


def gesture(index: float, middle: float, ring: float, pinky: float) -> int:
    """The C++ driver's gesture number: bits of the index, middle and ring fingers being open
    (below 0.5), plus 8 when the pinky is open (below 0.35); 16 on a threshold exactly."""
    if 0.5 in (index, middle, ring) or pinky == 0.35:
        return NO_GESTURE
    number = (index < 0.5) | (middle < 0.5) << 1 | (ring < 0.5) << 2 | (pinky < 0.35) << 3
    return _GESTURES.get(number, NO_GESTURE)


# The C++ table, by (index open, middle open, ring open, pinky open) bits. Its test for 6
# repeats the one for 4 and its test for 11 the one for 9, so 6 and 11 never happen.
_GESTURES = {
    0b0000: 0,
    0b0001: 1,
    0b0010: 2,
    0b0011: 3,
    0b0110: 4,
    0b0101: 5,
    0b0111: 7,
    0b1000: 8,
    0b1011: 9,
    0b1010: 10,
    0b1100: 12,
    0b1101: 13,
    0b1110: 14,
    0b1111: 15,
}


@dataclass(frozen=True)
class GloveSample:
    """One packet: flexures 0..1 (thumb..pinky), pitch and roll in degrees 0..180, the gesture
    number and the capability byte (0 right, 6 left)."""

    flexure: tuple[float, ...]
    pitch: float
    roll: float
    gesture: int
    capability: int

    @property
    def hand(self) -> str:
        return "left" if self.capability == LEFT else "right"

    @property
    def analog(self) -> tuple[float, ...]:
        """Analog units 0..8 as the C++ driver fills them."""
        return (*self.flexure, self.pitch, self.roll, float(self.gesture), float(self.capability))


def decode_packet(packet: bytes) -> GloveSample | None:
    """A 10-byte packet (header included); None unless header, checksum and capability hold."""
    if len(packet) != PACKET_SIZE or packet[0] != HEADER:
        return None
    data = packet[1 : 1 + DATA_BYTES]
    # The C++ driver returns "true" (an error) on a good checksum and its wrapper adds data
    # only then, so it keeps exactly the corrupt packets. Here a packet counts when the
    # checksum matches.
    if checksum(data) != packet[8] or packet[9] not in CAPABILITIES:
        return None
    flexure = tuple(b / 255.0 for b in data[:5])
    return GloveSample(
        flexure=flexure,
        pitch=180.0 * data[5] / 255.0,
        roll=180.0 * data[6] / 255.0,
        gesture=gesture(*flexure[1:]),
        capability=packet[9],
    )


@dataclass
class PacketScanner(ResyncScanner[GloveSample]):
    """Finds packets in a byte stream, bounded: ``records`` decoded, ``bad_records`` runs of
    junk between them, ``skipped_bytes`` the bytes of those runs."""

    HEAD = HEADER
    SIZE = PACKET_SIZE

    def decode(self, record: bytes) -> GloveSample | None:
        return decode_packet(record)


class DataGlove(ScannedDevice):
    """A 5DT DataGlove on a serial line. ``sample_timeout`` bounds one :meth:`poll`."""

    def __init__(
        self,
        port: object,
        baud: int = 38400,
        *,
        sample_timeout: float = 0.1,
        poll_interval: float = 0.01,
    ) -> None:
        self.line = SerialLine(port, LineSettings(baud=baud), poll_interval=poll_interval)  # type: ignore[arg-type]
        self.scanner = PacketScanner()
        self.sample_timeout = sample_timeout

    def open(self) -> None:
        try:
            self.line.open()
        except SerialLineLost as exc:
            raise DataGloveDisconnected(str(exc)) from exc

    def poll(self) -> list[GloveSample]:
        """The packets that arrive within ``sample_timeout`` (every one, in order)."""
        try:
            return self.scanner.feed(self.line.read(self.sample_timeout))
        except SerialLineLost as exc:
            raise DataGloveDisconnected(str(exc)) from exc

    def close(self) -> None:
        self.line.close()
