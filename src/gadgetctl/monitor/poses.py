"""How positions are written: 4x4 matrices, position + quaternion, or position + Euler angles.

``--pose`` of `gadgetctl monitor` and `gadgetctl replay` chooses one of :data:`POSE_FORMATS`:

* ``matrix``: the 4x4 transform, row by row, translation in meters (the recording format);
* ``quaternion``: ``{"position": [x, y, z], "quaternion_wxyz": [w, x, y, z]}``, meters, a unit
  quaternion with w >= 0 (scalar first, as the monitor's views show it; VRPN sends x, y, z, w);
* ``euler``: ``{"position": [x, y, z], "euler_xyz_degrees": [x, y, z]}``, meters and degrees,
  with ``R = Rx(x) · Ry(y) · Rz(z)``: gmtl's ``EulerAngleXYZ``, the convention VR Juggler's
  ``position_transform_filter`` reads ``pre_rotation``/``post_rotation`` in.

Conversions work on batches ((n, 4, 4) arrays) with numpy; :func:`matrix_from_pose` reads any
of the three back, so a stream written with ``--pose quaternion`` replays and summarises.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from gadgetctl.monitor.units import rotation_from_euler_xyz_degrees, rotation_from_quaternion

MATRIX, QUATERNION, EULER = "matrix", "quaternion", "euler"
POSE_FORMATS = (MATRIX, QUATERNION, EULER)
POSITION_KEY = "position"
QUATERNION_KEY = "quaternion_wxyz"
EULER_KEY = "euler_xyz_degrees"
GIMBAL_EPSILON = 1e-9


def _rotations(matrices: np.ndarray) -> np.ndarray:
    """The rotation blocks of (n, 4, 4) transforms with their columns normalised (a scale
    does not change the orientation); a zero column stays zero."""
    r = matrices[:, :3, :3]
    norms = np.linalg.norm(r, axis=1, keepdims=True)
    return np.divide(r, norms, out=np.zeros_like(r), where=norms > 0)


def euler_xyz_degrees_batch(matrices: np.ndarray) -> np.ndarray:
    """(n, 3) angles in degrees with ``R = Rx(x) · Ry(y) · Rz(z)``, y in [-90, 90]; at gimbal
    lock z is 0 and x carries the rest (as :func:`gadgetctl.monitor.units.euler_xyz_degrees`)."""
    r = _rotations(np.asarray(matrices, dtype=np.float64).reshape(-1, 4, 4))
    y = np.arcsin(np.clip(r[:, 0, 2], -1.0, 1.0))
    free = np.hypot(r[:, 0, 0], r[:, 0, 1]) > GIMBAL_EPSILON
    x = np.where(free, np.arctan2(0.0 - r[:, 1, 2], r[:, 2, 2]), np.arctan2(r[:, 2, 1], r[:, 1, 1]))
    z = np.where(free, np.arctan2(0.0 - r[:, 0, 1], r[:, 0, 0]), 0.0)
    return np.degrees(np.stack([x, y, z], axis=1)) + 0.0


def quaternions_wxyz(matrices: np.ndarray) -> np.ndarray:
    """(n, 4) unit quaternions (w, x, y, z) with w >= 0 of (n, 4, 4) transforms."""
    r = _rotations(np.asarray(matrices, dtype=np.float64).reshape(-1, 4, 4))
    m00, m11, m22 = r[:, 0, 0], r[:, 1, 1], r[:, 2, 2]
    # Each row of candidates is 4 * (w², x², y², z²) computed from the diagonal; the largest
    # one gives the best-conditioned formula (Shepperd's method).
    squares = np.stack(
        [1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22], axis=1
    )
    pick = np.argmax(squares, axis=1)
    s = np.sqrt(np.maximum(squares[np.arange(len(r)), pick], 1e-300))  # 2 * |component|
    d21, d02, d10 = r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]
    s01, s02, s12 = r[:, 0, 1] + r[:, 1, 0], r[:, 0, 2] + r[:, 2, 0], r[:, 1, 2] + r[:, 2, 1]
    q = np.empty((len(r), 4))
    cases = (
        (s, d21 / s, d02 / s, d10 / s),
        (d21 / s, s, s01 / s, s02 / s),
        (d02 / s, s01 / s, s, s12 / s),
        (d10 / s, s02 / s, s12 / s, s),
    )
    for index, parts in enumerate(cases):
        chosen = pick == index
        if chosen.any():
            q[chosen] = np.stack(parts, axis=1)[chosen]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1.0
    return q + 0.0


def pose_values(matrices: Any, pose: str) -> list[Any]:
    """JSON-ready values of a batch of transforms (any shape ending in 4x4) in ``pose``."""
    m = np.asarray(matrices, dtype=np.float64).reshape(-1, 4, 4)
    if pose == MATRIX:
        return m.tolist()
    positions = m[:, :3, 3].tolist()
    if pose == QUATERNION:
        return [
            {POSITION_KEY: p, QUATERNION_KEY: q}
            for p, q in zip(positions, quaternions_wxyz(m).tolist(), strict=True)
        ]
    if pose == EULER:
        return [
            {POSITION_KEY: p, EULER_KEY: a}
            for p, a in zip(positions, euler_xyz_degrees_batch(m).tolist(), strict=True)
        ]
    raise ValueError(f"unknown pose format {pose!r}; use one of {', '.join(POSE_FORMATS)}")


def pose_value(matrix: Any, pose: str) -> Any:
    """One transform's JSON-ready value in ``pose``."""
    return pose_values(matrix, pose)[0]


def matrix_from_pose(value: Any) -> np.ndarray:
    """A 4x4 transform from any pose value (a matrix, its 16 values, or a position with a
    quaternion or Euler angles); raises ValueError or TypeError for anything else."""
    if isinstance(value, Mapping):
        position = np.asarray(value[POSITION_KEY], dtype=np.float64).reshape(3)
        m = np.eye(4)
        if QUATERNION_KEY in value:
            w, x, y, z = (float(v) for v in value[QUATERNION_KEY])
            m[:3, :3] = rotation_from_quaternion(w, x, y, z)
        elif EULER_KEY in value:
            ax, ay, az = (float(v) for v in value[EULER_KEY])
            m[:3, :3] = rotation_from_euler_xyz_degrees(ax, ay, az)
        else:
            raise ValueError(f"a pose needs {QUATERNION_KEY!r} or {EULER_KEY!r}")
        m[:3, 3] = position
        return m
    return np.asarray(value, dtype=np.float64).reshape(4, 4)
