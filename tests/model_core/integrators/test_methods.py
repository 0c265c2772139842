"""Every integrator the FMU offers solves the same hybrid scene to its tolerance."""
import numpy as np
import pytest

from gimbal2axis.fmu import simulate

OUTPUTS = ["alpha", "beta", "alpha_dot", "beta_dot", "i_R1", "theta_b2", "los.omega[1]",
           "events.total", "solver.steps", "solver.rhs_evaluations", "solver.jacobian_evaluations"]


def scene(t, y):
    target = (0.3, -0.2) if t < 0.1 else (-0.1, 0.15)
    return {"u_R1": 50.0 * (target[0] - y["alpha"]) - 2.0 * y["alpha_dot"],
            "u_R2": 50.0 * (target[1] - y["beta"]) - 2.0 * y["beta_dot"],
            "base.gamma": 0.05 * np.sin(2 * t), "base.gamma_dot": 0.1 * np.cos(2 * t),
            "base.gamma_ddot": -0.2 * np.sin(2 * t)}


@pytest.fixture(scope="module")
def reference(gimbal_fmu):
    return simulate(gimbal_fmu, 0.25, 1e-3, {"solver.method": 1, "solver.rtol": 1e-12, "solver.atol": 1e-14},
                    scene, OUTPUTS)


@pytest.mark.parametrize("method", [0, 1, 2, 3, 4, 5, 6])
def test_method_agrees_with_the_reference(gimbal_fmu, reference, method):
    r = simulate(gimbal_fmu, 0.25, 1e-3, {"solver.method": method, "solver.rtol": 1e-9, "solver.atol": 1e-11},
                 scene, OUTPUTS)
    assert reference["events.total"][-1] > 10  # backlash and friction switched on the way
    for name in ("alpha", "beta"):
        assert np.max(np.abs(r[name] - reference[name])) < 1e-6, name
    assert np.max(np.abs(r["los.omega[1]"] - reference["los.omega[1]"])) < 1e-4
    if method == 0:
        # The analytic Jacobian replaces the 12 right-hand sides of each difference-quotient Jacobian.
        assert r["solver.jacobian_evaluations"][-1] > 0
    if method == 3:
        assert r["solver.jacobian_evaluations"][-1] == 0  # explicit: no Jacobian at all
