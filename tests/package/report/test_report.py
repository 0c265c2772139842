"""gimbal2axis report: a comparison file's cases, the page it writes, and its refusals."""
import csv
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.report import load_comparison, run_comparison, write_page
from gimbal2axis.report.comparison import run_metrics, table_rows

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]
EXAMPLE = REPO / "reports" / "gyro_grades_and_schemes.toml"


def comparison_file(tmp_path, body: str) -> pathlib.Path:
    path = tmp_path / "compare.toml"
    path.write_text(f'scene = "{REPO / "scenes" / "ship_stabilization.toml"}"\n' + body)
    return path


GRADES = '''
stop_time = 2.0
repeats = 2
[sensors]
seed = 4
[analysis]
bands = { sea = [0.0, 1.0], rest = [1.0, 500.0] }
[grades.good]
angle_random_walk_deg_rt_h = 0.01
[grades.poor]
label = "poor gyro"
angle_random_walk_deg_rt_h = 2.0
bandwidth_hz = 30.0
'''


def test_every_grade_runs_under_every_scheme_with_the_same_sea_and_seed(tmp_path, fmu_path):
    comparison = load_comparison(comparison_file(tmp_path, GRADES))
    assert [(c.grade, c.scheme) for c in comparison.cases] == [
        ("good", "direct"), ("good", "indirect"), ("poor", "direct"), ("poor", "indirect")]
    assert comparison.cases[2].name == "poor gyro, direct"
    with FMU(fmu_path) as fmu:
        results = run_comparison(comparison, fmu, progress=False)
        # a case is the scene with its sensors: the same run as the scene runner gives it
        alone = run(comparison.cases[3].scene, fmu, stop_time=2.0)
        second = run(comparison.cases[3].scene.with_changes(
            sensors_spec={**comparison.cases[3].scene.sensors_spec, "seed": 5}), fmu, stop_time=2.0)
    assert np.array_equal(alone.signals["los_error"], results[3][1][0].signals["los_error"])
    assert np.array_equal(second.signals["los_error"], results[3][1][1].signals["los_error"])   # seed 4 + 1
    assert not np.array_equal(second.signals["los_error"], alone.signals["los_error"])
    for _, runs in results:   # the same sea in every case and run
        for result in runs:
            assert np.array_equal(result.signals["base.gamma"], results[0][1][0].signals["base.gamma"])
    rows = table_rows(results)
    for row, (_, runs) in zip(rows, results):
        rms = [result.los_metrics()["rms"] * 1e3 for result in runs]
        assert row["runs"] == 2 and row["los_rms_mrad"] == pytest.approx(np.mean(rms))
        assert row["los_rms_spread_mrad"] == pytest.approx(np.std(rms, ddof=1))
    for _, runs in results:   # per run the bands tile the spectrum: they add in quadrature to the axes' deviations
        for m in (run_metrics(result) for result in runs):
            assert np.hypot(m["band_sea_mrad"], m["band_rest_mrad"]) == pytest.approx(
                np.hypot(m["los_error_xel_std_mrad"], m["los_error_el_std_mrad"]), rel=1e-9)
    assert rows[2]["los_rms_mrad"] != rows[0]["los_rms_mrad"]   # the grade changes the run
    paths = write_page(comparison, results, rows, tmp_path / "out")
    page = paths["html"].read_text()
    assert "poor gyro, indirect" in page and "data:image/png;base64," in page
    with open(paths["csv"]) as f:
        assert [r["case"] for r in csv.DictReader(f)] == [c.name for c in comparison.cases]
    assert paths["png"].stat().st_size > 10_000


@pytest.mark.parametrize("body, message", [
    ("[grades.a]\nangle_random_walk = 1.0\n", "[grades.a]: unknown key(s) ['angle_random_walk']"),
    ("schemes = ['inertial']\n[grades.a]\n", "schemes must be a non-empty list of 'direct', 'indirect'"),
    ("[sensors]\nstabilization = 'direct'\n[grades.a]\n", "[sensors] must be a table of the sensors shared"),
    ("stop_time = 100.0\n[grades.a]\n", "stop_time 100 is after the scene's (60 s)"),
    ("stop_time = 0.0015\n[grades.a]\n", "not a whole number of the scene's steps"),
    ("", "needs scene ="),
    ("repeats = 0\n[grades.a]\n", "repeats must be an integer in [1, 100]"),
    ("colour = 'red'\n[grades.a]\n", "unknown key(s) ['colour']"),
])
def test_a_wrong_comparison_file_is_refused_naming_the_file_and_the_key(tmp_path, body, message):
    path = comparison_file(tmp_path, body)
    with pytest.raises(SceneError) as refused:
        load_comparison(path)
    assert str(refused.value).startswith(f"{path}: ") and message in str(refused.value)


def test_the_command_refuses_in_one_line_and_the_example_file_loads(tmp_path):
    path = comparison_file(tmp_path, "[grades.a]\ndelay_samples = 99\n")
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "report", str(path), "--out", str(tmp_path)],
                          capture_output=True, text=True)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and "grades.a.delay_samples must be an integer in [0, 16]" in done.stderr
    example = load_comparison(EXAMPLE)
    assert len(example.cases) == 6 and example.repeats == 5 and example.scene.target_spec is not None


def test_the_table_in_the_sensors_page_is_what_the_example_comparison_gives(fmu_path):
    """docs/sensors.md quotes the example's table: it must be what the command computes."""
    documented = {}
    for line in (REPO / "docs" / "sensors.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 8 and cells[0].endswith(("direct", "indirect")):
            documented[cells[0]] = cells[1:]
    example = load_comparison(EXAMPLE)
    assert sorted(documented) == sorted(case.name for case in example.cases)
    with FMU(fmu_path) as fmu:
        rows = table_rows(run_comparison(example, fmu, progress=False))
    for row in rows:
        computed = [row["los_rms_mrad"], row["los_rms_spread_mrad"], row["los_error_xel_std_mrad"],
                    row["los_error_el_std_mrad"],
                    row["band_sea_mrad"], row["band_loop_mrad"], row["band_high_mrad"]]
        assert documented[row["case"]] == [f"{value:.4g}" for value in computed], row["case"]
