"""The scene runner with current-commanded drives (motor<j>.drive = current, gimbal2axis/scene/drives.py):
the controller's output goes to the FMU's current command i_R<j>_cmd, clamped to +-i_L; the record names
each command column by what it holds (i_R<j>_cmd, i_R<j>_ctrl, i_R<j>_asked in A, the amplifier's voltage
amplifier<j>.u), both loops and the streamed run give the same bits, a mixed scene keeps the voltage
motor's columns, and what cannot run current drive (the FMU system, a moving target's loop gain) says so."""
import pathlib
import subprocess
import sys

import numpy as np
import pyarrow.parquet as pq
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.master import run_scene_file
from gimbal2axis.scene.drives import command_columns

REPO = pathlib.Path(__file__).resolve().parents[3]
SCENES = REPO / "scenes"

# A fixed base, the payload balanced, a step of the azimuth set point that the PID (in A) answers with
# a command beyond the 4 A limit at first; motor 2 as the test asks.
SCENE = """
name = "current_step"
stop_time = 0.4
step_size = 1e-3
output_interval = 1e-3
[fidelity]
"base.fixed" = true
"motor1.drive" = 1
"motor2.drive" = {drive2}
[parameters]
"body2.d_bd[2]" = 0.0
"body2.d_bd[3]" = 0.0
[base_motion]
type = "fixed"
[controller]
type = "pid"
delay_steps = {delay}
[controller.azimuth]
reference = {{ type = "step", at_s = 0.05, from_deg = 0.0, to_deg = 2.0 }}
kp = 200.0
ki = 1000.0
k_gyro = 4.0
[controller.elevation]
reference = {{ type = "step", at_s = 0.1, from_deg = 0.0, to_deg = 1.0 }}
kp = {kp2}
ki = 0.0
k_gyro = {kg2}
"""


def scene_file(tmp_path, drive2=1, delay=1):
    kp2, kg2 = (160.0, 3.2) if drive2 == 1 else (400.0, 8.0)
    path = tmp_path / f"current_step_{drive2}_{delay}.toml"
    path.write_text(SCENE.format(drive2=drive2, delay=delay, kp2=kp2, kg2=kg2))
    return path


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


@pytest.mark.parametrize("delay", [0, 1, 2])
def test_the_command_reaches_the_current_input_clamped_and_delayed(tmp_path, fmu, delay):
    scene = load_scene(scene_file(tmp_path, delay=delay))
    result = run(scene, fmu)
    s = result.signals
    for voltage_column in ("u_R1", "u_R1_cmd", "u_R1_asked", "u_R2", "u_R2_cmd", "u_R2_asked"):
        assert voltage_column not in s, voltage_column
    for j, limit in ((1, 4.0), (2, 3.0)):
        applied, ctrl, asked = s[f"i_R{j}_cmd"], s[f"i_R{j}_ctrl"], s[f"i_R{j}_asked"]
        assert np.array_equal(ctrl, np.clip(asked, -limit, limit))
        assert np.array_equal(applied[delay:], ctrl[:len(ctrl) - delay]) and not applied[:delay].any()
        # the amplifier's 2 kHz loop follows the command held over the step: once the set points' steps
        # have settled (their bus saturation leaves a transient of L/R), the current at a step's end is the
        # command of that step to exp(-2 pi 2000 h) = 4e-6 of its changes (measured: 5e-7 A)
        k = np.flatnonzero(s["time"] > 0.15)
        error = np.abs(s[f"i_R{j}"][k] - applied[k - 1])
        assert np.max(error) <= 1e-4 * np.sqrt(np.mean(applied[k - 1] ** 2)), (j, np.max(error))
        assert np.max(np.abs(s[f"amplifier{j}.u"])) <= 24.0
    # the step asks more than 4 A of the azimuth: clamped, and the summary says so in amperes
    assert np.max(np.abs(s["i_R1_asked"])) > 4.0 and np.max(np.abs(s["i_R1_ctrl"])) == 4.0
    summary = result.voltage_clamp.summary()
    assert "current command clamped on" in summary and "(azimuth), max asked" in summary and summary.endswith(" A")
    assert "voltage" not in summary


def test_both_loops_give_the_same_bits_in_current_drive(tmp_path, fmu):
    scene = load_scene(scene_file(tmp_path))
    python = run(scene, fmu, compiled=False)
    compiled = run(scene, fmu, compiled=True)
    assert python.loop == "python" and compiled.loop == "compiled"
    assert python.signals.keys() == compiled.signals.keys()
    for signal, values in python.signals.items():
        assert np.array_equal(values, compiled.signals[signal], equal_nan=True), signal
    assert python.voltage_clamp.summary() == compiled.voltage_clamp.summary()


def test_a_motor_in_voltage_drive_keeps_its_columns_beside_one_in_current_drive(tmp_path, fmu):
    scene = load_scene(scene_file(tmp_path, drive2=0))
    s = run(scene, fmu).signals
    assert {"i_R1_cmd", "i_R1_ctrl", "i_R1_asked", "u_R2", "u_R2_cmd", "u_R2_asked", "amplifier1.u"} <= s.keys()
    assert not {"u_R1", "i_R2_ctrl", "amplifier2.u"} & s.keys()
    assert command_columns(s, 1).kind == "current" and command_columns(s, 2).kind == "voltage"
    assert np.max(np.abs(s["u_R2_cmd"])) <= 24.0 and np.max(np.abs(s["u_R2_asked"])) > 0


def test_the_streamed_run_writes_amperes_and_equals_the_run_in_memory(tmp_path, fmu_path, fmu):
    path = scene_file(tmp_path)
    streamed, csv_path, png = run_scene_file(path, fmu_path, tmp_path / "out", stream=True)
    header = csv_path.read_text().splitlines()[0].split(",")
    for label in ("i_R1_cmd [A]", "i_R1_ctrl [A]", "i_R1_asked [A]", "amplifier1.u [V]", "amplifier1.x_I [V]",
                  "motor1.amplifier_saturated [1]"):
        assert label in header, label
    schema = pq.read_schema(csv_path.with_suffix(".parquet"))
    assert schema.field("i_R2_ctrl").metadata[b"unit"] == b"A"
    table = pq.read_table(csv_path.with_suffix(".parquet"))
    in_memory = run(load_scene(path), fmu)
    for name in ("i_R1", "i_R1_cmd", "i_R1_ctrl", "amplifier1.u", "alpha"):
        assert np.array_equal(table.column(name).to_numpy(), in_memory.signals[name]), name
    assert png.is_file()


def test_the_keyhole_flyby_in_current_drive_is_held_by_the_bus_and_the_limit(fmu):
    scene = load_scene(SCENES / "track_flyby_keyhole_current.toml")
    near = scene.with_changes(target_spec={**scene.target_spec, "closest_approach_s": 0.6})
    result = run(near, fmu, stop_time=1.2)
    s = result.signals
    # near the keyhole the azimuth asks beyond its limit: commanded at +-4 A, the amplifier at the bus
    assert np.max(np.abs(s["i_R1_ctrl"])) == 4.0
    assert np.max(np.abs(s["amplifier1.u"])) == pytest.approx(24.0, abs=1e-9)
    assert np.any(s["motor1.amplifier_saturated"] != 0)
    # the current never passes the limit (the amplifier clamps the command; there is no limiter besides)
    assert np.max(np.abs(s["i_R1"])) <= 4.0 * (1 + 1e-9) and not np.any(s["motor1.limited"])
    metrics = result.tracking_metrics().as_dict()
    assert metrics["keyhole_asked_current_max"] > 4.0 and "keyhole_asked_voltage_max" not in metrics


def test_a_system_of_the_fmus_refuses_current_drive(tmp_path, build_dir):
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "system", str(SCENES / "track_flyby_keyhole_current.toml"),
                           "--build-dir", str(build_dir), "--out", str(tmp_path / "systems")],
                          capture_output=True, text=True)
    assert done.returncode == 2, done.stderr
    assert "motor1.drive = current" in done.stderr and "Traceback" not in done.stderr


def test_freqresp_loop_gain_of_a_moving_target_is_refused_in_one_line(tmp_path):
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "freqresp", "loop-gain", "--scene",
                           str(SCENES / "track_flyby_keyhole_current.toml"), "--points", "2", "--out", str(tmp_path)],
                          capture_output=True, text=True)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "its [target] moves" in done.stderr


def test_open_loop_frequency_response_of_a_current_command_follows_the_linear_model(tmp_path, fmu_path):
    # torque-driven (the amplifier cancels the back-emf), the azimuth rate integrates the current command
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "freqresp", "open-loop", "--axis", "1",
                           "--amplitude", "0.5", "--fmin", "5", "--fmax", "20", "--points", "2", "--serial",
                           "--linear-only", "--set", "body2.d_bd[2]=0", "--set", "body2.d_bd[3]=0",
                           "--set", "motor1.drive=1", "--set", "motor2.drive=1", "--fmu", str(fmu_path),
                           "--out", str(tmp_path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    import csv
    rows = list(csv.DictReader(open(tmp_path / "frequency_response_open_loop_1.csv")))
    assert {row["input"] for row in rows} == {"i_R1_cmd"}
    for f in {row["frequency_hz"] for row in rows if row["curve"] != "linear model"}:
        simulated = next(r for r in rows if r["curve"] != "linear model" and r["frequency_hz"] == f
                         and r["output"] == "alpha_dot")
        linear = next(r for r in rows if r["curve"] == "linear model" and r["frequency_hz"] == f
                      and r["output"] == "alpha_dot")
        assert float(simulated["gain"]) == pytest.approx(float(linear["gain"]), rel=0.02)
        assert abs(float(simulated["phase_deg"]) - float(linear["phase_deg"])) < 2.0
        assert -95.0 < float(linear["phase_deg"]) < -85.0   # an integrator


def test_linearize_at_a_time_of_a_current_driven_run_takes_its_current_commands(tmp_path, fmu):
    from gimbal2axis.cli.linearize import inputs_at_end

    scene = load_scene(scene_file(tmp_path, drive2=0))
    signals = run(scene, fmu, stop_time=0.2).signals
    inputs = inputs_at_end(scene, signals)
    assert inputs == {"i_R1_cmd": signals["i_R1_cmd"][-1], "u_R2": signals["u_R2"][-1]}
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "linearize", "--scene", str(scene.path), "--at-time",
                           "0.2", "--out", str(tmp_path / "lin.npz"), "--bode", "i_R1_cmd:alpha_dot"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    model = np.load(tmp_path / "lin.npz", allow_pickle=False)
    assert list(model["inputs"][:2]) == ["i_R1_cmd", "u_R2"]


@pytest.mark.parametrize("drive2, name, message", [
    (1, "u_R2_cmd", "motor2 is in current drive (motor2.drive), so its record has 'i_R2_ctrl' instead (A"),
    (0, "i_R2_asked", "motor2 is in voltage drive (motor2.drive), so its record has 'u_R2_asked' instead (V"),
    (0, "i_R2_cmd", "motor2 is in voltage drive (motor2.drive), so its record has 'u_R2' instead (V"),
    (1, "energy_accounting", "is an FMU parameter of type Boolean that a run does not record"),
])
def test_a_plot_of_a_column_the_record_cannot_have_is_refused_naming_the_one_it_has(tmp_path, fmu, drive2, name,
                                                                                     message):
    path = scene_file(tmp_path, drive2=drive2)
    path.write_text(path.read_text() + f'[plot]\nmine = ["{name}"]\n')
    with pytest.raises(SceneError, match=message.replace("(", r"\(").replace(")", r"\)")):
        run(load_scene(path), fmu, stop_time=0.01)


def test_an_fmu_variable_a_plot_names_is_recorded_for_it(tmp_path, fmu_path):
    path = scene_file(tmp_path)
    path.write_text(path.read_text() + '[plot]\nwork = ["solver.steps", "motor1.R", "i_R1_cmd"]\n')
    result, csv_path, png = run_scene_file(path, fmu_path, tmp_path / "out", stop_time=0.05)
    steps = result.signals["solver.steps"]
    assert steps[-1] > steps[0] and np.all(np.diff(steps) >= 0)
    assert np.all(result.signals["motor1.R"] == 2.0)
    assert "solver.steps [1]" in csv_path.read_text().splitlines()[0].split(",") and png.is_file()
