"""Conformance: the IS-900 decoder against records and conventions as other implementations read
them, not as our emulator writes them.

Sources:

* VRPN 07.38 ``vrpn_Tracker_Fastrak.C`` (its IS-900 mode), ``get_report``: a binary record is
  ``'0'``, the station character, a status character, little-endian float32 items; the button
  item (22) is one byte with the lowest-numbered button in the lowest bit; the joystick item (23)
  is two unsigned bytes, left/right then up/down, 0 the minimum, 127 the centre, 255 the maximum.
* VRPN 07.38 ``vrpn_Tracker_isense.C`` turns InterSense's Euler angles (degrees: azimuth,
  elevation, roll) into a rotation with quatlib's ``q_from_euler(yaw, pitch, roll)``: yaw about
  Z, pitch about Y, roll about X, ``p' = roll(pitch(yaw(p)))``. The quaternion below is that
  formula, and the matrix is built from it with the textbook quaternion-to-matrix identity, not
  with the driver's own Euler product.
"""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from IS900_drv.standalone import INCH, RecordScanner, pose_matrix

pytestmark = pytest.mark.timeout(10)


def is900_record(
    station: str,
    inches: tuple[float, float, float],
    euler_degrees: tuple[float, float, float],
    tracking: int,
    button_bits: int,
    joystick: tuple[int, int],
) -> bytes:
    """Output list 2 (position), 4 (Euler), 40 (tracking status), 22 (buttons), 23 (joystick),
    1 (CR LF), each item as VRPN's reader takes it."""
    floats = b"".join(struct.pack("<f", v) for v in (*inches, *euler_degrees))
    items = bytes([tracking, button_bits, *joystick])
    return b"0" + station.encode() + b" " + floats + items + b"\r\n"


def quatlib_from_euler(yaw: float, pitch: float, roll: float) -> tuple[float, ...]:
    """(x, y, z, w) from yaw, pitch, roll in radians, as quatlib's q_from_euler defines it."""
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def rotation_of(q: tuple[float, ...]) -> np.ndarray:
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_buttons_and_joystick_bytes_read_as_vrpn_reads_them() -> None:
    records = is900_record("1", (12.0, -6.0, 48.0), (0.0, 0.0, 0.0), 3, 0b0010_0101, (0, 255))
    records += is900_record("b", (1.0, 1.0, 1.0), (0.0, 0.0, 0.0), 3, 0, (127, 128))
    scanner = RecordScanner(scale=INCH)
    got = scanner.feed(records)
    assert scanner.bad_records == 0
    assert [r.station for r in got] == [0, 10]  # '1' is station 1, 'b' station 11: 0-based
    assert got[0].digital == (1, 0, 1, 0, 0, 1, 0, 0)  # lowest-numbered button, lowest bit
    assert got[0].analog == (0, 255)  # raw: minimum left/right, maximum up/down
    assert got[1].analog == (127, 128)
    assert [(a - 127) / 128.0 for a in got[0].analog] == [-127 / 128, 1.0]  # VRPN's scale
    assert got[0].position == pytest.approx((12 * 0.0254, -6 * 0.0254, 48 * 0.0254), rel=1e-6)


@pytest.mark.parametrize(
    "euler", [(30.0, 0.0, 0.0), (0.0, 45.0, 0.0), (0.0, 0.0, -60.0), (120.0, -35.0, 170.0)]
)
def test_euler_angles_give_the_rotation_quatlib_gives(euler: tuple[float, float, float]) -> None:
    record = is900_record("2", (0.0, 0.0, 0.0), euler, 3, 0, (127, 127))
    (decoded,) = RecordScanner(scale=INCH).feed(record)
    assert decoded.euler == pytest.approx(euler, abs=1e-4)
    yaw, pitch, roll = (math.radians(a) for a in euler)
    expected = rotation_of(quatlib_from_euler(yaw, pitch, roll))
    np.testing.assert_allclose(decoded.matrix()[:3, :3], expected, atol=1e-6)
    np.testing.assert_allclose(pose_matrix((0, 0, 0), euler)[:3, :3], expected, atol=1e-6)
