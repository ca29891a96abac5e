"""5DT DataGlove (the serial "Data Glove 5") protocol, independent of gadgetctl's input manager
(it uses only :mod:`gadgetctl.transport.serialline`).

Packets, at the configured speed (38400 baud by default), 8 data bits: ``0x80``, then thumb,
index, middle, ring and pinky flexure (0..255), pitch and roll (0..255 over 0..180 degrees)
and a checksum (the XOR of those seven bytes): 9 bytes, the manual's length as VRPN quotes it.
Many gloves add a 10th byte, whatever its value (VRPN ``vrpn_Analog_5dt.C``, VR Juggler
``DataGloveStandalone.cpp``): 0x00 (right) or 0x06 (left) as VR Juggler reads it, 0x01 (right)
or 0x40 (left) from the wireless kind VRPN handles, 0x55 seen from wired gloves. This driver
accepts every one of them, and 9-byte packets: the byte after a good checksum is the packet's
10th byte unless it is the next header (0x80, which no 10th byte is), so a packet is complete
once that byte is known (or the line goes quiet after it).

Start (VRPN's wired glove, which streams only when asked): ``A`` (the glove answers 0x55),
``G`` (32 bytes of information: ``B``, ``R``, version, bit 0 of byte 4 set for a right hand,
bit 4 of byte 5 for pitch and roll, the name from byte 16), ``D`` (stream). A glove that streams
anyway (the wireless kind, which ignores requests, or one left streaming) is taken as it is:
packets arriving after ``A`` end the start.

A packet whose checksum is wrong is not a packet: the decoder looks for the next ``0x80``
after its header, and every byte it passes over is counted in ``skipped_bytes``; each run of
such bytes between two good packets is one bad record, so junk costs one count per run, never
a fault, and the buffer never holds more than a packet.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

HEADER = 0x80
PACKET_SIZE = 9  # the manual's; many gloves add a 10th byte
LONG_PACKET_SIZE = 10
DATA_BYTES = 7
#: The 10th byte as VR Juggler reads it (its analog unit 8): 0 a right glove, 6 a left one.
RIGHT, LEFT = 0, 6
#: The 10th byte of VRPN's wireless kind: 0x01 a right glove, 0x40 a left one.
WIRELESS_RIGHT, WIRELESS_LEFT = 0x01, 0x40
#: The glove's answer to ``A`` (and a 10th byte VRPN saw from wired gloves).
ACK = 0x55
INIT, INFO, STREAM = b"A", b"G", b"D"
INFO_SIZE = 32
FINGERS = ("thumb", "index", "middle", "ring", "pinky")
#: Gestures the C++ driver numbers from the index..pinky flexures (0.5 for the index, middle
#: and ring fingers, 0.35 for the pinky); 16 is "none of them".
NO_GESTURE = 16


class DataGloveError(Exception):
    """Base class of the driver's errors."""


class DataGloveDisconnected(DataGloveError, SerialLineLost):
    """The serial line is gone; reopen to recover."""


class DataGloveNoAnswer(DataGloveError, TimeoutError):
    """The glove neither answered the start commands nor streamed."""


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
    number and the capability: the packet's 10th byte, or for a 9-byte packet the hand the
    glove's information gave in VR Juggler's values (0 right, 6 left; 0 when unknown)."""

    flexure: tuple[float, ...]
    pitch: float
    roll: float
    gesture: int
    capability: int

    @property
    def hand(self) -> str:
        return "left" if self.capability in (LEFT, WIRELESS_LEFT) else "right"

    @property
    def analog(self) -> tuple[float, ...]:
        """Analog units 0..8 as the C++ driver fills them."""
        return (*self.flexure, self.pitch, self.roll, float(self.gesture), float(self.capability))


def decode_packet(packet: bytes, capability: int = RIGHT) -> GloveSample | None:
    """A 9- or 10-byte packet (header included; a 10th byte is its capability, else
    ``capability``); None unless the header and the checksum hold (any 10th byte but a
    header does: real gloves send 0x00, 0x06, 0x01, 0x40 and 0x55 there)."""
    if len(packet) not in (PACKET_SIZE, LONG_PACKET_SIZE) or packet[0] != HEADER:
        return None
    data = packet[1 : 1 + DATA_BYTES]
    # The C++ driver returns "true" (an error) on a good checksum and its wrapper adds data
    # only then, so it keeps exactly the corrupt packets. Here a packet counts when the
    # checksum matches.
    if checksum(data) != packet[8]:
        return None
    if len(packet) == LONG_PACKET_SIZE:
        if packet[9] == HEADER:
            return None
        capability = packet[9]
    flexure = tuple(b / 255.0 for b in data[:5])
    return GloveSample(
        flexure=flexure,
        pitch=180.0 * data[5] / 255.0,
        roll=180.0 * data[6] / 255.0,
        gesture=gesture(*flexure[1:]),
        capability=capability,
    )


@dataclass
class PacketScanner(ResyncScanner[GloveSample]):
    """Finds packets of 9 or 10 bytes in a byte stream, bounded: ``records`` decoded,
    ``bad_records`` runs of junk between them, ``skipped_bytes`` the bytes of those runs.
    ``capability`` stands in for the 10th byte of 9-byte packets. A packet whose checksum
    holds waits for the byte after it (a 10th byte, or the next header), unless ``quiet``."""

    HEAD = bytes([HEADER])
    SIZE = PACKET_SIZE

    capability: int = RIGHT

    def decode(self, record: bytes) -> GloveSample | None:
        return decode_packet(record, self.capability)

    def complete(
        self, record: GloveSample, buffer: bytearray, end: int, quiet: bool
    ) -> tuple[GloveSample, int] | None:
        """The byte after a 9-byte packet is its 10th unless it is the next header."""
        if end == len(buffer):
            return (record, 0) if quiet else None  # is a 10th byte coming?
        if buffer[end] == HEADER:
            return record, 0
        return replace(record, capability=buffer[end]), 1


@dataclass(frozen=True)
class GloveInfo:
    """The answer to ``G``: version, hand, whether pitch and roll are fitted, and the name."""

    version: tuple[int, int]
    right: bool
    pitch_roll: bool
    name: str


def decode_info(reply: bytes) -> GloveInfo | None:
    """The 32-byte answer to ``G`` (as VRPN reads it); None unless it starts ``BR``."""
    if len(reply) != INFO_SIZE or reply[:2] != b"BR":
        return None
    name = reply[16:].split(b"\0", 1)[0].decode("latin-1").strip()
    return GloveInfo((reply[2], reply[3]), bool(reply[4] & 1), bool(reply[5] & 16), name)


class DataGlove(ScannedDevice):
    """A 5DT DataGlove on a serial line. ``sample_timeout`` bounds one :meth:`poll`;
    ``reply_timeout`` each wait for an answer at the start (VRPN's 2 s); ``info`` is the
    glove's answer to ``G`` (None for a glove that streams without being asked)."""

    def __init__(
        self,
        port: object,
        baud: int = 38400,
        *,
        sample_timeout: float = 0.1,
        poll_interval: float = 0.01,
        reply_timeout: float = 2.0,
    ) -> None:
        self.line = SerialLine(port, LineSettings(baud=baud), poll_interval=poll_interval)  # type: ignore[arg-type]
        self.scanner = PacketScanner()
        self.sample_timeout = sample_timeout
        self.reply_timeout = reply_timeout
        self.info: GloveInfo | None = None
        self._early: list[GloveSample] = []

    def open(self) -> None:
        try:
            self.line.open()
            self._start()
        except SerialLineLost as exc:
            self.line.close()
            raise DataGloveDisconnected(str(exc)) from exc
        except BaseException:
            self.line.close()
            raise

    def _start(self) -> None:
        """``A``; a glove that streams already is taken as it is, one that answers 0x55 is
        asked ``G`` and ``D`` (VRPN's wired start)."""
        self.line.discard_input()
        self.line.write(INIT)
        got = self._wait(lambda got: len(got) >= 1)
        if got == bytes([ACK]):
            got += self.line.read(0.05)  # a lone 0x55 is the answer; more is a stream
        if got[:1] != bytes([ACK]) or len(got) > 1:
            # a 0x55 among packets is a 10th byte: the glove streams
            self._early = self.scanner.feed(got)
            if self._early or self._wait_more(got):
                return
            raise DataGloveNoAnswer(f"the glove answered A with {got[:16]!r}, not 0x55")
        self.line.discard_input()
        self.line.write(INFO)
        reply = self._wait(lambda got: len(got) >= INFO_SIZE)
        self.info = decode_info(reply[:INFO_SIZE])
        if self.info is None:
            raise DataGloveNoAnswer(
                f"the glove's answer to G is not its information: {reply[:16]!r}"
            )
        self.scanner.capability = RIGHT if self.info.right else LEFT
        self.line.write(STREAM)

    def _wait(self, enough: object) -> bytes:
        """Bytes read until ``enough(got)`` or ``reply_timeout``; raises when none came."""
        got = bytearray()
        deadline = time.monotonic() + self.reply_timeout
        while not enough(got):  # type: ignore[operator]
            left = deadline - time.monotonic()
            if left <= 0:
                break
            got += self.line.read(min(left, 0.05))
        if not got:
            raise DataGloveNoAnswer(
                f"no answer from the glove within {self.reply_timeout:g} s (is it on and plugged in?)"
            )
        return bytes(got)

    def _wait_more(self, got: bytes) -> bool:
        """After an unclear answer: whether packets follow within ``reply_timeout``."""
        deadline = time.monotonic() + self.reply_timeout
        while time.monotonic() < deadline:
            self._early = self.scanner.feed(self.line.read(0.05))
            if self._early:
                return True
        return False

    def poll(self) -> list[GloveSample]:
        """The packets that arrive within ``sample_timeout`` (every one, in order)."""
        try:
            data = self.line.read(self.sample_timeout)
        except SerialLineLost as exc:
            raise DataGloveDisconnected(str(exc)) from exc
        packets = self.scanner.feed(data, quiet=not data)
        if self._early:
            packets, self._early = self._early + packets, []
        return packets

    def close(self) -> None:
        self.line.close()
