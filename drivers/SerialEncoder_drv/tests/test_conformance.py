"""Conformance: the SEI bus decoder and the table pose against VR Juggler's C++, not our emulator.

Source: VR Juggler's ``USDigital/SerialEncoder/SEIBus.h`` ``ED2GetPosition1``: the single-byte
read command is ``ED2RDPOS1 (0x10) + address`` (``SEIConstants.h``); the reply is 5 bytes, and
on a little-endian host the float is assembled as ``posc[0..3] = inData[4..1]``, i.e. bytes 1..4
hold the float most significant byte first. Byte 0 is the bus's echo of the command byte (the C++
reads it and does not look at it). ``SerialEncoderStandalone::getSample``: device 1's degrees
become ``EulerAngleXYZ(tilt, 0, 0)``, device 2's inches are divided by
``PositionUnitConversion::ConvertToInches`` (39.37) onto +Y, and the pose is
``translation * rotation``.

The replies below are laid out the way that C++ takes them apart: the host's own float bytes
(numpy float32, host order) reversed when the host is little-endian.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from SerialEncoder_drv.standalone import command, decode_reply, table_matrix

pytestmark = pytest.mark.timeout(10)

ED2RDPOS1 = 0x10
CONVERT_TO_INCHES = 39.37


def sei_reply(address: int, value: float) -> bytes:
    host = np.float32(value).tobytes()  # the float as the host stores it
    wire = host[::-1] if sys.byteorder == "little" else host  # posc[0] = inData[4], ...
    return bytes([ED2RDPOS1 + (address & 0x0F)]) + wire


@pytest.mark.parametrize("value", [0.0, 12.5, -37.25, 1234.0625])
def test_replies_decode_to_the_float_the_cxx_assembles(value: float) -> None:
    assert command(1) == ED2RDPOS1 + 1 and command(2) == ED2RDPOS1 + 2
    assert decode_reply(1, sei_reply(1, value)) == pytest.approx(value)
    assert decode_reply(2, sei_reply(1, value)) is None  # the echo names another device


def test_the_table_pose_is_translation_times_rotation_as_getsample_builds_it() -> None:
    tilt, height = 30.0, 20.0
    t = math.radians(tilt)
    rotation = np.array(
        [
            [1, 0, 0, 0],
            [0, math.cos(t), -math.sin(t), 0],
            [0, math.sin(t), math.cos(t), 0],
            [0, 0, 0, 1],
        ]
    )
    translation = np.eye(4)
    translation[1, 3] = height / CONVERT_TO_INCHES
    np.testing.assert_allclose(table_matrix(tilt, height), translation @ rotation, atol=1e-9)
