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
    m[:3, :3] = (
        (t * x * x + c, t * x * y - s * z, t * x * z + s * y),
        (t * x * y + s * z, t * y * y + c, t * y * z - s * x),
        (t * x * z - s * y, t * y * z + s * x, t * z * z + c),
    )
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


def quaternions_xyzw(matrices: object) -> np.ndarray:
    """The unit quaternions (x, y, z, w), w >= 0, of the rotations of 4x4 (or 3x3) matrices,
    shape (..., 4). Vectorised: rotations of less than 120 degrees (trace > 0) take the
    well-conditioned w branch; the others, per matrix, the branch of the largest diagonal
    term."""
    r = np.asarray(matrices, dtype=np.float64)[..., :3, :3]
    shape = r.shape[:-2]
    r = r.reshape(-1, 3, 3)
    q = np.empty((len(r), 4))
    trace = r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2]
    easy = trace > 0
    whole = bool(easy.all())
    sub = r if whole else r[easy]
    s = np.sqrt(1.0 + (trace if whole else trace[easy])) * 2.0
    rows = q if whole else np.empty((len(sub), 4))
    rows[:, 0] = (sub[:, 2, 1] - sub[:, 1, 2]) / s
    rows[:, 1] = (sub[:, 0, 2] - sub[:, 2, 0]) / s
    rows[:, 2] = (sub[:, 1, 0] - sub[:, 0, 1]) / s
    rows[:, 3] = 0.25 * s
    if not whole:
        q[easy] = rows
        q[~easy] = _quaternions_by_largest_term(r[~easy])
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q[q[:, 3] < 0] *= -1.0
    return q.reshape((*shape, 4))


def _quaternions_by_largest_term(r: np.ndarray) -> np.ndarray:
    """(x, y, z, w) of rotations (n, 3, 3), each from the branch of its largest diagonal term."""
    m00, m11, m22 = r[:, 0, 0], r[:, 1, 1], r[:, 2, 2]
    q = np.empty((len(r), 4))
    branch = np.argmax(np.stack([m00 + m11 + m22, m00, m11, m22], axis=-1), axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sqrt(np.maximum(1e-300, 1.0 + m00 + m11 + m22)) * 2.0
        w_branch = np.stack(
            [
                (r[:, 2, 1] - r[:, 1, 2]) / s,
                (r[:, 0, 2] - r[:, 2, 0]) / s,
                (r[:, 1, 0] - r[:, 0, 1]) / s,
                0.25 * s,
            ],
            axis=-1,
        )
        s = np.sqrt(np.maximum(1e-300, 1.0 + m00 - m11 - m22)) * 2.0
        x_branch = np.stack(
            [
                0.25 * s,
                (r[:, 0, 1] + r[:, 1, 0]) / s,
                (r[:, 0, 2] + r[:, 2, 0]) / s,
                (r[:, 2, 1] - r[:, 1, 2]) / s,
            ],
            axis=-1,
        )
        s = np.sqrt(np.maximum(1e-300, 1.0 + m11 - m00 - m22)) * 2.0
        y_branch = np.stack(
            [
                (r[:, 0, 1] + r[:, 1, 0]) / s,
                0.25 * s,
                (r[:, 1, 2] + r[:, 2, 1]) / s,
                (r[:, 0, 2] - r[:, 2, 0]) / s,
            ],
            axis=-1,
        )
        s = np.sqrt(np.maximum(1e-300, 1.0 + m22 - m00 - m11)) * 2.0
        z_branch = np.stack(
            [
                (r[:, 0, 2] + r[:, 2, 0]) / s,
                (r[:, 1, 2] + r[:, 2, 1]) / s,
                0.25 * s,
                (r[:, 1, 0] - r[:, 0, 1]) / s,
            ],
            axis=-1,
        )
    for index, candidate in enumerate((w_branch, x_branch, y_branch, z_branch)):
        chosen = branch == index
        q[chosen] = candidate[chosen]
    return q


def matrices_from_pos_quat(positions: object, quaternions: object) -> np.ndarray:
    """4x4 matrices from translations (..., 3) and quaternions (x, y, z, w) (..., 4); the
    quaternions are normalised first (a zero quaternion gives the identity rotation)."""
    p = np.asarray(positions, dtype=np.float64)
    q = np.asarray(quaternions, dtype=np.float64)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    q = np.where(norm > 0, q / np.where(norm > 0, norm, 1.0), np.array([0.0, 0.0, 0.0, 1.0]))
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    m = np.zeros((*np.broadcast_shapes(p.shape[:-1], q.shape[:-1]), 4, 4))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - w * z)
    m[..., 0, 2] = 2 * (x * z + w * y)
    m[..., 1, 0] = 2 * (x * y + w * z)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - w * x)
    m[..., 2, 0] = 2 * (x * z - w * y)
    m[..., 2, 1] = 2 * (y * z + w * x)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    m[..., :3, 3] = p
    m[..., 3, 3] = 1.0
    return m
