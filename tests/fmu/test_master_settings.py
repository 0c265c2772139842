"""What the master asks for is either done or said: the tolerance of fmi2SetupExperiment, steps whose
work is out of proportion, functions the FMU does not offer, and status queries in the wrong state."""
import ctypes

import pytest
from fmpy.fmi1 import FMICallException

OK, WARNING = 0, 1
VOLTAGES = {"u_R1": 2.0, "u_R2": -1.5}


def initialized(fmu, log, start_values=None, tolerance=None):
    slave = fmu.instantiate("settings", log=log, logging_on=True)
    slave.setupExperiment(tolerance=tolerance, startTime=0.0)
    fmu.set_values(slave, {**VOLTAGES, **(start_values or {})})
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def trajectory(fmu, slave, steps=200):
    rows = []
    for k in range(steps):
        slave.doStep(k * 1e-3, 1e-3)
        rows.append(fmu.get_values(slave, ["beta", "i_R2", "theta_b2"]))
    return rows


def test_master_tolerance_becomes_solver_rtol_when_left_at_its_start(gimbal_fmu):
    log = []
    slave = initialized(gimbal_fmu, log, tolerance=1e-9)
    try:
        assert gimbal_fmu.get_values(slave, ["solver.rtol"]) == [1e-9]
        assert any("solver.rtol = 1.0000000000000001e-09, the tolerance the master gave" in text
                   for _, _, text in log), log
        with_master_tolerance = trajectory(gimbal_fmu, slave)
    finally:
        slave.freeInstance()
    # The same run as setting solver.rtol = 1e-9 by hand, bit for bit.
    slave = initialized(gimbal_fmu, [], start_values={"solver.rtol": 1e-9})
    try:
        assert trajectory(gimbal_fmu, slave) == with_master_tolerance
    finally:
        slave.freeInstance()
    # And not the run at the default tolerance.
    slave = initialized(gimbal_fmu, [])
    try:
        assert trajectory(gimbal_fmu, slave) != with_master_tolerance
    finally:
        slave.freeInstance()


def test_explicit_solver_rtol_wins_over_the_master_tolerance_and_says_so(gimbal_fmu):
    log = []
    slave = initialized(gimbal_fmu, log, start_values={"solver.rtol": 1e-7}, tolerance=1e-4)
    try:
        assert gimbal_fmu.get_values(slave, ["solver.rtol"]) == [1e-7]
        assert any("tolerance = 0.0001 is not used: solver.rtol = 9.9999999999999995e-08 was set explicitly" in text
                   for _, _, text in log), log
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("tolerance", [0.0, -1e-6, 2.0])
def test_impossible_master_tolerance_is_ignored_with_a_warning(gimbal_fmu, tolerance):
    log = []
    slave = initialized(gimbal_fmu, log, tolerance=tolerance)
    try:
        assert gimbal_fmu.get_values(slave, ["solver.rtol"]) == [1e-6]
        assert any(status == WARNING and "is ignored" in text for status, _, text in log), log
    finally:
        slave.freeInstance()


def do_step_status(slave, t, h):
    """fmi2DoStep's status itself (fmpy's doStep raises only above fmi2Warning and hides a warning)."""
    return slave.dll.fmi2DoStep(slave.component, ctypes.c_double(t), ctypes.c_double(h), 1)


def test_a_step_far_over_its_work_budget_is_reported_with_its_likely_cause(gimbal_fmu):
    """Armatures of 20 nH under the explicit method: their circuits (R/L = 1e8 1/s) hold its step by
    stability, some 2e5 right-hand sides in one 1 ms step. The step completes, returns fmi2Warning and
    names the stiffness and the cure. (Stiff gears no longer serve here: they start in their gap, where
    the free play relaxes exactly and nothing is stiff.)"""
    log = []
    stiff = {"motor1.L": 2e-8, "motor2.L": 2e-8}
    slave = initialized(gimbal_fmu, log, start_values={**stiff, "solver.method": 5})
    try:
        assert do_step_status(slave, 0.0, 1e-3) == WARNING
        warnings = [text for status, category, text in log if status == WARNING and category == "logStatusWarning"]
        assert len(warnings) == 1, warnings
        assert "right-hand-side evaluations (budget 100000)" in warnings[0]
        assert "stiff" in warnings[0] and "solver.method = 4 or 6" in warnings[0]
        # Reported at the 1st, 2nd, 4th, 8th ... step over budget, not at every one.
        for k in range(1, 5):
            assert do_step_status(slave, k * 1e-3, 1e-3) == WARNING
        assert len([1 for status, category, _ in log if category == "logStatusWarning"]) == 3
    finally:
        slave.freeInstance()
    # The automatic method takes the same step within budget: no warning.
    log = []
    slave = initialized(gimbal_fmu, log, start_values=stiff)
    try:
        assert do_step_status(slave, 0.0, 1e-3) == OK
        assert not [text for status, _, text in log if status == WARNING]
    finally:
        slave.freeInstance()


def test_unsupported_functions_name_the_declaration_that_says_so(gimbal_fmu):
    log = []
    slave = initialized(gimbal_fmu, log)
    try:
        vr = (ctypes.c_uint * 1)(gimbal_fmu.vr("beta"))
        order = (ctypes.c_int * 1)(1)
        value = (ctypes.c_double * 1)()
        with pytest.raises(FMICallException):
            slave.fmi2GetRealOutputDerivatives(slave.component, vr, 1, order, value)
        assert 'maxOutputDerivativeOrder="0"' in log[-1][2]
    finally:
        slave.freeInstance()


def test_integer_status_is_checked_against_the_instance_state(gimbal_fmu):
    log = []
    slave = gimbal_fmu.instantiate("status", log=log)
    try:
        value = ctypes.c_int(0)
        with pytest.raises(FMICallException):
            slave.fmi2GetIntegerStatus(slave.component, 0, ctypes.byref(value))
        assert "fmi2GetIntegerStatus is not allowed in state 'instantiated'" in log[-1][2]
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        with pytest.raises(FMICallException):
            slave.fmi2GetIntegerStatus(slave.component, 0, ctypes.byref(value))
        assert "no status kind has an Integer value" in log[-1][2]
        with pytest.raises(FMICallException):
            slave.getRealStatus(5)  # not a status kind of fmi2GetRealStatus
    finally:
        slave.freeInstance()
