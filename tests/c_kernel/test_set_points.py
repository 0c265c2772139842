"""The target's set points from the C kernel (c_kernel/src/set_points.c), which the scene runner and
the controller FMU share, against an independent numpy form of the same inverse kinematics: equal
to rounding (numpy may take SIMD sin/cos/atan2/hypot that differ from libm in the last bit; the
rate, a difference over 1e-6 s, magnifies that by 1e6)."""
import math

import numpy as np
import pytest

from gimbal2axis.scene import geometry
from gimbal2axis.scene.setpoints import plan_set_points, target_direction, target_set_points


def numpy_target_angles(target, attitude):
    """The inverse kinematics row by row in numpy: the target in frame 0, then its azimuth and elevation."""
    delta, psi, gamma = attitude.T
    x, y, z = (np.full(len(attitude), component) for component in target)
    y, z = np.cos(delta) * y + np.sin(delta) * z, -np.sin(delta) * y + np.cos(delta) * z
    x, y = np.cos(psi) * x + np.sin(psi) * y, -np.sin(psi) * x + np.cos(psi) * y
    x, z = np.cos(gamma) * x - np.sin(gamma) * z, np.sin(gamma) * x + np.cos(gamma) * z
    return np.arctan2(-x, y), np.arctan2(z, np.hypot(x, y))


def numpy_set_points(target, attitude, rates, step=1e-6):
    alpha, beta = numpy_target_angles(target, attitude)
    alpha_ahead, beta_ahead = numpy_target_angles(target, attitude + step * rates)
    turn = alpha_ahead - alpha
    turn -= 2 * np.pi * np.round(turn / (2 * np.pi))
    return np.column_stack([alpha, beta]), np.column_stack([turn / step, (beta_ahead - beta) / step])


@pytest.fixture(scope="module")
def ship_attitude():
    rng = np.random.default_rng(3)
    attitude = rng.normal(0.0, [0.1, 0.05, 0.5], (4000, 3))
    attitude[:50, 1] = np.pi + rng.normal(0.0, 1e-3, 50)   # the target's azimuth near the branch cut
    return attitude, rng.normal(0.0, 0.2, (4000, 3))


@pytest.mark.parametrize("azimuth_deg, elevation_deg", [(30.0, 5.0), (180.0, 10.0), (-90.0, -60.0)])
def test_kernel_set_points_equal_numpy_to_rounding(ship_attitude, azimuth_deg, elevation_deg):
    attitude, rates = ship_attitude
    target = target_direction(math.radians(azimuth_deg), math.radians(elevation_deg))
    values, value_rates = target_set_points(target, attitude, rates)
    expected_values, expected_rates = numpy_set_points(np.array(target), attitude, rates)
    np.testing.assert_allclose(values.T, expected_values, rtol=0, atol=4e-16 * 8)
    np.testing.assert_allclose(value_rates.T, expected_rates, rtol=0, atol=1e-8)
    assert np.all(np.abs(values[0]) <= np.pi) and np.all(np.abs(values[1]) <= np.pi / 2)


def test_the_azimuth_rate_crossing_the_branch_cut_is_the_turn_not_a_jump():
    """A target behind the gimbal: alpha jumps by 2 pi between the two attitudes, its rate does not."""
    target = target_direction(math.radians(180.0), 0.0)
    attitude = np.array([[0.0, -1e-7, 0.0]])
    rates = np.array([[0.0, 1.0, 0.0]])   # psi turns through 0: alpha crosses +-pi
    values, value_rates = target_set_points(target, attitude, rates)
    assert abs(abs(values[0, 0]) - math.pi) < 1e-6
    assert value_rates[0, 0] == pytest.approx(-1.0, abs=1e-6)


def test_set_points_match_the_scalar_inverse_kinematics():
    target = target_direction(math.radians(30.0), math.radians(5.0))
    attitude, rates = np.array([[0.05, -0.02, 0.3]]), np.array([[0.1, 0.2, -0.1]])
    points = plan_set_points(["target", "target"], target, np.array([0.0]), 1e-3, attitude, rates)
    alpha, beta = geometry.gimbal_angles_for(target, *attitude[0])
    assert points.values[0] == pytest.approx([alpha, beta], abs=1e-15)
    assert points.unwrap == (True, False)


def test_target_direction_is_the_geometry_modules():
    for azimuth, elevation in [(0.3, 0.1), (-2.0, 1.2), (math.pi, -0.5)]:
        np.testing.assert_allclose(target_direction(azimuth, elevation),
                                   geometry.target_direction(azimuth, elevation), rtol=0, atol=2e-16)


def test_mismatched_shapes_are_refused():
    with pytest.raises(ValueError, match="must both be"):
        target_set_points((1.0, 0.0, 0.0), np.zeros((3, 3)), np.zeros((2, 3)))
