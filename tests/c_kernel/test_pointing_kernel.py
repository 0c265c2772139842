"""The C kernel's pointing command (c_kernel/src/pointing.c, what the controller FMU computes from its
target inputs) against the scene runner's numpy form (gimbal2axis/target/kinematics.py) on a carrier
that rolls, pitches and yaws with accelerations, for targets all around it (near the keyhole too),
and against forward kinematics: the commanded angles point the line of sight at the target. The
two forms are the same arithmetic: they may differ in the last bits only where numpy's sin and cos
round differently from libm's."""
import ctypes

import numpy as np
import pytest

from gimbal2axis import native
from gimbal2axis.scene import geometry
from gimbal2axis.target.kinematics import PointingCommand, unit_and_derivatives

FIELDS = ("alpha", "beta", "alpha_dot", "beta_dot", "alpha_ddot", "beta_ddot")


def kernel_command(p, p_dot, p_ddot, attitude, rates, accelerations):
    """(status, {field: value}) of gimbal_pointing_command for one sample."""
    arrays = [(ctypes.c_double * 3)(*np.asarray(x, dtype=float)) for x in (p, p_dot, p_ddot, attitude, rates,
                                                                           accelerations)]
    out = (ctypes.c_double * 11)()
    status = native.kernel().gimbal_pointing_command(*[ctypes.addressof(a) for a in arrays], ctypes.addressof(out))
    values = list(out)
    return status, {**dict(zip(FIELDS, values[:6])), "los_rate": np.array(values[6:9]), "range": values[9],
                    "range_rate": values[10]}


def samples(count=400, seed=3):
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=(count, 3))
    direction[:40, :2] *= 1e-3          # within about 0.1 deg of the zenith and the nadir: near the keyhole
    p = direction * rng.uniform(50.0, 20000.0, size=(count, 1))
    return (p, rng.normal(scale=80.0, size=(count, 3)), rng.normal(scale=5.0, size=(count, 3)),
            rng.uniform(-0.3, 0.3, size=(count, 3)) * [1, 10, 1], rng.normal(scale=0.2, size=(count, 3)),
            rng.normal(scale=0.5, size=(count, 3)))


def test_the_kernel_gives_the_numpy_pointing_command():
    p, p_dot, p_ddot, attitude, rates, accelerations = samples()
    u, u_dot, u_ddot, r, r_dot = unit_and_derivatives(p.T, p_dot.T, p_ddot.T)
    reference = PointingCommand(u, u_dot, u_ddot, attitude.T, rates.T, accelerations.T)
    for k in range(len(p)):
        status, got = kernel_command(p[k], p_dot[k], p_ddot[k], attitude[k], rates[k], accelerations[k])
        assert status == 0
        for name in FIELDS:
            want = getattr(reference, name)[k]
            assert got[name] == pytest.approx(want, rel=1e-12, abs=1e-12), (k, name)
        assert np.allclose(got["los_rate"], reference.los_rate[:, k], rtol=1e-12, atol=1e-14), k
        assert got["range"] == pytest.approx(r[k], rel=1e-15) and got["range_rate"] == pytest.approx(r_dot[k], rel=1e-12,
                                                                                                      abs=1e-12)


def test_the_kernels_angles_point_the_line_of_sight_at_the_target():
    p, p_dot, p_ddot, attitude, rates, accelerations = samples(seed=5)
    for k in range(len(p)):
        _, got = kernel_command(p[k], p_dot[k], p_ddot[k], attitude[k], rates[k], accelerations[k])
        line_of_sight = geometry.los_direction(got["alpha"], got["beta"], *attitude[k])
        assert np.linalg.norm(np.asarray(line_of_sight) - p[k] / np.linalg.norm(p[k])) < 1e-12, k


def test_the_kernels_rates_are_the_derivatives_of_its_angles_along_the_motion():
    # p(t) = p0 + v t + a t^2 / 2 and the attitude moving with its rates and accelerations: central
    # differences of alpha and beta over 1e-4 s against the rates, of the rates against the accelerations
    p, p_dot, p_ddot, attitude, rates, accelerations = samples(count=60, seed=8)
    h = 1e-4
    for k in range(40, 60):   # away from the keyhole, where the differences resolve the rates
        def at(t):
            return kernel_command(p[k] + p_dot[k] * t + p_ddot[k] * t * t / 2, p_dot[k] + p_ddot[k] * t, p_ddot[k],
                                  attitude[k] + rates[k] * t + accelerations[k] * t * t / 2,
                                  rates[k] + accelerations[k] * t, accelerations[k])[1]
        ahead, now, behind = at(h), at(0.0), at(-h)
        for angle in ("alpha", "beta"):
            turn = np.angle(np.exp(1j * (ahead[angle] - behind[angle])))
            assert turn / (2 * h) == pytest.approx(now[f"{angle}_dot"], rel=1e-6, abs=1e-8), (k, angle)
            assert (ahead[f"{angle}_dot"] - behind[f"{angle}_dot"]) / (2 * h) == \
                pytest.approx(now[f"{angle}_ddot"], rel=1e-5, abs=1e-6), (k, angle)


@pytest.mark.parametrize("position, status", [((0.0, 0.0, 0.0), 1), ((float("nan"), 0.0, 1.0), 1),
                                               ((0.0, 0.0, 250.0), 2), ((0.0, 0.0, -3.0), 2)])
def test_no_direction_and_the_azimuth_axis_itself_are_refused(position, status):
    assert kernel_command(position, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                          (0.0, 0.0, 0.0))[0] == status
