"""The ship-motion FMU (build/Gimbal2Axis-ShipMotion.fmu, fmu_src/ship_motion/): its outputs are the
scene runner's base inputs bit for bit (the same C kernel makes the components and sums them on the
same grid), its rates and accelerations are the derivatives of its attitudes and velocities, a bad
parameter or step is refused with a message naming it, and it is a valid FMU exporting only fmi2*."""
import math
import os
import pathlib
import re
import subprocess
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from gimbal2axis import FMU, load_scene
from gimbal2axis.errors import read_toml
from gimbal2axis.scene.base_motion import INPUTS, make_base_motion
from gimbal2axis.scene.ship_motion_fmu import ship_motion_fmu_parameters

REPO = pathlib.Path(__file__).resolve().parents[1]
SHIP_SCENE = REPO / "scenes" / "ship_stabilization.toml"
DOFS = ["pitch", "yaw", "roll", "surge", "sway", "heave"]


@pytest.fixture(scope="module")
def ship_fmu(build_dir):
    path = build_dir / "Gimbal2Axis-ShipMotion.fmu"
    if not path.is_file():
        pytest.fail(f"{path} is missing: the build did not package the ship-motion FMU")
    with FMU(path) as fmu:
        yield fmu


def parameters_of(base_motion: dict) -> dict:
    """The FMU's parameters for a scene's [base_motion] table of type sea_state."""
    return ship_motion_fmu_parameters(load_scene(SHIP_SCENE).with_changes(base_motion_spec=base_motion))


def run_fmu(fmu, parameters: dict, step: float, steps: int, start_time: float = 0.0) -> np.ndarray:
    """The outputs at the communication points start_time + k step, k = 0 .. steps, in INPUTS order."""
    slave = fmu.instantiate()
    try:
        slave.setupExperiment(startTime=start_time)
        fmu.set_values(slave, parameters)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        vrs = [fmu.vr(name) for name in INPUTS]
        rows = [slave.getReal(vrs)]
        for k in range(steps):
            slave.doStep(currentCommunicationPoint=start_time + k * step, communicationStepSize=step)
            rows.append(slave.getReal(vrs))
        slave.terminate()
    finally:
        slave.freeInstance()
    return np.array(rows)


def scene_base_inputs(step: float, steps: int) -> np.ndarray:
    """What the scene runner sets as the gimbal's base inputs at t_k = k step (master.Plan)."""
    return load_scene(SHIP_SCENE).base_motion().sample(np.arange(steps + 1) * step)


def bits(x):
    return np.ascontiguousarray(x, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("step, steps", [(1e-3, 5000), (0.004, 1500)])
def test_outputs_equal_the_scene_runners_base_inputs_bit_for_bit(ship_fmu, step, steps):
    parameters = parameters_of(read_toml(SHIP_SCENE)["base_motion"])
    outputs = run_fmu(ship_fmu, parameters, step, steps)
    expected = scene_base_inputs(step, steps)
    assert np.count_nonzero(expected[:, :9]) > 0.9 * 9 * (steps + 1)   # the motion is not trivially zero
    for column, name in enumerate(INPUTS):
        differ = np.nonzero(bits(outputs[:, column]) != bits(expected[:, column]))[0]
        assert len(differ) == 0, (f"{name}: {len(differ)} rows differ, first row {differ[0]}: "
                                  f"{outputs[differ[0], column]!r} != {expected[differ[0], column]!r}")


def test_the_start_time_does_not_change_the_motion(ship_fmu):
    parameters = parameters_of(read_toml(SHIP_SCENE)["base_motion"])
    assert np.array_equal(bits(run_fmu(ship_fmu, parameters, 0.01, 300, start_time=1234.5)),
                          bits(run_fmu(ship_fmu, parameters, 0.01, 300)))


def test_surge_and_sway_reach_the_velocities_as_in_the_scene_runner(ship_fmu, tmp_path):
    base_motion = {"type": "sea_state", "seed": 3, "components": 40, "velocity_m_s": [1.0, -2.0, 0.5],
                   "surge": {"significant_amplitude_m": 0.4, "peak_period_s": 10.0, "gamma": 2.0},
                   "sway": {"significant_amplitude_m": 0.7, "peak_period_s": 6.0, "gamma": 1.0, "components": 25}}
    step, steps = 0.02, 400
    expected = make_base_motion(base_motion, tmp_path).sample(np.arange(steps + 1) * step)
    outputs = run_fmu(ship_fmu, parameters_of(base_motion), step, steps)
    assert np.array_equal(bits(outputs), bits(expected))
    assert np.ptp(outputs[:, INPUTS.index("base.v_a[1]")]) > 0.1   # sway moves x


def central_difference(x, step):
    return (x[2:] - x[:-2]) / (2.0 * step)


def test_rates_and_accelerations_are_the_derivatives(ship_fmu):
    step = 1e-3
    outputs = run_fmu(ship_fmu, parameters_of(read_toml(SHIP_SCENE)["base_motion"]), step, 5000)
    column = {name: i for i, name in enumerate(INPUTS)}
    pairs = [(f"base.{a}", f"base.{a}_dot") for a in ("delta", "psi", "gamma")] + \
            [(f"base.{a}_dot", f"base.{a}_ddot") for a in ("delta", "psi", "gamma")] + [("base.v_a[3]", "base.a_a[3]")]
    for value, derivative in pairs:
        estimate = central_difference(outputs[:, column[value]], step)
        exact = outputs[1:-1, column[derivative]]
        # The central difference's error, h^2/6 q''', is below 1e-5 of the signal for these periods
        # (>= 7 s over a band to 3 w_p: w <= 2.7 rad/s).
        assert np.max(np.abs(estimate - exact)) < 1e-5 * np.max(np.abs(exact)), (value, derivative)


def instantiate_logged(fmu):
    log = []
    return fmu.instantiate(log=log), log


@pytest.mark.parametrize("name, value, message", [
    ("roll.gamma", 0.5, r"roll\.gamma = 0\.5 must be >= 1"),
    ("heave.peak_period", 0.0, r"heave\.peak_period = 0 must be > 0"),
    ("pitch.significant_amplitude", -0.1, r"pitch\.significant_amplitude = -0\.1.* must be >= 0"),
    ("velocity[2]", math.nan, r"velocity\[2\] = nan must be finite"),
    ("base.delta", 0.1, r"base\.delta is an output and cannot be set")])
def test_a_bad_real_is_refused_with_its_name(ship_fmu, name, value, message):
    slave, log = instantiate_logged(ship_fmu)
    try:
        with pytest.raises(FMICallException):
            slave.setReal([ship_fmu.vr(name)], [value])
        assert any(re.search(message, entry.text) for entry in log), log
    finally:
        slave.freeInstance()


def test_a_bad_integer_and_a_bad_band_are_refused(ship_fmu):
    slave, log = instantiate_logged(ship_fmu)
    try:
        with pytest.raises(FMICallException):
            slave.setInteger([ship_fmu.vr("seed")], [-1])
        assert "seed = -1 must be in [0, 2147483647]" in log[-1].text
        slave.setupExperiment(startTime=0.0)
        ship_fmu.set_values(slave, {"band.lower": 2.0, "band.upper": 1.5})
        slave.enterInitializationMode()
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        assert "fmi2ExitInitializationMode: band.lower = 2, band.upper = 1.5" in log[-1].text
        ship_fmu.set_values(slave, {"band.upper": 4.0})   # corrected, initialization succeeds
        slave.exitInitializationMode()
    finally:
        slave.freeInstance()


def test_a_changed_step_size_is_refused(ship_fmu):
    slave, log = instantiate_logged(ship_fmu)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
        with pytest.raises(FMICallException):
            slave.doStep(currentCommunicationPoint=0.01, communicationStepSize=0.02)
        assert "communicationStepSize = 0.02 differs from the first step's 0.01" in log[-1].text
        with pytest.raises(FMICallException):
            slave.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.01)
        assert "does not match the FMU's time" in log[-1].text
    finally:
        slave.freeInstance()


def test_a_step_a_few_ulps_off_is_the_same_grid_step(ship_fmu):
    # libcosim passes double(t + h) - double(t) with t, h in integer nanoseconds: h to a few ulps
    slave, log = instantiate_logged(ship_fmu)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
        slave.doStep(currentCommunicationPoint=0.01, communicationStepSize=np.nextafter(0.01, 1.0))
        slave.doStep(currentCommunicationPoint=0.02, communicationStepSize=np.nextafter(0.01, 0.0))
    finally:
        slave.freeInstance()


def test_outputs_connect_one_to_one_to_the_gimbals_base_inputs(ship_fmu, fmu_path):
    gimbal = {v.name: v for v in fmpy.read_model_description(str(fmu_path)).modelVariables}
    outputs = [v for v in ship_fmu.model_description.modelVariables if v.causality == "output"]
    assert [v.name for v in outputs] == INPUTS
    for v in outputs:
        assert gimbal[v.name].causality == "input"
        assert (v.unit, v.displayUnit) == (gimbal[v.name].unit, gimbal[v.name].displayUnit), v.name


def test_the_fmu_validates_and_has_both_binaries(ship_fmu):
    assert validate_fmu(str(ship_fmu.path)) == []
    assert ship_fmu.model_description.coSimulation.canHandleVariableCommunicationStepSize is False
    assert "binaries/linux64/Gimbal2Axis_ShipMotion.so" in zipfile.ZipFile(ship_fmu.path).namelist()


def test_start_values_are_the_ship_scenes(ship_fmu):
    expected = parameters_of(read_toml(SHIP_SCENE)["base_motion"])
    for name, value in expected.items():
        if name.startswith(("surge.", "sway.")) and not name.endswith("significant_amplitude"):
            continue   # at rest in the scene: their period and gamma do not matter
        assert ship_fmu.start(name) == value, name


@pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                    reason="a sanitizer build links the sanitizer runtimes dynamically by design")
def test_shared_object_exports_only_fmi2_and_links_only_libc(build_dir):
    so = build_dir / "ship_motion_staging" / "binaries" / "linux64" / "Gimbal2Axis_ShipMotion.so"
    exported = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True)
    symbols = [line.split()[-1] for line in exported.stdout.splitlines() if line.strip()]
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2GetReal"} <= set(symbols)
    assert [s for s in symbols if not s.startswith("fmi2")] == []
    ldd = subprocess.run(["ldd", str(so)], capture_output=True, text=True, check=True).stdout
    allowed = re.compile(r"^(linux-vdso\.so\.1|libc\.so\.6|libm\.so\.6|/lib64/ld-linux-x86-64\.so\.2)$")
    assert [line.split()[0] for line in ldd.splitlines() if line.strip() and not allowed.match(line.split()[0])] == []
