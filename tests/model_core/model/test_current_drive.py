"""Current drive (docs/physics.md section 4.6) through the FMUs: bad amplifier parameters and a non-finite
current command refused by name in FMI 2.0 and FMI 3.0, the new variables in both model descriptions, and
Model Exchange under fmpy's CVode agreeing with Co-Simulation. The loop's physics in every integration
method is tests/model_core/model/test_current_drive.cpp's."""
import math

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

from support import declared_counts

ERROR = 3


@pytest.fixture(scope="module")
def fmu3(build_dir, tmp_path_factory):
    path = build_dir / "Gimbal2Axis-fmi3.fmu"
    md = read_model_description(str(path))
    return path, md, extract(str(path), str(tmp_path_factory.mktemp("fmi3_current")))


def fmi3_slave(fmu3, log):
    path, md, unzipdir = fmu3
    instance = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipdir, modelIdentifier="Gimbal2Axis",
                         instanceName="current")

    def logger(environment, status, category, message):
        log.append((int(status), category.decode(), message.decode()))
    instance.instantiate(logMessage=logger, loggingOn=True)
    return instance


def vr3(fmu3, name):
    return next(v.valueReference for v in fmu3[1].modelVariables if v.name == name)


def test_both_model_descriptions_declare_current_drive(fmu_path, fmu3):
    for md in (read_model_description(str(fmu_path)), fmu3[1]):
        variables = {v.name: v for v in md.modelVariables}
        for j in (1, 2):
            assert variables[f"i_R{j}_cmd"].causality == "input" and variables[f"i_R{j}_cmd"].unit == "A"
            assert variables[f"amplifier{j}.f_c"].unit == "Hz" and float(variables[f"amplifier{j}.f_c"].start) == 2000.0
            assert variables[f"amplifier{j}.K_p"].unit == "V/A" and variables[f"amplifier{j}.K_i"].unit == "V/(A.s)"
            assert variables[f"amplifier{j}.u"].causality == "output" and variables[f"amplifier{j}.u"].unit == "V"
            assert variables[f"motor{j}.drive"].type == "Enumeration"
            assert variables[f"motor{j}.amplifier_saturated"].causality == "output"
            assert variables[f"amplifier{j}.back_emf_feedforward"].type == "Boolean"
        assert md.numberOfContinuousStates == declared_counts.continuous_states()
        assert md.numberOfEventIndicators == declared_counts.event_indicators()
        states = [d.variable.derivative.name for d in md.derivatives]
        assert states[-2:] == ["amplifier1.x_I", "amplifier2.x_I"]


@pytest.mark.parametrize("name, value, rule", [
    ("amplifier1.f_c", 0.0, "> 0"),
    ("amplifier2.f_c", -1.0, "> 0"),
    ("amplifier1.K_p", -2.0, ">= 0"),
    ("amplifier2.K_i", -1.0, ">= 0"),
])
def test_bad_amplifier_parameters_are_refused_by_name(gimbal_fmu, fmu3, name, value, rule):
    log = []
    slave = gimbal_fmu.instantiate("refusals", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.setInteger([gimbal_fmu.vr("motor1.drive"), gimbal_fmu.vr("motor2.drive")], [1, 1])
        slave.setReal([gimbal_fmu.vr(name)], [value])
        slave.enterInitializationMode()
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        assert any(status == ERROR and name in text and rule in text for status, _, text in log), log
    finally:
        slave.freeInstance()
    log = []
    slave = fmi3_slave(fmu3, log)
    try:
        slave.setFloat64([vr3(fmu3, name)], [value])
        slave.enterInitializationMode(startTime=0.0)
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        assert any(status == ERROR and name in text for status, _, text in log), log
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_non_finite_current_command_is_refused_by_name(gimbal_fmu, fmu3, value):
    log = []
    slave = gimbal_fmu.instantiate("nan", log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.setInteger([gimbal_fmu.vr("motor1.drive")], [1])
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.setReal([gimbal_fmu.vr("i_R1_cmd")], [1.0])
        slave.doStep(0.0, 1e-3)
        with pytest.raises(FMICallException):
            slave.setReal([gimbal_fmu.vr("i_R1_cmd")], [value])
        assert any(status == ERROR and "i_R1_cmd" in text for status, _, text in log), log
        slave.doStep(1e-3, 1e-3)  # still usable
    finally:
        slave.freeInstance()
    log = []
    slave = fmi3_slave(fmu3, log)
    try:
        slave.enterInitializationMode(startTime=0.0)
        slave.exitInitializationMode()
        with pytest.raises(FMICallException):
            slave.setFloat64([vr3(fmu3, "i_R2_cmd")], [value])
        assert any(status == ERROR and "i_R2_cmd" in text for status, _, text in log), log
    finally:
        slave.freeInstance()


def test_model_exchange_agrees_with_co_simulation_in_current_drive(fmu_path):
    """A current step through the amplifiers: an inductive motor with its PI loop (saturating first: a 3 A
    step needs 75 V), a quasi-static one bus-limited, the mechanics moving. CVode with its own event
    location against the FMU's own integrator, both tight."""
    start = {"motor1.drive": 1, "motor2.drive": 1, "motor2.model": 0, "base.fixed": True, "beta": 0.3,
             "motor2.U_L": 6.0}
    inputs = np.array([(0.0, 3.0, -2.8)], dtype=[("time", float), ("i_R1_cmd", float), ("i_R2_cmd", float)])
    outputs = ["alpha", "beta", "i_R1", "i_R2", "amplifier1.u", "amplifier1.x_I", "motor1.amplifier_saturated"]
    runs = {}
    for fmi_type in ("CoSimulation", "ModelExchange"):
        values = dict(start)
        if fmi_type == "CoSimulation":
            values.update({"solver.rtol": 1e-10, "solver.atol": 1e-12})
        runs[fmi_type] = simulate_fmu(str(fmu_path), fmi_type=fmi_type, stop_time=0.05, output_interval=1e-3,
                                      start_values=values, input=inputs, output=outputs,
                                      relative_tolerance=1e-10 if fmi_type == "ModelExchange" else None)
    cs, me = runs["CoSimulation"], runs["ModelExchange"]
    times = me["time"]
    last = np.append(times[1:] != times[:-1], True)
    on_grid = np.abs(times * 1000 - np.round(times * 1000)) < 1e-6
    me = me[on_grid & last]
    assert len(me) == len(cs)
    assert cs["motor1.amplifier_saturated"].max() == 1 and cs["motor1.amplifier_saturated"][-1] == 0
    assert abs(cs["i_R1"][-1] - 3.0) < 1e-2 and np.abs(cs["amplifier1.u"]).max() <= 24.0 * (1 + 1e-12)
    for name, tolerance in (("alpha", 1e-6), ("beta", 1e-6), ("i_R1", 1e-5), ("i_R2", 1e-5), ("amplifier1.x_I", 1e-4)):
        assert np.abs(cs[name] - me[name]).max() <= tolerance, (name, np.abs(cs[name] - me[name]).max())


def test_linear_model_in_current_drive_has_the_amplifier_and_the_current_command_columns(build_dir):
    """Motor 1 current-driven (inductive, pole-zero gains at 2 kHz), motor 2 in voltage drive: A carries
    x_I, the first B column is i_R1_cmd's, the second still u_R2's."""
    from gimbal2axis.analysis.linearization import linearize

    model = linearize({"motor1.drive": 1, "i_R1_cmd": 0.5, "base.fixed": 1}, build_dir=build_dir)
    assert model.inputs[:2] == ["i_R1_cmd", "u_R2"]
    assert "amplifier1.x_I" in model.states and "amplifier2.x_I" not in model.states
    i, x = model.states.index("i_R1"), model.states.index("amplifier1.x_I")
    L, R, f_c = 0.002, 2.0, 2000.0
    K_p, K_i = 2 * math.pi * f_c * L, 2 * math.pi * f_c * R
    assert math.isclose(model.A[i, x], 1 / L, rel_tol=1e-12)
    assert math.isclose(model.A[i, i], -(R + K_p) / L, rel_tol=1e-12)
    assert math.isclose(model.A[x, i], -K_i, rel_tol=1e-12)
    assert math.isclose(model.B[i, 0], K_p / L, rel_tol=1e-6) and math.isclose(model.B[x, 0], K_i, rel_tol=1e-6)
    # The locked-rotor current loop i/i_cmd of the (i, x_I) block: one pole at -2 pi f_c, one at -R/L
    # cancelled by its zero.
    block = model.A[np.ix_([i, x], [i, x])]
    assert np.allclose(sorted(np.linalg.eigvals(block).real), sorted([-2 * math.pi * f_c, -R / L]), rtol=1e-9)
