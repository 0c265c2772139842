"""The real-time method (solver.method = 7): RODAS4 in solver.substeps fixed substeps per doStep.

Its order in the substeps on a hybrid scene, its fixed work per doStep, and its refusal of a gear
contact or a motor armature it cannot resolve. The bound on mode changes per doStep is tested on a bouncing ball in
tests/model_core/integrators/test_hybrid_integrator.cpp. Timings are benchmarks, not tests (docs/benchmarks.md).
"""
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from gimbal2axis.fmu import simulate
from test_fast_core import ship_inputs as ship_loop  # a PD loop against a rolling, pitching carrier

ERROR, DISCARD = 3, 2
REAL_TIME = 7
OUTPUTS = ["alpha", "beta", "alpha_dot", "beta_dot", "i_R1", "events.total", "solver.steps",
           "solver.rhs_evaluations", "solver.jacobian_evaluations"]


def angle_error(run, reference):
    return max(np.max(np.abs(run[name] - reference[name])) for name in ("alpha", "beta"))


def test_fourth_order_in_the_substeps_on_a_hybrid_scene(gimbal_fmu):
    # h = 1e-3: the master's clock is not exact in binary, as a rig's is not.
    reference = simulate(gimbal_fmu, 0.3, 1e-3, {"solver.rtol": 1e-11, "solver.atol": 1e-13}, ship_loop, OUTPUTS)
    errors = []
    for substeps in (1, 2, 4):
        run = simulate(gimbal_fmu, 0.3, 1e-3, {"solver.method": REAL_TIME, "solver.substeps": substeps},
                       ship_loop, OUTPUTS)
        # The same mode changes, located within the method's bounded iterations.
        assert abs(run["events.total"][-1] - reference["events.total"][-1]) <= 2
        errors.append(angle_error(run, reference))
    assert reference["events.total"][-1] > 10
    assert errors[0] < 5e-6, errors  # one substep is within the product's 1e-6 rad class on this scene
    # Order 4: a halved substep divides the error by about 16; 8 allows for the event location's share.
    assert errors[0] / errors[1] > 8 and errors[1] / errors[2] > 8, errors


def test_work_per_doStep_is_fixed_when_no_mode_changes(gimbal_fmu):
    # Compliant gears without backlash, no dry friction, voltages below the current limit: no events.
    smooth = {"gear1.model": 1, "gear2.model": 1, "dry_friction": False, "solver.method": REAL_TIME}

    def inputs(t, y):
        return {"u_R1": 4.0 * np.sin(20.0 * t), "u_R2": -3.0 * np.cos(15.0 * t),
                "base.gamma": 0.05 * np.sin(2 * t), "base.gamma_dot": 0.1 * np.cos(2 * t),
                "base.gamma_ddot": -0.2 * np.sin(2 * t)}

    for substeps in (1, 3):
        run = simulate(gimbal_fmu, 0.2, 1e-3, {**smooth, "solver.substeps": substeps}, inputs, OUTPUTS)
        assert run["events.total"][-1] == 0
        rhs = np.diff(run["solver.rhs_evaluations"][1:])  # the first doStep also starts the integrator
        jacobians = np.diff(run["solver.jacobian_evaluations"])
        steps = np.diff(run["solver.steps"])
        assert np.all(steps == substeps) and np.all(jacobians == substeps)
        assert np.all(rhs == rhs[0]), np.unique(rhs)
        assert rhs[0] <= 7 * substeps + 1  # RODAS4: 6 stages and df/dt per substep, one restart


def _run_until_failure(fmu, start_values, inputs, stop_time, log):
    slave = fmu.instantiate("real_time", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        fmu.set_values(slave, start_values)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        latest = dict(zip(OUTPUTS, fmu.get_values(slave, OUTPUTS)))
        for k in range(int(round(stop_time / 1e-3))):
            fmu.set_values(slave, inputs(k * 1e-3, latest))
            try:
                slave.doStep(currentCommunicationPoint=k * 1e-3, communicationStepSize=1e-3)
            except FMICallException:
                return k
            latest = dict(zip(OUTPUTS, fmu.get_values(slave, OUTPUTS)))
        return None
    finally:
        slave.freeInstance()


def test_an_unresolved_gear_contact_is_refused_with_the_substeps_it_needs(gimbal_fmu):
    stiff = {"gear1.k_s": 1e6, "gear2.k_s": 1e6, "solver.method": REAL_TIME}
    log = []
    assert _run_until_failure(gimbal_fmu, stiff, ship_loop, 0.01, log) == 0
    errors = [entry.text for entry in log if entry.status == ERROR]
    # Both gears named; the substeps asked for are those of the stiffer contact (gear2: lighter load).
    assert any("gear1's contact oscillation" in text and "gear2's contact oscillation" in text and
               "solver.substeps >= 6" in text for text in errors), errors
    # With the substeps it asked for, the same scene runs.
    log = []
    assert _run_until_failure(gimbal_fmu, {**stiff, "solver.substeps": 6}, ship_loop, 0.05, log) is None


def reversing_voltage(t, y):
    """+-12 V on motor 2, reversed every 50 ms: the current crosses from one limit to the other."""
    return {"u_R2": 12.0 if int(t / 0.05) % 2 == 0 else -12.0}


def test_an_unresolved_armature_is_refused_and_its_cures_are_accurate(gimbal_fmu):
    """A 10 uH armature (L/R = 4e-6 s) at 1 ms substeps: its current limit would be located on an
    interpolant that does not follow the transient (beta was 1.3e-3 rad off at one substep, 1.6e-4 at
    eight: first order). Refused, with the substeps that resolve it and the quasi-static motor named;
    both cures agree with CVODE BDF at a tight tolerance."""
    small = {"motor2.L": 1e-5, "base.fixed": True, "dry_friction": False}
    log = []
    assert _run_until_failure(gimbal_fmu, {**small, "solver.method": REAL_TIME}, reversing_voltage, 0.01, log) == 0
    errors = [entry.text for entry in log if entry.status == ERROR]
    assert any("motor2's armature transient" in text and "solver.substeps >= 25" in text and
               "motor2" in text and "motor<k>.model = 0" in text for text in errors), errors
    outputs = ["beta", "events.total"]
    # At the bound (L/R = 0.1 substep) the error is the method's usual one at one substep on the ship
    # scene (1.3e-6 rad); the quasi-static motor keeps its fourth order (9e-7 at one substep).
    for cure, bound in (({"solver.substeps": 25}, 5e-6), ({"motor2.model": 0}, 2e-6)):
        start = {**small, **cure}
        reference = simulate(gimbal_fmu, 0.2, 1e-3, {**start, "solver.method": 0, "solver.rtol": 1e-11,
                                                      "solver.atol": 1e-13}, reversing_voltage, outputs)
        run = simulate(gimbal_fmu, 0.2, 1e-3, {**start, "solver.method": REAL_TIME}, reversing_voltage, outputs)
        # (The quasi-static motor at one substep passes over two brief limiter releases, 24 mode
        # changes against 26, at no cost in beta.)
        assert reference["events.total"][-1] - run["events.total"][-1] <= (2 if "motor2.model" in cure else 0), cure
        assert np.max(np.abs(run["beta"] - reference["beta"])) < bound, cure


@pytest.mark.parametrize("substeps", [0, 10001])
def test_substeps_out_of_range_are_refused(gimbal_fmu, substeps):
    log = []
    slave = gimbal_fmu.instantiate("real_time", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        gimbal_fmu.set_values(slave, {"solver.method": REAL_TIME, "solver.substeps": substeps})
        slave.enterInitializationMode()
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        assert any("solver.substeps" in entry.text for entry in log if entry.status == ERROR)
    finally:
        slave.freeInstance()
