"""5DT Data Glove Ultra Wireless (a receiver with two glove ports, A and B), independent of
gadgetctl's input manager (it uses only :mod:`gadgetctl.transport.serialline`).

The receiver streams 29-byte records at 115200 baud, 8N1, whichever glove has news: ``<``
(0x3C); a byte whose low nibble names the port (2 or 3: port A, anything else: port B); a
byte the driver does not use; fourteen 12-bit sensor readings packed three nibbles each, most
significant first, in the next 21 bytes; four status bytes; and ``>`` (0x3E) closing the
record (VR Juggler's driver reads 28 bytes after ``<`` without checking the end; its test
program counts the ``>``). The sensors are thumb near, thumb far, thumb-index, index near,
index far, index-middle, middle near, middle far, middle-ring, ring near, ring far,
ring-little, little near and little far.

Readings are auto-ranged, as the C++ driver does: each sensor of each glove keeps the least
and greatest raw reading seen since the range was last reset and reports where the reading
lies between them (0..1; 0 while the range is empty).

Decoding is bounded: a record whose end byte is not ``>`` is a bad record, the bytes up to
the next ``<`` are skipped as one run, and the buffer never holds more than one record.
"""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

START, END = 0x3C, 0x3E
RECORD_SIZE = 29
SENSORS = 14
PORT_A, PORT_B = 0, 1
PORT_A_IDS = (2, 3)
MAX_READING = 0xFFF
#: The four fingers whose bend makes a gesture, as (near, far) sensor indices.
GESTURE_FINGERS = ((3, 4), (6, 7), (9, 10), (12, 13))
NO_GESTURE = -1


class UltraGloveError(Exception):
    """Base class of the driver's errors."""


class UltraGloveDisconnected(UltraGloveError, SerialLineLost):
    """The serial line is gone; reopen to recover."""


@dataclass(frozen=True)
class GloveRecord:
    """One record: the glove port (0 = A, 1 = B) and its fourteen raw readings (0..4095)."""

    port: int
    raw: tuple[int, ...]


def decode_record(record: bytes) -> GloveRecord | None:
    """A 29-byte record, ``<`` .. ``>`` included; None when it is not one."""
    if len(record) != RECORD_SIZE or record[0] != START or record[-1] != END:
        return None
    port = PORT_A if record[1] & 0x0F in PORT_A_IDS else PORT_B
    packed = int.from_bytes(record[3:24], "big")  # 42 nibbles = fourteen 12-bit readings
    raw = tuple(packed >> (12 * (SENSORS - 1 - i)) & MAX_READING for i in range(SENSORS))
    return GloveRecord(port, raw)


@dataclass
class RecordScanner(ResyncScanner[GloveRecord]):
    """Finds records in a byte stream, bounded: ``records`` decoded, ``bad_records`` runs of
    junk (broken records included), ``skipped_bytes`` their bytes."""

    HEAD = START
    SIZE = RECORD_SIZE

    def decode(self, record: bytes) -> GloveRecord | None:
        return decode_record(record)


class AutoRange:
    """Per glove and sensor: the least and greatest reading since :meth:`reset`."""

    def __init__(self) -> None:
        self.low: list[list[int | None]] = [[None] * SENSORS for _ in (PORT_A, PORT_B)]
        self.high: list[list[int | None]] = [[None] * SENSORS for _ in (PORT_A, PORT_B)]

    def reset(self) -> None:
        self.__init__()

    def scale(self, record: GloveRecord) -> tuple[float, ...]:
        """Each reading's place in its sensor's range so far (0 while the range is empty)."""
        low, high = self.low[record.port], self.high[record.port]
        out = []
        for i, value in enumerate(record.raw):
            lo = value if low[i] is None else min(low[i], value)  # type: ignore[type-var]
            hi = value if high[i] is None else max(high[i], value)  # type: ignore[type-var]
            low[i], high[i] = lo, hi
            out.append((value - lo) / (hi - lo) if hi > lo else 0.0)
        return tuple(out)


def gesture(scaled: tuple[float, ...], lower: float = 0.35, upper: float = 0.65) -> int:
    """A gesture number 0..15 from the index, middle, ring and little fingers (bit k set when
    finger k is bent past ``upper``, clear when open below ``lower``); -1 while any of them
    is between the thresholds."""
    number = 0
    for bit, (near, far) in enumerate(GESTURE_FINGERS):
        bend = (scaled[near] + scaled[far]) / 2
        if bend > upper:
            number |= 1 << bit
        elif bend >= lower:
            return NO_GESTURE
    return number


class UltraGlove(ScannedDevice):
    """The wireless receiver on a serial line. ``sample_timeout`` bounds one :meth:`poll`."""

    def __init__(
        self,
        port: object,
        baud: int = 115200,
        *,
        sample_timeout: float = 0.1,
        poll_interval: float = 0.01,
    ) -> None:
        self.line = SerialLine(port, LineSettings(baud=baud), poll_interval=poll_interval)  # type: ignore[arg-type]
        self.scanner = RecordScanner()
        self.sample_timeout = sample_timeout

    def open(self) -> None:
        try:
            self.line.open()
        except SerialLineLost as exc:
            raise UltraGloveDisconnected(str(exc)) from exc

    def poll(self) -> list[GloveRecord]:
        """The records that arrive within ``sample_timeout`` (every one, in order)."""
        try:
            return self.scanner.feed(self.line.read(self.sample_timeout))
        except SerialLineLost as exc:
            raise UltraGloveDisconnected(str(exc)) from exc

    def close(self) -> None:
        self.line.close()
