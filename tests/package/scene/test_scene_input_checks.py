"""Strict, explicit scene input (issue 34): every value checked by its key before the FMU is opened
(type, finiteness, range; the angle rule of docs/scenes.md, "Units"), close matches wherever a name is
looked up, and messages that quote what the user wrote in bounded excerpts, and nothing of a file that
is not a recorded motion. Through load_scene and through the commands, as a user meets them: exit
status 2 and one line on stderr."""
import math
import pathlib
import subprocess
import sys
import warnings

import pytest

from gimbal2axis import FMU, SceneError, check_against_fmu, load_scene
from gimbal2axis.errors import EXCERPT_CHARS, excerpt
from test_scene_messages import QUIET   # a scene that draws no warning

pytestmark = pytest.mark.python_bound

GIMBAL2AXIS = [sys.executable, "-m", "gimbal2axis"]


SEA_STATE = """name = "sea"
stop_time = 0.01
step_size = 1e-3
[base_motion]
type = "sea_state"
roll = { significant_amplitude_deg = AMPLITUDE, peak_period_s = 8.0 }
[controller]
type = "none"
"""

RECORDED = """name = "recorded"
stop_time = 0.01
step_size = 1e-3
[base_motion]
type = "recorded"
file = "FILE"
[controller]
type = "none"
"""


def write_scene(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def with_table(table: str, body: str) -> str:
    """QUIET with `body` in [table] (a table QUIET has gets the lines added)."""
    if f"[{table}]\n" in QUIET:
        return QUIET.replace(f"[{table}]\n", f"[{table}]\n{body}\n")
    return QUIET + f"[{table}]\n{body}\n"


def load_quietly(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_scene(path)


def refusal(path) -> str:
    with pytest.raises(SceneError) as caught:
        load_quietly(path)
    return str(caught.value)


def gimbal2axis(*args, cwd):
    done = subprocess.run([*GIMBAL2AXIS, *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=300)
    assert "Traceback" not in done.stderr, done.stderr
    return done


def assert_one_line_error(done, command, *fragments):
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"gimbal2axis {command}: error: "), done.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


# --- types, finiteness, ranges: refused by key --------------------------------------------------------

REFUSED_BY_KEY = {
    "string_stop_time": (QUIET.replace("stop_time = 0.01", 'stop_time = "0.01"'),
                         ["stop_time must be a finite number", "'0.01'", "without quotes"]),
    "string_initial": (with_table("initial", 'beta = "0.5"'), ["initial.beta must be a finite number", "'0.5'", "without quotes"]),
    "string_parameter": (with_table("parameters", '"body2.m" = "2.5"'),
                         ["parameters.body2.m must be a finite number or true/false", "'2.5'", "without quotes"]),
    "string_boolean": (with_table("target", 'start_on_target = "false"'),
                       ["target.start_on_target must be true or false", "'false'"]),
    "string_sea_state": (SEA_STATE.replace("AMPLITUDE", '"5"'), ["base_motion.roll.significant_amplitude_deg", "'5'"]),
    "string_sinusoid": (QUIET.replace('type = "fixed"', 'type = "sinusoids"\nroll = { amplitude_deg = "x", '
                                                          'period_s = 8.0 }').replace('"base.fixed" = true', ""),
                        ["base_motion.roll.amplitude_deg must be a finite number", "'x'"]),
    "three_values_initial": (with_table("initial", "beta = [0.1, 0.2, 0.3]"),
                             ["initial.beta must be a finite number, got [0.1, 0.2, 0.3]"]),
    "three_values_parameter": (with_table("parameters", '"body2.d_bd" = [0.0, 0.015, 0.0]'),
                               ["parameters.body2.d_bd must be a finite number or true/false", '"body2.d_bd[1]" = ...']),
    "three_values_stop_time": (QUIET.replace("stop_time = 0.01", "stop_time = [0.01, 0.02, 0.03]"),
                               ["stop_time must be a finite number, got [0.01, 0.02, 0.03]"]),
    "degree_sized_beta": (with_table("initial", "beta = 30"),
                          ["initial.beta = 30 rad (1719 deg)", "±3.1416 rad", "did you mean beta_deg = 30?"]),
    "degree_sized_alpha": (with_table("initial", "alpha = -4.0"), ["initial.alpha = -4 rad (-229 deg)"]),
    "beyond_half_turn_deg": (with_table("initial", "beta_deg = 300"),
                             ["initial.beta_deg = 300 deg is beyond ±180 deg", "same pose as -60 deg"]),
    "both_units": (with_table("initial", "beta = 0.5\nbeta_deg = 28.6"),
                   ["initial.beta and initial.beta_deg are the same angle"]),
    "nan_sea_state": (SEA_STATE.replace("AMPLITUDE", "nan"),
                      ["base_motion.roll.significant_amplitude_deg must be a finite number, got nan"]),
    "inf_sea_state": (SEA_STATE.replace("AMPLITUDE", "inf"),
                      ["base_motion.roll.significant_amplitude_deg must be a finite number, got inf"]),
    "negative_sea_state": (SEA_STATE.replace("AMPLITUDE", "-1.0"),
                           ["base_motion.roll.significant_amplitude_deg must be >= 0, got -1.0"]),
    "zero_peak_period": (SEA_STATE.replace("AMPLITUDE", "5.0").replace("peak_period_s = 8.0", "peak_period_s = 0"),
                         ["base_motion.roll.peak_period_s must be positive"]),
    "nan_gamma": (SEA_STATE.replace("AMPLITUDE", "5.0").replace("8.0 }", "8.0, gamma = nan }"),
                  ["base_motion.roll.gamma must be a finite number, got nan"]),
    "fractional_components": (SEA_STATE.replace("AMPLITUDE", "5.0").replace("8.0 }", "8.0, components = 2.5 }"),
                              ["base_motion.roll.components must be an integer >= 1, got 2.5"]),
    "nan_velocity": (SEA_STATE.replace("AMPLITUDE", "5.0").replace('"sea_state"', '"sea_state"\n'
                                                                     "velocity_m_s = [0.0, nan, 0.0]"),
                     ["base_motion.velocity_m_s[1] must be a finite number, got nan"]),
    "nan_parameter": (with_table("parameters", '"body2.m" = nan'), ["parameters.body2.m", "got nan"]),
    "negative_step": (QUIET.replace("step_size = 1e-3", "step_size = -1e-3"), ["step_size must be positive"]),
    "zero_steps": (QUIET.replace("stop_time = 0.01", "stop_time = 1e-4"),
                   ["stop_time = 0.0001 s is shorter than one step (step_size = 0.001 s)"]),
    "negative_noise": (with_table("sensors", "gyro_noise_deg_s = -0.1"), ["sensors.gyro_noise_deg_s must be >= 0"]),
    "string_seed": (with_table("sensors", 'seed = "abc"'), ["sensors.seed must be an integer >= 0, got 'abc'"]),
    "file_not_a_string": (RECORDED.replace('"FILE"', "5"), ["base_motion.file must be a path (a string), got 5"]),
    "from_s_after_the_end": (with_table("target", "azimuth_deg = 0.0") + "[requirements]\nfrom_s = 0.02\n",
                             ["requirements.from_s = 0.02 s is not before stop_time = 0.01 s"]),
}


@pytest.mark.parametrize("text, fragments", REFUSED_BY_KEY.values(), ids=REFUSED_BY_KEY.keys())
def test_a_wrong_value_is_refused_by_its_key_on_loading(tmp_path, text, fragments):
    path = write_scene(tmp_path, text)
    message = refusal(path)
    assert message.startswith(f"{path}: "), message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


@pytest.mark.parametrize("name", ["string_initial", "three_values_parameter", "degree_sized_beta", "nan_sea_state"])
def test_a_wrong_value_stops_the_run_command_in_one_line(tmp_path, fmu_path, name):
    text, fragments = REFUSED_BY_KEY[name]
    path = write_scene(tmp_path, text)
    done = gimbal2axis("run", path, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    assert_one_line_error(done, "run", str(path), *fragments)
    assert not (tmp_path / "out" / "scene.csv").exists()


def test_an_angle_in_degrees_is_the_same_start_as_in_radians(tmp_path):
    in_degrees = load_quietly(write_scene(tmp_path, with_table("initial", "beta_deg = 30.0\nalpha_deg = -180.0")))
    assert in_degrees.initial == {"beta": math.radians(30.0), "alpha": -math.pi}
    in_radians = load_quietly(write_scene(tmp_path, with_table("initial", f"beta = {math.radians(30.0)!r}"), "r.toml"))
    assert in_radians.initial == {"beta": math.radians(30.0)}
    # a rotor angle has no half-turn bound: it is N times its load's
    rotor = load_quietly(write_scene(tmp_path, with_table("initial", "alpha_m = 40.0\nbeta_m_deg = 900.0"), "m.toml"))
    assert rotor.initial == {"alpha_m": 40.0, "beta_m": math.radians(900.0)}


# --- names: close matches wherever a name is looked up -------------------------------------------------

NAME_TYPOS = {
    "top_level": (QUIET.replace("stop_time", "stop_tme"), "did you mean 'stop_time'"),
    "table_key": (with_table("target", "azimuth_dg = 10.0"), "did you mean 'azimuth_deg'"),
    "base_motion_type": (QUIET.replace('type = "fixed"', 'type = "fixd"'), "did you mean 'fixed'"),
    "stabilization": (with_table("sensors", 'stabilization = "indirekt"'), "did you mean 'indirect'"),
    "fidelity_switch": (QUIET.replace('"base.fixed" = true', '"base.fixed" = true\n"gear1.modle" = 1'),
                        "did you mean 'gear1.model'"),
    "controller_type": (QUIET.replace('type = "none"', 'type = "pdi"'), "did you mean 'pid'"),
    "reference_type": (QUIET.replace('type = "none"', 'type = "pid"\n[controller.azimuth]\nkp = 1.0\n'
                                                      'reference = { type = "stepp" }'), "did you mean 'step'"),
}


@pytest.mark.parametrize("text, suggestion", NAME_TYPOS.values(), ids=NAME_TYPOS.keys())
def test_a_misspelt_scene_name_gets_the_close_match(tmp_path, text, suggestion):
    assert suggestion in refusal(write_scene(tmp_path, text))


FMU_NAME_TYPOS = {
    "parameters": (with_table("parameters", '"motor1.RR" = 1.0'), "[parameters] 'motor1.RR'", "'motor1.R'"),
    "initial": (with_table("initial", "betaa = 0.1"), "[initial]: 'betaa' is not a state", "'beta'"),
    "initial_in_degrees": (with_table("initial", "beta_dg = 10.0"), "'beta_dg' is not a state", "'beta_deg'"),
    "plot": (QUIET + '[plot]\nerrors = ["los_eror"]\n', "[plot] 'los_eror'", "'los_error'"),
}


@pytest.mark.parametrize("text, fragment, suggestion", FMU_NAME_TYPOS.values(), ids=FMU_NAME_TYPOS.keys())
def test_a_misspelt_fmu_name_gets_the_close_match(tmp_path, fmu_path, text, fragment, suggestion):
    scene = load_quietly(write_scene(tmp_path, text))
    with FMU(fmu_path) as fmu, pytest.raises(SceneError) as caught:
        check_against_fmu(scene, fmu)
    message = str(caught.value)
    assert fragment in message and f"did you mean {suggestion}" in message, message
    assert "older than the scene" not in message   # a typo is the scene's, not the FMU's age


def test_a_misspelt_parameter_gets_the_close_match_from_the_run_command(tmp_path, fmu_path):
    path = write_scene(tmp_path, with_table("parameters", '"motor1.RR" = 1.0'))
    done = gimbal2axis("run", path, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    assert_one_line_error(done, "run", str(path), "[parameters] 'motor1.RR'", "did you mean 'motor1.R'")


# --- bounded messages -----------------------------------------------------------------------------------

def test_a_40_mb_unknown_key_is_quoted_as_an_excerpt(tmp_path, fmu_path):
    key = "k" * 40_000_000
    path = write_scene(tmp_path, QUIET + f"{key} = 1\n")
    message = refusal(path)
    assert f"'{'k' * EXCERPT_CHARS}…(40000000 characters)'" in message
    assert len(message) < 600 + len(str(path)), len(message)
    done = gimbal2axis("run", path, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    line = assert_one_line_error(done, "run", "unknown key(s)", "…(40000000 characters)")
    assert len(line) < 700 + len(str(path))


def test_long_values_and_names_are_quoted_as_excerpts(tmp_path):
    long_text = "x" * 10_000
    for table, body in (("initial", f'beta = "{long_text}"'), ("target", f'"{long_text}" = 1.0'),
                        ("parameters", f'"body2.m" = ["{long_text}"]')):
        path = write_scene(tmp_path, with_table(table, body))
        message = refusal(path)
        assert "x" * (EXCERPT_CHARS - 2) + "…(" in message and long_text not in message, message[:300]
        assert len(message) < 500 + len(str(path)), message
    assert excerpt("abc") == "abc" and excerpt("a" * 81) == "a" * 80 + "…(81 characters)"


def test_a_scene_file_that_is_not_text_is_named_not_shown(tmp_path, fmu_path):
    path = tmp_path / "scene.toml"
    path.write_bytes(b"\x7fELF\x02\x01\x01\x00" + bytes(range(256)))
    done = gimbal2axis("run", path, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    assert_one_line_error(done, "run", str(path), "not a text file")


# --- recorded motions: a file that is not one is named, not shown --------------------------------------

NOT_A_RECORDING = "operator:x:0:0:SECRET-FIRST-LINE:/root:/bin/bash\ndaemon:x:1:1:SECRET-SECOND:/usr/sbin\n"


@pytest.mark.parametrize("content", [NOT_A_RECORDING, "user,SECRET-NAME,more\n1,2,3\n"], ids=["passwd", "csv"])
def test_a_file_that_is_not_a_recording_is_not_quoted(tmp_path, fmu_path, content):
    (tmp_path / "motion.csv").write_text(content)
    path = write_scene(tmp_path, RECORDED.replace("FILE", "motion.csv"))
    message = refusal(path)
    assert "SECRET" not in message and "motion.csv" in message and "not a recorded motion" in message, message
    done = gimbal2axis("run", path, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    line = assert_one_line_error(done, "run", "motion.csv", "no 'time' column")
    assert "SECRET" not in line


@pytest.mark.skipif(not pathlib.Path("/etc/passwd").is_file(), reason="no /etc/passwd here")
def test_etc_passwd_as_a_recorded_motion_is_not_quoted(tmp_path, fmu_path):
    first_line = pathlib.Path("/etc/passwd").read_text(errors="replace").splitlines()[0]
    path = write_scene(tmp_path, RECORDED.replace("FILE", "/etc/passwd"))
    done = gimbal2axis("run", path, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    line = assert_one_line_error(done, "run", "/etc/passwd", "not a recorded motion")
    assert first_line not in line and first_line.split(":")[0] + ":" not in line, line


def test_a_long_cell_of_a_recording_is_quoted_as_an_excerpt(tmp_path):
    cell = "y" * 5000
    (tmp_path / "motion.csv").write_text(f"time,gamma\n0,0\n0.005,0.001\n0.01,{cell}\n0.015,0.003\n")
    message = refusal(write_scene(tmp_path, RECORDED.replace("FILE", "motion.csv")))
    assert "line 4" in message and "column 'gamma'" in message and "…(5000 bytes)" in message, message
    assert cell not in message


# --- every command that reads a scene: one bad value, exit 2, one line ---------------------------------

def command_arguments(command, scene, tmp_path, fmu_path, build_dir):
    out = tmp_path / "out"
    if command == "sweep":
        sweep = tmp_path / "sweep.toml"
        sweep.write_text('[grid]\n"controller.delay_steps" = [1]\n')
        return [scene, sweep, "--fmu", fmu_path, "--out", out, "--serial", "--quiet"]
    if command == "linearize":
        return ["--scene", scene, "--fmu", fmu_path, "--build-dir", build_dir, "--out", out / "model.npz"]
    if command == "freqresp":
        return ["open-loop", "--scene", scene, "--fmu", fmu_path, "--out", out, "--serial"]
    if command == "system":
        return [scene, "--build-dir", build_dir, "--out", out]
    if command == "report":
        comparison = tmp_path / "comparison.toml"
        comparison.write_text(f'scene = "{scene.name}"\n[grades.ideal]\n')
        return [comparison, "--fmu", fmu_path, "--out", out, "--quiet"]
    if command == "bench":
        return [scene, "--fmu", fmu_path, "--out", out / "bench.json"]
    return [scene, "--fmu", fmu_path, "--out", out, "--quiet"]


@pytest.mark.parametrize("command", ["run", "sweep", "linearize", "freqresp", "system", "bench", "report"])
def test_every_command_refuses_a_bad_scene_value_in_one_line(tmp_path, fmu_path, build_dir, command):
    path = write_scene(tmp_path, with_table("initial", "beta = 30"))
    done = gimbal2axis(command, *command_arguments(command, path, tmp_path, fmu_path, build_dir), cwd=tmp_path)
    assert_one_line_error(done, command, str(path), "initial.beta = 30 rad", "beta_deg = 30")


# --- sweeps take the angle rule too --------------------------------------------------------------------

def test_a_sweep_of_an_angle_in_degrees_replaces_the_scenes_angle(tmp_path):
    from gimbal2axis.sweep.spec import apply_case

    scene = load_quietly(write_scene(tmp_path, with_table("initial", "beta = 0.5")))
    swept = apply_case(scene, {"initial.beta_deg": ("initial", ["beta_deg"])}, {"initial.beta_deg": 10.0})
    assert swept.initial == {"beta": math.radians(10.0)}
    with pytest.raises(SceneError, match=r"initial.beta_deg = 200 deg is beyond ±180 deg"):
        apply_case(scene, {"initial.beta_deg": ("initial", ["beta_deg"])}, {"initial.beta_deg": 200.0})


# --- sweep files: refused by key, before any case ------------------------------------------------------

SWEEP_REFUSALS = {
    "nan_stop_time": ('stop_time = nan\n[grid]\n"body2.m" = [1.0]\n', "'stop_time' must be a finite number >= 0, got nan"),
    "zero_stop_time": ('stop_time = 0\n[grid]\n"body2.m" = [1.0]\n', "'stop_time' must be positive"),
    "string_metrics_from": ('metrics_from_s = "1"\n[grid]\n"body2.m" = [1.0]\n',
                            "'metrics_from_s' must be a finite number >= 0, got '1'"),
    "nan_linspace": ('[grid]\n"body2.m" = { linspace = [nan, 1.0, 2] }\n',
                     "[grid] 'body2.m': linspace: nan is not a finite number"),
    "string_uniform": ('[random]\n"body2.m" = { uniform = ["a", 1.0] }\n',
                       "[random] 'body2.m': uniform: 'a' is not a finite number"),
    "negative_std": ('[random]\n"body2.m" = { normal = [1.0, -0.1] }\n', "needs std >= 0"),
    "top_level_typo": ('stop_tme = 1.0\n[grid]\n"body2.m" = [1.0]\n', "did you mean 'stop_time'"),
}


@pytest.mark.parametrize("text, fragment", SWEEP_REFUSALS.values(), ids=SWEEP_REFUSALS.keys())
def test_a_wrong_sweep_value_is_refused_naming_the_sweep_file(tmp_path, text, fragment):
    from gimbal2axis.sweep.spec import SweepError, load_sweep

    path = tmp_path / "sweep.toml"
    path.write_text(text)
    with pytest.raises(SweepError) as caught:
        load_sweep(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: ") and fragment in message, message


def test_a_wrong_sweep_value_stops_the_sweep_command_in_one_line(tmp_path, fmu_path):
    scene = write_scene(tmp_path, QUIET)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(SWEEP_REFUSALS["nan_stop_time"][0])
    done = gimbal2axis("sweep", scene, sweep, "--fmu", fmu_path, "--out", tmp_path / "out", "--serial", "--quiet",
                       cwd=tmp_path)
    assert_one_line_error(done, "sweep", str(sweep), "'stop_time' must be a finite number >= 0, got nan")
