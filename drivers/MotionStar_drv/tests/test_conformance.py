"""Conformance: the MotionStar decoder against data packets packed as VR Juggler's C++ reads them
and quaternions computed as Ascension's manual describes them, not as our emulator writes them.

Sources:

* VR Juggler ``MotionStarStandalone.cpp`` (snapshot 7790bf97, read through the ``fetch``
  tool): a BIRDNET header is 16 bytes, big-endian (sequence, milliseconds, time[4], type,
  xtype, protocol 3, error code, error extension, payload length); a DATA_PACKET_MULTI (210)
  payload is records of: an address byte (bit 7: two button bytes follow the data), a data
  info byte (format code in the high nibble, word count in the low one), big-endian int16
  words. The reader steps over each record by its own word count (and the buttons), whatever
  its format code; code 15 marks a sampling error. Positions are ``full scale * word /
  32767`` inches, angles ``180 * word / 32767`` degrees in the order Z (azimuth), Y
  (elevation), X (roll); quaternion words are q0 (scalar) .. q3 scaled by 32768.
* The feed-through record ``0xE1`` (code 14, one word) is what an independent MotionStar
  driver built on Ascension's sample code met while a wand button was held.
* Ascension's manuals (Flock of Birds and laserBIRD guides, read through the ``search`` tool):
  the MATRIX output M has M11 = cos E cos A, M12 = cos E sin A, M13 = -sin E, M21 = -cos R
  sin A + sin R sin E cos A, ...; the QUATERNION output is q0..q3 "extracted from the MATRIX
  output using the algorithm described in 'Quaternion from Rotation Matrix' by Stanley W.
  Shepperd", q0 the scalar part. Shepperd's q1 is (M23 - M32) / (4 q0), and so on.

So a quaternion record and an angles record of the same pose must give the same rotation,
with the quaternion used as sent: that is the convention checked here.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest
from MotionStar_drv.standalone import (
    DATA_PACKET_MULTI,
    Framer,
    decode_record,
    parse_records,
)

from gadgetctl.input.testing.ascension import bird_matrix, shepperd_quaternion

pytestmark = pytest.mark.timeout(10)

FULL_SCALE = 144.0  # inches


def header(sequence: int, payload: bytes, kind: int = DATA_PACKET_MULTI) -> bytes:
    return struct.pack(">HH4sBBBBHH", sequence, 250, b"\0\0\0\x10", kind, 0, 3, 0, 0, len(payload))


def record(address: int, code: int, words: tuple[int, ...], buttons: bytes = b"") -> bytes:
    head = bytes(((address | 0x80) if buttons else address, code << 4 | len(words)))
    return head + struct.pack(f">{len(words)}h", *words) + buttons


def word(value: float, scale: float) -> int:
    return max(-32768, min(32767, round(value * scale)))


def test_a_packet_with_a_feed_through_record_decodes_every_pose() -> None:
    pose1 = record(
        1,
        4,
        (word(12.0, 32767 / FULL_SCALE), 0, word(-6.0, 32767 / FULL_SCALE), 0, 0, 0),
        b"\x01\x00",
    )
    feed_through = bytes((0x01, 0xE1)) + struct.pack(">h", 1)  # a wand button held
    pose2 = record(2, 4, (0, word(30.0, 32767 / FULL_SCALE), 0, word(90.0, 32767 / 180), 0, 0))
    payload = pose1 + feed_through + pose2
    framer = Framer()
    framer.feed(header(7, payload) + payload)
    message = framer.next(frozenset({DATA_PACKET_MULTI}))
    assert message is not None and framer.bad_packets == 0
    records = message[2]
    assert records is not None and [r.format_code for r in records] == [4, 14, 4]
    poses = [
        decode_record(r, unit, FULL_SCALE) for unit, r in enumerate(records) if r.format_code == 4
    ]
    assert poses[0].position == pytest.approx((12.0, 0.0, -6.0), abs=0.01)
    assert poses[0].buttons == (1, 0)
    assert poses[1].position == pytest.approx((0.0, 30.0, 0.0), abs=0.01)
    assert poses[1].angles == pytest.approx((90.0, 0.0, 0.0), abs=0.01)


@pytest.mark.parametrize(
    "angles", [(30.0, -20.0, 45.0), (170.0, 80.0, -170.0), (-90.0, 10.0, 0.0), (0.0, 0.0, 179.0)]
)
def test_the_quaternion_used_as_sent_turns_as_the_angles_do(angles) -> None:
    q = shepperd_quaternion(bird_matrix(*angles))
    quaternion = record(1, 7, tuple(word(v, 32768) for v in q))
    euler = record(1, 2, tuple(word(v, 32767 / 180) for v in angles))
    by_quaternion, by_angles = (
        decode_record(parse_records(r)[0], 0, FULL_SCALE).matrix[:3, :3]
        for r in (quaternion, euler)
    )
    np.testing.assert_allclose(by_quaternion, by_angles, atol=2e-4)
    # and the manual's M is that rotation transposed (rows: sensor axes in transmitter terms)
    np.testing.assert_allclose(by_angles, bird_matrix(*angles).T, atol=2e-4)
