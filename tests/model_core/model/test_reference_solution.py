"""A closed-loop scene on a moving base against an independent high-accuracy solution."""
import numpy as np
import pytest

from gimbal2axis.fmu import simulate

from support.expected_names import STATES
from support.reference_model import ReferenceModel

pytestmark = pytest.mark.python_bound

STEP = 2e-3
STOP = 0.4


def base_motion(t):
    """Ship-like roll, pitch and heave, sampled at the step start (the FMU extrapolates within a step)."""
    w_roll, w_pitch, w_heave = 1.1, 0.7, 0.9
    return {
        "base.gamma": 0.15 * np.sin(w_roll * t), "base.gamma_dot": 0.15 * w_roll * np.cos(w_roll * t),
        "base.gamma_ddot": -0.15 * w_roll**2 * np.sin(w_roll * t),
        "base.delta": 0.05 * np.cos(w_pitch * t), "base.delta_dot": -0.05 * w_pitch * np.sin(w_pitch * t),
        "base.delta_ddot": -0.05 * w_pitch**2 * np.cos(w_pitch * t),
        "base.psi": 0.4, "base.psi_dot": 0.02, "base.psi_ddot": 0.0,
        "base.v_a[1]": 5.0, "base.a_a[3]": 1.5 * np.sin(w_heave * t),
    }


class DelayedPD:
    """Stabilization loop in the master: the voltage computed at t_k is applied over [t_{k+1}, t_{k+2}]
    (the seed's one-sample zero-order-hold delay)."""

    def __init__(self):
        self.pending = {"u_R1": 0.0, "u_R2": 0.0}

    def __call__(self, t, outputs):
        applied = self.pending
        self.pending = {
            "u_R1": 60.0 * (0.3 - outputs["alpha"]) - 4.0 * outputs["alpha_dot"],
            "u_R2": 60.0 * (-0.2 - outputs["beta"]) - 4.0 * outputs["beta_dot"],
        }
        return dict(base_motion(t), **applied)


# The smooth part of the model: the reference has no backlash, current limit or dry friction.
SMOOTH = {"gear1.eta": 0.0, "gear2.eta": 0.0, "motor1.i_L": 1e3, "motor2.i_L": 1e3,
          "rotor1.T_din": 0.0, "rotor1.T_max": 0.0, "rotor2.T_din": 0.0, "rotor2.T_max": 0.0}
# Both cable restraints and both motors' cogging (docs/physics.md section 4.5), strong enough to bend the
# trajectories far beyond the tolerances below.
DISTURBANCES = {"cable1.k": 3.0, "cable1.c": 0.05, "cable1.angle_0": -0.1,
                "cable2.k": 2.0, "cable2.c": 0.02, "cable2.angle_0": 0.3,
                "motor1.T_cogging": 0.01, "motor1.cogging_periods": 12, "motor1.cogging_phase": 0.4,
                "motor2.T_cogging": 0.008, "motor2.cogging_periods": 18, "motor2.cogging_phase": -1.0}


def fmu_and_reference(gimbal_fmu, parameters):
    start = {v.name: float(v.start) for v in gimbal_fmu.model_description.modelVariables
             if v.causality == "parameter" and v.type in ("Real", "Integer")}
    start.update(parameters)
    overrides = dict(parameters, **{"solver.rtol": 1e-8, "solver.atol": 1e-10, "beta": 0.1,
                                    "beta_m": 0.1 * start["gear2.N"]})
    fmu = simulate(gimbal_fmu, STOP, STEP, overrides, DelayedPD(), STATES)

    model = ReferenceModel(start)
    x = np.zeros(12)
    x[2], x[3] = overrides["beta"], overrides["beta_m"]
    controller = DelayedPD()
    states = [x]
    for k in range(int(round(STOP / STEP))):
        t = k * STEP
        outputs = dict(zip(STATES, x))
        x = model.step(x, t, STEP, controller(t, outputs))
        states.append(x)
    return fmu, np.array(states)


def assert_agreement(fmu, reference):
    for j, name in enumerate(STATES[:4]):
        error = np.max(np.abs(fmu[name] - reference[:, j]))
        print(f"{name}: max error against the reference {error:.2e} rad")
        assert error < 1e-7, f"{name}: max error {error:.3e} rad"
    for j, name in enumerate(STATES[4:8], start=4):
        error = np.max(np.abs(fmu[name] - reference[:, j]))
        assert error < 1e-5, f"{name}: max error {error:.3e} rad/s"


def test_closed_loop_on_moving_base_matches_independent_solution(gimbal_fmu):
    fmu, reference = fmu_and_reference(gimbal_fmu, SMOOTH)
    # The loop really moved the gimbal and the gears really flexed, else agreement would prove little.
    assert np.ptp(reference[:, 0]) > 0.1 and np.ptp(reference[:, 2]) > 0.1
    assert_agreement(fmu, reference)


def test_cable_restraints_and_cogging_match_independent_solution(gimbal_fmu):
    fmu, reference = fmu_and_reference(gimbal_fmu, dict(SMOOTH, **DISTURBANCES))
    # The elements bend every coordinate's path by far more than the agreement asked below.
    plain = simulate(gimbal_fmu, STOP, STEP, dict(SMOOTH, **{"solver.rtol": 1e-8, "solver.atol": 1e-10,
                                                            "beta": 0.1,
                                                            "beta_m": 0.1 * gimbal_fmu.start("gear2.N")}),
                     DelayedPD(), STATES)
    for name in STATES[:4]:
        assert np.max(np.abs(plain[name] - fmu[name])) > 1e-4, name
    assert_agreement(fmu, reference)
