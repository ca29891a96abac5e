"""Batched matrix <-> (position, quaternion) conversions used by `serve` (and VRPN clients)."""

from __future__ import annotations

import math

import numpy as np

from gadgetctl.input.transforms import matrices_from_pos_quat, quaternions_xyzw, rotation_axis
from gadgetctl.monitor.units import quaternion_wxyz


def test_round_trip_of_random_poses_is_exact_to_rounding():
    rng = np.random.default_rng(7)
    q = rng.normal(size=(2000, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 3] < 0] *= -1
    p = rng.normal(size=(2000, 3)) * 5
    m = matrices_from_pos_quat(p, q)
    np.testing.assert_allclose(quaternions_xyzw(m), q, atol=1e-12)
    np.testing.assert_array_equal(m[:, :3, 3], p)
    np.testing.assert_allclose(
        m[:, :3, :3] @ m[:, :3, :3].transpose(0, 2, 1),
        np.broadcast_to(np.eye(3), (2000, 3, 3)),
        atol=1e-12,
    )


def test_half_turns_and_identity_take_the_stable_branch():
    for axis in ([1, 0, 0], [0, 1, 0], [0, 0, 1], [math.sqrt(0.5), math.sqrt(0.5), 0]):
        for angle in (math.pi, math.pi - 1e-9, 0.0, 1e-9):
            m = rotation_axis(axis, angle)
            q = quaternions_xyzw(m)
            assert abs(np.linalg.norm(q) - 1) < 1e-12 and q[3] >= 0
            np.testing.assert_allclose(
                matrices_from_pos_quat([0, 0, 0], q)[:3, :3], m[:3, :3], atol=1e-12
            )


def test_agrees_with_the_monitors_single_matrix_conversion():
    m = rotation_axis(np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8]), 2.1)
    w, x, y, z = quaternion_wxyz(m)
    np.testing.assert_allclose(quaternions_xyzw(m), [x, y, z, w], atol=1e-12)


def test_a_zero_quaternion_is_the_identity():
    np.testing.assert_array_equal(
        matrices_from_pos_quat([1, 2, 3], [0, 0, 0, 0])[:3, :3], np.eye(3)
    )
