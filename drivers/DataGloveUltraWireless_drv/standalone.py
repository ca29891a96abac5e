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
lies between them (0..1; unknown while the range is empty, which the wrapper shows as 0).
A greater raw reading is a more bent joint.

Gestures follow ``DataGloveUltraWirelessStandalone.cpp`` (``getSensorState``,
``getJointState``, ``computeGesture``): a sensor is *closed* above the upper threshold, *open*
below the lower one and undefined between them (or while its range is empty); a finger (its
near and far sensors) is closed when either sensor is closed, else open when either is open,
and undefined only when both are. Bit k of the gesture (index 1, middle 2, ring 4, little 8)
is set while finger k is **open**, as in the C++ and gadgetctl's DataGlove: a flat hand is 15,
a fist 0, and any undefined finger makes the gesture -1.

``auto_range_reset`` (the definition: "reset minimum and maximum joint values on all-open and
all-closed gestures"): a record whose gesture is 15 (all open) becomes its glove's minimum on
every sensor, one whose gesture is 0 (a fist) its maximum, so an old extreme (a glove pulled
on, a knock) is forgotten at the next flat hand or fist. Fixed from the C++, marked in
:meth:`AutoRange.after_gesture`: it resets the minimum after gesture 0 and the maximum after
15 (written for bits set on bent fingers, before its gesture set them on open ones), so a held
fist collapses each range to one value and reads 0/0; and it resets at the glove's next record,
unless a record of the other glove came between.

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


#: Finger states (``JOINT_OPEN``, ``JOINT_CLOSED``, ``JOINT_UNDEFINED`` in the C++).
OPEN, CLOSED, UNDEFINED = 1, 0, -1
#: The gestures after which ``auto_range_reset`` restarts a glove's range ends.
ALL_OPEN, ALL_CLOSED = 15, 0


class AutoRange:
    """Per glove and sensor: the least and greatest reading since the range was (re)started.
    With ``auto_reset``, :meth:`after_gesture` restarts one end of a glove's ranges (see the
    module's description)."""

    def __init__(self, auto_reset: bool = False) -> None:
        self.auto_reset = auto_reset
        self.reset()

    def reset(self) -> None:
        self.low: list[list[int | None]] = [[None] * SENSORS for _ in (PORT_A, PORT_B)]
        self.high: list[list[int | None]] = [[None] * SENSORS for _ in (PORT_A, PORT_B)]

    def scale(self, record: GloveRecord) -> tuple[float | None, ...]:
        """Each reading's place in its sensor's range so far (None while the range is empty)."""
        low, high = self.low[record.port], self.high[record.port]
        out: list[float | None] = []
        for i, value in enumerate(record.raw):
            lo = value if low[i] is None else min(low[i], value)  # type: ignore[type-var]
            hi = value if high[i] is None else max(high[i], value)  # type: ignore[type-var]
            low[i], high[i] = lo, hi
            out.append((value - lo) / (hi - lo) if hi > lo else None)
        return tuple(out)

    def after_gesture(self, record: GloveRecord, number: int) -> None:
        """``record`` gave gesture ``number``: with ``auto_reset``, all open (15) restarts the
        glove's minima at this record's readings and a fist (0) its maxima."""
        if not self.auto_reset or number not in (ALL_OPEN, ALL_CLOSED):
            return
        # Fixed from the C++, which restarts the minima after 0 and the maxima after 15, and
        # only at the next record (and only if no record of the other glove came between):
        # a held fist then collapses every range to one value and reads 0/0.
        ends = self.low if number == ALL_OPEN else self.high
        ends[record.port] = list(record.raw)


def sensor_state(value: float | None, lower: float, upper: float) -> int:
    """Closed above ``upper``, open below ``lower``, else (an empty range too) undefined."""
    if value is None:
        return UNDEFINED
    if value > upper:
        return CLOSED
    if value < lower:
        return OPEN
    return UNDEFINED


def finger_state(near: int, far: int) -> int:
    """A finger from its two sensors: closed when either is closed, else open when either is
    open, undefined only when both are (the C++ ``getJointState``)."""
    if CLOSED in (near, far):
        return CLOSED
    if OPEN in (near, far):
        return OPEN
    return UNDEFINED


def gesture(scaled: tuple[float | None, ...], lower: float = 0.35, upper: float = 0.65) -> int:
    """A gesture number 0..15 from the index, middle, ring and little fingers: bit k set
    while finger k is open (flat hand 15, fist 0); -1 while any of them is undefined."""
    number = 0
    for bit, (near, far) in enumerate(GESTURE_FINGERS):
        state = finger_state(
            sensor_state(scaled[near], lower, upper), sensor_state(scaled[far], lower, upper)
        )
        if state == UNDEFINED:
            return NO_GESTURE
        if state == OPEN:
            number |= 1 << bit
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
