"""Conformance: the SpaceBall / SpaceMouse decoder against records packed as VRPN's and VR
Juggler's drivers read them, not as our emulator writes them.

Sources (read through the ``fetch`` tool):

* VRPN ``vrpn_Spaceball.C`` (``get_report``): every incoming byte is unescaped first, for every
  model: ``^`` starts an escape, ``^^`` is a caret, ``^Q``, ``^S``, ``^M`` are the letter
  ``& 0x1F`` (XON, XOFF, CR). A ``D`` record is ``D``, two timer bytes, six big-endian int16
  (channel = value / 32768, Z translation and Z rotation negated), CR. A ``K`` record (2003):
  buttons 1-4 in bits 0-3 of the second byte, 5-7 in bits 0-2 of the first, the rezero button
  in bit 3 ("8") and the pick button in bit 4 ("9"). A ``.`` record (4000 FLX): buttons 1-6 in
  bits 0-5 of the second byte, 7 in its bit 7, 8-12 in bits 0-4 of the first.
* VR Juggler ``puck_device.cpp``: the same layouts (``spaceBall4000FLX::processAnalogData``,
  ``spaceBall2003B::processDigitalData`` with its bit diagram ``0 1 0 P 8 7 6 5`` /
  ``0 1 0 0 4 3 2 1``); ``processBuffer`` unescapes for both SpaceBalls.
* VRPN ``vrpn_Magellan.C``: a SpaceMouse ``d`` record carries each axis in the low nibbles of
  four characters, ``N0 * 4096 + N1 * 256 + N2 * 16 + N3 - 32768``; ``k``: buttons 1-4 in the
  first character's low bits, 5-8 in the second's, the ``*`` button in the third's bit 0.

VRPN skips values within its null radius (8 counts); the values below are larger.
"""

from __future__ import annotations

import pytest
from SpaceBall_drv.standalone import RecordSplitter

pytestmark = pytest.mark.timeout(10)

ESCAPES = {0x0D: b"^M", 0x11: b"^Q", 0x13: b"^S", 0x5E: b"^^"}


def escaped(body: bytes) -> bytes:
    return b"".join(ESCAPES.get(c, bytes((c,))) for c in body)


def d_record(words: tuple[int, ...], timer: int = 0x1234) -> bytes:
    body = timer.to_bytes(2, "big") + b"".join(w.to_bytes(2, "big", signed=True) for w in words)
    return b"D" + escaped(body) + b"\r"


def vrpn_channels(words: tuple[int, ...]) -> list[float]:
    channels = [w / 32768.0 for w in words]
    channels[2], channels[5] = -channels[2], -channels[5]
    return channels


# words chosen so that their bytes hold CR, XON, XOFF and the caret
WORDS = [
    (0x0D0D, -0x1111, 0x1313, 0x5E5E, -0x0D5E, 0x115E),
    (1000, -2000, 300, -400, 500, -600),
    (0x000D, 0x0011, 0x0013, 0x005E, -32768, 32767),
]


@pytest.mark.parametrize("model", ["SpaceBall 2003B", "SpaceBall 4000 FLX"])
def test_d_records_escaped_as_vrpn_unescapes_them_read_for_every_model(model: str) -> None:
    splitter = RecordSplitter(model)
    stream = b"".join(d_record(w) for w in WORDS)
    got = []
    for start in range(0, len(stream), 5):
        got += splitter.feed(stream[start : start + 5])
    assert splitter.bad_records == 0
    assert [[a / 32768.0 for a in s.axes] for s in got] == [vrpn_channels(w) for w in WORDS]


def k_record(buttons: set[int]) -> bytes:
    """A 2003B button record for buttons 1..9 (8 rezero, 9 pick), as VRPN reads one."""
    first = 0x40 | sum(1 << (b - 5) for b in buttons if 5 <= b <= 9)
    second = 0x40 | sum(1 << (b - 1) for b in buttons if 1 <= b <= 4)
    return b"K" + escaped(bytes((first, second))) + b"\r"


def test_2003b_button_records_read_as_vrpn_and_the_cpp_number_them() -> None:
    presses = [{1}, {4, 5}, {6, 7, 8, 9}, set(), {2, 3, 9}]  # {6, 7, 8, 9}: first byte 0x5E
    splitter = RecordSplitter("SpaceBall 2003B")
    got = splitter.feed(b"".join(k_record(p) for p in presses))
    assert splitter.bad_records == 0
    assert [{i + 1 for i, v in enumerate(s.buttons) if v} for s in got] == presses


def dot_record(buttons: set[int], right_handed_bit: bool = True) -> bytes:
    first = 0x40 | (0x20 if right_handed_bit else 0) | sum(1 << (b - 8) for b in buttons if b >= 8)
    second = 0x40 | sum(1 << (b - 1) for b in buttons if b <= 6) | (0x80 if 7 in buttons else 0)
    return b"." + escaped(bytes((first, second))) + b"\r"


def test_4000_button_records_read_as_vrpn_numbers_them() -> None:
    presses = [{1}, {6, 7}, {8, 12}, set(), {2, 9, 10, 11}]
    splitter = RecordSplitter("SpaceBall 4000 FLX")
    got = splitter.feed(b"".join(dot_record(p) for p in presses))
    assert splitter.bad_records == 0
    assert [{i + 1 for i, v in enumerate(s.buttons) if v} for s in got] == presses


def nibbles(value: int, count: int) -> bytes:
    """``value`` in ``count`` characters, most significant nibble first; the Magellan sends
    each nibble in a character whose low four bits hold it (bit 4 or 6 set for parity)."""
    out = []
    for shift in range(4 * (count - 1), -1, -4):
        n = value >> shift & 0xF
        out.append((0x30 if bin(n).count("1") % 2 == 0 else 0x40) | n)
    return bytes(out)


def test_spacemouse_records_read_as_vrpn_magellan_reads_them() -> None:
    axes = (0, 5, -1, 3072, -32768, 32767)
    record = b"d" + b"".join(nibbles(a + 32768, 4) for a in axes) + b"\r"
    buttons = b"k" + nibbles(0b0101, 1) + nibbles(0b1000, 1) + nibbles(0b0001, 1) + b"\r"
    splitter = RecordSplitter("SpaceMouse")
    got = splitter.feed(record + buttons)
    assert splitter.bad_records == 0
    assert got[0].axes == axes
    # VRPN: buttons 1-4 from the first character, 5-8 the second, "*" the third's bit 0
    assert {i + 1 for i, v in enumerate(got[1].buttons) if v} == {1, 3, 8, 9}
