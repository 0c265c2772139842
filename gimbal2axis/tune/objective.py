"""Judging a candidate from its runs on the robustness set: the objective, the constraints, and the one
number the optimizer minimizes.

  objective      per run: sum of weight x metric (LOS RMS over the window, or a band RMS from the run's
                 PSD) [mrad]; over the set: mean, max or rms (the tuning's `aggregate`)
  violations     per constraint, normalized, > 0 when violated (the worst member of the set counts):
                   peak current      (max i_frac_peak - limit) / limit
                   saturation        (max u_sat_s - limit) / max(limit, 0.1 s)
                   gain margin       (min_db - min(gm_az, gm_el)) / max(|min_db|, 1 dB)
                   phase margin      (min_deg - min(pm_az, pm_el)) / max(|min_deg|, 1 deg)
                   lower gain margin (min_db + max(lower_gm_az, lower_gm_el)) / max(min_db, 1 dB): the
                                     lower margin (< 0 dB, -inf without one) of a conditionally stable loop
                   (a linear closed loop that is unstable violates each margin by 1)
                   requirements      1 when a run misses the scene's requirements
                   time on target    (min_fraction - min on_target_fraction) / min_fraction (moving targets)
  value          log10(objective) + PENALTY x sum of the positive violations; FAILED_VALUE when a run
                 failed (diverged, refused) or gave no objective. The log makes a decade of LOS RMS one
                 unit whatever its level, which suits CMA-ES's step-size adaptation and TPE's densities.

The best candidate is the feasible one (no violation, no failed run) of least objective; of equal ones the
earlier trial. Toward a moving target the LOS error is the error to where the target is: "tracking_rms"
reads the same column as "los_rms" (`Term.column`); the rest here is metric-agnostic.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

PENALTY = 2.0          # value units (decades of objective) per unit of normalized violation
FAILED_VALUE = 10.0    # a candidate with a failed run: worse than any objective below 1e10 mrad


@dataclass
class Judgement:
    objective: float               # aggregated over the set, mrad (nan when a run failed)
    value: float                   # what the optimizer minimizes
    violations: dict               # constraint -> normalized violation (> 0: violated)
    feasible: bool
    failed_runs: int
    worst: dict = field(default_factory=dict)   # worst over the set: i_frac_peak, u_sat_s, los_rms_mrad
    per_run: list = field(default_factory=list)


def run_objective(tuning, row: dict) -> float:
    total = 0.0
    for term in tuning.objective.terms:
        value = row.get(term.column)
        if value is None or not math.isfinite(value):
            return math.nan
        total += term.weight * value
    return total


def aggregate(values: list, how: str) -> float:
    if not values or any(not math.isfinite(v) for v in values):
        return math.nan
    if how == "max":
        return max(values)
    if how == "rms":
        return math.sqrt(sum(v * v for v in values) / len(values))
    return sum(values) / len(values)


def judge(tuning, rows: list, margins: dict) -> Judgement:
    ok = [r for r in rows if r.get("status") == "ok"]
    failed = len(rows) - len(ok)
    per_run = [run_objective(tuning, r) if r.get("status") == "ok" else math.nan for r in rows]
    objective = aggregate(per_run, tuning.objective.aggregate) if not failed else math.nan
    worst = _worst(ok, tuning.constraints)
    violations = _violations(tuning.constraints, worst, margins, ok)
    excess = sum(max(v, 0.0) for v in violations.values())
    if failed or not math.isfinite(objective) or objective <= 0:
        value = FAILED_VALUE + PENALTY * excess
    else:
        value = math.log10(objective) + PENALTY * excess
    feasible = not failed and math.isfinite(objective) and excess == 0.0
    return Judgement(objective, value, violations, feasible, failed, worst, per_run)


def _worst(ok: list, constraints) -> dict:
    """The worst of the ok runs per constrained column (NaN: none has it); the on-target share's least
    with an on-target constraint."""
    worst = {}
    for column in ("i_frac_peak", "u_sat_s", "los_rms_mrad", "i_peak_A"):
        values = [r[column] for r in ok if r.get(column) is not None and math.isfinite(r[column])]
        worst[column] = max(values) if values else math.nan
    if constraints.on_target_min_fraction is not None:   # the least on-target share of the set counts
        shares = [r["on_target_fraction"] for r in ok if r.get("on_target_fraction") is not None]
        worst["on_target_fraction"] = min(shares) if shares else math.nan
    return worst


def _margin_violation(limit: float, margins: dict, keys: tuple) -> float:
    """The smaller margin of the two axes under `limit`, relative; 1 for an unstable loop or a margin that
    is not a number (an infinite margin meets any limit)."""
    value = min(margins.get(keys[0], math.nan), margins.get(keys[1], math.nan))
    if not margins.get("linear_stable", True) or not math.isfinite(value) and not value == math.inf:
        return 1.0
    return (limit - value) / max(abs(limit), 1.0)


# (constraint, violation name, its violation: > 0 by how much it is broken, relative to the limit), in
# the order of the table's violation_* columns
_VIOLATIONS = [
    ("peak_current_fraction", "peak_current",
     lambda limit, worst, margins: (worst["i_frac_peak"] - limit) / limit),
    ("voltage_saturation_max_s", "voltage_saturation",
     lambda limit, worst, margins: (worst["u_sat_s"] - limit) / max(limit, 0.1)),
    ("gain_margin_min_db", "gain_margin",
     lambda limit, worst, margins: _margin_violation(limit, margins, ("gm_az_db", "gm_el_db"))),
    ("phase_margin_min_deg", "phase_margin",
     lambda limit, worst, margins: _margin_violation(limit, margins, ("pm_az_deg", "pm_el_deg"))),
    ("lower_gain_margin_min_db", "lower_gain_margin",
     lambda limit, worst, margins: _lower_margin_violation(limit, margins, margins.get("linear_stable", True))),
    ("on_target_min_fraction", "on_target",
     lambda limit, worst, margins: (limit - worst["on_target_fraction"]) / limit),
]


def _violations(constraints, worst: dict, margins: dict, ok: list) -> dict:
    """{constraint: violation} of every constraint the tuning has, a non-finite one made 1 (-inf: -1)."""
    violations = {name: violation(getattr(constraints, limit), worst, margins)
                  for limit, name, violation in _VIOLATIONS if getattr(constraints, limit) is not None}
    if constraints.requirements:
        violations["requirements"] = 1.0 if any(r.get("requirements_met") is False for r in ok) else 0.0
    return {k: (v if math.isfinite(v) else -1.0 if v == -math.inf else 1.0) for k, v in violations.items()}


def _lower_margin_violation(drop_db: float, margins: dict, stable: bool) -> float:
    """The axis whose lower gain margin is nearest 0 dB counts; an axis without one (-inf) meets any limit."""
    lower = [margins.get(f"lower_gm_{axis}_db", math.nan) for axis in ("az", "el")]
    if not stable or any(math.isnan(value) for value in lower):
        return 1.0
    return (drop_db + max(lower)) / max(drop_db, 1.0)


def trial_row(problem, number: int, batch: int, candidate: dict, verdict: Judgement, margins: dict) -> dict:
    """One row of the trials table (case_id 'trial-<n>')."""
    row = {"case_id": f"trial-{number:05d}", "case": number, "sweep": problem.tuning.name,
           "scene": problem.scene.name, "scene_hash": problem.scene_digest, "trial": number, "batch": batch}
    row.update(candidate)
    row.update({"objective_mrad": verdict.objective, "value": verdict.value, "feasible": verdict.feasible,
                "failed_runs": verdict.failed_runs, "runs": len(verdict.per_run),
                "worst_los_rms_mrad": verdict.worst.get("los_rms_mrad"),
                "worst_i_frac_peak": verdict.worst.get("i_frac_peak"),
                "worst_i_peak_A": verdict.worst.get("i_peak_A"),
                "worst_u_sat_s": verdict.worst.get("u_sat_s")})
    if "on_target_fraction" in verdict.worst:
        row["worst_on_target_fraction"] = verdict.worst["on_target_fraction"]
    for name, value in verdict.violations.items():
        row[f"violation_{name}"] = value
    for name, value in margins.items():
        if name != "margins_note":
            row[name] = value
    if margins.get("margins_note"):
        row["margins_note"] = margins["margins_note"]
    row["sampling_seed"] = problem.tuning.seed
    row["status"] = "ok" if verdict.feasible else ("failed" if verdict.failed_runs else "infeasible")
    return row


def pick_best(rows: list) -> tuple:
    """(best feasible row or None, least violating row when none is feasible, else None)."""
    feasible = [r for r in rows if r.get("feasible")]
    if feasible:
        return min(feasible, key=lambda r: (r["objective_mrad"], r["trial"])), None
    if not rows:
        return None, None
    return None, min(rows, key=lambda r: (r["value"], r["trial"]))
