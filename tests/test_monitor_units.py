"""Length units and rotation conversions against known rotations and the filter convention."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gadgetctl.input.transforms import euler_xyz_degrees as filter_rotation
from gadgetctl.input.transforms import rotation_axis
from gadgetctl.monitor.units import (
    euler_xyz_degrees,
    from_meters,
    length_factor,
    length_unit,
    quaternion_wxyz,
    rotation_from_euler_xyz_degrees,
    rotation_from_quaternion,
    to_meters,
    translation,
)

S = math.sqrt(0.5)


@pytest.mark.parametrize(
    ("unit", "factor"),
    [
        ("meters", 1.0),
        ("feet", 3.28084),
        ("inches", 39.3701),
        ("centimeters", 100.0),
        ("m", 1.0),
        ("FT", 3.28084),
        ("in", 39.3701),
        ("cm", 100.0),
    ],
)
def test_length_factors(unit, factor):
    assert length_factor(unit) == factor
    assert from_meters(2.0, unit) == pytest.approx(2.0 * factor)
    assert to_meters(from_meters(1.7, unit), unit) == pytest.approx(1.7)


def test_lengths_of_arrays_and_unknown_units():
    assert from_meters(np.array([1.0, 0.5]), "cm") == pytest.approx([100.0, 50.0])
    assert length_unit(" Inch ") == "inches"
    with pytest.raises(ValueError, match="meters, feet, inches, centimeters"):
        length_factor("furlongs")


def test_the_convention_is_rx_ry_rz_as_in_position_transform_filter():
    for angles in [(10, 20, 30), (-45, 60, 170), (90, 0, 0), (0, -30, 0), (0, 0, -45)]:
        ours = rotation_from_euler_xyz_degrees(*angles)
        assert ours == pytest.approx(filter_rotation(*angles)[:3, :3])


@pytest.mark.parametrize(
    ("matrix", "angles"),
    [
        (np.eye(3), (0, 0, 0)),
        ([[1, 0, 0], [0, 0, -1], [0, 1, 0]], (90, 0, 0)),  # 90 about x
        ([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], (0, 90, 0)),  # 90 about y (gimbal lock)
        ([[S, S, 0], [-S, S, 0], [0, 0, 1]], (0, 0, -45)),  # -45 about z
        ([[-1, 0, 0], [0, -1, 0], [0, 0, 1]], (0, 0, 180)),
    ],
)
def test_known_rotations_to_euler(matrix, angles):
    assert euler_xyz_degrees(matrix) == pytest.approx(angles, abs=1e-9)


def test_euler_round_trip_over_many_rotations():
    rng = np.random.default_rng(11)
    for _ in range(500):
        angles = (rng.uniform(-180, 180), rng.uniform(-89.9, 89.9), rng.uniform(-180, 180))
        m = filter_rotation(*angles)
        assert euler_xyz_degrees(m) == pytest.approx(angles, abs=1e-7)


def test_gimbal_lock_reproduces_the_rotation():
    for angles in [(30, 90, 40), (-20, -90, 75)]:
        m = rotation_from_euler_xyz_degrees(*angles)
        back = euler_xyz_degrees(m)
        assert back[2] == 0.0
        assert rotation_from_euler_xyz_degrees(*back) == pytest.approx(m, abs=1e-9)


def test_scale_and_translation_do_not_disturb_angles():
    m = filter_rotation(10, 20, 30)
    m[:3, :3] *= 2.5
    m[:3, 3] = (1.0, 2.0, 3.0)
    assert euler_xyz_degrees(m) == pytest.approx((10, 20, 30))
    assert euler_xyz_degrees(m.tolist()) == pytest.approx((10, 20, 30))
    assert euler_xyz_degrees(m.ravel().tolist()) == pytest.approx((10, 20, 30))
    assert translation(m.tolist()) == (1.0, 2.0, 3.0)


@pytest.mark.parametrize(
    ("matrix", "quat"),
    [
        (np.eye(4), (1, 0, 0, 0)),
        ([[S, -S, 0], [S, S, 0], [0, 0, 1]], (math.cos(math.pi / 8), 0, 0, math.sin(math.pi / 8))),
        ([[1, 0, 0], [0, -1, 0], [0, 0, -1]], (0, 1, 0, 0)),  # 180 about x
        ([[-1, 0, 0], [0, 1, 0], [0, 0, -1]], (0, 0, 1, 0)),  # 180 about y
        ([[-1, 0, 0], [0, -1, 0], [0, 0, 1]], (0, 0, 0, 1)),  # 180 about z
        ([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], (S, 0, S, 0)),  # 90 about y
    ],
)
def test_known_rotations_to_quaternions(matrix, quat):
    assert quaternion_wxyz(matrix) == pytest.approx(quat, abs=1e-12)


def test_quaternion_round_trip_over_many_rotations():
    rng = np.random.default_rng(5)
    for _ in range(500):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        q = q if q[0] >= 0 else -q
        m = rotation_from_quaternion(*q)
        assert quaternion_wxyz(m) == pytest.approx(q, abs=1e-9)
        angles = euler_xyz_degrees(m)
        assert rotation_from_euler_xyz_degrees(*angles) == pytest.approx(m, abs=1e-9)


def test_quaternion_matches_axis_angle():
    angle = math.radians(73)
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    m = rotation_axis(axis, angle)
    expected = (math.cos(angle / 2), *(axis * math.sin(angle / 2)))
    assert quaternion_wxyz(m) == pytest.approx(expected)


def test_bad_matrices():
    with pytest.raises(ValueError, match="3x3 or 4x4"):
        euler_xyz_degrees([[1, 0], [0, 1]])
    with pytest.raises(ValueError, match="zero column"):
        quaternion_wxyz(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="zero quaternion"):
        rotation_from_quaternion(0, 0, 0, 0)
