"""Display conversions: lengths from meters, rotation matrices to Euler angles and quaternions.

Rotations follow the convention of ``position_transform_filter`` (gmtl ``EulerAngleXYZ``):
``R = Rx(x) · Ry(y) · Rz(z)`` for column vectors, angles in degrees.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

LENGTH_UNITS: dict[str, float] = {
    "meters": 1.0,
    "feet": 3.28084,
    "inches": 39.3701,
    "centimeters": 100.0,
}
LENGTH_ALIASES = {
    "m": "meters",
    "ft": "feet",
    "in": "inches",
    "cm": "centimeters",
    "meter": "meters",
    "foot": "feet",
    "inch": "inches",
    "centimeter": "centimeters",
}
GIMBAL_EPSILON = 1e-9


def length_unit(name: str) -> str:
    """The canonical name of a length unit (``m``, ``ft``, ``in`` and ``cm`` are accepted)."""
    key = name.strip().lower()
    key = LENGTH_ALIASES.get(key, key)
    if key not in LENGTH_UNITS:
        raise ValueError(f"unknown length unit {name!r}; use one of {', '.join(LENGTH_UNITS)}")
    return key


def length_factor(unit: str) -> float:
    """How many ``unit`` make one meter."""
    return LENGTH_UNITS[length_unit(unit)]


def from_meters(value: float | np.ndarray, unit: str) -> float | np.ndarray:
    """``value`` (meters; a number or an array) in ``unit`` (beyond any float: inf, without
    numpy's overflow warning on stderr)."""
    with np.errstate(over="ignore"):
        return value * length_factor(unit)


def to_meters(value: float | np.ndarray, unit: str) -> float | np.ndarray:
    """``value`` given in ``unit``, in meters."""
    return value / length_factor(unit)


def _rotation_rows(matrix: Sequence[Sequence[float]] | np.ndarray) -> list[list[float]]:
    """The rotation block of a 3x3 or 4x4 matrix (or its 16 values), each column scaled to
    unit length (uniform or per-axis scale does not change the angles), as Python floats:
    one 3x3 block costs a table of 10,000 poses less this way than a dozen numpy calls a row
    (the same operations, in the same order, so the same numbers; inf and nan come out as
    such)."""
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape == (16,):
        m = m.reshape(4, 4)
    if m.shape not in ((3, 3), (4, 4)):
        raise ValueError(f"expected a 3x3 or 4x4 matrix, got shape {m.shape}")
    (a, b, c, *_), (d, e, f, *_), (g, h, i, *_) = m[:3].tolist()
    norms = [math.sqrt(a * a + d * d + g * g), math.sqrt(b * b + e * e + h * h)]
    norms.append(math.sqrt(c * c + f * f + i * i))
    if not all(n > 0 for n in norms):
        raise ValueError("the rotation block has a zero column")
    x, y, z = norms
    return [[a / x, b / y, c / z], [d / x, e / y, f / z], [g / x, h / y, i / z]]


def _rotation_block(matrix: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
    """:func:`_rotation_rows` as a 3x3 array."""
    return np.array(_rotation_rows(matrix))


def translation(matrix: Sequence[Sequence[float]] | np.ndarray) -> tuple[float, float, float]:
    """The translation (meters) of a 4x4 row-major transform (or its 16 values)."""
    m = np.asarray(matrix, dtype=np.float64).reshape(4, 4)
    return float(m[0, 3]), float(m[1, 3]), float(m[2, 3])


def euler_xyz_degrees(matrix: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
    """Angles (x, y, z) in degrees with ``R = Rx(x) · Ry(y) · Rz(z)``; y in [-90, 90].

    At gimbal lock (y = ±90°) z is reported as 0 and x carries the whole remaining turn.
    """
    r = _rotation_rows(matrix)
    sy = min(max(r[0][2], -1.0), 1.0) if r[0][2] == r[0][2] else r[0][2]
    y = math.asin(sy)
    if math.sqrt(r[0][0] ** 2 + r[0][1] ** 2) > GIMBAL_EPSILON:
        x = math.atan2(0.0 - r[1][2], r[2][2])  # 0.0 - v: no -0.0, so no -180 for 180
        z = math.atan2(0.0 - r[0][1], r[0][0])
    else:
        x = math.atan2(r[2][1], r[1][1])
        z = 0.0
    return np.array([math.degrees(x) + 0.0, math.degrees(y) + 0.0, math.degrees(z) + 0.0])


def rotation_from_euler_xyz_degrees(x: float, y: float, z: float) -> np.ndarray:
    """The 3x3 rotation ``Rx(x) · Ry(y) · Rz(z)`` (degrees)."""
    a, b, c = (math.radians(v) for v in (x, y, z))
    ca, sa, cb, sb, cc, sc = (
        math.cos(a),
        math.sin(a),
        math.cos(b),
        math.sin(b),
        math.cos(c),
        math.sin(c),
    )
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return rx @ ry @ rz


def quaternion_wxyz(matrix: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
    """The unit quaternion (w, x, y, z) of a rotation, with w >= 0."""
    r = _rotation_block(matrix)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif r[0, 0] >= r[1, 1] and r[0, 0] >= r[2, 2]:
        s = 2.0 * math.sqrt(max(1e-300, 1.0 + r[0, 0] - r[1, 1] - r[2, 2]))
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif r[1, 1] >= r[2, 2]:
        s = 2.0 * math.sqrt(max(1e-300, 1.0 + r[1, 1] - r[0, 0] - r[2, 2]))
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(max(1e-300, 1.0 + r[2, 2] - r[0, 0] - r[1, 1]))
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    quat = np.array(q)
    quat /= np.linalg.norm(quat)
    return -quat if quat[0] < 0 else quat


def rotation_from_quaternion(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The 3x3 rotation of a (not necessarily unit) quaternion."""
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if n == 0:
        raise ValueError("the zero quaternion is not a rotation")
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
