"""Conformance: the PinchGlove decoder against touch frames as two implementations independent of
VR Juggler and of our emulator read them.

Sources:

* Vrui's VRDeviceDaemon ``FakespacePinchGlove.cpp`` (Oliver Kreylos): a frame is ``0x80``, then
  ``(left, right)`` byte pairs until ``0x8F``; a contact with the thumb is bit ``0x10`` of that
  hand's byte, and the other fingers are ``0x08`` (index) down to ``0x01`` (pinky).
* VESS's ``vsPinchGloveBox`` (University of Central Florida): the same digit bits, named
  ``THUMB 0x10, FORE 0x08, MIDDLE 0x04, RING 0x02, PINKY 0x01``.
* FreeVR's ``vr_input.pinch.c`` (Bill Sherman): ``0x81`` frames carry two timestamp bytes
  before ``0x8F``, the first the low seven bits (``first + 128 * second``).

VR Juggler's ``PinchGloveStandalone`` passes bit k on as digital unit k, and
``Glove::getGloveDataFromDigitalData`` then fills glove component k (thumb first) from unit k: the
glove angles put the pinky's contact in the thumb's row. gadgetctl keeps VR Juggler's unit
numbers and puts each finger's contact in its own glove row.
"""

from __future__ import annotations

import math

import pytest
from PinchGlove_drv.standalone import FINGERS, UNIT_FINGERS, decode_frame

pytestmark = pytest.mark.timeout(10)

THUMB, FORE, MIDDLE, RING, PINKY = 0x10, 0x08, 0x04, 0x02, 0x01


def test_thumb_and_forefinger_of_the_left_hand() -> None:
    sample = decode_frame(0x80, bytes([THUMB | FORE, 0x00]))
    assert sample is not None
    assert sample.left.finger("thumb") and sample.left.finger("index")
    assert not any(sample.left.finger(f) for f in ("middle", "ring", "pinky"))
    assert not any(sample.right.contacts)
    # VR Juggler's units: bit k is unit k, so the thumb is unit 4 and the forefinger unit 3
    assert sample.digital == (0, 0, 0, 1, 1, 0, 0, 0, 0, 0)
    assert sample.left.angles[FINGERS.index("thumb")] == (math.pi / 2,) * 4
    assert sample.left.angles[FINGERS.index("pinky")] == (0.0,) * 4


def test_a_right_pinky_touching_the_left_ring_finger_in_a_timestamped_frame() -> None:
    sample = decode_frame(0x81, bytes([RING, PINKY, 0x12, 0x05]))
    assert sample is not None
    assert sample.groups == ((RING, PINKY),)
    assert sample.timestamp == 0x12 + 128 * 0x05
    assert sample.left.finger("ring") and sample.right.finger("pinky")
    assert sum(sample.left.contacts) == 1 and sum(sample.right.contacts) == 1
    assert sample.digital == (0, 1, 0, 0, 0, 1, 0, 0, 0, 0)
    assert [UNIT_FINGERS[k] for k in range(5)] == ["pinky", "ring", "middle", "index", "thumb"]


def test_all_fingers_of_both_hands_in_several_groups() -> None:
    groups = bytes([THUMB | MIDDLE, 0, 0, FORE | RING | PINKY, PINKY, THUMB])
    sample = decode_frame(0x80, groups)
    assert sample is not None
    assert sample.left.contacts == (True, False, True, False, True)  # thumb, middle, pinky
    assert sample.right.contacts == (True, True, False, True, True)
