"""The evidence of a tuning: <out>/<tuning>__<scene>_report.html with its figures (PNG files beside it)
and <out>/<tuning>__<scene>_summary.json.

  - convergence: the objective of every candidate against its trial (feasible, violating, failed) and
    the best feasible so far;
  - the best candidates (up to 5 feasible ones): their values, objective, margins and peak currents;
  - the best against the scene's own values of the tuned parameters (and any `compare` candidates) on
    the scene's own sea (its nominal run, the tuning's stop_time): the LOS error per axis in time and its
    PSD, and the pointing error budget per axis (budget.py: bias, drift, jitter in the sea, loop and high
    bands);
  - the loops: |S| and |T| per axis for the best and the scene's own gains, with the margins
    (margins.py: the lower gain margin too, of a conditionally stable loop);
  - the held-out check: the best and the others on the tuning file's [holdout] set, which the tuning never
    ran, objective per member and aggregated as the tuning aggregates.
"""
from __future__ import annotations

import dataclasses
import html
import json
import math
import pathlib
import urllib.parse

import numpy as np

from ..sweep import store
from . import budget as budgets
from .engine import TuneResult, describe_candidate, evaluate, scene_gains

TOP_CANDIDATES = 5


def _nominal_run(problem, candidate: dict):
    from ..master.master import run

    return run(problem.apply(candidate), problem.fmu)


def _from_s(problem, result) -> float:
    from_s = problem.tuning.metrics_from_s
    if from_s is None:
        start = result.window_start()
        from_s = start if start < result.stop_time else 0.0
    return from_s


def compared_candidates(result: TuneResult, compare: dict | None) -> dict:
    """{label: candidate}: the best (or least violating), the scene's own values, and `compare`'s."""
    problem = result.problem
    names = problem.tuning.parameter_names
    chosen = result.best or result.least_violating
    out = {}
    if chosen is not None:
        out["tuned"] = {n: chosen[n] for n in names}
    own = scene_gains(problem)
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in own.values()):
        out["scene's own"] = {n: float(v) for n, v in own.items()}
    for label, candidate in (compare or {}).items():
        out[label] = dict(candidate)
    return out


def holdout_check(result: TuneResult, evaluator, candidates: dict) -> dict:
    """{label: judged row on the holdout set} (empty without [holdout])."""
    problem = result.problem
    if not problem.holdout:
        return {}
    return {label: evaluate(problem, evaluator, candidate, problem.holdout, "holdout")
            for label, candidate in candidates.items()}


@dataclasses.dataclass
class _Evidence:
    """What the report's sections show, computed once."""
    result: TuneResult
    candidates: dict        # {label: candidate} (compared_candidates)
    held: dict              # {label: judged row on the holdout set}
    runs: dict              # {label: nominal run}
    loops: dict             # {label: {"az"|"el": margins.frequency_response} or why there is none}
    budget_rows: dict       # {label: budgets.budget of its nominal run}
    figures: dict = dataclasses.field(default_factory=dict)   # {name: PNG path}

    @property
    def problem(self):
        return self.result.problem

    @property
    def top(self) -> list:
        """The best feasible trials, up to TOP_CANDIDATES."""
        feasible = [r for r in self.result.trials if r["feasible"]]
        return sorted(feasible, key=lambda r: (r["objective_mrad"], r["trial"]))[:TOP_CANDIDATES]

    def path(self, suffix: str) -> pathlib.Path:
        return self.problem.trials_files.folder / f"{self.problem.evaluations.parquet.stem}_{suffix}"


def write_report(result: TuneResult, evaluator, compare: dict | None = None) -> pathlib.Path:
    """Writes the report page, its figures and the summary JSON; returns the page's path. Sets
    result.holdout (best and scene's own objective on the holdout set)."""
    import matplotlib
    matplotlib.use("Agg")

    problem = result.problem
    candidates = compared_candidates(result, compare)
    _add_pid_loops(problem)
    held = holdout_check(result, evaluator, candidates)
    if held and "tuned" in held and "scene's own" in held:
        result.holdout = {"runs": len(problem.holdout), "best_mrad": held["tuned"]["objective_mrad"],
                          "own_mrad": held["scene's own"]["objective_mrad"]}
    runs = {label: _nominal_run(problem, c) for label, c in candidates.items()}
    evidence = _Evidence(result, candidates, held, runs, _loop_responses(problem, candidates),
                         {label: budgets.budget(run, _from_s(problem, run)) for label, run in runs.items()})
    evidence.figures["convergence"] = _convergence_figure(evidence)
    evidence.figures["time_psd"] = _time_psd_figure(evidence)
    if evidence.loops:
        evidence.figures["loops"] = _loops_figure(evidence)
    summary = _summary(evidence)
    store.publish(evidence.path("summary.json"),
                  lambda p: pathlib.Path(p).write_text(json.dumps(summary, indent=1, default=_json)))
    page = (_head_section(evidence) + _best_section(evidence) + _comparison_section(evidence)
            + _loops_section(evidence) + _holdout_section(evidence) + ["</body></html>"])
    path = evidence.path("report.html")
    store.publish(path, lambda p: pathlib.Path(p).write_text("".join(page), encoding="utf-8"))
    return path


def _add_pid_loops(problem) -> None:
    """Without a margin constraint the tuning has no loop models: the report shows S, T and the margins
    of a PID scene still."""
    if problem.loops is not None:
        return
    from ..analysis.isolation_prediction import pid_gains
    from ..errors import SceneError
    from .margins import LoopModels
    try:
        pid_gains(problem.scene, problem.fmu)
        problem.loops = LoopModels(problem.scene, problem.fmu, problem.apply)
    except SceneError:
        pass


def _loop_responses(problem, candidates: dict) -> dict:
    """{label: {"az": response, "el": response}, or the reason why the candidate has no linear loop}."""
    if problem.loops is None:
        return {}
    from .margins import frequency_response

    loops = {}
    for label, c in candidates.items():
        try:
            loop = problem.loops.loop(c)
            loops[label] = {axis: frequency_response(loop, motor) for motor, axis in (("1", "az"), ("2", "el"))}
        except Exception as exc:   # no linear loop for this candidate: said on the page
            loops[label] = str(exc)
    return loops


# -- figures ----------------------------------------------------------------------------------------

_TRIAL_STYLES = (("ok", dict(marker="o", color="C0", label="feasible")),
                 ("infeasible", dict(marker="x", color="C3", label="violates a constraint")),
                 ("failed", dict(marker="v", color="k", label="a run failed")))


def _convergence_figure(evidence: _Evidence) -> pathlib.Path:
    """The objective of every candidate against its trial, and the best feasible so far."""
    import matplotlib.pyplot as plt

    problem, trials = evidence.problem, evidence.result.trials
    fig, ax = plt.subplots(figsize=(8, 4))
    for status, style in _TRIAL_STYLES:
        pts = [(r["trial"], r["objective_mrad"]) for r in trials if r["status"] == status
               and r["objective_mrad"] is not None and math.isfinite(r["objective_mrad"])]
        if pts:
            ax.plot(*zip(*pts), linestyle="none", ms=4, **style)
    ax.plot([r["trial"] for r in trials], _best_so_far(trials), color="C2", label="best feasible so far")
    ax.set_yscale("log")
    ax.set_xlabel("trial")
    ax.set_ylabel("objective [mrad]")
    ax.set_title(f"{problem.tuning.name} on {problem.scene.name}: {problem.tuning.objective.describe()}", fontsize=8)
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    return _save(fig, evidence.path("convergence.png"))


def _best_so_far(trials: list) -> list:
    """The best feasible objective up to each trial (NaN before the first feasible one)."""
    best, line = math.inf, []
    for r in trials:
        if r["feasible"]:
            best = min(best, r["objective_mrad"])
        line.append(best if math.isfinite(best) else np.nan)
    return line


def _time_psd_figure(evidence: _Evidence) -> pathlib.Path:
    """The LOS error per axis of each candidate's nominal run in time and its PSD."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 6))
    for k, (label, run) in enumerate(evidence.runs.items()):
        from_s = _from_s(evidence.problem, run)
        t = run.signals["time"]
        for col, (axis, name) in enumerate(budgets.AXES.items()):
            axes[0, col].plot(t, run.derived[name] * 1e3, lw=0.7, label=label, color=f"C{k}")
            f, p = budgets.spectra_of(run, from_s)[axis]
            axes[1, col].loglog(f[1:], p[1:], lw=0.8, label=label, color=f"C{k}")
    for col, axis in enumerate(budgets.AXES):
        axes[0, col].set_title(f"LOS error, {axis} [mrad] (nominal sea)", fontsize=9)
        axes[0, col].set_xlabel("time [s]")
        axes[1, col].set_title(f"PSD of the LOS error, {axis} [mrad^2/Hz]", fontsize=9)
        axes[1, col].set_xlabel("frequency [Hz]")
        for row in axes[:, col]:
            row.grid(True, which="both", alpha=0.3)
            row.legend(fontsize=7)
        for edge in (budgets.SEA_HZ, budgets.HIGH_HZ):
            axes[1, col].axvline(edge, color="grey", lw=0.5, ls="--")
    fig.tight_layout()
    return _save(fig, evidence.path("time_psd.png"))


def _loops_figure(evidence: _Evidence) -> pathlib.Path:
    """|S| and |T| per axis of each candidate with a linear loop, its margins in the legend."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for k, (label, by_axis) in enumerate(evidence.loops.items()):
        if isinstance(by_axis, str):
            continue
        for col, axis in enumerate(("az", "el")):
            r = by_axis[axis]
            margins = f"GM {r['gm_db']:.3g} dB{_lower_margin(r)}, PM {r['pm_deg']:.3g} deg, Ms {r['ms']:.3g}"
            axes[col].loglog(r["f_hz"], np.abs(r["S"]), color=f"C{k}", label=f"{label} |S| ({margins})")
            axes[col].loglog(r["f_hz"], np.abs(r["T"]), color=f"C{k}", ls="--", label=f"{label} |T|")
    for col, axis in enumerate(("azimuth (motor 1)", "elevation (motor 2)")):
        axes[col].set_title(f"loop broken at {axis}: S and T", fontsize=9)
        axes[col].set_xlabel("frequency [Hz]")
        axes[col].grid(True, which="both", alpha=0.3)
        axes[col].legend(fontsize=6)
    fig.tight_layout()
    return _save(fig, evidence.path("loops.png"))


# -- the summary JSON ----------------------------------------------------------------------------------

_MARGIN_KEYS = ("gm_db", "gm_hz", "lower_gm_db", "lower_gm_hz", "pm_deg", "crossover_hz", "ms")


def _summary(evidence: _Evidence) -> dict:
    result, problem = evidence.result, evidence.problem
    tuning = problem.tuning
    return {
        "tuning": tuning.name, "scene": problem.scene.name, "sampler": tuning.sampler, "seed": tuning.seed,
        "objective": tuning.objective.describe(), "trials": len(result.trials),
        "runs_per_candidate": len(problem.scenarios),
        "evaluations_run": result.evaluations_run, "evaluations_reused": result.evaluations_reused,
        "wall_time_s": result.wall_time, "feasible": bool(result.best),
        "best": _clean(result.best or result.least_violating),
        "top": [_clean(r) for r in evidence.top],
        "candidates": evidence.candidates,
        "nominal_los_rms_mrad": {label: _nominal_los_rms_mrad(problem, run) for label, run in evidence.runs.items()},
        "budget_mrad": evidence.budget_rows,
        "margins": {label: ({axis: {k: r[k] for k in _MARGIN_KEYS} for axis, r in by_axis.items()}
                            if not isinstance(by_axis, str) else by_axis)
                    for label, by_axis in evidence.loops.items()},
        "holdout": {label: {"objective_mrad": row["objective_mrad"], "per_run_mrad": row["per_scenario"],
                            "feasible": row["feasible"], "worst_i_frac_peak": row["worst_i_frac_peak"]}
                    for label, row in evidence.held.items()},
        "holdout_scenarios": problem.holdout,
    }


def _nominal_los_rms_mrad(problem, run) -> float:
    window = run.metrics_window(_from_s(problem, run))
    return float(np.sqrt(np.mean(run.signals["los_error"][window] ** 2))) * 1e3


# -- the page's sections (lists of HTML pieces) -------------------------------------------------------

_BEST_COLUMNS = ["objective_mrad", "worst_i_frac_peak", "worst_i_peak_A", "worst_u_sat_s", "gm_az_db",
                 "lower_gm_az_db", "pm_az_deg", "gm_el_db", "lower_gm_el_db", "pm_el_deg"]
_BUDGET_COLUMNS = ["candidate", "axis", "bias", "drift_slope_per_s", "drift_rms", "sea", "loop", "high", "total",
                   "rms"]
_HOLDOUT_KEYS = ("objective_mrad", "feasible", "worst_i_frac_peak")


def _head_section(evidence: _Evidence) -> list:
    result, problem = evidence.result, evidence.problem
    tuning, stem = problem.tuning, problem.evaluations.parquet.stem
    return [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(stem)}</title>",
            "<style>body{font-family:sans-serif;max-width:1100px}td,th{padding:2px 8px;text-align:right}"
            "table{border-collapse:collapse}tr:nth-child(even){background:#f4f4f4}</style></head><body>",
            f"<h1>Tuning {html.escape(tuning.name)} on {html.escape(problem.scene.name)}</h1>",
            f"<p>{html.escape(tuning.description)}</p>",
            f"<p>Objective: {html.escape(tuning.objective.describe())}; {len(problem.scenarios)} runs per candidate "
            f"(robustness set), sampler {tuning.sampler}, seed {tuning.seed}; {len(result.trials)} candidates, "
            f"{result.evaluations_run} evaluations run now, {result.evaluations_reused} from the table.</p>",
            "<h2>Convergence</h2>", _image(evidence.figures['convergence'], 800)]


def _best_section(evidence: _Evidence) -> list:
    result = evidence.result
    names = evidence.problem.tuning.parameter_names
    page = ["<h2>Best candidates</h2>", _table(["trial"] + names + _BEST_COLUMNS, evidence.top)]
    if not result.best:
        least = {n: (result.least_violating or {}).get(n, math.nan) for n in names}
        page.append("<p><b>No candidate met the constraints</b>; the least violating: "
                    f"{html.escape(describe_candidate(least))}</p>")
    return page


def _comparison_section(evidence: _Evidence) -> list:
    return ["<h2>Compared on the scene's own sea</h2>",
            "<p>" + "<br>".join(f"{html.escape(label)}: {html.escape(describe_candidate(c))}"
                                for label, c in evidence.candidates.items()) + "</p>",
            _image(evidence.figures['time_psd'], 1000),
            "<h3>Pointing error budget per axis [mrad] (slope in mrad/s)</h3>",
            _table(_BUDGET_COLUMNS, [dict(candidate=label, axis=axis, **values)
                                     for label, by_axis in evidence.budget_rows.items()
                                     for axis, values in by_axis.items()]),
            f"<p>Bands: sea [0, {budgets.SEA_HZ:g}) Hz, loop [{budgets.SEA_HZ:g}, {budgets.HIGH_HZ:g}) Hz, high "
            f"[{budgets.HIGH_HZ:g} Hz, Nyquist]; total = root-sum-square of the bias and the bands.</p>"]


def _loops_section(evidence: _Evidence) -> list:
    if "loops" not in evidence.figures:
        return []
    return ["<h2>Sensitivity and complementary sensitivity</h2>", _image(evidence.figures['loops'], 1000)]


def _holdout_section(evidence: _Evidence) -> list:
    if not evidence.held:
        return []
    return [f"<h2>Held out: {len(evidence.problem.holdout)} runs the tuning did not see</h2>",
            _table(["candidate", *_HOLDOUT_KEYS],
                   [dict(candidate=label, **{k: row[k] for k in _HOLDOUT_KEYS}) for label, row in evidence.held.items()])]


def _lower_margin(response: dict) -> str:
    """The lower gain margin of a conditionally stable loop, for the legend ('' without one)."""
    if not math.isfinite(response["lower_gm_db"]):
        return ""
    return f" (lower {response['lower_gm_db']:.3g} dB at {response['lower_gm_hz']:.3g} Hz)"


def _save(fig, path: pathlib.Path) -> pathlib.Path:
    import matplotlib.pyplot as plt

    store.publish(path, lambda p: fig.savefig(p, dpi=100, format="png"))
    plt.close(fig)
    return path


def _image(path: pathlib.Path, width: int) -> str:
    """An <img> of the figure file `path` beside the page: its name (the scene's file name is part of
    it) URL-quoted, then escaped for the attribute, so that it is a link to that file and never markup."""
    return f"<img src='{html.escape(urllib.parse.quote(path.name), quote=True)}' width='{width}'>"


def _table(columns: list, rows: list) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = "".join("<tr>" + "".join(f"<td>{_cell(row.get(c))}</td>" for c in columns) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _cell(value) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return html.escape("" if value is None else str(value))


def _clean(row):
    if row is None:
        return None
    return {k: v for k, v in row.items() if k not in ("per_scenario",)}


def _json(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)
