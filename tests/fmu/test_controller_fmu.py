"""The controller FMU (build/Gimbal2Axis-Controller.fmu, docs/controller_fmu.md) coupled with the
gimbal FMU by a plain fixed-step co-simulation loop gives the compiled master loop's results bit
for bit: the same kernel computes the same voltages from the same inputs.

The delay follows from the order of the exchanges, and both orders are shown:
- Jacobi (every FMU's outputs read at t_k, all inputs set, then every FMU stepped: libcosim's and
  fmpy's fixed-step masters): the voltage the controller computes in its step from t_k is an output
  from t_k+1 on, which the gimbal applies over [t_k+1, t_k+2]: the scene runner's delay_steps = 1
  (0 V over the first step: the output's start value);
- Gauss-Seidel with the controller first (its fresh output handed to the gimbal before the gimbal's
  step from t_k): the voltage computed at t_k is applied over [t_k, t_k+1], delay_steps = 0."""
import math
import os
import re
import subprocess

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from gimbal2axis import load_scene, run
from gimbal2axis.errors import SceneError
from gimbal2axis.fmu import FMU
from gimbal2axis.master.master import Plan, initialize
from gimbal2axis.scene.controller_fmu import controller_fmu_parameters
from gimbal2axis.scene.scene import parameter_value
from conftest import REPO_ROOT

STOP_TIME = 2.0
MEASURED = ["alpha", "beta", "los.omega[1]", "los.omega[2]", "los.omega[3]", "alpha_dot", "beta_dot"]
BASE = ["base.delta", "base.psi", "base.gamma", "base.delta_dot", "base.psi_dot", "base.gamma_dot"]
ENCODERS = {"encoder_resolution_deg": 0.002, "encoder_offset_deg": [0.01, -0.02]}
GYRO = {"gyro": {"scale_factor_error_ppm": [300.0, -200.0, 100.0], "misalignment_mrad": [0.1, 0.2, -0.1, 0.05, 0.0, 0.3],
                 "quantization_deg_s": 0.0005, "delay_samples": 2}}
STATE_FEEDBACK = {"type": "state_feedback", "delay_steps": 1, "reference": "target",
                  "K": [[400.0, 0.0, 8.0, 0.0], [0.0, 400.0, 0.0, 8.0]], "ki": [8000.0, 8000.0]}


@pytest.fixture(scope="module")
def controller_fmu(build_dir):
    path = build_dir / "Gimbal2Axis-Controller.fmu"
    if not path.is_file():
        pytest.fail(f"{path} is missing: the build did not package the controller FMU")
    with FMU(path) as fmu:
        yield fmu


@pytest.fixture(scope="module")
def ship():
    return load_scene(REPO_ROOT / "scenes" / "ship_stabilization.toml")


def u_limits(scene, gimbal_fmu):
    return tuple(float(parameter_value(scene, gimbal_fmu, f"motor{j}.U_L")) for j in (1, 2))


def start_controller(controller_fmu, parameters: dict, log: list):
    controller = controller_fmu.instantiate("controller", log)
    # no stop time: controller first, it also steps from the last communication point (the record's last row)
    controller.setupExperiment(startTime=0.0)
    controller_fmu.set_values(controller, parameters)
    controller.enterInitializationMode()
    controller.exitInitializationMode()
    return controller


def coupled_run(scene, gimbal_fmu, controller_fmu, controller_first: bool) -> dict:
    """The two FMUs in a fixed-step loop of step h: the gimbal initialized as the scene runner does
    (master.initialize: start values, on target), the base motion sampled by the scene's own object
    and set on both FMUs at every communication point. Row k of the record: the gimbal's outputs at
    t_k and the voltages it applies over [t_k, t_k+1]."""
    plan = Plan(scene, gimbal_fmu, STOP_TIME, None)
    gimbal_log, controller_log = [], []
    gimbal = gimbal_fmu.instantiate("gimbal", gimbal_log)
    controller = start_controller(controller_fmu, controller_fmu_parameters(scene, u_limits(scene, gimbal_fmu)),
                                  controller_log)
    initialize(gimbal, scene, gimbal_fmu, plan)
    measured_vrs = [gimbal_fmu.vr(name) for name in MEASURED]
    controller_inputs = [controller_fmu.vr(name) for name in MEASURED + BASE]
    voltage_vrs = [controller_fmu.vr(name) for name in ("u_R1", "u_R2", "set_point.alpha", "set_point.beta")]
    h, n = plan.h, plan.n
    measured, applied, set_points = np.zeros((n + 1, 7)), np.zeros((n + 1, 2)), np.zeros((n + 1, 2))
    for k in range(n + 1):
        t = k * h
        measured[k] = gimbal.getReal(measured_vrs)
        controller_input = measured[k].tolist() + plan.measured_attitude[k].tolist() + plan.base[k, 3:6].tolist()
        if controller_first:
            controller.setReal(controller_inputs, controller_input)
            controller.doStep(t, h)
        outputs = controller.getReal(voltage_vrs)
        applied[k], set_points[k] = outputs[:2], outputs[2:]
        if k == n:
            break
        gimbal.setReal(plan.input_vrs, outputs[:2] + plan.base[k].tolist())
        if not controller_first:   # Jacobi: the controller's inputs at t_k, its new output from t_k+1
            controller.setReal(controller_inputs, controller_input)
        gimbal.doStep(t, h)
        if not controller_first:
            controller.doStep(t, h)
    for instance in (gimbal, controller):
        instance.terminate()
        instance.freeInstance()
    return {"alpha": measured[:, 0], "beta": measured[:, 1], "u_R1": applied[:, 0], "u_R2": applied[:, 1],
            "set_points": set_points}


def compiled_run(scene, gimbal_fmu) -> dict:
    result = run(scene, gimbal_fmu, stop_time=STOP_TIME, compiled=True)
    assert result.loop == "compiled"
    return result.signals


def assert_bit_identical(coupled: dict, compiled: dict) -> None:
    for name in ("alpha", "beta", "u_R1", "u_R2"):
        np.testing.assert_array_equal(coupled[name], compiled[name], err_msg=name)
    assert np.max(np.abs(compiled["u_R1"])) > 0.1, "the loop must have done something"


def variants(ship):
    return {"ideal sensors": ship,
            "encoder resolution and offset": ship.with_changes(sensors_spec=ENCODERS),
            "gyro axes, quantization and delay": ship.with_changes(sensors_spec={**ENCODERS, **GYRO}),
            "state feedback": ship.with_changes(controller_spec=STATE_FEEDBACK, sensors_spec=ENCODERS),
            "state feedback, rates from the encoders": ship.with_changes(
                controller_spec={**STATE_FEEDBACK, "rate_source": "encoder", "K": [[400.0, 0.0, 4.0, 0.0],
                                                                                    [0.0, 400.0, 0.0, 4.0]]},
                sensors_spec=ENCODERS)}


@pytest.mark.parametrize("variant", ["ideal sensors", "encoder resolution and offset",
                                     "gyro axes, quantization and delay", "state feedback",
                                     "state feedback, rates from the encoders"])
def test_jacobi_coupling_equals_the_compiled_loop_with_one_step_delay(ship, gimbal_fmu, controller_fmu, variant):
    scene = variants(ship)[variant]
    assert scene.delay_steps == 1
    coupled = coupled_run(scene, gimbal_fmu, controller_fmu, controller_first=False)
    compiled = compiled_run(scene, gimbal_fmu)
    assert_bit_identical(coupled, compiled)
    assert coupled["u_R1"][0] == 0.0 and coupled["u_R2"][0] == 0.0   # the outputs' start: 0 V over the first step
    # the set points the controller used at t_k are its outputs from t_k+1 on
    np.testing.assert_array_equal(coupled["set_points"][1:, 0], compiled["alpha_ref"][:-1])
    np.testing.assert_array_equal(coupled["set_points"][1:, 1], compiled["beta_ref"][:-1])


def test_controller_first_coupling_is_the_loop_without_delay(ship, gimbal_fmu, controller_fmu):
    scene = ship.with_changes(controller_spec={**ship.controller_spec, "delay_steps": 0}, sensors_spec=ENCODERS)
    coupled = coupled_run(scene, gimbal_fmu, controller_fmu, controller_first=True)
    assert_bit_identical(coupled, compiled_run(scene, gimbal_fmu))
    jacobi = coupled_run(scene, gimbal_fmu, controller_fmu, controller_first=False)
    assert not np.array_equal(jacobi["u_R1"], coupled["u_R1"])   # the other order is the other delay


def test_constant_voltages(ship, gimbal_fmu, controller_fmu):
    scene = ship.with_changes(controller_spec={"type": "none", "voltage_V": [1.5, -2.0]})
    coupled = coupled_run(scene, gimbal_fmu, controller_fmu, controller_first=False)
    compiled = compiled_run(scene, gimbal_fmu)
    for name in ("alpha", "beta", "u_R1", "u_R2"):
        np.testing.assert_array_equal(coupled[name], compiled[name], err_msg=name)
    assert coupled["u_R1"][1] == 1.5 and coupled["u_R2"][-1] == -2.0


@pytest.mark.parametrize("name, value, message", [
    ("controller.kind", 3, r"controller\.kind = 3 is outside \[0, 2\]"),
    ("azimuth.u_limit", 0.0, r"azimuth\.u_limit = 0 must be > 0"),
    ("elevation.d_filter_s", -1e-3, r"elevation\.d_filter_s = -0\.001 is outside"),
    ("target.elevation", 2.0, r"target\.elevation = 2 is outside"),
    ("gyro.delay_samples", 17, r"gyro\.delay_samples = 17 is outside \[0, 16\]"),
])
def test_a_bad_parameter_is_refused_naming_it(controller_fmu, name, value, message):
    log = []
    controller = controller_fmu.instantiate("controller", log)
    controller.setupExperiment(startTime=0.0)
    controller_fmu.set_values(controller, {name: value})
    controller.enterInitializationMode()
    with pytest.raises(FMICallException):
        controller.exitInitializationMode()
    assert any(re.search(r"fmi2ExitInitializationMode: " + message, str(entry)) for entry in log), log
    controller_fmu.set_values(controller, {name: controller_fmu.start(name)})   # corrected, it starts
    controller.exitInitializationMode()
    controller.freeInstance()


def test_bad_calls_are_refused_naming_the_culprit(controller_fmu):
    log = []
    controller = start_controller(controller_fmu, {}, log)
    with pytest.raises(FMICallException):
        controller.setReal([controller_fmu.vr("alpha")], [math.nan])
    with pytest.raises(FMICallException):
        controller.setReal([controller_fmu.vr("azimuth.kp")], [1.0])   # a fixed parameter, after initialization
    with pytest.raises(FMICallException):
        controller.setReal([controller_fmu.vr("u_R1")], [1.0])         # an output
    with pytest.raises(FMICallException):
        controller.doStep(0.5, 1e-3)                                    # not the FMU's time
    with pytest.raises(FMICallException):
        controller.getFMUState()
    messages = [str(entry) for entry in log]
    for expected in ("fmi2SetReal: alpha = nan is not finite", "fmi2SetReal: azimuth.kp cannot be set in state 'step complete'",
                     "fmi2SetReal: u_R1 cannot be set", "fmi2DoStep: currentCommunicationPoint = 0.5 does not match",
                     "fmi2GetFMUstate: canGetAndSetFMUstate is false"):
        assert any(expected in message for message in messages), (expected, messages)
    controller.doStep(0.0, 1e-3)   # the refusals left it usable
    controller.freeInstance()


def test_scene_terms_the_fmu_lacks_are_refused(ship, gimbal_fmu):
    u_limit = u_limits(ship, gimbal_fmu)
    for sensors, message in [({"gyro_noise_deg_s": 0.01}, "no random sensor terms"),
                             ({"stabilization": "indirect"}, "direct scheme only"),
                             ({"gyro": {"bandwidth_hz": 100.0}}, "no gyro bandwidth filter"),
                             ({"gyro": {"angle_random_walk_deg_rt_h": 0.1}}, "deterministic terms only")]:
        with pytest.raises(SceneError, match=message):
            controller_fmu_parameters(ship.with_changes(sensors_spec=sensors), u_limit)
    step = {**ship.controller_spec, "reference": {"type": "constant", "value_deg": 1.0}}
    with pytest.raises(SceneError, match="toward the \\[target\\] only"):
        controller_fmu_parameters(ship.with_changes(controller_spec=step), u_limit)


def test_the_fmu_validates_and_names_its_inputs_as_the_gimbal_fmu(controller_fmu, gimbal_fmu):
    assert validate_fmu(str(controller_fmu.path)) == []
    for name in MEASURED:
        assert controller_fmu.variable(name).causality == "input" and gimbal_fmu.variable(name).causality == "output"
    for name in BASE:
        assert controller_fmu.variable(name).causality == "input" and gimbal_fmu.variable(name).causality == "input"
    for name in ("u_R1", "u_R2"):
        assert controller_fmu.variable(name).causality == "output" and gimbal_fmu.variable(name).causality == "input"


@pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                    reason="a sanitizer build links the sanitizer runtimes dynamically by design")
def test_shared_object_exports_only_fmi2_and_links_only_libc(build_dir):
    so = build_dir / "controller_staging" / "binaries" / "linux64" / "Gimbal2AxisController.so"
    exported = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True)
    symbols = [line.split()[-1] for line in exported.stdout.splitlines() if line.strip()]
    assert [s for s in symbols if not s.startswith("fmi2")] == []
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2GetReal", "fmi2SetReal"} <= set(symbols)
    ldd = subprocess.run(["ldd", str(so)], capture_output=True, text=True, check=True).stdout
    libraries = [line.split()[0] for line in ldd.splitlines() if line.strip()]
    allowed = re.compile(r"^(linux-vdso\.so\.1|libc\.so\.6|libm\.so\.6|/lib64/ld-linux-x86-64\.so\.2)$")
    assert [lib for lib in libraries if not allowed.match(lib)] == []
