"""Conformance: the Flock of Birds decoder against bytes laid out as Ascension's manual and VRPN's
``vrpn_Flock.C`` describe them, not as our emulator writes them.

Sources:

* Ascension's RS-232 command reference (the Flock of Birds Installation and Operation Guide,
  and the laserBIRD manual, which documents the same command set, read through the ``search``
  tool): EXAMINE VALUE, "If the PARAMETERdata returned is a word then the Least Significant
  byte (LSbyte) is received before the Most Significant byte (MSbyte)"; POSITION SCALING
  (parameter 3), "The most significant byte of the parameter word returned is always zero. If
  the least significant byte = 0, the scale factor is 36 inches for a full scale position
  output. If the least significant byte is = 1, the full scale output is 72 inches". Record
  words: byte 1 is ``1 X8 X7 X6 X5 X4 X3 X2`` (the phasing bit, then bits 8..2, the LSbyte),
  byte 2 ``0 X15 .. X9`` (the MSbyte); the next words have bit 7 clear in both bytes; the
  word is two's complement, full scale 0x7FFF.
* VRPN ``vrpn_Flock.C``: a word is ``((LS & 0x7F) << 1) + (MS << 8)``, shifted left once more,
  as a signed short; ``getMeasurementRate`` reads examine words low byte first
  (``response[2] + (response[3] << 8)``); the quaternion is taken as sent ("According to the
  Flock manual, the Flock should report things in the same way other trackers do"; inverting
  it is an option, no longer the default).
* The manuals' MATRIX output M and the QUATERNION output extracted from it by Shepperd's
  method (``gadgetctl.input.testing.ascension``): a POSITION/QUATERNION record of a pose must
  turn the sensor as a POSITION/ANGLES record of the same pose does.
"""

from __future__ import annotations

import numpy as np
import pytest
from Flock_drv.standalone import (
    POS_ANGLES,
    POS_QUATERNION,
    FlockProtocolError,
    RecordScanner,
    decode_word,
    scale_from_reply,
)

from gadgetctl.input.testing.ascension import bird_matrix, shepperd_quaternion

pytestmark = pytest.mark.timeout(10)


def vrpn_word(ls: int, ms: int) -> int:
    value = (((ls & 0x7F) << 1) + (ms << 8)) << 1
    value &= 0xFFFF
    return value - 0x10000 if value & 0x8000 else value


def manual_word(value: int, first: bool) -> bytes:
    """A 16-bit two's complement word as the manual lays it out (bits 1..0 are not sent)."""
    raw = value & 0xFFFF
    return bytes(((0x80 if first else 0) | (raw >> 2 & 0x7F), raw >> 9 & 0x7F))


def test_position_scaling_replies_are_read_low_byte_first() -> None:
    assert scale_from_reply(bytes((0x00, 0x00))) == 36.0  # LSbyte 0: 36 inches
    assert scale_from_reply(bytes((0x01, 0x00))) == 72.0  # LSbyte 1: 72 inches
    with pytest.raises(FlockProtocolError):
        scale_from_reply(bytes((0x00, 0x01)))  # the MSbyte "is always zero"


def test_words_agree_with_vrpns_reading() -> None:
    for ls in range(0, 128, 3):
        for ms in range(0, 128, 5):
            assert decode_word(ls, ms) == vrpn_word(ls, ms) / 32768.0


def test_a_72_inch_position_angles_record_in_the_manuals_layout() -> None:
    # x, y, z: half scale, minus a quarter, full negative; azimuth 90, elevation -45, roll 180
    words = (0x4000, -0x2000, -0x8000, 0x4000, -0x2000, -0x8000)
    record = b"".join(manual_word(w, i == 0) for i, w in enumerate(words)) + bytes((2,))
    scanner = RecordScanner(POS_ANGLES, scale_from_reply(b"\x01\x00") / 12.0, True, frozenset({2}))
    (got,) = scanner.feed(record)
    inches = [w * 72.0 / 32768 for w in words[:3]]  # the full scale the reply announced
    assert [p * 12.0 for p in got.position] == pytest.approx(inches)  # 36, -18, -72 inches
    assert got.angles == pytest.approx((90.0, -45.0, -180.0))
    assert got.address == 2 and scanner.bad_records == 0


@pytest.mark.parametrize(
    "angles", [(30.0, -20.0, 45.0), (170.0, 80.0, -170.0), (-90.0, 10.0, 0.0), (0.0, 0.0, 179.0)]
)
def test_the_quaternion_used_as_sent_turns_as_the_angles_do(angles) -> None:
    q = shepperd_quaternion(bird_matrix(*angles))
    position = (0x1000, -0x0800, 0x0400)
    quaternion = b"".join(
        manual_word(w, i == 0)
        for i, w in enumerate((*position, *(max(-32768, min(32767, round(v * 32768))) for v in q)))
    )
    euler = b"".join(
        manual_word(w, i == 0)
        for i, w in enumerate((*position, *(round(a / 180 * 32768) for a in angles)))
    )
    (by_quaternion,) = RecordScanner(POS_QUATERNION, 3.0).feed(quaternion)
    (by_angles,) = RecordScanner(POS_ANGLES, 3.0).feed(euler)
    np.testing.assert_allclose(by_quaternion.matrix(), by_angles.matrix(), atol=2e-3)
    # and the manual's M is that rotation transposed (its rows: the sensor's axes)
    np.testing.assert_allclose(by_angles.matrix()[:3, :3], bird_matrix(*angles).T, atol=2e-3)
