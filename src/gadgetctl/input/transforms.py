"""4x4 homogeneous transforms (numpy float64, column-vector convention, meters)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def identity() -> np.ndarray:
    return np.eye(4)


def translation(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def rotation_x(radians: float) -> np.ndarray:
    c, s = math.cos(radians), math.sin(radians)
    m = np.eye(4)
    m[1, 1], m[1, 2], m[2, 1], m[2, 2] = c, -s, s, c
    return m


def rotation_y(radians: float) -> np.ndarray:
    c, s = math.cos(radians), math.sin(radians)
    m = np.eye(4)
    m[0, 0], m[0, 2], m[2, 0], m[2, 2] = c, s, -s, c
    return m


def rotation_z(radians: float) -> np.ndarray:
    c, s = math.cos(radians), math.sin(radians)
    m = np.eye(4)
    m[0, 0], m[0, 1], m[1, 0], m[1, 1] = c, -s, s, c
    return m


def rotation_axis(axis: Sequence[float], radians: float) -> np.ndarray:
    """Rotation by ``radians`` about a unit ``axis`` (right-handed)."""
    x, y, z = axis
    c, s, t = math.cos(radians), math.sin(radians), 1.0 - math.cos(radians)
    m = np.eye(4)
    m[:3, :3] = ((t * x * x + c, t * x * y - s * z, t * x * z + s * y),
                 (t * x * y + s * z, t * y * y + c, t * y * z - s * x),
                 (t * x * z - s * y, t * y * z + s * x, t * z * z + c))
    return m


def euler_xyz_degrees(x: float, y: float, z: float) -> np.ndarray:
    """The rotation VR Juggler builds from Euler XYZ angles in degrees: Rx·Ry·Rz."""
    return rotation_x(math.radians(x)) @ rotation_y(math.radians(y)) @ rotation_z(math.radians(z))


def from_row_major(values: Sequence[float]) -> np.ndarray:
    """A matrix from 16 values written row by row (element [r][c] = values[4r+c])."""
    if len(values) != 16:
        raise ValueError(f"a 4x4 matrix needs 16 values, not {len(values)}")
    return np.asarray(values, dtype=np.float64).reshape(4, 4)


def as_matrices(data: object) -> np.ndarray:
    """``data`` as an array of 4x4 float64 matrices, shape (..., 4, 4)."""
    array = np.asarray(data, dtype=np.float64)
    if array.shape[-2:] != (4, 4):
        raise ValueError(f"expected 4x4 matrices, got shape {array.shape}")
    return array
