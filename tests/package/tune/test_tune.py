"""gimbal2axis tune: the tuner finds a known optimum through the whole machinery (the FMU, the sweep
engine's worker, the tables, the seeded study), respects its constraints, resumes an interrupted tuning
to the same result, and refuses bad tuning files in one line (exit status 2)."""
import pathlib
import subprocess
import sys
import textwrap

import pytest

from gimbal2axis.tune import engine
from gimbal2axis.tune.spec import TuneError, load_tuning

pytestmark = pytest.mark.dask_workers

ROOT = pathlib.Path(__file__).resolve().parents[3]
COMMAND = [sys.executable, "-m", "gimbal2axis"]

# A fixed base and a PI(+gyro) loop holding constant set points: the LOS error is the angle between where
# the set points point and the target, so the LOS RMS is least with the set points on the target's angles
# (az 30 deg, el 5 deg: on a level base the gimbal's angles are the target's).
KNOWN_OPTIMUM_SCENE = """\
name = "known_optimum"
stop_time = 1.0
step_size = 1e-3
[fidelity]
"gear1.model" = 1
"gear2.model" = 1
dry_friction = false
"base.fixed" = true
[base_motion]
type = "fixed"
[target]
azimuth_deg = 30.0
elevation_deg = 5.0
[controller]
type = "pid"
delay_steps = 1
azimuth = { kp = 400.0, ki = 8000.0, k_gyro = 8.0, reference = { type = "constant", value_deg = 25.0 } }
elevation = { kp = 400.0, ki = 8000.0, k_gyro = 8.0, reference = { type = "constant", value_deg = 2.0 } }
[initial]
alpha_deg = 25.0
beta_deg = 2.0
[requirements]
from_s = 0.6
"""

KNOWN_OPTIMUM_TUNING = """\
seed = {seed}
[parameters]
"controller.azimuth.reference.value_deg" = {{ bounds = [20.0, 40.0] }}
"controller.elevation.reference.value_deg" = {{ bounds = [0.0, 12.0] }}
{extra}
[optimizer]
sampler = "{sampler}"
trials = {trials}
batch = 6
"""


def write(path: pathlib.Path, text: str) -> pathlib.Path:
    path.write_text(textwrap.dedent(text))
    return path


def tune(tmp_path, fmu_path, tuning_text: str, out="out", options=engine.TuneOptions(serial=True, progress=False),
         evaluator_class=None, name="tuning.toml"):
    scene = write(tmp_path / "known_optimum.toml", KNOWN_OPTIMUM_SCENE)
    tuning = write(tmp_path / name, tuning_text)
    problem = engine.plan(scene, tuning, fmu_path, tmp_path / out)
    try:
        evaluator = (evaluator_class or engine.Evaluator)(problem, options)
        try:
            return engine.run_tuning(problem, options, evaluator)
        finally:
            evaluator.close()
    finally:
        problem.fmu.close()


@pytest.mark.parametrize("sampler", ["cmaes", "tpe"])
def test_the_tuner_finds_the_known_optimum(tmp_path, fmu_path, sampler):
    result = tune(tmp_path, fmu_path, KNOWN_OPTIMUM_TUNING.format(seed=5, sampler=sampler, trials=42, extra=""))
    best = result.best
    assert best is not None
    az, el = best["controller.azimuth.reference.value_deg"], best["controller.elevation.reference.value_deg"]
    assert abs(az - 30.0) < 0.5 and abs(el - 5.0) < 0.5, (az, el)
    # far better than the scene's own set points (5 deg and 3 deg off): ~100 mrad there
    assert best["objective_mrad"] < 10.0
    assert len(result.trials) == 42 and result.evaluations_run == 42


def test_the_constraint_keeps_the_best_away_from_the_unconstrained_optimum(tmp_path, fmu_path):
    """The slew from the start angles (25, 2) deg to the set points saturates the voltage (kp = 400 V/rad:
    24 V at 3.4 deg of error) when the set points are far: no saturation allowed keeps them near the start,
    and the returned best respects it, at a cost in LOS RMS."""
    extra = "[constraints]\nvoltage_saturation_max_s = 0.0\n"
    result = tune(tmp_path, fmu_path, KNOWN_OPTIMUM_TUNING.format(seed=5, sampler="cmaes", trials=42, extra=extra))
    assert result.best is not None
    assert result.best["worst_u_sat_s"] == 0.0
    assert result.best["violation_voltage_saturation"] <= 0
    # near the unconstrained optimum the slew saturates: not feasible here
    unconstrained = [r for r in result.trials if abs(r["controller.azimuth.reference.value_deg"] - 30) < 1
                     and abs(r["controller.elevation.reference.value_deg"] - 5) < 1]
    assert all(not r["feasible"] for r in unconstrained)
    assert any(not r["feasible"] for r in result.trials)   # the constraint did bind
    assert result.best["objective_mrad"] > 20.0             # 5.8 deg from the target cannot all be slewed
    feasible = [r["objective_mrad"] for r in result.trials if r["feasible"]]
    assert result.best["objective_mrad"] == min(feasible)


class Interrupting(engine.Evaluator):
    """Ctrl-C after a number of evaluations, in the middle of a batch."""
    after = 14

    def _record(self, *args, **kwargs):
        if self.ran == self.after:
            raise KeyboardInterrupt
        super()._record(*args, **kwargs)


def test_an_interrupted_tuning_resumed_ends_as_an_uninterrupted_one(tmp_path, fmu_path):
    text = KNOWN_OPTIMUM_TUNING.format(seed=11, sampler="cmaes", trials=24, extra="[robustness]\ndraws = 2\n"
                                                                         "[robustness.draw]\n"
                                                                         "\"controller.azimuth.kp\" = { uniform = [300.0, 500.0] }\n")
    whole = tune(tmp_path, fmu_path, text, out="whole")
    with pytest.raises(KeyboardInterrupt):
        tune(tmp_path, fmu_path, text, out="resumed", evaluator_class=Interrupting)
    from gimbal2axis.sweep.table import read_rows
    kept = read_rows(tmp_path / "resumed" / "tuning__known_optimum.parquet")
    assert len(kept) == Interrupting.after   # every evaluation finished before the interruption was stored
    resumed = tune(tmp_path, fmu_path, text, out="resumed")
    assert resumed.evaluations_reused == Interrupting.after
    assert resumed.evaluations_run == whole.evaluations_run - Interrupting.after
    columns = ["controller.azimuth.reference.value_deg", "controller.elevation.reference.value_deg",
               "objective_mrad", "value"]
    assert [[r[c] for c in columns] for r in resumed.trials] == [[r[c] for c in columns] for r in whole.trials]
    assert resumed.best["trial"] == whole.best["trial"]
    # and a third run takes everything from the table
    again = tune(tmp_path, fmu_path, text, out="resumed")
    assert again.evaluations_run == 0 and again.best["objective_mrad"] == whole.best["objective_mrad"]


def test_another_seed_gives_another_study(tmp_path, fmu_path):
    """The seed is what makes it repeatable: a different one asks for different candidates."""
    a = tune(tmp_path, fmu_path, KNOWN_OPTIMUM_TUNING.format(seed=1, sampler="tpe", trials=6, extra=""), out="a")
    b = tune(tmp_path, fmu_path, KNOWN_OPTIMUM_TUNING.format(seed=2, sampler="tpe", trials=6, extra=""), out="b")
    name = "controller.azimuth.reference.value_deg"
    assert [r[name] for r in a.trials] != [r[name] for r in b.trials]


def test_the_robustness_set_is_the_same_for_every_candidate(tmp_path):
    path = write(tmp_path / "t.toml", """\
        seed = 4
        [parameters]
        "controller.azimuth.kp" = { bounds = [100.0, 1000.0], scale = "log" }
        [robustness]
        seeds = [3, 4]
        sea_states = [{ "base_motion.roll.significant_amplitude_deg" = 3.0 }, { "base_motion.roll.significant_amplitude_deg" = 6.0 }]
        draws = 3
        [robustness.draw]
        "body2.m" = { normal = [2.0, 0.1] }
        """)
    tuning = load_tuning(path)
    scenarios = tuning.robustness.scenarios()
    assert len(scenarios) == 2 * 2 * 3
    assert scenarios == load_tuning(path).robustness.scenarios()   # common random numbers: the same draws
    masses = sorted({s["body2.m"] for s in scenarios})
    assert len(masses) == 3 and all(1.5 < m < 2.5 for m in masses)
    assert {s["base_motion.seed"] for s in scenarios} == {3, 4}


BAD_FILES = [
    ("[optimiser]\nsampler = 'tpe'\n", ["unknown key 'optimiser'", "did you mean 'optimizer'"]),
    ("[optimizer]\nsampler = 'cma'\n", ["sampler", "did you mean 'cmaes'"]),
    ("[objective]\nmetric = 'los_rsm'\n", ["metric", "did you mean 'los_rms'"]),
    ("[constraints]\non_target_min_fraction = 1.5\n", ["on_target_min_fraction", "at most 1"]),
    ("[constraints]\npeak_current_fractoin = 0.5\n", ["peak_current_fractoin", "did you mean 'peak_current_fraction'"]),
    ("[objective]\nmetric = 'band_rms'\n", ["band = [f_lo, f_hi]"]),
]
GOOD_PARAMETER = '[parameters]\n"controller.azimuth.kp" = { bounds = [100.0, 1000.0], scale = "log" }\n'


def refused(tmp_path, tuning_text: str, scene="scenes/ship_stabilization.toml"):
    path = tmp_path / "bad.toml"
    path.write_text(tuning_text)
    done = subprocess.run([*COMMAND, "tune", scene, str(path), "--serial", "--out", str(tmp_path / "out"), "--quiet"],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert done.returncode == 2, (done.returncode, done.stderr)
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("gimbal2axis tune: error: "), lines[0]
    assert done.stdout == ""
    return lines[0]


@pytest.mark.parametrize("text, named", BAD_FILES)
def test_a_bad_tuning_file_is_refused_in_one_line_naming_the_key(tmp_path, text, named):
    """Checked by the loader (fast), and once through the command for the exit status and the one line."""
    path = tmp_path / "bad.toml"
    path.write_text(GOOD_PARAMETER + text)
    with pytest.raises(TuneError) as refusal:
        load_tuning(path)
    message = str(refusal.value)
    assert "\n" not in message
    for fragment in named:
        assert fragment in message, (fragment, message)


@pytest.mark.parametrize("text, named", [
    ('[parameters]\n"controller.azimuth.kp" = { bounds = [1000.0, 100.0] }\n', ["controller.azimuth.kp", "below"]),
    ('[parameters]\n"controller.azimuth.kpp" = { bounds = [100.0, 1000.0] }\n',
     ["controller.azimuth.kpp", "did you mean", "'controller.azimuth.kp'"]),
    ('[parameters]\n"gear1.k_ss" = { bounds = [100.0, 1000.0] }\n', ["gear1.k_ss", "did you mean", "'gear1.k_s'"]),
    (GOOD_PARAMETER + "[robustness]\nsede = [1]\n", ["sede", "did you mean 'seed'"]),
])
def test_the_command_refuses_a_bad_tuning_file_with_status_2(tmp_path, text, named):
    line = refused(tmp_path, text)
    for fragment in named:
        assert fragment in line, (fragment, line)


@pytest.mark.parametrize("text, named", [
    ("[objective]\nmetric = 'tracking_rms'\n", ["tracking_rms", "needs a moving target", "fixed direction"]),
    ("[constraints]\non_target_min_fraction = 0.9\n", ["on_target_min_fraction", "needs a moving target"]),
])
def test_tracking_figures_are_refused_for_a_fixed_direction(tmp_path, text, named):
    line = refused(tmp_path, GOOD_PARAMETER + text)
    for fragment in named:
        assert fragment in line, (fragment, line)


def test_a_tracking_tuning_minimizes_the_error_to_the_moving_target_under_a_time_on_target_floor(tmp_path, fmu_path):
    """The flyby scene with its aircraft 200 m to the side at 0.5 s (an azimuth rate near 30 deg/s), its
    azimuth feed-forward tuned: without it (k_ff = 0) the gimbal lags the aircraft, near the motor's
    back-EMF constant times the gear ratio it follows. The objective is the error to where the aircraft
    is; the floor on the time on target is judged on the worst run; the evaluations carry the sweep's
    tracking columns."""
    text = (ROOT / "scenes" / "track_flyby_keyhole.toml").read_text()
    for old, new in (('name = "track_flyby_keyhole"', 'name = "scene"'),
                     ("closest_approach_m = 10.0", "closest_approach_m = 200.0"),
                     ("closest_approach_s = 15.0", "closest_approach_s = 0.5")):
        assert old in text
        text = text.replace(old, new)
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    tuning = write(tmp_path / "track.toml", """\
        seed = 5
        stop_time = 0.8
        metrics_from_s = 0.2
        [parameters]
        "controller.azimuth.k_ff" = { bounds = [0.0, 8.0] }
        [objective]
        metric = "tracking_rms"
        [constraints]
        on_target_min_fraction = 0.5
        [optimizer]
        sampler = "cmaes"
        trials = 12
        batch = 4
        """)
    options = engine.TuneOptions(serial=True, progress=False)
    problem = engine.plan(scene, tuning, fmu_path, tmp_path / "out")
    try:
        evaluator = engine.Evaluator(problem, options)
        try:
            outcome = engine.run_tuning(problem, options, evaluator)
        finally:
            evaluator.close()
    finally:
        problem.fmu.close()
    from gimbal2axis.sweep.table import read_rows
    evaluations = read_rows(tmp_path / "out" / "track__scene.parquet")
    assert len(evaluations) == 12
    assert all(0.0 <= r["on_target_fraction"] <= 1.0 and r["time_lost_s"] >= 0.0 for r in evaluations)
    trials = outcome.trials
    for trial in trials:   # the floor, judged on the worst run of the set
        assert trial["feasible"] == (trial["worst_on_target_fraction"] >= 0.5 and trial["failed_runs"] == 0)
    # the objective is the run's error to where the aircraft is: the best's gain run directly agrees
    best = outcome.best
    gain = best["controller.azimuth.k_ff"]
    scene.write_text(text.replace("k_ff = 4.8", f"k_ff = {gain!r}", 1))
    from gimbal2axis import FMU, load_scene, run
    with FMU(fmu_path) as loaded:
        direct = run(load_scene(scene), loaded, stop_time=0.8)
    assert direct.scene.moving_target is not None
    assert best["objective_mrad"] == pytest.approx(direct.los_metrics(from_s=0.2)["rms"] * 1e3, rel=1e-12)
    assert best["objective_mrad"] == min(t["objective_mrad"] for t in trials if t["feasible"])


def test_the_command_line_imports_nothing_heavy_for_tune_help():
    probe = ("import sys\nfrom gimbal2axis.cli.main import build_parser\n"
             "try:\n    build_parser().parse_args(['tune', '--help'])\nexcept SystemExit:\n    pass\n"
             "print(sorted(m for m in ('numpy', 'scipy', 'optuna', 'dask', 'control', 'matplotlib') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "[]"
    assert "exit status:" in done.stdout and "143" in done.stdout


def test_the_command_on_dask_gives_the_serial_result_and_the_evidence(tmp_path, fmu_path):
    """Through the sweep engine's Dask path (a local cluster, threads: cheap to start), with the report:
    the same trials as a serial tuning, bit for bit, and the report's files, the held-out check included."""
    text = KNOWN_OPTIMUM_TUNING.format(seed=3, sampler="cmaes", trials=12,
                                       extra="[holdout]\ndraws = 2\n[holdout.draw]\n"
                                             "\"controller.azimuth.kp\" = { uniform = [300.0, 500.0] }\n")
    serial = tune(tmp_path, fmu_path, text, out="serial")
    done = subprocess.run([*COMMAND, "tune", str(tmp_path / "known_optimum.toml"), str(tmp_path / "tuning.toml"),
                           "--workers", "1", "--threads", "--out", str(tmp_path / "dask"), "--fmu", str(fmu_path)],
                          capture_output=True, text=True, cwd=ROOT, timeout=180)
    assert done.returncode == 0, done.stderr
    assert "best: trial" in done.stdout and "held out (2 runs)" in done.stdout
    from gimbal2axis.sweep.table import read_rows
    rows = read_rows(tmp_path / "dask" / "tuning__known_optimum_trials.parquet")
    assert [r["value"] for r in rows] == [r["value"] for r in serial.trials]
    evaluations = read_rows(tmp_path / "dask" / "tuning__known_optimum.parquet")
    assert len(evaluations) == 12 + 2 * 2   # the trials, and the best and the scene's own on the held-out set
    assert {r["worker"] for r in evaluations if r["role"] == "tuning"} != {"client"}
    for suffix in ("_report.html", "_convergence.png", "_time_psd.png", "_summary.json"):
        assert (tmp_path / "dask" / f"tuning__known_optimum{suffix}").stat().st_size > 0
    import json
    summary = json.loads((tmp_path / "dask" / "tuning__known_optimum_summary.json").read_text())
    assert set(summary["budget_mrad"]["tuned"]) == {"xel", "el"}
    assert summary["holdout"]["tuned"]["objective_mrad"] < summary["holdout"]["scene's own"]["objective_mrad"]


@pytest.mark.parametrize("arguments, named", [
    (["--no-such-option"], ["--no-such-option", "see gimbal2axis tune --help"]),
    (["--workers", "0"], ["--workers"]),
    (["--trials", "0"], ["--trials"]),
])
def test_bad_options_are_refused_in_one_line(arguments, named):
    done = subprocess.run([*COMMAND, "tune", "a.toml", "b.toml", *arguments], capture_output=True, text=True,
                          cwd=ROOT, timeout=60)
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1, done.stderr
    assert done.stderr.startswith("gimbal2axis tune: error: ")
    for fragment in named:
        assert fragment in done.stderr


def test_ctrl_c_ends_with_130_in_one_line(monkeypatch, capsys):
    import signal

    from gimbal2axis.cli import main as cli_main

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("gimbal2axis.cli.tune.fmu_path", interrupted)
    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        status = cli_main.main(["tune", "a.toml", "b.toml"])
    finally:
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
    captured = capsys.readouterr()
    lines = [line for line in captured.err.splitlines() if line.strip()]
    assert status == 130 and len(lines) == 1 and "interrupted" in lines[0], captured.err
    assert captured.out == ""


def test_the_start_is_trial_0_alone_and_a_weighted_band_objective_reads_the_runs_psd(tmp_path, fmu_path):
    text = """\
        seed = 2
        [parameters]
        "controller.azimuth.reference.value_deg" = { bounds = [20.0, 40.0], start = 25.0 }
        "controller.elevation.reference.value_deg" = { bounds = [0.0, 12.0], start = 2.0 }
        [objective]
        metric = "weighted"
        aggregate = "max"
        terms = [{ metric = "los_rms", weight = 1.0 }, { metric = "band_rms", band = [0.0, 5.0], axis = "xel", weight = 3.0 }]
        [optimizer]
        trials = 7
        batch = 3
        """
    result = tune(tmp_path, fmu_path, text)
    first = result.trials[0]
    assert (first["controller.azimuth.reference.value_deg"], first["controller.elevation.reference.value_deg"]) == (25.0, 2.0)
    assert [r["batch"] for r in result.trials] == [0, 1, 1, 1, 2, 2, 2]
    from gimbal2axis.sweep.table import read_rows
    rows = {r["trial"]: r for r in read_rows(tmp_path / "out" / "tuning__known_optimum.parquet")}
    for trial in result.trials:
        run = rows[trial["trial"]]
        band = run["psd_band_0_5Hz_xel_rms_mrad"]
        # the band of a slow, steady offset: mostly the 0-Hz bin's neighbours, below the LOS RMS (mean included)
        assert 0 < band < run["los_rms_mrad"] * 1.01
        assert trial["objective_mrad"] == pytest.approx(run["los_rms_mrad"] + 3.0 * band, rel=1e-12)
