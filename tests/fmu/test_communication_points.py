"""The communication-point rule (fmu_src/common/communication_point.h) in every FMU and both FMI
versions: masters that keep time as t0 + k*h, as a running sum, as a Kahan sum or in integer
nanoseconds are all accepted where the old rule (the FMU's own running sum against the master's
point, within 1e-12 |t| + 1e-6 h) refused them: at a Unix-epoch start time with steps of 1 ms and
0.1 ms, with steps of 1 ns, with a step no double represents (0.1/3). Each case runs past the step
where the old rule failed, and checks that it did reach the clocks' disagreement that made it fail.
The results are the same bits for every clock style that passes the same steps and for every start
time; the reported time is the master's; a repeated or a skipped step is still refused."""
from __future__ import annotations

import ctypes
import math
import os

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from gimbal2axis.fmu import FMU
from gimbal2axis.scene import load_scene
from gimbal2axis.scene.controller_fmu import controller_fmu_parameters
from gimbal2axis.scene.ship_motion_fmu import ship_motion_fmu_parameters

from conftest import REPO_ROOT

SHIP_SCENE = REPO_ROOT / "scenes" / "ship_stabilization.toml"
GIMBAL_OUTPUTS = ["alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "i_R1", "i_R2", "theta_b1", "T_E1"]


# ---------------------------------------------------------------- the masters' clocks


def t0_plus_k_h(t0: float, h: float, n: int):
    """The careful master's clock (and the package's own): every point from the integer k."""
    for k in range(n):
        yield t0 + k * h, h


def running_sum(t0: float, h: float, n: int):
    t = t0
    for _ in range(n):
        yield t, h
        t += h


def kahan_sum(t0: float, h: float, n: int):
    t, compensation = t0, 0.0
    for _ in range(n):
        yield t, h
        y = h - compensation
        s = t + y
        compensation = (s - t) - y
        t = s


def integer_nanoseconds(t0: float, h: float, n: int):
    """libcosim's clock: int64 nanoseconds, converted to double seconds at each call (the step too,
    rounded to whole nanoseconds)."""
    start_ns, step_ns = round(t0 * 1e9), max(1, round(h * 1e9))
    for k in range(n):
        yield float(start_ns + k * step_ns) / 1e9, float(step_ns) / 1e9


CLOCKS = {"t0+k*h": t0_plus_k_h, "running sum": running_sum, "Kahan sum": kahan_sum,
          "integer ns": integer_nanoseconds}

# (start time, step, steps): each past the step where the old rule refused one of the clocks
# (test_every_case_reaches_where_the_old_rule_refused: 23,456, 16,568, 12,100 and 53,479 steps).
CASES = {"epoch start, 1 ms": (1.7e9, 1e-3, 24_000), "epoch start, 0.1 ms": (1.7e9, 1e-4, 17_000),
         "1 ns steps from 1 s": (1.0, 1e-9, 12_500), "epoch start, 0.1/3 s": (1.7e9, 0.1 / 3, 54_000)}


def old_rule_would_refuse(t0: float, h: float, n: int) -> bool:
    """Whether the old rule refuses some clock of CLOCKS within n steps (a test that cannot fail
    with the old rule proves nothing)."""
    fmu_time = t0
    for (t_kh, _), (t_sum, _) in zip(t0_plus_k_h(t0, h, n), running_sum(t0, h, n)):
        for point in (t_kh, t_sum):
            if abs(point - fmu_time) > 1e-12 * max(1.0, abs(fmu_time)) + 1e-6 * h:
                return True
        fmu_time += h
    return False


@pytest.mark.parametrize("case", CASES)
def test_every_case_reaches_where_the_old_rule_refused(case):
    assert old_rule_would_refuse(*CASES[case])


# ---------------------------------------------------------------- the FMUs, driven through raw calls


class FMI2Stepper:
    """An FMI 2.0 Co-Simulation instance whose fmi2DoStep is called without fmpy's checks (tens of
    thousands of steps per case)."""

    def __init__(self, fmu: FMU, slave, log: list):
        self.fmu, self.slave, self.log = fmu, slave, log
        self._do_step = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                         ctypes.c_int)(("fmi2DoStep", slave.dll))

    def step(self, t: float, h: float) -> int:
        return self._do_step(self.slave.component, t, h, 1)

    def last_successful_time(self) -> float:
        from fmpy.fmi2 import fmi2LastSuccessfulTime
        return self.slave.getRealStatus(fmi2LastSuccessfulTime)

    def outputs(self, names) -> list:
        return self.fmu.get_values(self.slave, names)

    def close(self):
        self.slave.freeInstance()


class FMI3Stepper:
    def __init__(self, md, slave, log: list):
        self.md, self.slave, self.log = md, slave, log
        b = ctypes.POINTER(ctypes.c_bool)
        self._do_step = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                         ctypes.c_bool, b, b, b, ctypes.POINTER(ctypes.c_double))(
            ("fmi3DoStep", slave.dll))
        self.event, self.terminate, self.early = ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool()
        self.last = ctypes.c_double()

    def step(self, t: float, h: float) -> int:
        return self._do_step(self.slave.component, t, h, True, ctypes.byref(self.event), ctypes.byref(self.terminate),
                             ctypes.byref(self.early), ctypes.byref(self.last))

    def last_successful_time(self) -> float:
        return self.last.value

    def vr(self, name):
        return next(v.valueReference for v in self.md.modelVariables if v.name == name)

    def outputs(self, names) -> list:
        return self.slave.getFloat64([self.vr(n) for n in names])

    def close(self):
        self.slave.freeInstance()


@pytest.fixture(scope="module")
def fmu3(build_dir, tmp_path_factory):
    path = build_dir / "Gimbal2Axis-fmi3.fmu"
    md = read_model_description(str(path))
    return md, extract(str(path), str(tmp_path_factory.mktemp("fmi3_clock")))


@pytest.fixture(scope="module")
def controller_fmu(build_dir):
    with FMU(build_dir / "Gimbal2Axis-Controller.fmu") as fmu:
        yield fmu


@pytest.fixture(scope="module")
def ship_fmu(build_dir):
    with FMU(build_dir / "Gimbal2Axis-ShipMotion.fmu") as fmu:
        yield fmu


@pytest.fixture(scope="module")
def small_fmus3(build_dir, tmp_path_factory):
    """The ship-motion and controller FMUs for FMI 3.0: {name: (model description, unzipped folder)}."""
    opened = {}
    for name in ("Gimbal2Axis-ShipMotion-fmi3.fmu", "Gimbal2Axis-Controller-fmi3.fmu"):
        path = build_dir / name
        opened[name] = read_model_description(str(path)), extract(str(path), str(tmp_path_factory.mktemp("fmi3_small")))
    return opened


# The gimbal driven by a constant voltage on both motors: the rotors accelerate, the gears and the
# current limiters switch, the outputs depend on every step.
GIMBAL_START = {"base.fixed": True, "u_R1": 4.0, "u_R2": -3.0}


def start_gimbal_fmi2(gimbal_fmu: FMU, t0: float) -> FMI2Stepper:
    log: list = []
    slave = gimbal_fmu.instantiate("clock", log)
    slave.setupExperiment(startTime=t0)
    gimbal_fmu.set_values(slave, GIMBAL_START)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return FMI2Stepper(gimbal_fmu, slave, log)


def start_gimbal_fmi3(fmu3, t0: float) -> FMI3Stepper:
    md, unzipdir = fmu3
    log: list = []
    slave = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipdir, modelIdentifier="Gimbal2Axis",
                      instanceName="clock")

    def logger(environment, status, category, message):
        log.append(message.decode())

    slave.instantiate(logMessage=logger, loggingOn=True)
    stepper = FMI3Stepper(md, slave, log)
    slave.enterInitializationMode(startTime=t0)
    slave.setBoolean([stepper.vr("base.fixed")], [True])
    slave.setFloat64([stepper.vr("u_R1"), stepper.vr("u_R2")], [GIMBAL_START["u_R1"], GIMBAL_START["u_R2"]])
    slave.exitInitializationMode()
    return stepper


def start_controller(controller_fmu: FMU, t0: float) -> FMI2Stepper:
    scene = load_scene(SHIP_SCENE)
    log: list = []
    slave = controller_fmu.instantiate("clock", log)
    slave.setupExperiment(startTime=t0)
    controller_fmu.set_values(slave, controller_fmu_parameters(scene, (24.0, 24.0)))
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    # A measured attitude error, so that the controller's integrators and filters move at every step.
    controller_fmu.set_values(slave, {"alpha": 0.01, "beta": -0.02})
    return FMI2Stepper(controller_fmu, slave, log)


def start_ship(ship_fmu: FMU, t0: float) -> FMI2Stepper:
    log: list = []
    slave = ship_fmu.instantiate("clock", log)
    slave.setupExperiment(startTime=t0)
    ship_fmu.set_values(slave, ship_motion_fmu_parameters(load_scene(SHIP_SCENE)))
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return FMI2Stepper(ship_fmu, slave, log)


def start_small_fmi3(fmu3, t0: float, parameters: dict, inputs: dict) -> FMI3Stepper:
    """A small FMU's FMI 3.0 twin started as its FMI 2.0 one is above (the same names and values)."""
    md, unzipdir = fmu3
    log: list = []
    slave = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipdir,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="clock")
    slave.instantiate(logMessage=lambda environment, status, category, message: log.append(message.decode()),
                      loggingOn=True)
    stepper = FMI3Stepper(md, slave, log)
    types = {v.name: v.type for v in md.modelVariables}

    def set_values(values: dict) -> None:
        for name, value in values.items():
            getattr(slave, "set" + types[name])([stepper.vr(name)], [value])

    slave.enterInitializationMode(startTime=t0)
    set_values(parameters)
    slave.exitInitializationMode()
    set_values(inputs)
    return stepper


def output_names(fmu: FMU) -> list:
    return [v.name for v in fmu.model_description.modelVariables if v.causality == "output" and v.type == "Real"]


@pytest.fixture(params=["gimbal FMI 2.0", "gimbal FMI 3.0", "controller", "controller FMI 3.0", "ship motion",
                        "ship motion FMI 3.0"])
def which(request):
    return request.param


@pytest.fixture
def starter(which, gimbal_fmu, fmu3, controller_fmu, ship_fmu, small_fmus3):
    """(start(t0) -> stepper, the output names compared)."""
    controller_parameters = controller_fmu_parameters(load_scene(SHIP_SCENE), (24.0, 24.0))
    ship_parameters = ship_motion_fmu_parameters(load_scene(SHIP_SCENE))
    return {"gimbal FMI 2.0": (lambda t0: start_gimbal_fmi2(gimbal_fmu, t0), GIMBAL_OUTPUTS),
            "gimbal FMI 3.0": (lambda t0: start_gimbal_fmi3(fmu3, t0), GIMBAL_OUTPUTS),
            "controller": (lambda t0: start_controller(controller_fmu, t0), output_names(controller_fmu)),
            "controller FMI 3.0": (lambda t0: start_small_fmi3(small_fmus3["Gimbal2Axis-Controller-fmi3.fmu"], t0,
                                                               controller_parameters, {"alpha": 0.01, "beta": -0.02}),
                                   output_names(controller_fmu)),
            "ship motion": (lambda t0: start_ship(ship_fmu, t0), output_names(ship_fmu)),
            "ship motion FMI 3.0": (lambda t0: start_small_fmi3(small_fmus3["Gimbal2Axis-ShipMotion-fmi3.fmu"], t0,
                                                                ship_parameters, {}), output_names(ship_fmu))}[which]


def run_clock(start, clock, t0: float, h: float, n: int, names) -> tuple[list, float, float]:
    """Steps a new instance through n points of `clock`; (the outputs at the end, the FMU's reported
    time, the master's last point + step)."""
    stepper = start(t0)
    try:
        for t, step in clock(t0, h, n):
            status = stepper.step(t, step)
            assert status <= 1, f"doStep({t!r}, {step!r}) refused: {stepper.log[-3:]}"
        return stepper.outputs(names), stepper.last_successful_time(), t + step
    finally:
        stepper.close()


@pytest.mark.parametrize("case", CASES)
def test_every_clock_style_runs_past_the_old_refusal_with_the_same_results(which, starter, case):
    if os.environ.get("GIMBAL_SANITIZED") == "1" and which.startswith("gimbal") and "0.1/3" in case:
        pytest.skip("30 minutes of the gimbal per clock: the release pass runs it; the sanitizer pass runs the rest")
    start, names = starter
    t0, h, n = CASES[case]
    results = {}
    for clock_name, clock in CLOCKS.items():
        outputs, reported, master_end = run_clock(start, clock, t0, h, n, names)
        # The FMU's time is the master's: its last point plus its step.
        assert reported == master_end, (clock_name, reported, master_end)
        results[clock_name] = outputs
    reference = results["t0+k*h"]
    assert all(math.isfinite(v) for v in reference)
    for clock_name, outputs in results.items():
        assert outputs == reference or clock_name == "integer ns", f"{clock_name} differs from t0+k*h"
    # Integer nanoseconds round the step itself (0.1/3 s to 33,333,333 ns): the same bits as a careful
    # master that passes that rounded step.
    rounded_step = float(max(1, round(h * 1e9))) / 1e9
    expected = reference if rounded_step == h else run_clock(start, t0_plus_k_h, t0, rounded_step, n, names)[0]
    assert results["integer ns"] == expected


def test_the_start_time_changes_no_bit(starter):
    start, names = starter
    h, n = 1e-3, 2_000
    late = run_clock(start, t0_plus_k_h, 1.7e9, h, n, names)[0]
    early = run_clock(start, t0_plus_k_h, 0.0, h, n, names)[0]
    assert late == early


@pytest.mark.parametrize("wrong", ["repeated", "skipped"])
def test_a_repeated_or_skipped_step_is_still_refused(starter, wrong):
    start, _ = starter
    t0, h, n = 1.7e9, 1e-3, 500
    stepper = start(t0)
    try:
        for t, step in t0_plus_k_h(t0, h, n):
            assert stepper.step(t, step) <= 1
        point = t0 + (n - 1) * h if wrong == "repeated" else t0 + (n + 1) * h
        assert stepper.step(point, h) >= 3, f"a {wrong} step at {point!r} was accepted"
        assert any("does not match the FMU's time" in str(entry) for entry in stepper.log), stepper.log[-3:]
    finally:
        stepper.close()


def test_fmi3_early_returns_at_an_epoch_start_follow_the_masters_clock(fmu3):
    """With early return, a step ends at the first mode change; a master continues from the
    lastSuccessfulTime it was given, to its next grid point, and is never refused."""
    md, unzipdir = fmu3
    slave = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipdir, modelIdentifier="Gimbal2Axis",
                      instanceName="early")
    log: list = []
    slave.instantiate(earlyReturnAllowed=True, loggingOn=True,
                      logMessage=lambda env, status, category, message: log.append(message.decode()))
    stepper = FMI3Stepper(md, slave, log)
    t0, h = 1.7e9, 1e-3
    u = [stepper.vr("u_R1"), stepper.vr("u_R2")]
    try:
        slave.enterInitializationMode(startTime=t0)
        slave.setBoolean([stepper.vr("base.fixed")], [True])
        slave.exitInitializationMode()
        early_returns, t = 0, t0
        for k in range(1, 3_001):
            target = t0 + k * h
            slave.setFloat64(u, [12.0 if (k // 50) % 2 else -12.0, 6.0 if (k // 70) % 2 else -6.0])
            # A mode change closer to t than half its unit in the last place (1.2e-7 s here) ends a step
            # where the double time cannot move; the model's own clock still does, and the step after
            # it goes on from there.
            for _ in range(100):
                if t >= target:
                    break
                assert stepper.step(t, target - t) <= 1, log[-3:]
                assert stepper.last.value >= t
                t = stepper.last.value
                early_returns += bool(stepper.early.value)
            assert t == target
        assert early_returns > 10  # the voltage reversals did make steps end early
        assert slave.getFloat64([stepper.vr("time")]) == [t]
    finally:
        slave.freeInstance()


def test_the_ship_motion_fmu_takes_a_master_s_rounding_step_at_the_stop_time(ship_fmu):
    """An SSP engine whose clock ends on its stop time with a last step of 4.9e-11 s: the rows stay,
    the time follows; a step of another real size is still refused."""
    stepper = start_ship(ship_fmu, 0.0)
    names = output_names(ship_fmu)
    try:
        h = 1e-3
        for t, step in running_sum(0.0, h, 100):
            assert stepper.step(t, step) <= 1
        before = stepper.outputs(names)
        t = 100 * h
        assert stepper.step(t, 4.9e-11) <= 1, stepper.log[-2:]
        assert stepper.outputs(names) == before
        assert stepper.last_successful_time() == t + 4.9e-11
        assert stepper.step(t + 4.9e-11, 0.5 * h) >= 3
        assert "differs from the first step's" in str(stepper.log[-1])
    finally:
        stepper.close()
