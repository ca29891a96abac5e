"""Immersion Interface Box (HCI protocol), independent of gadgetctl's input manager.

Start: ``END`` (ends a session left open), then ``IMMC`` until the box echoes it, then
``BEGIN``, answered by a NUL-ended product id. Info commands 0xC8..0xCE (product name, id,
model, serial number, comment, parameter format, version) are echoed, then answered by a
NUL-ended string.

Data: a standard query byte (bit 7 clear) asks for a packet: bit 0x20 the timer, bits 0x0C the
analog count (0x04: 2, 0x08: 4, 0x0C: 8), bits 0x03 the encoder count (1: 2, 2: 3, 3: 6). The
box answers with the query byte with bit 7 set, one button byte (bits 0..6 = buttons 0..6),
[2 timer bytes], the analog bytes (7 high bits each), one byte of their low bits (0x40 for
analog 0, 0x20 for analog 1, ...; analog 7 has none) and 2 bytes per encoder. Every byte after
the first has bit 7 clear. An analog value is ``byte << 1 | low bit``, 0..255. Gadgeteer asks
0x08: buttons and 4 analogs, a 7-byte packet.

Only the standard library and pyserial (through :mod:`gadgetctl.transport.serialline`) are used.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import serial

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

INFO_COMMANDS = {
    0xC8: "product name",
    0xC9: "product id",
    0xCA: "model",
    0xCB: "serial number",
    0xCC: "comment",
    0xCD: "parameter format",
    0xCE: "version",
}
#: Gadgeteer's query: 4 analogs, no timer, no encoders.
QUERY = 0x08
ANALOG_COUNTS = {0x00: 0, 0x04: 2, 0x08: 4, 0x0C: 8}
ENCODER_COUNTS = {0: 0, 1: 2, 2: 3, 3: 6}
BUTTONS = 7
#: NUL-ended strings longer than this are no answer.
MAX_STRING = 256
SIGN_ON_ATTEMPTS = 10
#: Queries in flight at most (each is answered by one packet, in order).
PIPELINE = 2


class IBoxError(Exception):
    """Base class of the driver's errors."""


class IBoxTimeout(IBoxError, TimeoutError):
    """The box did not answer in time."""


class IBoxProtocolError(IBoxError):
    """The box answered, but not as the protocol says."""


class IBoxDisconnected(IBoxError):
    """The serial line is gone; reopen to recover."""


def packet_size(query: int) -> int:
    """Bytes of the packet answering ``query`` (the echoed query byte included)."""
    analogs = ANALOG_COUNTS[query & 0x0C]
    return (
        1
        + 1
        + (2 if query & 0x20 else 0)
        + analogs
        + (1 if analogs else 0)
        + 2 * ENCODER_COUNTS[query & 0x03]
    )


@dataclass(frozen=True)
class IBoxPacket:
    """One decoded packet: buttons 0..6 as 0/1, analogs 0..255, timer and encoder words."""

    buttons: tuple[int, ...]
    analog: tuple[int, ...]
    timer: int | None = None
    encoders: tuple[int, ...] = ()


def decode_packet(packet: bytes, query: int = QUERY) -> IBoxPacket | None:
    """Decode one packet answering ``query``; None when it is none (framing, bit 7)."""
    if len(packet) != packet_size(query) or packet[0] != (query | 0x80):
        return None
    if any(b & 0x80 for b in packet[1:]):
        return None
    buttons = tuple(packet[1] >> k & 1 for k in range(BUTTONS))
    pos = 2
    timer = None
    if query & 0x20:
        timer = packet[pos] << 7 | packet[pos + 1]
        pos += 2
    count = ANALOG_COUNTS[query & 0x0C]
    analog: tuple[int, ...] = ()
    if count:
        low = packet[pos + count]
        analog = tuple(
            packet[pos + i] << 1 | (low >> (6 - i) & 1 if i < 7 else 0) for i in range(count)
        )
        pos += count + 1
    encoders = tuple(
        packet[pos + 2 * i] << 7 | packet[pos + 2 * i + 1]
        for i in range(ENCODER_COUNTS[query & 0x03])
    )
    return IBoxPacket(buttons, analog, timer, encoders)


@dataclass
class PacketScanner(ResyncScanner[IBoxPacket]):
    """Finds packets by their echoed query byte. Junk runs are skipped whole (one search to
    the next echo), counted once in ``bad_records`` and byte by byte in ``skipped_bytes``."""

    query: int = QUERY

    def find_head(self, buffer: bytearray, start: int) -> int:
        return buffer.find(self.query | 0x80, start)

    def record_size(self) -> int:
        return packet_size(self.query)

    def decode(self, record: bytes) -> IBoxPacket | None:
        return decode_packet(record, self.query)


class IBox(ScannedDevice):
    """An Immersion Interface Box on a serial line, polled with :data:`QUERY`.

    ``settle`` is the pause after ``END`` (0.1 s upstream); ``read_timeout`` the wait for an
    answer during the start; ``poll_timeout`` of no packet before the queries in flight count
    as lost and are asked again;
    ``silence_timeout`` of no data after which the box counts as gone.
    """

    def __init__(
        self,
        port: str | serial.SerialBase,
        baud: int = 38400,
        *,
        settle: float = 0.1,
        read_timeout: float = 1.0,
        poll_timeout: float = 0.1,
        silence_timeout: float = 2.0,
        poll_interval: float = 0.01,
    ) -> None:
        self.line = SerialLine(port, LineSettings(baud), poll_interval=poll_interval)
        self.settle = settle
        self.read_timeout = read_timeout
        self.poll_timeout = poll_timeout
        self.silence_timeout = silence_timeout
        self.info: dict[str, str] = {}
        self.polls = 0
        self.scanner = PacketScanner()
        self._pending = bytearray()  # answer bytes read but not yet used, during the start
        self._outstanding = 0
        self._polled_at = 0.0
        self._heard_at = 0.0

    # -- life cycle -------------------------------------------------------------------------

    def open(self) -> None:
        self.line.open_with(self._sign_on, IBoxDisconnected)

    def close(self) -> None:
        self.line.close(farewell=b"END")

    # -- data -------------------------------------------------------------------------------

    def read(self) -> list[IBoxPacket]:
        """Query when due and return the packets that arrived (possibly none). Raises
        :class:`IBoxDisconnected` when the line is lost or silent for ``silence_timeout``."""
        try:
            now = time.monotonic()
            if now - self._polled_at >= self.poll_timeout:
                self._outstanding = 0  # queries lost (or a box that restarted): ask again
            if self._outstanding < PIPELINE:
                # one query in flight while the box answers the other: the line stays busy
                count = PIPELINE - self._outstanding
                self._outstanding = PIPELINE
                self._polled_at = now
                self.polls += count
                self.line.write(bytes((QUERY,)) * count)
            data = self.line.read(self.line.poll_interval)
        except SerialLineLost as exc:
            raise IBoxDisconnected(str(exc)) from exc
        packets = self.scanner.feed(data)
        now = time.monotonic()
        if packets:
            self._outstanding = max(0, self._outstanding - len(packets))
            self._polled_at = self._heard_at = now
        elif now - self._heard_at > self.silence_timeout:
            raise IBoxDisconnected(f"no data from the IBox for {self.silence_timeout:g} s")
        return packets

    # -- start-up ---------------------------------------------------------------------------

    def _sign_on(self) -> None:
        self._discard()
        self.line.write(b"END")
        if self.settle > 0:
            time.sleep(self.settle)
        self._discard()
        for _ in range(SIGN_ON_ATTEMPTS):
            self.line.write(b"IMMC")
            first = self._read_exactly(1, allow_timeout=True)
            if first == b"I" and self._read_exactly(3) == b"MMC":
                break
        else:
            raise IBoxTimeout(f"no IMMC echo after {SIGN_ON_ATTEMPTS} attempts")
        self.line.write(b"BEGIN")
        self.info["sign-on"] = self._read_string()
        for command, name in INFO_COMMANDS.items():
            self.info[name] = self._info(command)
        self.scanner.feed(bytes(self._pending))  # nothing, unless the box sent data already
        self._pending.clear()
        self._heard_at = time.monotonic()

    def _info(self, command: int) -> str:
        for _ in range(2):  # one retry, as the C++
            self._discard()
            self.line.write(bytes((command,)))
            if self._read_exactly(1, allow_timeout=True) == bytes((command,)):
                return self._read_string()
        raise IBoxProtocolError(f"the box did not echo info command 0x{command:02X}")

    def _discard(self) -> None:
        self._pending.clear()
        self.line.discard_input()

    def _read_exactly(self, count: int, *, allow_timeout: bool = False) -> bytes:
        """``count`` bytes of an answer (fewer only with ``allow_timeout``, at the deadline)."""
        pending = self._pending
        deadline = time.monotonic() + self.read_timeout
        while len(pending) < count:
            left = deadline - time.monotonic()
            if left <= 0:
                if allow_timeout:
                    break
                raise IBoxTimeout(f"no {count}-byte answer from the IBox")
            pending += self.line.read(min(left, 0.05))
        out = bytes(pending[:count])
        del pending[:count]
        return out

    def _read_string(self) -> str:
        data = bytearray()
        while True:
            byte = self._read_exactly(1)
            if byte == b"\0":
                return data.decode("ascii", "replace")
            data += byte
            if len(data) > MAX_STRING:
                raise IBoxProtocolError(f"an answer longer than {MAX_STRING} bytes")
