"""Conformance: the 5DT Data Glove Ultra Wireless decoder against records packed as VR Juggler's
C++ driver reads them, and gestures as its C++ computes them, not as our emulator writes them.

Source: VR Juggler 3.x, ``modules/gadgeteer/drivers/5DT/DataGloveUltraWireless/
DataGloveUltraWirelessStandalone.cpp`` (snapshot 7790bf97, read through the project's
reference notes):

* ``readGloveData`` waits for ``0x3C``, reads 28 more bytes and splits every byte into two
  nibbles, high first; ``updateData`` takes nibble 3 (the low nibble of the byte after ``<``)
  as the port, 2 or 3 meaning port A; ``processGloveData`` reads sensor i from nibbles
  6 + 3i .. 8 + 3i, most significant first. The last byte is ``>`` (the glove test program
  ``glove.cpp`` counts it); the four bytes before it are status, unused.
* ``getSensorState`` / ``getJointState`` / ``computeGesture``: closed above the upper
  threshold, open below the lower, a finger closed if either of its sensors (3/4, 6/7, 9/10,
  12/13) is, open if either is open, and bits 1, 2, 4, 8 (index..little) set while open.

The packing and the reference gesture below are written here from that reading, not imported
from ``DataGloveUltraWireless_drv.emulator`` or the driver.
"""

from __future__ import annotations

import pytest
from DataGloveUltraWireless_drv.standalone import AutoRange, RecordScanner, gesture

pytestmark = pytest.mark.timeout(10)


def packed_as_the_cpp_reads(port_nibble: int, readings: list[int]) -> bytes:
    """``<``, a byte whose low nibble is the port, an unused byte, 42 nibbles of readings,
    four status bytes, ``>``."""
    nibbles = [0x4, port_nibble, 0x0, 0x1]  # bytes 1 and 2 as nibbles (0x40 | port, 0x01)
    for value in readings:
        nibbles += [(value >> 8) & 0xF, (value >> 4) & 0xF, value & 0xF]
    nibbles += [0x0] * 8  # four status bytes
    body = bytes((nibbles[i] << 4) | nibbles[i + 1] for i in range(0, len(nibbles), 2))
    return b"\x3c" + body + b"\x3e"


def cpp_gesture(values: list[float], upper: float = 0.65, lower: float = 0.35) -> int:
    """computeGesture as the C++ writes it, for values whose ranges are known."""

    def state(v: float) -> int:
        return 0 if v > upper else (1 if v < lower else -1)  # CLOSED 0, OPEN 1, UNDEFINED -1

    number = 0
    for bit, (a, b) in zip((1, 2, 4, 8), ((3, 4), (6, 7), (9, 10), (12, 13)), strict=True):
        s1, s2 = state(values[a]), state(values[b])
        if s1 == -1 and s2 == -1:
            return -1
        if s1 != 0 and s2 != 0:  # neither closed, so one of them is open
            number |= bit
    return number


# Raw readings per sensor (thumb near .. little far). The first two records of each glove
# span the range; then a flat hand, a fist, pointing with the index, and a "V".
LOW, HIGH = 300, 3800
SPAN = [[LOW] * 14, [HIGH] * 14]
FLAT = [350, 400, 500, 320, 340, 500, 330, 310, 500, 360, 305, 500, 340, 330]
FIST = [3000, 3200, 500, 3700, 3650, 500, 3750, 3600, 500, 3700, 3790, 500, 3650, 3700]
POINT = [3000, 3200, 500, 330, 900, 500, 3750, 3600, 500, 3700, 3790, 500, 3650, 3700]
VEE = [3000, 3200, 900, 330, 340, 2500, 330, 320, 500, 3700, 3790, 500, 3650, 3700]
HANDS = [*SPAN, FLAT, FIST, POINT, VEE]


def test_records_packed_as_the_cpp_reads_them_decode_to_the_same_port_and_readings() -> None:
    stream = b"".join(packed_as_the_cpp_reads(p, r) for p in (2, 3, 5, 0xA) for r in HANDS)
    scanner = RecordScanner()
    got = []
    for start in range(0, len(stream), 7):  # reads split records anywhere
        got += scanner.feed(stream[start : start + 7])
    assert scanner.bad_records == 0 and scanner.skipped_bytes == 0
    assert [r.port for r in got] == [0] * 12 + [1] * 12  # nibble 2 or 3: port A
    assert [list(r.raw) for r in got] == HANDS * 4


def test_gestures_agree_with_the_cpp_computation() -> None:
    scanner, ranged = RecordScanner(), AutoRange(auto_reset=False)
    records = scanner.feed(b"".join(packed_as_the_cpp_reads(2, r) for r in HANDS))
    got = []
    for record in records:
        got.append(gesture(ranged.scale(record)))
    lo, hi = [LOW] * 14, [HIGH] * 14
    expected = [
        cpp_gesture([(v - a) / (b - a) for v, a, b in zip(raw, lo, hi, strict=True)])
        for raw in HANDS[2:]
    ]
    assert expected == [15, 0, 1, 3]  # flat hand, fist, pointing, "V"
    assert got == [-1, 0, *expected]  # the first record of a glove has empty ranges
