"""The FMU never lies: what it refuses, it refuses with fmi2Error and a message naming the culprit."""
import math

import pytest
from fmpy.fmi1 import FMICallException

ERROR, DISCARD = 3, 2


def initialized(fmu, log, start_values=None):
    slave = fmu.instantiate("refusals", log=log)
    slave.setupExperiment(startTime=0.0)
    if start_values:
        slave.setReal([fmu.vr(n) for n in start_values], list(start_values.values()))
    slave.enterInitializationMode()
    return slave


@pytest.mark.parametrize("name, value, rule", [
    ("body2.m", -1.0, ">= 0"),
    ("gear1.N", 0.0, "must not be 0"),
    ("gear2.k_s", -10.0, ">= 0"),
    ("motor1.L", 0.0, "> 0"),
    ("body1.I_zz", 0.5, "triangle inequality"),
    ("rotor2.I_xx", -1e-5, "positive definite"),
])
def test_invalid_parameter_is_refused_at_initialization(gimbal_fmu, name, value, rule):
    log = []
    slave = initialized(gimbal_fmu, log, {name: value})
    try:
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        errors = [text for status, _, text in log if status == ERROR]
        prefix = name.split(".")[0]
        assert any((name in text or prefix in text) and rule in text for text in errors), errors
        # The instance is not corrupted: fix the value and initialize.
        slave.setReal([gimbal_fmu.vr(name)], [float(_start(gimbal_fmu, name))])
        slave.exitInitializationMode()
        slave.doStep(0.0, 1e-3)
    finally:
        slave.freeInstance()


def _start(fmu, name):
    return next(v.start for v in fmu.model_description.modelVariables if v.name == name)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_input_is_refused_and_state_kept(gimbal_fmu, value):
    log = []
    slave = initialized(gimbal_fmu, log)
    try:
        slave.exitInitializationMode()
        slave.doStep(0.0, 1e-3)
        before = slave.getReal([gimbal_fmu.vr("u_R1")])[0]
        with pytest.raises(FMICallException):
            slave.setReal([gimbal_fmu.vr("u_R1")], [value])
        assert any(status == ERROR and "u_R1" in text for status, _, text in log), log
        assert slave.getReal([gimbal_fmu.vr("u_R1")])[0] == before
        slave.doStep(1e-3, 1e-3)  # still usable
    finally:
        slave.freeInstance()


def test_do_step_checks_step_size_and_time(gimbal_fmu):
    log = []
    slave = initialized(gimbal_fmu, log)
    try:
        slave.exitInitializationMode()
        for h in (0.0, -1e-3, math.nan):
            with pytest.raises(FMICallException):
                slave.doStep(0.0, h)
        assert sum("communicationStepSize" in text for _, _, text in log) == 3
        with pytest.raises(FMICallException):
            slave.doStep(0.5, 1e-3)
        assert "does not match" in log[-1][2]
        slave.doStep(0.0, 1e-3)
    finally:
        slave.freeInstance()


def test_fixed_parameter_cannot_change_after_initialization(gimbal_fmu):
    log = []
    slave = initialized(gimbal_fmu, log)
    try:
        slave.exitInitializationMode()
        with pytest.raises(FMICallException):
            slave.setReal([gimbal_fmu.vr("gear1.k_s")], [1.0])
        assert "gear1.k_s" in log[-1][2] and "cannot be set" in log[-1][2]
    finally:
        slave.freeInstance()


def test_wrong_guid_is_refused(gimbal_fmu):
    from fmpy.fmi2 import FMU2Slave
    slave = FMU2Slave(guid="{00000000-0000-0000-0000-000000000000}", unzipDirectory=gimbal_fmu.unzipdir,
                      modelIdentifier="Gimbal2Axis", instanceName="bad")
    with pytest.raises(Exception):
        slave.instantiate()
