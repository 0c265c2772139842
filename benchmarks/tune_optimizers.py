"""Which optimizer for `gimbal2axis tune`: Optuna (CMA-ES sampler, TPE, random), pycma, nevergrad and
SciPy's differential evolution compared on the same tuning problem, through the same evaluations (the
FMU runs of gimbal2axis.tune: objective, constraints, margins, the penalized value every optimizer
minimizes).

The problem: tunings/ship_pid.toml (the ship scene's PID with gyro rate feedback, 6 gains on a log
scale, LOS RMS under a current limit and margins), reduced by default to keep the comparison affordable on
a shared 2-core machine: `--stop-time` s runs, the robustness set cut to its first sea state x 2 seeds
(no parameter draws), `--budget` candidates per optimizer and `--repeats` seeds each. Measured per
optimizer: the best feasible objective after the budget (median, min, max over the seeds), the
evaluations to come within 5, 15 and 30 % of the best any optimizer found (median over the seeds that do), and the objective of each seed's best on
a held-out set (other seeds and sea states: the noise of the chaotic sea the tuning did not see).

  .venv/bin/python benchmarks/tune_optimizers.py [--budget 64] [--repeats 3] [--stop-time 6]
      [--out benchmarks/results/tune_optimizers.json]

nevergrad is not a dependency of gimbal2axis: it is compared when importable (e.g.
`pip install --target /tmp/ngpkgs --no-deps nevergrad` and PYTHONPATH=/tmp/ngpkgs), else skipped and said.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import pathlib
import platform
import statistics
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gimbal2axis.locations import fmu_path   # noqa: E402
from gimbal2axis.tune import engine          # noqa: E402
from gimbal2axis.tune.spec import ScenarioSet, load_tuning   # noqa: E402

WITHIN = (0.05, 0.15, 0.30)   # "reached": within 5, 15, 30 % of the best objective any run found


def to_values(problem, u) -> dict:
    """A point of the unit cube to the tuned parameters (log or linear between the bounds)."""
    out = {}
    for p, x in zip(problem.tuning.parameters, np.clip(np.asarray(u, float), 0.0, 1.0)):
        if p.log:
            out[p.name] = float(math.exp(math.log(p.low) + x * (math.log(p.high) - math.log(p.low))))
        else:
            out[p.name] = float(p.low + x * (p.high - p.low))
    return out


class Budgeted:
    """Evaluates candidates, one judged row each, until the budget; records the history."""

    def __init__(self, problem, evaluator, budget: int):
        self.problem, self.evaluator, self.budget = problem, evaluator, budget
        self.history: list = []

    def value(self, candidate: dict) -> float:
        if len(self.history) >= self.budget:
            raise StopIteration
        row = engine.evaluate(self.problem, self.evaluator, candidate, self.problem.scenarios, "tuning")
        self.history.append(row)
        return row["value"]


def run_optuna(problem, evaluator, sampler: str, seed: int, budget: int) -> list:
    problem.tuning.sampler, problem.tuning.seed = sampler, seed
    result = engine.run_tuning(problem, engine.TuneOptions(serial=True, progress=False, trials=budget), evaluator)
    return result.trials


def run_pycma(problem, evaluator, seed: int, budget: int, batch: int) -> list:
    import cma

    run = Budgeted(problem, evaluator, budget)
    d = len(problem.tuning.parameters)
    es = cma.CMAEvolutionStrategy([0.5] * d, 0.25, {"bounds": [0, 1], "seed": seed + 1, "popsize": batch,
                                                     "verbose": -9})
    try:
        while True:
            xs = es.ask()
            es.tell(xs, [run.value(to_values(problem, x)) for x in xs])
    except StopIteration:
        pass
    return run.history


def run_scipy_de(problem, evaluator, seed: int, budget: int, batch: int) -> list:
    from scipy.optimize import differential_evolution

    run = Budgeted(problem, evaluator, budget)
    d = len(problem.tuning.parameters)

    def batch_map(function, xs):   # a generation at once, as the sweep engine would run it
        return [function(x) for x in xs]

    def f(x):
        try:
            return run.value(to_values(problem, x))
        except StopIteration:
            return math.inf   # past the budget: DE's remaining calls count for nothing

    popsize = max(1, batch // d)
    differential_evolution(f, [(0.0, 1.0)] * d, popsize=popsize, maxiter=budget, seed=seed, polish=False,
                           updating="deferred", workers=batch_map, tol=0, atol=0, init="latinhypercube")
    return run.history


def run_nevergrad(problem, evaluator, seed: int, budget: int, batch: int) -> list:
    import nevergrad as ng

    run = Budgeted(problem, evaluator, budget)
    d = len(problem.tuning.parameters)
    parametrization = ng.p.Array(shape=(d,), lower=0.0, upper=1.0)
    parametrization.random_state = np.random.RandomState(seed)
    # TwoPointsDE: nevergrad's differential evolution for parallel budgets (NGOpt, its default, picks a
    # metamodel-based optimizer for this budget, which needs scikit-learn)
    optimizer = ng.optimizers.TwoPointsDE(parametrization=parametrization, budget=budget, num_workers=batch)
    try:
        while True:
            asked = [optimizer.ask() for _ in range(batch)]
            for candidate in asked:
                optimizer.tell(candidate, run.value(to_values(problem, candidate.value)))
    except StopIteration:
        pass
    return run.history


def best_curve(history: list) -> list:
    best, curve = math.inf, []
    for row in history:
        if row.get("feasible") and row["objective_mrad"] < best:
            best = row["objective_mrad"]
        curve.append(best)
    return curve


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--budget", type=int, default=64, help="candidates per optimizer run (default 64)")
    parser.add_argument("--repeats", type=int, default=3, help="seeds per optimizer (default 3)")
    parser.add_argument("--stop-time", type=float, default=6.0, help="simulated s per run (default 6)")
    parser.add_argument("--batch", type=int, default=8, help="candidates per batch (default 8)")
    parser.add_argument("--optimizers", default="optuna-cmaes,optuna-tpe,optuna-random,pycma,scipy-de,nevergrad")
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "tune_optimizers.json"))
    parser.add_argument("--work", default=str(ROOT / "results" / "tune_optimizers"),
                        help="the evaluations table (a rerun takes the evaluations it has from it)")
    args = parser.parse_args()

    tuning = reduced_tuning(args)
    work = pathlib.Path(args.work)
    problem = engine.plan(ROOT / "scenes" / "ship_stabilization.toml", tuning.path, fmu_path(None), work, tuning=tuning)
    evaluator = engine.Evaluator(problem, engine.TuneOptions(serial=True, progress=False))
    runners = {
        "optuna-cmaes": lambda seed: run_optuna(problem, evaluator, "cmaes", seed, args.budget),
        "optuna-tpe": lambda seed: run_optuna(problem, evaluator, "tpe", seed, args.budget),
        "optuna-random": lambda seed: run_optuna(problem, evaluator, "random", seed, args.budget),
        "pycma": lambda seed: run_pycma(problem, evaluator, seed, args.budget, args.batch),
        "scipy-de": lambda seed: run_scipy_de(problem, evaluator, seed, args.budget, args.batch),
        "nevergrad": lambda seed: run_nevergrad(problem, evaluator, seed, args.budget, args.batch),
    }
    histories, skipped, times = run_optimizers(args, runners)
    overall = min(best_curve(h)[-1] for runs in histories.values() for h in runs)
    targets = {f"{within:.0%}": overall * (1 + within) for within in WITHIN}
    summary = {name: summarize(runs, targets, times[name], problem, evaluator) for name, runs in histories.items()}
    result = {
        "benchmark": "tune_optimizers", "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "problem": {"tuning": "tunings/ship_pid.toml (reduced)", "scene": "scenes/ship_stabilization.toml",
                    "parameters": tuning.parameter_names, "stop_time_s": tuning.stop_time,
                    "metrics_from_s": tuning.metrics_from_s, "runs_per_candidate": len(problem.scenarios),
                    "holdout_runs": len(problem.holdout), "budget": args.budget, "repeats": args.repeats,
                    "batch": args.batch, "objective": tuning.objective.describe(),
                    "constraints": {k: v for k, v in vars(tuning.constraints).items() if v not in (None, False)}},
        "targets_mrad": targets, "best_found_mrad": overall,
        "optimizers": summary, "skipped": skipped,
        "versions": _versions(), "machine": f"{platform.machine()}, {platform.python_version()}",
    }
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))
    print_table(result, args.repeats)
    print(f"wrote {out}")
    evaluator.close()
    problem.fmu.close()
    return 0


def reduced_tuning(args):
    """tunings/ship_pid.toml made cheaper for the comparison: shorter runs, fewer sea states, no start."""
    tuning = load_tuning(ROOT / "tunings" / "ship_pid.toml")
    tuning.stop_time = args.stop_time
    tuning.metrics_from_s = min(tuning.metrics_from_s, args.stop_time / 3)
    tuning.robustness = ScenarioSet(tuning.robustness.sea_states[:1], tuning.robustness.seeds[:2])
    tuning.holdout = ScenarioSet(tuning.holdout.sea_states, tuning.holdout.seeds[:2])
    tuning.batch = args.batch
    # every optimizer from scratch: no start point (pycma, DE and nevergrad start from the box alone too)
    tuning.parameters = [dataclasses.replace(p, start=None) for p in tuning.parameters]
    return tuning


def run_optimizers(args, runners: dict):
    """Each optimizer of --optimizers, --repeats seeds: its histories and wall times; the skipped ones
    and why (one that cannot run here is reported, not fatal)."""
    histories, skipped, times = {}, {}, {}
    for name in args.optimizers.split(","):
        if name == "nevergrad":
            try:
                import nevergrad  # noqa: F401
            except ImportError as exc:
                skipped[name] = f"not importable ({exc})"
                print(f"{name}: skipped, {skipped[name]}", file=sys.stderr)
                continue
        histories[name], times[name] = [], []
        for seed in range(1, args.repeats + 1):
            wall0 = time.perf_counter()
            try:
                history = runners[name](seed)[:args.budget]
            except Exception as exc:   # an optimizer that cannot run here is reported, not fatal
                skipped[name] = f"{type(exc).__name__}: {exc}"
                print(f"{name}: failed, {skipped[name]}", file=sys.stderr)
                break
            times[name].append(time.perf_counter() - wall0)
            histories[name].append(history)
            curve = best_curve(history)
            print(f"{name} seed {seed}: {len(history)} candidates, best feasible {curve[-1]:.5g} mrad "
                  f"({times[name][-1]:.1f} s)", file=sys.stderr)
    histories = {name: runs for name, runs in histories.items() if runs and name not in skipped}
    return histories, skipped, times


def summarize(runs: list, targets: dict, times: list, problem, evaluator) -> dict:
    """One optimizer's figures over its seeds: best found, evaluations to each target, the held-out
    objective of its best candidates, the feasible fraction, the wall time, the curves."""
    curves = [best_curve(history) for history in runs]
    finals = [curve[-1] for curve in curves]
    reached = {label: [first_at_or_below(curve, target) for curve in curves] for label, target in targets.items()}
    held = held_out(runs, problem, evaluator)
    return {
        "best_mrad_median": statistics.median(finals), "best_mrad_min": min(finals), "best_mrad_max": max(finals),
        "evaluations_to_target": reached,
        "reached": {label: sum(h is not None for h in hits) for label, hits in reached.items()},
        "evaluations_to_target_median": {label: median_of_found(hits) for label, hits in reached.items()},
        "holdout_mrad_median": statistics.median(held) if held else None,
        "holdout_mrad": held,
        "feasible_fraction": sum(r.get("feasible", False) for h in runs for r in h) / sum(len(h) for h in runs),
        "wall_time_s_median": statistics.median(times),
        "curves": curves,
    }


def first_at_or_below(curve: list, target: float):
    """The evaluations a best-so-far curve took to reach `target`, None if it did not."""
    return next((i + 1 for i, v in enumerate(curve) if v <= target), None)


def median_of_found(hits: list):
    found = [h for h in hits if h is not None]
    return statistics.median(found) if found else None


def held_out(runs: list, problem, evaluator) -> list:
    """The held-out objective of each run's best feasible candidate."""
    held = []
    for history in runs:
        feasible = [r for r in history if r.get("feasible")]
        if feasible and problem.holdout:
            best = min(feasible, key=lambda r: r["objective_mrad"])
            candidate = {p: best[p] for p in problem.tuning.parameter_names}
            held.append(engine.evaluate(problem, evaluator, candidate, problem.holdout, "holdout")["objective_mrad"])
    return held


def print_table(result: dict, repeats: int) -> None:
    targets, summary = result["targets_mrad"], result["optimizers"]
    print(f"best found by any run: {result['best_found_mrad']:.5g} mrad; targets: " +
          ", ".join(f"+{label} = {t:.5g} mrad" for label, t in targets.items()))
    print(f"{'optimizer':<15} {'best median [min, max] mrad':<34}" + "".join(f"{'+' + label + ': n, evals':<16}"
                                                                             for label in targets)
          + f"{'held out median':<16} feasible")
    for name, s in summary.items():
        cells = ""
        for label in targets:
            median = s["evaluations_to_target_median"][label]
            cells += f"{s['reached'][label]}/{repeats}, {'-' if median is None else f'{median:g}'}".ljust(16)
        held = "-" if s["holdout_mrad_median"] is None else f"{s['holdout_mrad_median']:.5g}"
        print(f"{name:<15} " + f"{s['best_mrad_median']:.5g} [{s['best_mrad_min']:.5g}, {s['best_mrad_max']:.5g}]".ljust(34)
              + cells + f"{held:<16} {s['feasible_fraction']:.2f}")
    for name, why in result["skipped"].items():
        print(f"{name}: skipped, {why}")


def _versions() -> dict:
    out = {}
    for module in ("optuna", "cma", "cmaes", "scipy", "nevergrad", "numpy"):
        try:
            out[module] = __import__(module).__version__
        except Exception:
            out[module] = None
    return out


if __name__ == "__main__":
    sys.exit(main())
