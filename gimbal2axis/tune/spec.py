"""Tuning files (tunings/*.toml): loading and checking, and the robustness set they describe.

A tuning file (TOML):

  name = "ship_pid"            # names the result files (default: the file's stem)
  description = "..."
  seed = 1                     # seeds the optimizer and the parameter draws (default 0)
  stop_time = 12.0             # optional: every evaluation ends here instead of the scene's stop_time
  metrics_from_s = 2.0         # optional: the metrics window [from, end] (default as a sweep's)

  [parameters]                 # what is tuned: the paths a sweep takes (docs/sweeps.md)
  "controller.azimuth.kp" = { bounds = [100.0, 3000.0], scale = "log" }      # scale: "linear" (default) or "log"
  "controller.azimuth.k_gyro" = { bounds = [1.0, 30.0], scale = "log", start = 8.0 }   # start: optional first guess

  [objective]                  # minimized; aggregated over the robustness set
  metric = "los_rms"           # "los_rms" (RMS of the LOS error over the window), "band_rms" (needs band = [f_lo, f_hi]
                               # in Hz, from the run's own PSD; axis = "both" | "xel" | "el"), or "weighted" (terms = [...])
  aggregate = "mean"           # over the robustness set: "mean", "max" or "rms"
  # terms = [{ metric = "los_rms", weight = 1.0 }, { metric = "band_rms", band = [10.0, 500.0], weight = 2.0 }]
  # metric = "tracking_rms": the RMS of the error to a moving target ([target] type earth_point, flyby or
  #   track) over the window; refused for a fixed direction, whose error is los_rms

  [constraints]                # every one judged on each member of the robustness set (the worst counts)
  peak_current_fraction = 0.5  # max |i_R| / motor.i_L, both motors
  voltage_saturation_max_s = 0.0   # time a controller asks for |u| >= motor.U_L, per run
  gain_margin_min_db = 6.0     # classical margins of the linearized loop (nominal plant, candidate's gains),
  phase_margin_min_deg = 35.0  #   each motor's loop broken with the other closed
  lower_gain_margin_min_db = 20.0   # a conditionally stable loop (open-loop unstable plant): the gain may drop
                               #   by this many dB before it goes unstable (lower gain margin <= -20 dB)
  requirements = true          # the scene's [requirements] met on every run
  on_target_min_fraction = 0.9 # a moving target: the share of the window with the error within half the beam

  [robustness]                 # every candidate runs on all of these (common random numbers)
  seeds = [11, 23]             # base_motion.seed values
  sea_states = [{ "base_motion.roll.significant_amplitude_deg" = 3.0 }, { ... }]   # scene overrides
  draws = 2                    # parameter draws, each a set of values of [robustness.draw]
  [robustness.draw]            # distributions as a sweep's [random] (uniform, loguniform, normal, integers, choice)
  "body2.J[1,1]" = { uniform = [0.9, 1.1] }

  [holdout]                    # the same keys as [robustness]: the final check on what tuning did not see
  [optimizer]
  sampler = "cmaes"            # "cmaes" (Optuna CmaEsSampler, default), "tpe" (Optuna TPESampler), "random"
  trials = 60                  # candidates in all
  batch = 6                    # candidates asked at once and run together (default: CMA-ES's population)

Scenarios: sea states x seeds x draws, in that order; each is a dict of scene paths to values, the same
for every candidate. Draw j of a parameter is sample j of its own stream (sweep.spec.draw, seeded by the
robustness seed and its name), so adding a draw leaves the others unchanged.
"""
from __future__ import annotations

import math
import pathlib
import sys
from dataclasses import dataclass, field

from ..errors import did_you_mean, excerpt, shown
from ..limits import read_toml
from ..limits import (MAX_DESCRIPTION_CHARS, MAX_SCENARIOS, MAX_TUNE_BATCH, MAX_TUNE_PARAMETERS, MAX_TUNE_TRIALS,
                      over_limit, too_long)
from ..sweep.spec import DISTRIBUTIONS, SweepError, _check_distribution, check_metrics_window, draw, parse_name

TOP_KEYS = {"name", "description", "seed", "stop_time", "metrics_from_s", "parameters", "objective", "constraints",
            "robustness", "holdout", "optimizer"}
PARAMETER_KEYS = {"bounds", "scale", "start"}
SCALES = ("linear", "log")
OBJECTIVE_KEYS = {"metric", "aggregate", "band", "axis", "terms"}
TERM_KEYS = {"metric", "weight", "band", "axis"}
# The metrics an objective can name. "tracking_rms" reads the run's LOS error, which toward a moving target is
# the error to where the target is: the name says what is tuned, and the engine refuses it for a fixed direction.
METRICS = ("los_rms", "band_rms", "weighted", "tracking_rms")
AGGREGATES = ("mean", "max", "rms")
AXES = ("both", "xel", "el")
CONSTRAINT_KEYS = {"peak_current_fraction", "voltage_saturation_max_s", "gain_margin_min_db", "phase_margin_min_deg",
                   "lower_gain_margin_min_db", "requirements", "on_target_min_fraction"}
ROBUSTNESS_KEYS = {"seeds", "sea_states", "draws", "draw", "seed"}
OPTIMIZER_KEYS = {"sampler", "trials", "batch"}
SAMPLERS = ("cmaes", "tpe", "random")


# Optuna's samplers seed numpy's legacy RandomState, which takes 32 bits.
MAX_SAMPLER_SEED = 2 ** 32 - 1


class TuneError(SweepError):
    """A tuning file that cannot be used; the message names the key."""


@dataclass(frozen=True)
class Parameter:
    name: str
    low: float
    high: float
    scale: str = "linear"
    start: float | None = None

    @property
    def log(self) -> bool:
        return self.scale == "log"


@dataclass(frozen=True)
class Term:
    metric: str          # los_rms | band_rms | tracking_rms
    weight: float = 1.0
    band: tuple | None = None
    axis: str = "both"

    @property
    def column(self) -> str:
        """The per-run column this term reads (written by tune.worker)."""
        if self.metric in ("los_rms", "tracking_rms"):
            return "los_rms_mrad"
        lo, hi = self.band
        return band_column(lo, hi, self.axis)


def band_column(lo: float, hi: float, axis: str) -> str:
    return f"psd_band_{lo:g}_{hi:g}Hz_{axis}_rms_mrad"


@dataclass(frozen=True)
class Objective:
    terms: tuple            # of Term: the objective of one run is sum(weight * value)
    aggregate: str = "mean"
    metric: str = "los_rms"

    def describe(self) -> str:
        parts = []
        for t in self.terms:
            what = {"los_rms": "LOS RMS", "tracking_rms": "tracking error RMS"}.get(t.metric) or \
                f"{t.axis} LOS RMS in [{t.band[0]:g}, {t.band[1]:g}) Hz"
            parts.append(what if t.weight == 1.0 and len(self.terms) == 1 else f"{t.weight:g} x {what}")
        return f"{self.aggregate} over the robustness set of " + " + ".join(parts) + " [mrad]"


@dataclass(frozen=True)
class Constraints:
    peak_current_fraction: float | None = None
    voltage_saturation_max_s: float | None = None
    gain_margin_min_db: float | None = None
    phase_margin_min_deg: float | None = None
    lower_gain_margin_min_db: float | None = None   # the size of the allowed drop, >= 0 dB
    requirements: bool = False
    on_target_min_fraction: float | None = None

    @property
    def needs_margins(self) -> bool:
        return any(limit is not None for limit in (self.gain_margin_min_db, self.phase_margin_min_deg,
                                                   self.lower_gain_margin_min_db))


@dataclass(frozen=True)
class ScenarioSet:
    sea_states: tuple = ({},)
    seeds: tuple = ()
    draws: int = 0
    draw: dict = field(default_factory=dict)
    seed: int = 0

    def scenarios(self) -> list[dict]:
        """Every member: sea state x seed x draw, as {scene path: value}; the same list for every candidate."""
        drawn = [{}]
        if self.draws:
            values = {name: draw(name, spec, self.draws, self.seed) for name, spec in self.draw.items()}
            drawn = [{name: values[name][j] for name in self.draw} for j in range(self.draws)]
        seeds = [{"base_motion.seed": s} for s in self.seeds] or [{}]
        return [dict(sea, **seed, **d) for sea in self.sea_states for seed in seeds for d in drawn]

    @property
    def names(self) -> list[str]:
        names = [n for sea in self.sea_states for n in sea]
        if self.seeds:
            names.append("base_motion.seed")
        names += list(self.draw)
        return list(dict.fromkeys(names))


@dataclass
class Tuning:
    path: pathlib.Path
    name: str
    description: str
    seed: int
    stop_time: float | None
    metrics_from_s: float | None
    parameters: list          # of Parameter
    objective: Objective
    constraints: Constraints
    robustness: ScenarioSet
    holdout: ScenarioSet | None
    sampler: str
    trials: int
    batch: int
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def parameter_names(self) -> list[str]:
        return [p.name for p in self.parameters]

    @property
    def bands(self) -> dict:
        """{column: (f_lo, f_hi, axis)} of the band terms: what the workers compute besides the usual metrics."""
        return {t.column: (t.band[0], t.band[1], t.axis) for t in self.objective.terms if t.metric == "band_rms"}


def _unknown(where: str, table: dict, allowed: set) -> None:
    unknown = sorted(set(table) - set(allowed), key=str)
    if unknown:
        raise TuneError(f"{where}unknown key {shown(unknown[0])}{did_you_mean(unknown[0], sorted(allowed))}; "
                        f"allowed: {', '.join(sorted(allowed))}")


def _number(where: str, value, positive: bool = False, minimum: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise TuneError(f"{where} must be a finite number, got {shown(value)}")
    if positive and not value > 0:
        raise TuneError(f"{where} must be positive, got {value!r}")
    if minimum is not None and value < minimum:
        raise TuneError(f"{where} must be >= {minimum:g}, got {value!r}")
    return float(value)


def _integer(where: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise TuneError(f"{where} must be an integer >= {minimum}, got {shown(value)}")
    return value


def _table(where: str, value) -> dict:
    if not isinstance(value, dict):
        raise TuneError(f"{where} must be a table, got {shown(value)}")
    return value


def _flatten(table: dict, prefix: str = "") -> dict:
    """Dotted keys written unquoted (controller.azimuth.kp = {...}) make nested tables: join them back,
    stopping at a parameter's own table (it has 'bounds')."""
    flat = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and not (set(value) & PARAMETER_KEYS or
                                            (len(value) == 1 and next(iter(value)) in DISTRIBUTIONS)):
            flat.update(_flatten(value, name + "."))
        else:
            flat[name] = value
    return flat


def _parameter(name: str, spec) -> Parameter:
    where = f"[parameters] '{excerpt(name)}'"
    if not isinstance(spec, dict):
        raise TuneError(f"{where}: expected {{ bounds = [low, high], scale = \"linear\" | \"log\" }}, got {shown(spec)}")
    _unknown(f"{where}: ", spec, PARAMETER_KEYS)
    if "bounds" not in spec:
        raise TuneError(f"{where}: 'bounds' = [low, high] is missing")
    bounds = spec["bounds"]
    if not (isinstance(bounds, list) and len(bounds) == 2):
        raise TuneError(f"{where}: 'bounds' must be [low, high], got {shown(bounds)}")
    low, high = (_number(f"{where}: bounds", b) for b in bounds)
    if not low < high:
        raise TuneError(f"{where}: bounds = [{low:g}, {high:g}]: low must be below high")
    if not math.isfinite(high - low):   # the samplers draw and scale by the width
        raise TuneError(f"{where}: bounds = [{low:g}, {high:g}] are {high - low:g} apart: their width must be a "
                        f"finite number (at most {sys.float_info.max:.3g})")
    scale = spec.get("scale", "linear")
    if scale not in SCALES:
        raise TuneError(f"{where}: 'scale' must be \"linear\" or \"log\", got {shown(scale)}"
                        f"{did_you_mean(scale, SCALES)}")
    if scale == "log" and not low > 0:
        raise TuneError(f"{where}: scale = \"log\" needs positive bounds, got [{low:g}, {high:g}]")
    start = spec.get("start")
    if start is not None:
        start = _number(f"{where}: start", start)
        if not low <= start <= high:
            raise TuneError(f"{where}: start = {start:g} is outside bounds [{low:g}, {high:g}]")
    parse_name(name)
    return Parameter(name, low, high, scale, start)


def _term(where: str, spec: dict, weight_allowed: bool) -> Term:
    _unknown(f"{where}: ", spec, TERM_KEYS if weight_allowed else OBJECTIVE_KEYS)
    metric = spec.get("metric", "los_rms")
    if metric not in METRICS or metric == "weighted" and weight_allowed:
        allowed = [m for m in METRICS if not (weight_allowed and m == "weighted")]
        raise TuneError(f"{where}: metric must be one of {', '.join(allowed)}, got {shown(metric)}"
                        f"{did_you_mean(metric, allowed)}")
    weight = _number(f"{where}: weight", spec.get("weight", 1.0), positive=True)
    band, axis = None, spec.get("axis", "both")
    if axis not in AXES:
        raise TuneError(f"{where}: axis must be one of {', '.join(AXES)}, got {shown(axis)}{did_you_mean(axis, AXES)}")
    if metric == "band_rms":
        value = spec.get("band")
        if not (isinstance(value, list) and len(value) == 2):
            raise TuneError(f"{where}: metric = \"band_rms\" needs band = [f_lo, f_hi] in Hz, got {shown(value)}")
        lo, hi = (_number(f"{where}: band", v, minimum=0.0) for v in value)
        if not lo < hi:
            raise TuneError(f"{where}: band = [{lo:g}, {hi:g}]: f_lo must be below f_hi")
        band = (lo, hi)
    elif "band" in spec:
        raise TuneError(f"{where}: 'band' belongs to metric = \"band_rms\" only")
    return Term(metric, weight, band, axis)


def _objective(raw) -> Objective:
    table = _table("[objective]", raw)
    _unknown("[objective]: ", table, OBJECTIVE_KEYS)
    aggregate = table.get("aggregate", "mean")
    if aggregate not in AGGREGATES:
        raise TuneError(f"[objective]: aggregate must be one of {', '.join(AGGREGATES)}, got {shown(aggregate)}"
                        f"{did_you_mean(aggregate, AGGREGATES)}")
    metric = table.get("metric", "los_rms")
    if metric == "weighted":
        terms = table.get("terms")
        if not (isinstance(terms, list) and terms and all(isinstance(t, dict) for t in terms)):
            raise TuneError("[objective]: metric = \"weighted\" needs terms = [{ metric = ..., weight = ... }, ...]")
        extra = set(table) & {"band", "axis"}
        if extra:
            raise TuneError(f"[objective]: '{sorted(extra)[0]}' goes into each term of a weighted objective")
        parsed = tuple(_term(f"[objective] terms[{i}]", t, True) for i, t in enumerate(terms))
    else:
        if "terms" in table:
            raise TuneError("[objective]: 'terms' belongs to metric = \"weighted\"")
        parsed = (_term("[objective]", {k: v for k, v in table.items() if k != "aggregate"}, False),)
    return Objective(parsed, aggregate, metric)


def _constraints(raw) -> Constraints:
    table = _table("[constraints]", raw)
    _unknown("[constraints]: ", table, CONSTRAINT_KEYS)
    values = {}
    if "peak_current_fraction" in table:
        values["peak_current_fraction"] = _number("[constraints] peak_current_fraction", table["peak_current_fraction"],
                                                  positive=True)
    if "voltage_saturation_max_s" in table:
        values["voltage_saturation_max_s"] = _number("[constraints] voltage_saturation_max_s",
                                                     table["voltage_saturation_max_s"], minimum=0.0)
    for key in ("gain_margin_min_db", "phase_margin_min_deg"):
        if key in table:
            values[key] = _number(f"[constraints] {key}", table[key])
    if "lower_gain_margin_min_db" in table:   # a size: the lower margin itself is negative
        drop = _number("[constraints] lower_gain_margin_min_db", table["lower_gain_margin_min_db"])
        if drop < 0:
            raise TuneError(f"[constraints] lower_gain_margin_min_db is the gain drop the loop must tolerate, in dB, "
                            f"at least 0 (20 asks for a lower gain margin of -20 dB or less), got {drop:g}")
        values["lower_gain_margin_min_db"] = drop
    if "on_target_min_fraction" in table:
        fraction = _number("[constraints] on_target_min_fraction", table["on_target_min_fraction"], positive=True)
        if fraction > 1.0:
            raise TuneError(f"[constraints] on_target_min_fraction is a share of the window, at most 1, got {fraction:g}")
        values["on_target_min_fraction"] = fraction
    if "requirements" in table:
        if not isinstance(table["requirements"], bool):
            raise TuneError(f"[constraints] requirements must be true or false, got {shown(table['requirements'])}")
        values["requirements"] = table["requirements"]
    return Constraints(**values)


def _scenario_set(section: str, raw, default_seed: int) -> ScenarioSet:
    table = _table(f"[{section}]", raw)
    _unknown(f"[{section}]: ", table, ROBUSTNESS_KEYS)
    seeds = _seeds(section, table.get("seeds", []))
    seas = _sea_states(section, table.get("sea_states", [{}]))
    draws = _integer(f"[{section}] draws", table.get("draws", 0), 0)
    over_limit(f"[{section}] draws", draws, MAX_SCENARIOS, " draws", TuneError)
    spec = _draw_spec(section, table.get("draw", {}))
    if draws and not spec:
        raise TuneError(f"[{section}] draws = {draws} needs a [{section}.draw] table of distributions")
    if spec and not draws:
        raise TuneError(f"[{section}.draw] is given but draws = 0: say how many draws (draws = N)")
    seed = _integer(f"[{section}] seed", table.get("seed", default_seed), 0)
    members = len(seas) * max(len(seeds), 1) * max(draws, 1)
    if members > MAX_SCENARIOS:   # every candidate runs on each
        raise TuneError(f"[{section}]: {len(seas)} sea states x {max(len(seeds), 1)} seeds x {max(draws, 1)} draws = "
                        f"{members:,} runs per candidate, over the limit of {MAX_SCENARIOS:,}")
    return ScenarioSet(seas, tuple(seeds), draws, spec, seed)


def _seeds(section: str, seeds) -> list:
    if not isinstance(seeds, list) or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds):
        raise TuneError(f"[{section}] seeds must be a list of non-negative integers (base_motion.seed values), "
                        f"got {shown(seeds)}")
    return seeds


def _sea_states(section: str, seas) -> tuple:
    """The sea states, each a flat table of scene overrides {name: value}."""
    if not isinstance(seas, list) or not seas or not all(isinstance(s, dict) for s in seas):
        raise TuneError(f"[{section}] sea_states must be a non-empty list of tables of scene overrides, got {shown(seas)}")
    seas = tuple(_flatten(s) for s in seas)
    for sea in seas:
        for name, value in sea.items():
            parse_name(name)
            if isinstance(value, (dict, list)):
                raise TuneError(f"[{section}] sea_states: '{excerpt(name)}' must be a value, got {shown(value)}")
    return seas


def _draw_spec(section: str, raw) -> dict:
    """[<section>.draw]: {name: distribution} as a sweep's [random] takes them."""
    spec = _flatten(_table(f"[{section}.draw]", raw))
    try:
        spec = {name: _check_distribution(name, value) for name, value in spec.items()}
    except SweepError as exc:
        raise TuneError(f"[{section}.draw] {str(exc).removeprefix('[random] ')}") from None
    for name in spec:
        parse_name(name)
    return spec


def load_tuning(path) -> Tuning:
    """The tuning file at `path`, checked; TuneError (one line, naming the file and the key) otherwise."""
    path = pathlib.Path(path)
    raw = read_toml(path, TuneError)
    try:
        _unknown("", raw, TOP_KEYS)
        name = raw.get("name", path.stem)
        if not isinstance(name, str) or not name.replace("_", "").replace("-", "").isalnum():
            raise TuneError("'name' must be a string of letters, digits, '_' and '-' (it names the result files)")
        seed = _integer("'seed'", raw.get("seed", 0), 0)
        over_limit("'seed'", seed, MAX_SAMPLER_SEED, " (the seeds Optuna's samplers take)", TuneError)
        stop_time, from_s = _times(raw)
        parameters = _parameters(raw)
        objective = _objective(raw.get("objective", {}))
        constraints = _constraints(raw.get("constraints", {}))
        robustness = _scenario_set("robustness", raw.get("robustness", {}), seed)
        holdout = _scenario_set("holdout", raw["holdout"], seed + 1) if "holdout" in raw else None
        _check_not_tuned(parameters, robustness, holdout)
        sampler, trials, batch = _optimizer(raw.get("optimizer", {}), len(parameters))
        description = raw.get("description", "")
        if not isinstance(description, str):
            raise TuneError(f"'description' must be a string, got {shown(description)}")
        too_long("'description'", len(description), MAX_DESCRIPTION_CHARS, error=TuneError)
    except TuneError as exc:
        raise TuneError(f"{path}: {exc}") from None
    return Tuning(path=path, name=name, description=description, seed=seed, stop_time=stop_time,
                  metrics_from_s=from_s, parameters=parameters, objective=objective, constraints=constraints,
                  robustness=robustness, holdout=holdout, sampler=sampler, trials=trials, batch=batch, raw=raw)


def _times(raw: dict) -> tuple:
    """(stop_time, metrics_from_s), each None when not given."""
    stop_time = raw.get("stop_time")
    if stop_time is not None:
        stop_time = _number("'stop_time'", stop_time, positive=True)
    from_s = raw.get("metrics_from_s")
    if from_s is not None:
        from_s = _number("'metrics_from_s'", from_s, minimum=0.0)
        check_metrics_window(from_s, stop_time, error=TuneError)
    return stop_time, from_s


def _parameters(raw: dict) -> list:
    if "parameters" not in raw:
        raise TuneError("nothing to tune: give a [parameters] table of name = { bounds = [low, high] }")
    parameters = [_parameter(n, s) for n, s in _flatten(_table("[parameters]", raw["parameters"])).items()]
    if not parameters:
        raise TuneError("[parameters] is empty: nothing to tune")
    over_limit("[parameters]: the number of tuned parameters", len(parameters), MAX_TUNE_PARAMETERS, "",
               TuneError)
    return parameters


def _check_not_tuned(parameters: list, robustness: ScenarioSet, holdout: ScenarioSet | None) -> None:
    """A scenario must not set what is tuned: it would overwrite the candidate's value."""
    tuned = {p.name for p in parameters}
    for section, scenario_set in (("robustness", robustness), ("holdout", holdout)):
        clash = tuned & set(scenario_set.names) if scenario_set else set()
        if clash:
            raise TuneError(f"[{section}] sets '{sorted(clash)[0]}', which is tuned in [parameters]")


def _optimizer(raw, parameter_count: int) -> tuple:
    """[optimizer]: (sampler, trials, batch)."""
    optimizer = _table("[optimizer]", raw)
    _unknown("[optimizer]: ", optimizer, OPTIMIZER_KEYS)
    sampler = optimizer.get("sampler", "cmaes")
    if sampler not in SAMPLERS:
        raise TuneError(f"[optimizer] sampler must be one of {', '.join(SAMPLERS)}, got {shown(sampler)}"
                        f"{did_you_mean(sampler, SAMPLERS)}")
    trials = _integer("[optimizer] trials", optimizer.get("trials", 60), 1)
    over_limit("[optimizer] trials", trials, MAX_TUNE_TRIALS, " candidates", TuneError)
    default_batch = 4 + int(3 * math.log(parameter_count))   # CMA-ES's default population
    batch = _integer("[optimizer] batch", optimizer.get("batch", default_batch), 1)
    over_limit("[optimizer] batch", batch, MAX_TUNE_BATCH, " candidates", TuneError)
    return sampler, trials, batch
