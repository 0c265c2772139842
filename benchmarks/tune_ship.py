"""The worked example of docs/tuning.md, measured: `gimbal2axis tune` of the ship scene's PID with gyro
rate feedback (tunings/ship_pid.toml) on a local Dask cluster, against the scene's own gains and the best
of the 1,000-case grid sweep (sweeps/gains_1000.toml), all three judged on the tuning file's held-out set
(sea states, seeds and parameter draws the tuning never ran).

  .venv/bin/python benchmarks/tune_ship.py [--workers 2] [--trials 96] [--out results/tune_ship]
      [--results benchmarks/results/tune_ship.json] [--figures docs/figures/tuning]

Prints the figures and writes them to --results: evaluations and wall time of the tuning (the whole
tuning: cluster start, runs, margins, tables; the report's runs apart), the tuned gains, their margins and
peak current, and the held-out LOS RMS of the three. The grid's best: the grid point (azimuth kp, ki,
k_gyro) of least median LOS RMS over its 10 sea states, the elevation gains as the scene has them.
A rerun with the same --out takes every evaluation from the tables (and says so: evaluations run 0).
"""
from __future__ import annotations

import argparse
import json
import pathlib
import platform
import shutil
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gimbal2axis.locations import fmu_path   # noqa: E402

SCENE = ROOT / "scenes" / "ship_stabilization.toml"
TUNING = ROOT / "tunings" / "ship_pid.toml"
GRID = ROOT / "sweeps" / "gains_1000.toml"


def grid_best(out: pathlib.Path, workers: int) -> tuple[dict, dict]:
    """(the grid's best azimuth gains, the sweep's figures): the sweep run (or taken from its table)."""
    from gimbal2axis.sweep import SweepOptions, run_sweep

    wall0 = time.perf_counter()
    outcome = run_sweep(SCENE, GRID, fmu_path(None), out, SweepOptions(workers=workers, progress=False, plot=False))
    wall = time.perf_counter() - wall0
    names = ["controller.azimuth.kp", "controller.azimuth.ki", "controller.azimuth.k_gyro"]
    by_point: dict = {}
    for row in outcome.rows:
        if row.get("status") == "ok":
            by_point.setdefault(tuple(row[n] for n in names), []).append(row["los_rms_mrad"])
    point, values = min(by_point.items(), key=lambda item: statistics.median(item[1]))
    return dict(zip(names, point)), {"cases": len(outcome.rows), "ran": outcome.ran, "wall_time_s": wall,
                                     "median_los_rms_mrad_of_best_point": statistics.median(values)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--trials", type=int, default=None, help="candidates (default: the file's, 96)")
    parser.add_argument("--out", default=str(ROOT / "results" / "tune_ship"))
    parser.add_argument("--results", default=str(ROOT / "benchmarks" / "results" / "tune_ship.json"))
    parser.add_argument("--figures", default=str(ROOT / "docs" / "figures" / "tuning"))
    args = parser.parse_args()

    from gimbal2axis.tune import engine

    out = pathlib.Path(args.out)
    grid, grid_figures = grid_best(out / "grid", args.workers)
    grid_candidate = with_scene_elevation(grid)
    print(f"grid best (azimuth, of {grid_figures['cases']} cases): {engine.describe_candidate(grid)}; median LOS RMS "
          f"over its sea states {grid_figures['median_los_rms_mrad_of_best_point']:.5g} mrad (0.5-s runs)")
    problem, result, report, walls = tune(args, out, grid_candidate)
    summary = json.loads((out / f"{problem.evaluations.parquet.stem}_summary.json").read_text())
    copy_figures(out, problem.evaluations.parquet.stem, pathlib.Path(args.figures))
    results = record(args, problem, result, summary, report, walls, (grid_candidate, grid_figures))
    path = pathlib.Path(args.results)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(results, indent=1))
    print_summary(results, summary["best"], args.workers, len(problem.holdout))
    print(f"wrote {path} and {report}")
    return 0


def with_scene_elevation(grid: dict) -> dict:
    """The grid's best azimuth gains with the scene's own elevation gains: a whole candidate."""
    from gimbal2axis.scene.scene import load_scene

    scene = load_scene(SCENE)
    candidate = dict(grid)
    for key in ("kp", "ki", "k_gyro"):
        candidate[f"controller.elevation.{key}"] = float(scene.controller_spec["elevation"][key])
    return candidate


def tune(args, out: pathlib.Path, grid_candidate: dict):
    """The tuning run and its report (which compares the grid's best): the problem, the result, the
    report's path, and the wall times of both."""
    from gimbal2axis.tune import engine
    from gimbal2axis.tune.report import write_report

    options = engine.TuneOptions(workers=args.workers, progress=False, trials=args.trials)
    problem = engine.plan(SCENE, TUNING, fmu_path(None), out)
    evaluator = engine.Evaluator(problem, options)
    try:
        wall0 = time.perf_counter()
        result = engine.run_tuning(problem, options, evaluator)
        tuning_wall = time.perf_counter() - wall0
        wall0 = time.perf_counter()
        report = write_report(result, evaluator, compare={"grid best": grid_candidate})
        report_wall = time.perf_counter() - wall0
    finally:
        evaluator.close()
        problem.fmu.close()
    return problem, result, report, (tuning_wall, report_wall)


def copy_figures(out: pathlib.Path, stem: str, figures: pathlib.Path) -> None:
    """The report's figures that docs/tuning.md shows, copied to docs/figures/tuning/."""
    figures.mkdir(parents=True, exist_ok=True)
    for suffix in ("convergence", "time_psd", "loops"):
        source = out / f"{stem}_{suffix}.png"
        if source.is_file():
            shutil.copyfile(source, figures / f"ship_pid_{suffix}.png")


def record(args, problem, result, summary: dict, report: pathlib.Path, walls: tuple, grid: tuple) -> dict:
    """What tune_ship.json holds; `grid`: the grid's best candidate and the sweep's figures."""
    best, held = summary["best"], summary["holdout"]
    tuning_wall, report_wall = walls
    return {
        "benchmark": "tune_ship", "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "machine": f"{platform.machine()}, {platform.python_version()}, workers {args.workers} (2 cores shared)",
        "tuning": {"file": "tunings/ship_pid.toml", "sampler": problem.tuning.sampler, "seed": problem.tuning.seed,
                   "candidates": len(result.trials), "runs_per_candidate": len(problem.scenarios),
                   "evaluations_run": result.evaluations_run, "evaluations_reused": result.evaluations_reused,
                   "wall_time_s": tuning_wall, "report_and_holdout_wall_time_s": report_wall,
                   "feasible_candidates": sum(bool(r["feasible"]) for r in result.trials)},
        "tuned": {n: best[n] for n in problem.tuning.parameter_names},
        "tuned_trial": best["trial"], "tuned_objective_mrad": best["objective_mrad"],
        "tuned_margins": {k: best.get(k) for k in ("gm_az_db", "pm_az_deg", "gm_el_db", "pm_el_deg", "ms_az", "ms_el")},
        "tuned_worst_i_peak_A": best["worst_i_peak_A"],
        "scene_own": summary["candidates"].get("scene's own"),
        "grid_best": grid[0], "grid": grid[1],
        "holdout_runs": len(problem.holdout),
        "holdout_los_rms_mrad": {label: h["objective_mrad"] for label, h in held.items()},
        "holdout_per_run_mrad": {label: h["per_run_mrad"] for label, h in held.items()},
        "holdout_feasible": {label: h["feasible"] for label, h in held.items()},
        "holdout_worst_i_frac_peak": {label: h["worst_i_frac_peak"] for label, h in held.items()},
        "margins": summary["margins"], "budget_mrad_nominal_sea": summary["budget_mrad"],
        "nominal_los_rms_mrad": summary["nominal_los_rms_mrad"], "report": str(report.relative_to(ROOT))
        if report.is_relative_to(ROOT) else str(report),
    }


def print_summary(results: dict, best: dict, workers: int, holdout_runs: int) -> None:
    from gimbal2axis.tune import engine

    t = results["tuning"]
    print(f"tuning: {t['candidates']} candidates x {t['runs_per_candidate']} runs: {t['evaluations_run']} evaluations "
          f"run, {t['evaluations_reused']} from the table, {t['wall_time_s']:.1f} s wall on {workers} workers "
          f"(report and held-out check {t['report_and_holdout_wall_time_s']:.1f} s); {t['feasible_candidates']} feasible")
    print(f"tuned (trial {best['trial']}): {engine.describe_candidate(results['tuned'])}; objective "
          f"{best['objective_mrad']:.5g} mrad; peak current {best['worst_i_peak_A']:.3g} A; margins az "
          f"{best['gm_az_db']:.3g} dB / {best['pm_az_deg']:.3g} deg, el {best['gm_el_db']:.3g} dB / {best['pm_el_deg']:.3g} deg")
    print(f"held out ({holdout_runs} runs), mean LOS RMS: " + ", ".join(
        f"{label} {value:.5g} mrad" for label, value in results["holdout_los_rms_mrad"].items()))


if __name__ == "__main__":
    sys.exit(main())
