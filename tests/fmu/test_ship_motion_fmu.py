"""The ship-motion FMU (build/Gimbal2Axis-ShipMotion.fmu, fmu_src/ship_motion/): its outputs are the
scene runner's base inputs bit for bit (the same C kernel makes the components and sums them on the
same grid), its rates and accelerations are the derivatives of its attitudes and velocities, a bad
parameter or step is refused with a message naming it, and it is a valid FMU exporting only fmi2*.
With motion = 1 it splines a recorded motion (the C kernel's reader and not-a-knot spline, which the
scene runner uses too): the same bits as the scene runner's base inputs, the spline scipy's, a bad
file refused with the Python side's message."""
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
from scipy.interpolate import CubicSpline

from gimbal2axis import FMU, load_scene, native
from gimbal2axis.errors import SceneError
from gimbal2axis.limits import read_toml
from gimbal2axis.scene.base_motion import INPUTS, Recorded, make_base_motion
from gimbal2axis.scene.ship_motion_fmu import recording_parameters, ship_motion_fmu_parameters

REPO = pathlib.Path(__file__).resolve().parents[2]
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


def initialize_and_record(fmu, slave, step: float, steps: int, start_time: float) -> np.ndarray:
    """Initializes a set-up instance and records INPUTS at start_time + k step, k = 0 .. steps."""
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    vrs = [fmu.vr(name) for name in INPUTS]
    rows = [slave.getReal(vrs)]
    for k in range(steps):
        slave.doStep(currentCommunicationPoint=start_time + k * step, communicationStepSize=step)
        rows.append(slave.getReal(vrs))
    slave.terminate()
    return np.array(rows)


def run_fmu(fmu, parameters: dict, step: float, steps: int, start_time: float = 0.0) -> np.ndarray:
    """The outputs at the communication points start_time + k step, k = 0 .. steps, in INPUTS order."""
    slave = fmu.instantiate()
    try:
        slave.setupExperiment(startTime=start_time)
        fmu.set_values(slave, parameters)
        return initialize_and_record(fmu, slave, step, steps, start_time)
    finally:
        slave.freeInstance()


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
    # the motion's outputs, then the target's, which feed the controller FMU (tests/package/system/test_system_target.py)
    assert [v.name for v in outputs[:len(INPUTS)]] == INPUTS
    assert [v.name for v in outputs[len(INPUTS):]] == [f"target.{q}[{i}]" for q in ("position", "velocity",
                                                                                    "acceleration") for i in (1, 2, 3)]
    for v in outputs[:len(INPUTS)]:
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


# --- recorded motion (motion = 1) ---------------------------------------------------------------------

RECORDED_SCENE = """name = "recorded"
stop_time = {stop_time}
step_size = {step}
[base_motion]
type = "recorded"
file = "motion.csv"
[controller]
type = "none"
"""


def write_recording(path: pathlib.Path, columns: dict, preamble: str = "") -> pathlib.Path:
    """A CSV of the columns {name: values}, every number as Python writes it (repr: exact)."""
    rows = zip(*columns.values())
    path.write_text(preamble + ",".join(columns) + "\n" +
                    "".join(",".join(repr(float(v)) for v in row) + "\n" for row in rows))
    return path


def irregular_times(duration: float, samples: int, seed: int) -> np.ndarray:
    """Sample times from 0 past `duration`, unevenly spaced (as a logger's time stamps are)."""
    steps = np.random.default_rng(seed).uniform(0.5, 1.5, samples - 1)
    return np.concatenate([[0.0], np.cumsum(steps) * (1.05 * duration / steps.sum())])


def run_recorded_fmu(fmu, values: dict, step: float, steps: int, start_time: float = 0.0, stop_time=None,
                     log=None) -> np.ndarray:
    """The outputs at start_time + k step, k = 0 .. steps, with the recording parameters `values`."""
    slave = fmu.instantiate(log=log)
    try:
        if stop_time is None:
            slave.setupExperiment(startTime=start_time)
        else:
            slave.setupExperiment(startTime=start_time, stopTime=stop_time)
        slave.setInteger([fmu.vr("motion")], [values["motion"]])
        if "recording_file" in values:
            slave.setString([fmu.vr("recording_file")], [values["recording_file"]])
        return initialize_and_record(fmu, slave, step, steps, start_time)
    finally:
        slave.freeInstance()


def recorded_columns(kind: str, t: np.ndarray) -> dict:
    """Recordings with derivatives missing (the spline's are used) and, for "degrees", angles in degrees."""
    if kind == "radians":
        return {"time": t, "delta": 0.03 * np.sin(0.9 * t), "gamma": 0.08 * np.sin(0.7 * t + 1.0),
                "gamma_dot": 0.056 * np.cos(0.7 * t + 1.0), "x": 0.2 * np.cos(0.5 * t), "z": 0.9 * np.sin(0.6 * t)}
    return {"time": t, "pitch_deg": 2.0 * np.sin(0.9 * t), "yaw_deg": 0.5 * np.cos(0.2 * t),
            "roll_deg": 5.0 * np.sin(0.7 * t)}


@pytest.mark.parametrize("kind", ["radians", "degrees"])
def test_recorded_outputs_equal_the_scene_runners_base_inputs_bit_for_bit(ship_fmu, tmp_path, kind):
    step, steps = 1e-3, 6000
    columns = recorded_columns(kind, irregular_times(steps * step, 400, 5))
    write_recording(tmp_path / "motion.csv", columns, preamble="# logged on the bridge\n")
    scene_path = tmp_path / "scene.toml"
    scene_path.write_text(RECORDED_SCENE.format(stop_time=steps * step, step=step))
    scene = load_scene(scene_path)
    expected = scene.base_motion().sample(np.arange(steps + 1) * step)   # master.Plan's grid
    outputs = run_recorded_fmu(ship_fmu, recording_parameters(scene), step, steps, stop_time=steps * step)
    spline_derived = ["base.delta_dot", "base.delta_ddot", "base.gamma_ddot", "base.v_a[1]", "base.a_a[3]"] \
        if kind == "radians" else ["base.delta_dot", "base.psi_ddot", "base.gamma_dot", "base.gamma_ddot"]
    for name in spline_derived:
        assert np.count_nonzero(expected[:, INPUTS.index(name)]) > 0.9 * (steps + 1), name
    for column, name in enumerate(INPUTS):
        differ = np.nonzero(bits(outputs[:, column]) != bits(expected[:, column]))[0]
        assert len(differ) == 0, (f"{name}: {len(differ)} rows differ, first row {differ[0]}: "
                                  f"{outputs[differ[0], column]!r} != {expected[differ[0], column]!r}")


def kernel_spline(x: np.ndarray, y: np.ndarray):
    """The C kernel's not-a-knot spline through (x, y), as a function of (t, derivative)."""
    kernel = native.kernel()
    x, y = np.ascontiguousarray(x, dtype=float), np.ascontiguousarray(y, dtype=float)
    coefficients = np.empty(kernel.gimbal_cubic_spline_coefficient_count(len(x)))
    assert kernel.gimbal_cubic_spline_fit(len(x), x.ctypes.data, y.ctypes.data, coefficients.ctypes.data) == 0
    return lambda t, derivative: np.array([kernel.gimbal_cubic_spline_evaluate(len(x), x.ctypes.data,
                                                                                coefficients.ctypes.data, float(ti),
                                                                                derivative) for ti in t])


@pytest.mark.parametrize("samples", [4, 5, 7, 60, 500])
def test_the_kernels_spline_is_scipys_not_a_knot_spline(samples):
    rng = np.random.default_rng(samples)
    x = np.cumsum(rng.uniform(0.01, 1.0, samples))
    y = rng.normal(size=samples) + np.sin(x)
    t = np.concatenate([np.linspace(x[0] - 0.3, x[-1] + 0.3, 2001), x])   # inside, the knots, a little outside
    ours, reference = kernel_spline(x, y), CubicSpline(x, y)   # scipy's default: not-a-knot at both ends
    for derivative in range(3):
        expected = reference(t, derivative)
        error = np.max(np.abs(ours(t, derivative) - expected))
        assert error <= 1e-12 * np.max(np.abs(expected)), (derivative, error)


def test_recorded_motion_is_scipys_spline_of_the_columns(tmp_path):
    t = irregular_times(5.0, 80, 9)
    roll_deg, y = 4.0 * np.sin(0.8 * t), 0.3 * np.cos(1.1 * t)
    gamma_ddot_given = -0.1 * np.sin(0.8 * t)
    motion = Recorded(write_recording(tmp_path / "motion.csv", {"time": t, "roll_deg": roll_deg, "y": y,
                                                                  "gamma_ddot": gamma_ddot_given}))
    tt = np.linspace(0.0, 5.0, 777)
    sampled = motion.sample(tt)
    roll, position = CubicSpline(t, np.radians(roll_deg)), CubicSpline(t, y)
    references = {"base.gamma": roll(tt), "base.gamma_dot": roll(tt, 1), "base.gamma_ddot": CubicSpline(t, gamma_ddot_given)(tt),
                  "base.v_a[2]": position(tt, 1), "base.a_a[2]": position(tt, 2)}
    for name, expected in references.items():
        assert np.max(np.abs(sampled[:, INPUTS.index(name)] - expected)) <= 1e-12 * np.max(np.abs(expected)), name
    untouched = [i for i, name in enumerate(INPUTS) if name not in references]
    assert np.all(sampled[:, untouched] == 0.0)
    np.testing.assert_allclose(motion.position(tt)[:, 1], position(tt) - position(tt[0]), rtol=0, atol=1e-14)


@pytest.mark.parametrize("content", [
    "time,gamma\n0,0\n0.005,0.001\n0.01,abc\n0.015,0.003\n",
    "time,gamma\n0,0\n0.005,0.001\n0.01,\n0.015,0.003\n",
    "time,gamma,heading\n0,0,1\n0.005,0.001,1\n0.01,0.002,1\n0.015,0.003,1\n",
    "time,gamma_dot\n0,0\n0.005,0.001\n0.01,0.002\n0.015,0.003\n",
    "time,gamma\n0,0\n0.005,0.001\n0.005,0.002\n0.015,0.003\n",
    None,
    "a directory",
], ids=["non_numeric_cell", "empty_cell", "unknown_column", "rate_without_angle", "time_not_increasing", "missing",
        "directory"])
def test_a_bad_recording_is_refused_with_the_scene_runners_message(ship_fmu, tmp_path, content):
    path = tmp_path / "motion.csv"
    if content == "a directory":
        path.mkdir()
    elif content is not None:
        path.write_text(content)
    with pytest.raises(SceneError) as refused:
        Recorded(path)
    reason = str(refused.value).split(f"{path}: ", 1)[1]   # after the file's name: line, column, why
    slave, log = instantiate_logged(ship_fmu)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.setInteger([ship_fmu.vr("motion")], [1])
        slave.setString([ship_fmu.vr("recording_file")], [str(path)])
        slave.enterInitializationMode()
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        assert log[-1].text == f"fmi2ExitInitializationMode: recorded motion {path}: {reason}", (log[-1].text, reason)
    finally:
        slave.freeInstance()
    if content is not None and "abc" in content:
        assert reason == "line 4 (data row 3), column 'gamma' is not a number: 'abc'"


def test_the_example_recording_in_the_resources_is_the_default(ship_fmu):
    step, steps = 0.01, 500
    outputs = run_recorded_fmu(ship_fmu, {"motion": 1}, step, steps, start_time=10.0)
    resources = pathlib.Path(ship_fmu.unzipdir) / "resources"
    assert ship_fmu.variable("recording_file").start == "ship_recording.csv"
    expected = Recorded(resources / "ship_recording.csv").sample(np.arange(steps + 1) * step)
    assert np.array_equal(bits(outputs), bits(expected))
    assert np.ptp(outputs[:, INPUTS.index("base.gamma_ddot")]) > 0.01   # the roll recording's spline


def test_a_recording_that_does_not_cover_the_run_is_refused(ship_fmu, tmp_path):
    t = np.linspace(0.0, 1.0, 11)
    path = write_recording(tmp_path / "motion.csv", {"time": t, "gamma": 0.01 * t})
    log = []
    with pytest.raises(FMICallException):
        run_recorded_fmu(ship_fmu, {"motion": 1, "recording_file": str(path)}, 0.1, 10, stop_time=2.0, log=log)
    assert f"recorded motion {path} covers [0, 1] s, not [0, 2] s" in log[-1].text
    log.clear()
    with pytest.raises(FMICallException):   # no stopTime: the step past the end is refused
        run_recorded_fmu(ship_fmu, {"motion": 1, "recording_file": str(path)}, 0.1, 11, log=log)
    assert "passes the recording's end at 1 s" in log[-1].text, log[-1].text
    late = write_recording(tmp_path / "late.csv", {"time": t + 0.5, "gamma": 0.01 * t})
    log.clear()
    with pytest.raises(FMICallException):
        run_recorded_fmu(ship_fmu, {"motion": 1, "recording_file": str(late)}, 0.1, 5, log=log)
    assert f"recorded motion {late} covers [0.5, 1.5] s, not t = 0, where the outputs start" in log[-1].text


def test_the_reader_has_pythons_doubles_and_line_endings(tmp_path):
    # At a knot other than the last the spline's value is its sample exactly (d = 0 leaves it), so
    # there are the reader's doubles: float()'s, for decimal notation however long or small.
    numbers = ["1e-3", ".5", "7.", "+1.5", "-2.5e+2", "123456789012345678901234567890", "0.1000000000000000055511151231257827",
               "2.2250738585072011e-308", "4.9e-324", "1e-400", "3.141592653589793238462643383279"]
    times = [str(k) for k in range(len(numbers))]
    text = "\ufeff\"time\" , gamma\r\n" + "".join(f"{t}, {n}  # sample\r\n" for t, n in zip(times, numbers)) + \
        f"{len(numbers)},0\r\n"   # the last knot, whose value the last cubic computes
    (tmp_path / "motion.csv").write_bytes(text.encode("utf-8"))
    sampled = Recorded(tmp_path / "motion.csv").sample(np.array([float(t) for t in times]))
    assert np.array_equal(bits(sampled[:, INPUTS.index("base.gamma")]), bits(np.array([float(n) for n in numbers])))
    (tmp_path / "old_mac.csv").write_bytes(b"time,gamma\r0,0\r1,1\r2,4\r3,9")
    assert Recorded(tmp_path / "old_mac.csv").sample(np.array([2.0]))[0, 2] == 4.0   # lines end at "\r" too
    (tmp_path / "underscore.csv").write_text("time,gamma\n0,0\n1,1_0\n2,4\n3,9\n")
    with pytest.raises(SceneError, match=r"line 3 \(data row 2\), column 'gamma' is not a number: '1_0'"):
        Recorded(tmp_path / "underscore.csv")
