"""What the scene runner tells its user: one-line errors instead of tracebacks, warnings for scenes
that run but probably not as meant, results named after the scene file, plots that hide no sample,
help texts, and the limit-cycle figure of docs/scenes.md against the script that measures it."""
import math
import pathlib
import re
import runpy
import subprocess
import sys
import warnings

import numpy as np
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.errors import SceneWarning

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]

RUN_SCENE = [sys.executable, "-m", "gimbal2axis", "run"]   # the installed package's command

# a scene that draws no warning: fixed base said twice, an explicit (open-loop) controller
QUIET = """name = "quiet"
stop_time = 0.01
step_size = 1e-3
[fidelity]
"base.fixed" = true
[base_motion]
type = "fixed"
[controller]
type = "none"
"""

RECORDED = """name = "recorded"
stop_time = 0.01
step_size = 1e-3
[base_motion]
type = "recorded"
file = "motion.csv"
[controller]
type = "none"
"""

GOOD_MOTION = "time,gamma\n0,0\n0.005,0.001\n0.01,0.002\n0.015,0.003\n"


def run_cli(*args, cwd):
    done = subprocess.run([*RUN_SCENE, *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300)
    assert "Traceback" not in done.stderr, done.stderr
    return done


def assert_one_line_error(done, *fragments):
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gimbal2axis run: error: "), done.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


def scene_file(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def load_quietly(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_scene(path)
    return scene, [str(w.message) for w in caught if issubclass(w.category, SceneWarning)]


# --- recorded motion files -------------------------------------------------------------------------

@pytest.mark.parametrize("content, fragments", [
    ("time,gamma\n0,0\n0.005,0.001\n0.01,\n0.015,0.003\n", ["line 4", "column 'gamma'", "empty"]),
    ("time,gamma\n0,0\n0.005,0.001\n0.01,0.002\n0.015,abc\n", ["line 5", "column 'gamma'", "'abc'"]),
    ("time,gamma\n0,0\n0.005,0.001\n,0.002\n0.015,0.003\n", ["line 4", "column 'time'", "empty"]),
    ("time;gamma\n0;0\n0,005;0,001\n0,01;0,002\n0,015;0,003\n", ["semicolons", "line 1"]),
], ids=["empty_cell", "non_numeric_cell", "empty_time", "semicolons"])
def test_a_bad_recorded_motion_names_file_line_and_column(tmp_path, fmu_path, content, fragments):
    (tmp_path / "motion.csv").write_text(content)
    path = scene_file(tmp_path, RECORDED)
    done = run_cli(path, "--fmu", fmu_path, "--out", tmp_path / "out", cwd=tmp_path)
    assert_one_line_error(done, "motion.csv", *fragments)
    assert not (tmp_path / "out" / "scene.csv").exists()


def test_recorded_motion_refusals_in_the_library(tmp_path):
    cases = {
        "time,gamma\n0,0\n0.005,0.001\n0.005,0.002\n0.015,0.003\n": r"'time' must increase strictly, but line 4",
        "time,gamma\n0,0\n0.005,0.001,7\n0.01,0.002\n0.015,0.003\n": r"line 3 \(data row 2\) has 3 cells",
        "time,gamma\n0,0\n0.005,inf\n0.01,0.002\n0.015,0.003\n": r"column 'gamma' is 'inf', not a finite number",
        "time,gamma_dot\n0,0\n0.005,0.001\n0.01,0.002\n0.015,0.003\n": r"'gamma_dot' without the angle",
        "time,gamma,roll_deg\n0,0,0\n0.005,0,0\n0.01,0,0\n0.015,0,0\n": r"'gamma' and 'roll_deg' are the same angle",
        "time,gamma,gamma\n0,0,0\n0.005,0,0\n0.01,0,0\n0.015,0,0\n": r"column 'gamma' appears twice",
        "# only a comment\n": r"empty",
    }
    path = scene_file(tmp_path, RECORDED)
    for content, message in cases.items():
        (tmp_path / "motion.csv").write_text(content)
        with pytest.raises(SceneError, match=message):
            load_scene(path)
    (tmp_path / "motion.csv").write_text("# a comment line\n" + GOOD_MOTION.replace("0.001", "0.001  # inline"))
    scene, _ = load_quietly(path)
    np.testing.assert_allclose(scene.base_motion().sample(np.array([0.005]))[0, 2], 0.001)


def test_many_long_unknown_columns_are_quoted_in_part(tmp_path):
    # A header is any text: the message names the first five columns, each cut, and counts the rest.
    names = [f"column_{k:02d}_" + "x" * 200 for k in range(20)]
    rows = "".join(f"{t},0," + ",".join("0" for _ in names) + "\n" for t in (0, 0.005, 0.01, 0.015))
    (tmp_path / "motion.csv").write_text("time,gamma," + ",".join(names) + "\n" + rows)
    with pytest.raises(SceneError) as refused:
        load_scene(scene_file(tmp_path, RECORDED))
    message = str(refused.value)
    assert "column_00_" in message and "column_04_" in message and "column_05_" not in message, message
    quoted = message[message.index("unknown columns"):]
    assert "and 15 more" in quoted and "x" * 41 not in quoted and len(quoted) < 450, message


# --- options -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("value", ["-1", "0", "nan"])
def test_a_stop_time_that_is_not_positive_is_refused_and_keeps_the_results(tmp_path, fmu_path, value):
    path = scene_file(tmp_path, QUIET)
    out = tmp_path / "out"
    out.mkdir()
    (out / "scene.csv").write_text("earlier results\n")
    done = run_cli(path, "--fmu", fmu_path, "--out", out, "--stop-time", value, cwd=tmp_path)
    assert_one_line_error(done, "--stop-time", "positive")
    assert (out / "scene.csv").read_text() == "earlier results\n"
    assert not (out / "scene.png").exists()


@pytest.mark.parametrize("value, fragment", [("0.0015", "not a whole number of steps")])
def test_a_stop_time_the_scene_cannot_take_is_refused(tmp_path, fmu_path, value, fragment):
    done = run_cli(scene_file(tmp_path, QUIET), "--fmu", fmu_path, "--out", tmp_path / "out", "--stop-time", value,
                   cwd=tmp_path)
    assert_one_line_error(done, fragment)


def test_an_unwritable_output_directory_is_named_with_the_reason(tmp_path, fmu_path):
    path = scene_file(tmp_path, QUIET)
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    done = run_cli(path, "--fmu", fmu_path, "--out", a_file, cwd=tmp_path)
    assert_one_line_error(done, str(a_file), "not a directory")
    done = run_cli(path, "--fmu", fmu_path, "--out", a_file / "results", cwd=tmp_path)
    assert_one_line_error(done, str(a_file / "results"), "cannot create the directory", "Not a directory")
    (tmp_path / "out" / "scene.csv").mkdir(parents=True)
    done = run_cli(path, "--fmu", fmu_path, "--out", tmp_path / "out", cwd=tmp_path)
    assert_one_line_error(done, str(tmp_path / "out" / "scene.csv"), "is a directory")


# --- warnings and refusals of scene content ----------------------------------------------------------

PID_TARGET = """name = "pid"
stop_time = 0.01
step_size = 1e-3
[fidelity]
"base.fixed" = true
[base_motion]
type = "fixed"
[target]
azimuth_deg = 1.0
elevation_deg = {elevation}
[controller]
type = "pid"
reference = "target"
[controller.elevation]
kp = {kp}
"""


def test_a_pid_without_an_azimuth_table_runs_with_a_warning_naming_it(tmp_path, fmu_path):
    path = scene_file(tmp_path, PID_TARGET.format(elevation=0.0, kp=30.0))
    done = run_cli(path, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gimbal2axis run: warning: "), done.stderr
    assert "[controller.azimuth]" in lines[0] and "0 V" in lines[0]
    assert (tmp_path / "out" / "scene.csv").exists()


@pytest.mark.parametrize("edit, key", [
    (lambda s: s.replace('[controller]\ntype = "none"\n', ""), "no [controller]"),
    (lambda s: s.replace('[base_motion]\ntype = "fixed"\n', "").replace('"base.fixed" = true', '"base.fixed" = false'),
     "no [base_motion] while [fidelity] base.fixed = false"),
    (lambda s: s.replace('[base_motion]\ntype = "fixed"\n', "").replace('"base.fixed" = true', ""),
     "no [base_motion] while [fidelity] base.fixed is not set"),
    (lambda s: s.replace('type = "none"', 'type = "pid"\nreference = { type = "constant" }\n'
                                           '[controller.azimuth]\nkp = 1.0\n[controller.elevation]\nreference = '
                                           '{ type = "constant" }'),
     "[controller.elevation] has no nonzero gain"),
    (lambda s: s.replace('type = "none"', 'type = "state_feedback"\nreference = { type = "constant" }\n'
                                           'K = [[1.0, 0.0, 0.1, 0.0], [0.0, 0.0, 0.0, 0.0]]'),
     "K[1] and ki[1] are all zero: the elevation motor (u_R2) gets 0 V"),
], ids=["no_controller", "no_base_motion_base_not_fixed", "no_base_motion_default", "pid_axis_without_gains",
        "state_feedback_zero_row"])
def test_scenes_that_run_but_probably_not_as_meant_warn_naming_the_key(tmp_path, edit, key):
    scene, messages = load_quietly(scene_file(tmp_path, edit(QUIET)))
    assert len(messages) == 1 and key in messages[0], messages
    assert str(scene.path) in messages[0]
    assert [key in m for m in scene.warnings] == [True]


def test_the_shipped_scenes_load_without_warnings():
    for path in sorted((REPO / "scenes").glob("*.toml")):
        scene, messages = load_quietly(path)
        assert messages == [] and scene.warnings == [], (path, messages)


def test_a_target_elevation_outside_the_range_is_refused_on_the_command_line(tmp_path, fmu_path):
    path = scene_file(tmp_path, PID_TARGET.format(elevation=100.0, kp=30.0))
    done = run_cli(path, "--fmu", fmu_path, "--out", tmp_path / "out", cwd=tmp_path)
    assert_one_line_error(done, "target.elevation_deg = 100", "[-90, 90]")


@pytest.mark.parametrize("edit, message", [
    (lambda s: s + '[parameters]\n"base.fixed" = true\n', r"'base.fixed' set in both \[fidelity\] and \[parameters\]"),
    (lambda s: s.replace("elevation_deg = 0.0", "elevation_deg = -90.5"), r"target.elevation_deg = -90.5 is outside"),
    (lambda s: s.replace("kp = 30.0", "kp = -30.0"), r"controller.elevation.kp = -30 is negative"),
    (lambda s: s.replace("kp = 30.0", "kp = 30.0\nk_gyro = -1.0"), r"controller.elevation.k_gyro = -1 is negative"),
    (lambda s: s.replace("kp = 30.0", "kp = 30.0\nd_filter_s = -0.01"), r"controller.elevation.d_filter_s = -0.01"),
    (lambda s: s.replace('type = "pid"', 'type = "state_feedback"\nK = [[1, 0, 0.1, 0], [0, 1, 0, -0.1]]')
     .replace("[controller.elevation]\nkp = 30.0\n", ""), r"controller.K\[1\]\[3\] = -0.1 .*is negative"),
    (lambda s: s.replace('type = "pid"', 'type = "state_feedback"\nK = [[1, 0, 0.1, 0], [0, 1, 0, 0.1]]\n'
                                         'ki = [1.0, -2.0]')
     .replace("[controller.elevation]\nkp = 30.0\n", ""), r"controller.ki\[1\] = -2 .*is negative"),
], ids=["same_name_in_fidelity_and_parameters", "elevation_below_range", "negative_kp", "negative_k_gyro",
        "negative_filter", "negative_state_feedback_rate_gain", "negative_state_feedback_ki"])
def test_scenes_that_cannot_be_right_are_refused_naming_the_key(tmp_path, edit, message):
    with pytest.raises(SceneError, match=message):
        load_scene(scene_file(tmp_path, edit(PID_TARGET.format(elevation=0.0, kp=30.0))))


@pytest.mark.parametrize("value, fragments", [
    ("5", ["'gear1.model' = 5 is none of its values", "0 (rigid), 1 (compliant), 2 (backlash)"]),
    ('"rigid"', ["fidelity.gear1.model must be a finite number or true/false", "got 'rigid'", "integer value"]),
], ids=["no_item", "item_name"])
def test_a_structural_selector_is_one_of_its_enumeration_values(tmp_path, fmu_path, value, fragments):
    path = scene_file(tmp_path, QUIET.replace('[fidelity]\n', f'[fidelity]\n"gear1.model" = {value}\n'))
    done = run_cli(path, "--fmu", fmu_path, "--out", tmp_path / "out", cwd=tmp_path)
    assert_one_line_error(done, *fragments)


def test_the_edges_of_the_elevation_range_are_accepted(tmp_path):
    for elevation in (-90.0, 90.0):
        load_quietly(scene_file(tmp_path, PID_TARGET.format(elevation=elevation, kp=30.0)))


# --- result names --------------------------------------------------------------------------------------

def test_results_are_named_after_the_scene_file_not_its_name(tmp_path, fmu_path):
    copy = tmp_path / "my_copy.toml"
    copy.write_text((REPO / "scenes" / "free_swing.toml").read_text())
    scene, _ = load_quietly(copy)
    assert (scene.name, scene.title) == ("my_copy", "free_swing")
    out = tmp_path / "out"
    done = run_cli(copy, "--fmu", fmu_path, "--out", out, "--stop-time", "0.01", cwd=tmp_path)   # the "wrote" line
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in out.iterdir()) == ["my_copy.csv", "my_copy.parquet", "my_copy.png",
                                                      "my_copy_run.json"]
    assert f"wrote {out / 'my_copy.csv'}" in done.stdout


# --- plots -----------------------------------------------------------------------------------------------

def los_axes(fig):
    [ax] = [ax for ax in fig.axes if ax.get_ylabel().startswith("line-of-sight error")]
    [line] = [line for line in ax.get_lines() if line.get_label() == "LOS error"]
    return ax, line


def test_the_line_of_sight_panel_draws_every_sample_and_its_rms_where_it_belongs(fmu_path):
    from gimbal2axis.master.plotting import figure

    scene = load_scene(REPO / "scenes" / "pointing_step.toml")
    with FMU(fmu_path) as fmu:
        result = run(scene, fmu, stop_time=1.5)
    error = result.signals["los_error"] * 1e3
    fig = figure(result)
    ax, line = los_axes(fig)
    np.testing.assert_array_equal(line.get_ydata(), error)          # nothing clipped or floored
    low, high = ax.get_ylim()
    assert ax.get_yscale() == "log" and low <= error.min() and high >= error.max()
    assert high < 10 * error.max() and low > error.min() / 10   # ... and the limits come from the data
    window = result.signals["time"] >= 1.2 - 1e-12
    rms = math.sqrt(np.mean(error[window] ** 2))
    assert error[window].min() < rms < error[window].max()           # the settled error is spread around its RMS
    [(x0, y0), (x1, y1)] = next(c for c in ax.collections if "RMS" in c.get_label()).get_segments()[0]
    assert y0 == y1 == pytest.approx(rms) and x0 == pytest.approx(1.2) and x1 == pytest.approx(1.5)


def test_an_error_of_zero_is_drawn_at_zero_not_dropped(fmu_path):
    from gimbal2axis.master.plotting import ROUND_OFF_MRAD, figure

    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")   # starts on target: error 0 at t = 0
    with FMU(fmu_path) as fmu:
        result = run(scene, fmu, stop_time=0.3)
    error = result.signals["los_error"] * 1e3
    assert error[0] < ROUND_OFF_MRAD
    ax, line = los_axes(figure(result))
    np.testing.assert_array_equal(line.get_ydata(), error)
    assert ax.get_yscale() == "symlog" and ax.get_ylim()[0] <= 0.0 and ax.get_ylim()[1] >= error.max()


# --- help texts and docs ------------------------------------------------------------------------------

def test_help_is_whole_sentences_without_internal_jargon():
    done = subprocess.run([*RUN_SCENE, "--help"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0
    text = " ".join(done.stdout.split())
    assert "real-time factor, events, requirements)." in text                      # the description is whole
    for option in ("--fmu FMU", "--out OUT", "--stop-time T", "--check", "--quiet"):
        entry = re.search(re.escape(option) + r" +([^-].*?)(?= --|\Z)", text)
        assert entry and len(entry.group(1)) > 10, option                          # every option explains itself
    assert "scene the scene file" in text
    assert not re.search(r"issue \d|seed's|section \d", text)


def test_the_scenes_page_speaks_to_users():
    page = (REPO / "docs" / "scenes.md").read_text()
    section = page[page.index("## Scenes"):page.index("## Your own controller")]
    assert not re.search(r"issue \d|seed's|section \d", section)
    assert "named after the scene file" in section


def test_the_documented_limit_cycle_frequency_is_what_the_script_prints(fmu_path):
    script = runpy.run_path(str(REPO / "scripts" / "limit_cycle_frequency.py"))   # its functions, not its main
    measured = script["measure"](REPO / "scenes" / "backlash_limit_cycle.toml", fmu_path)
    printed = script["describe"](measured)
    frequency = re.search(r"oscillates at (\d+\.\d) Hz", printed).group(1)
    assert abs(measured["spectral_peak"] - measured["frequency"]) <= measured["resolution"]
    page = (REPO / "docs" / "scenes.md").read_text()
    row = next(line for line in page.splitlines() if line.startswith("| `backlash_limit_cycle`"))
    assert f"{frequency} Hz limit cycle (`scripts/limit_cycle_frequency.py`)" in row
    assert f"oscillates at {frequency} Hz" in page


# --- [imbalance] ----------------------------------------------------------------------------------------

IMBALANCE = '[imbalance]\npayload_offset_mm = [1.5, -20, 4]\nazimuth_housing_offset_mm = [0, 2, -80]\n'


def test_imbalance_in_millimetres_becomes_the_centre_of_mass_parameters_in_metres(tmp_path, fmu_path):
    from gimbal2axis.scene.scene import check_against_fmu

    scene, found = load_quietly(scene_file(tmp_path, QUIET + IMBALANCE))
    assert not found
    expected = {"body2.d_bd[1]": 1.5e-3, "body2.d_bd[2]": -20e-3, "body2.d_bd[3]": 4e-3,
                "body1.d_bc[1]": 0.0, "body1.d_bc[2]": 2e-3, "body1.d_bc[3]": -80e-3}
    assert scene.parameters == pytest.approx(expected, rel=1e-15)
    check_against_fmu(scene, FMU(fmu_path))  # the names are the FMU's own


@pytest.mark.parametrize("table, message", [
    ('[parameters]\n"body2.d_bd[2]" = 0.02\n' + IMBALANCE,
     r"imbalance.payload_offset_mm and \[parameters\] 'body2.d_bd\[2\]' both set body2.d_bd\[2\]"),
    ('[parameters]\n"body1.d_bc[3]" = -0.05\n' + IMBALANCE,
     r"imbalance.azimuth_housing_offset_mm and \[parameters\] 'body1.d_bc\[3\]' both set"),
    ('[imbalance]\npayload_offset_mm = [1, 2]\n', r"imbalance.payload_offset_mm must be \[x, y, z\] in mm"),
    ('[imbalance]\npayload_offset_mm = [1, "2", 3]\n', r"imbalance.payload_offset_mm\[1\] must be a finite number"),
    ('[imbalance]\npayload_offset = [1, 2, 3]\n', r"\[imbalance\]: unknown key\(s\) \['payload_offset'\]"),
], ids=["payload_twice", "housing_twice", "two_components", "not_a_number", "unknown_key"])
def test_a_wrong_imbalance_is_refused_in_one_line_naming_it(tmp_path, table, message):
    with pytest.raises(SceneError, match=message) as refused:
        load_scene(scene_file(tmp_path, QUIET + table))
    assert "\n" not in str(refused.value)
