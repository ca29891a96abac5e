"""Ascension's orientation outputs as its manuals define them, for conformance tests of the
Flock of Birds and MotionStar drivers (written from the manuals, independently of the drivers
and their emulators).

The Flock of Birds and laserBIRD guides define the MATRIX output M for azimuth A, elevation
E and roll R as the product of the frame rotations roll x elevation x azimuth, with elements
M11 = cos E cos A, M12 = cos E sin A, M13 = -sin E, M21 = -cos R sin A + sin R sin E cos A,
and so on; and the QUATERNION output as q0..q3 (q0 the scalar part) "extracted from the MATRIX
output using the algorithm described in 'Quaternion from Rotation Matrix' by Stanley W.
Shepperd" (Journal of Guidance and Control, 1978).
"""

from __future__ import annotations

import math

import numpy as np


def bird_matrix(azimuth: float, elevation: float, roll: float) -> np.ndarray:
    """The manual's 3x3 M for angles in degrees (rows: the sensor's axes in transmitter
    coordinates)."""

    def frame(axis: int, degrees: float) -> np.ndarray:
        c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
        i, j = [k for k in range(3) if k != axis]
        m = np.eye(3)
        m[i, i], m[i, j], m[j, i], m[j, j] = c, s, -s, c
        return m

    return frame(0, roll) @ frame(1, elevation).T @ frame(2, azimuth)


def shepperd_quaternion(m: np.ndarray) -> tuple[float, float, float, float]:
    """q0..q3 of M by Shepperd's method: the largest of the four squares picks the branch, and
    q1 = (M23 - M32) / (4 q0), q2 = (M31 - M13) / (4 q0), q3 = (M12 - M21) / (4 q0) in the
    first one; q0 is kept non-negative."""
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    squares = [1 + tr, 1 + 2 * m[0, 0] - tr, 1 + 2 * m[1, 1] - tr, 1 + 2 * m[2, 2] - tr]
    big = int(np.argmax(squares))
    q = [0.0] * 4
    q[big] = math.sqrt(squares[big]) / 2
    d = 4 * q[big]
    # the off-diagonal sums and differences each branch divides by 4 q[big]
    pairs = {
        (0, 1): m[1, 2] - m[2, 1],
        (0, 2): m[2, 0] - m[0, 2],
        (0, 3): m[0, 1] - m[1, 0],
        (1, 2): m[0, 1] + m[1, 0],
        (1, 3): m[0, 2] + m[2, 0],
        (2, 3): m[1, 2] + m[2, 1],
    }
    for other in range(4):
        if other != big:
            q[other] = pairs[tuple(sorted((big, other)))] / d  # type: ignore[index]
    if q[0] < 0:
        q = [-v for v in q]
    return q[0], q[1], q[2], q[3]
