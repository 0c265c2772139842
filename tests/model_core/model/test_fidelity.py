"""Reduced models: fewer states, less stiffness, and the exact limits of the full model."""
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from gimbal2axis.fmu import simulate

ANGLES = ["alpha", "beta", "alpha_dot", "beta_dot"]
COUNTERS = ["solver.states", "solver.steps", "solver.rhs_evaluations"]
SMOOTH = {"dry_friction": False, "solver.rtol": 1e-10, "solver.atol": 1e-12, "beta": 0.2}


def loop(t, y):
    """A PD loop with a set-point step, so that the drive train carries real torques."""
    target_alpha, target_beta = (0.3, -0.1) if t < 0.15 else (-0.2, 0.25)
    return {"u_R1": 40.0 * (target_alpha - y["alpha"]) - 2.0 * y["alpha_dot"],
            "u_R2": 40.0 * (target_beta - y["beta"]) - 2.0 * y["beta_dot"]}


def run(fmu, values, stop=0.3):
    return simulate(fmu, stop, 1e-3, dict(SMOOTH, **values), loop, ANGLES + COUNTERS)


def max_error(a, b):
    return max(np.max(np.abs(a[n] - b[n])) for n in ("alpha", "beta"))


def test_rigid_gears_are_the_limit_of_stiffening_compliant_gears(gimbal_fmu):
    rigid = run(gimbal_fmu, {"gear1.model": 0, "gear2.model": 0, "beta_m": 0.0})
    errors, steps = [], []
    for stiffness in (1e4, 1e5, 1e6):
        # beta_m = N beta: the compliant gear starts relaxed, like the rigid one.
        compliant = run(gimbal_fmu, {"gear1.model": 1, "gear2.model": 1, "gear1.k_s": stiffness,
                                     "gear2.k_s": stiffness, "beta_m": 60.0 * 0.2})
        errors.append(max_error(compliant, rigid))
        steps.append(compliant["solver.steps"][-1])
    # Deflection ~ torque / k_s: the error falls about tenfold per decade of stiffness.
    print("errors", errors)
    assert errors[0] / errors[1] > 5 and errors[1] / errors[2] > 5, errors
    assert errors[2] < 1e-4
    # Fewer states and no shaft mode to resolve.
    assert rigid["solver.states"][-1] == 6 and compliant["solver.states"][-1] == 10
    assert rigid["solver.steps"][-1] < min(steps)
    assert np.ptp(rigid["alpha"]) > 0.1  # the loop really slewed


def test_quasi_static_motors_are_the_limit_of_vanishing_inductance(gimbal_fmu):
    quasi = run(gimbal_fmu, {"motor1.model": 0, "motor2.model": 0, "beta_m": 12.0})
    errors = []
    for inductance in (1e-3, 1e-4, 1e-5):
        full = run(gimbal_fmu, {"motor1.L": inductance, "motor2.L": inductance, "beta_m": 12.0})
        errors.append(max_error(full, quasi))
    print("errors", errors)
    assert errors[0] / errors[1] > 5 and errors[1] / errors[2] > 5, errors
    assert quasi["solver.states"][-1] == 10


def test_rigid_gear_and_quasi_static_motor_together(gimbal_fmu):
    reduced = run(gimbal_fmu, {"gear1.model": 0, "gear2.model": 0, "motor1.model": 0, "motor2.model": 0,
                               "base.fixed": True})
    assert reduced["solver.states"][-1] == 4
    assert np.all(np.isfinite(reduced["alpha"])) and np.ptp(reduced["alpha"]) > 0.1


def test_backlash_model_with_zero_backlash_equals_the_compliant_model(gimbal_fmu):
    with_slot = run(gimbal_fmu, {"gear1.eta": 0.0, "gear2.eta": 0.0, "beta_m": 12.0})
    compliant = run(gimbal_fmu, {"gear1.model": 1, "gear2.model": 1, "beta_m": 12.0})
    assert with_slot["solver.states"][-1] == 12 and compliant["solver.states"][-1] == 10
    assert max_error(with_slot, compliant) < 1e-8


def test_dry_friction_off_equals_frictionless_parameters(gimbal_fmu):
    off = run(gimbal_fmu, {"beta_m": 12.0})
    zero = run(gimbal_fmu, {"dry_friction": True, "rotor1.T_max": 0.0, "rotor1.T_din": 0.0,
                            "rotor2.T_max": 0.0, "rotor2.T_din": 0.0, "beta_m": 12.0})
    assert max_error(off, zero) == 0.0


def test_rigid_axis_merges_rotor_and_load_friction(gimbal_fmu):
    """docs/physics.md section 6 (a rigid axis with dry friction on both sides): T_max = T_max_load + N T_max_rotor on the load axis. A load torque just below
    that holds the axis; just above it breaks away."""
    N, t_max_rotor, t_max_load = 60.0, 0.0025, 0.05
    held_limit = t_max_load + N * t_max_rotor
    base = {"gear2.model": 0, "g": 0.0, "dry_friction": True, "body2.T_max": t_max_load, "body2.T_din": 0.04,
            "body2.w_min": 1e-3, "rotor2.T_max": t_max_rotor, "rotor2.T_din": 0.0015, "motor2.k_emf": 0.0,
            "solver.rtol": 1e-10, "solver.atol": 1e-12}
    k_torque, resistance = 0.04, 2.5

    def with_motor_torque(load_torque):
        current = load_torque / N / k_torque  # the rotor's torque reaches the load multiplied by N
        return simulate(gimbal_fmu, 0.2, 1e-3, dict(base, **{"i_R2": current}),
                        lambda t, y: {"u_R2": resistance * current}, ["beta", "beta_dot", "body2.stick_slip"])

    held = with_motor_torque(0.97 * held_limit)
    moving = with_motor_torque(1.03 * held_limit)
    assert held["body2.stick_slip"][-1] == 0 and abs(held["beta"][-1]) < 1e-3 * 0.2
    assert moving["body2.stick_slip"][-1] == 2 and moving["beta"][-1] > 1e-3


def test_fixed_base_refuses_base_motion(gimbal_fmu):
    with pytest.raises(FMICallException):
        simulate(gimbal_fmu, 0.01, 1e-3, {"base.fixed": True}, lambda t, y: {"base.gamma_dot": 0.1}, ANGLES)
    fixed = run(gimbal_fmu, {"base.fixed": True, "beta_m": 12.0})
    free = run(gimbal_fmu, {"beta_m": 12.0})
    assert max_error(fixed, free) < 1e-12
