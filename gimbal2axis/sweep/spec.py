"""Sweep descriptions (sweeps/*.toml): loading, expansion into cases, applying a case to a scene,
and the stable case key.

A sweep file (TOML, comments allowed):

  name = "gains"              # names the result files (default: the file's stem)
  description = "..."
  cases = 1000                # upper limit on the number of cases (see below)
  seed = 1                    # seed of the random sampling (default 0)
  samples = 10                # random draws per grid point (default: cases // grid points, else 1)
  stop_time = 0.5             # optional: every case ends here instead of the scene's stop_time
  metrics_from_s = 0.2        # optional: line-of-sight metrics over [from, end] (default: the scene's
                              # [requirements] from_s when the run reaches it, else the whole run)

  [grid]                      # every combination of these values (Cartesian product)
  "controller.azimuth.kp" = [200.0, 400.0, 800.0]
  "gear1.k_s" = { geomspace = [1e3, 1e5, 5] }       # or linspace = [a, b, n]

  [random]                    # drawn independently per case, reproducibly from `seed`
  "controller.azimuth.ki" = { uniform = [1000.0, 10000.0] }
  "gear1.eta" = { loguniform = [1e-4, 1e-2] }
  "body2.m" = { normal = [2.0, 0.1] }
  "base_motion.seed" = { integers = [0, 9999] }      # inclusive
  "gear1.model" = { choice = [0, 1, 2] }

Cases: grid points x samples, the first grid parameter varying slowest, then truncated to `cases`
(Sweep.limit_warning says what that leaves out; the runner prints it). Sample j of every grid
point uses the same random draws (common random numbers); each parameter has its own
random stream (seeded by `seed` and its name), so adding a parameter or raising `cases`/`samples`
leaves the draws of the others, and the cases already run, unchanged.

Parameter names (paths into the scene):
  parameters.<FMU name>, fidelity.<FMU name>, initial.<state>   the scene's flat tables (an angle state
                                also as initial.<state>_deg, in degrees: it replaces the scene's angle
                                in either unit)
  controller.<key>[.<key>...]   the scene's [controller] (e.g. controller.azimuth.kp; list items
                                by index: controller.K.0.2)
  base_motion.<key>[...]        e.g. base_motion.seed, base_motion.roll.significant_amplitude_deg
  sensors.<key>, target.<key>   likewise
  stop_time                     the scene's end time
  <FMU name>                    shorthand: a structural switch goes to [fidelity], any other
                                parameter to [parameters] (e.g. "gear1.k_s", "body2.m")
"""
from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import pathlib
import re
import zlib
from dataclasses import dataclass, field

import numpy as np

from ..errors import SceneError, did_you_mean, excerpt, positive, shown
from ..limits import read_toml
from ..limits import MAX_DESCRIPTION_CHARS, MAX_SWEEP_CASES, over_limit, too_long
from ..scene.scene import Scene

TOP_KEYS = {"name", "description", "cases", "seed", "samples", "stop_time", "metrics_from_s", "grid", "random"}
FLAT_SECTIONS = {"parameters", "fidelity", "initial"}
NESTED_SECTIONS = {"controller": "controller_spec", "base_motion": "base_motion_spec", "sensors": "sensors_spec",
                   "target": "target_spec"}
DISTRIBUTIONS = {"uniform", "loguniform", "normal", "integers", "choice"}
# The values of a grid parameter a warning lists at most (a linspace may have a million).
WARNING_VALUES = 8
# A swept target.* on a scene without [target] starts from load_scene's defaults of a [target].
NO_TARGET = {"azimuth_deg": 0.0, "elevation_deg": 0.0, "start_on_target": False}


class SweepError(ValueError):
    """A sweep file that cannot be expanded; the message says where and why."""


@dataclass
class Sweep:
    path: pathlib.Path
    name: str
    description: str
    cases_limit: int | None
    seed: int
    samples: int | None
    stop_time: float | None
    metrics_from_s: float | None
    grid: dict = field(default_factory=dict)      # name -> list of values
    random: dict = field(default_factory=dict)    # name -> {distribution: args}
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def parameters(self) -> list[str]:
        return list(self.grid) + [n for n in self.random if n not in self.grid]

    @property
    def grid_points(self) -> int:
        return math.prod(len(values) for values in self.grid.values())

    @property
    def samples_per_point(self) -> int:
        if not self.random:
            return 1
        if self.samples is not None:
            return self.samples
        return max(1, self.cases_limit // self.grid_points) if self.cases_limit else 1

    @property
    def full_size(self) -> int:
        """Cases before the `cases` limit: grid points x samples."""
        return self.grid_points * self.samples_per_point

    def expand(self) -> list[dict]:
        """The cases: one dict {parameter name: value} per case, in a fixed order."""
        names = list(self.grid)
        # lazily, up to the `cases` limit: the full product may be far larger than what is run
        points = (dict(zip(names, combo)) for combo in itertools.product(*(self.grid[n] for n in names)))
        if self.random:
            samples = self.samples_per_point
            draws = {name: draw(name, spec, samples, self.seed) for name, spec in self.random.items()}
            cases = (dict(point, **{name: values[j] for name, values in draws.items()})
                     for point in points for j in range(samples))
        else:
            cases = points
        return list(itertools.islice(cases, self.cases_limit))

    def drive_warning(self) -> str | None:
        """A sweep over a motor's drive (voltage or current) with the controller's gains as they are:
        the same numbers are volts per unit in one case and amperes in the other (docs/scenes.md,
        "Current-commanded drives"); in words, None when no drive is swept."""
        swept = [name for name in self.parameters if re.fullmatch(r"(?:fidelity\.)?motor[12]\.drive", name)]
        if not swept:
            return None
        return (f"{', '.join(swept)} is swept: the controller's gains and limits are volts per unit where a "
                f"motor is voltage-driven and amperes per unit where it is current-driven, the same numbers "
                f"in both; sweep a scene per drive with its own gains to compare tuned loops")

    def limit_warning(self) -> str | None:
        """What a `cases` limit below grid points x samples leaves out, in words; None when nothing."""
        limit, full = self.cases_limit, self.full_size
        if limit is None or limit >= full:
            return None
        text = self._what_the_limit_keeps()
        missing = self._never_run()
        if missing:
            text += f"; never run: {'; '.join(missing)}"
        if full > MAX_SWEEP_CASES:
            return text + f". A sweep runs at most {MAX_SWEEP_CASES:,} cases: split the grid to run them all."
        return text + f". Raise 'cases' to {full} (or leave it out) to run them all."

    def _what_the_limit_keeps(self) -> str:
        limit, full = self.cases_limit, self.full_size
        points, samples = self.grid_points, self.samples_per_point
        shape = " x ".join(str(len(v)) for v in self.grid.values())
        grid = f"{shape} = {points} grid points" if len(self.grid) > 1 else f"{points} grid points"
        order = "the cases go in order, the first grid parameter varying slowest, so the limit keeps"
        if not self.grid:
            return f"cases = {limit} runs the first {limit} of the {samples} samples"
        if samples == 1:
            return f"cases = {limit} runs {limit} of the {grid}: {order} the first {limit} and drops the last " \
                   f"{points - limit}"
        whole, part = divmod(limit, samples)
        dropped = points - whole - (part > 0)
        kept = [f"{'grid point 1' if whole == 1 else f'the first {whole} grid points'} with all {samples} "
                f"samples"] if whole else []
        kept += [f"grid point {whole + 1} with {part} of its {samples} samples"] if part else []
        return (f"cases = {limit} runs {limit} of the {full} cases ({grid} x {samples} samples): {order} "
                + " and ".join(kept)
                + (f", and drops the last {dropped} grid point{'s' * (dropped != 1)}" if dropped else ""))

    def _never_run(self) -> list:
        """'name = values' of the grid values no kept case has."""
        kept_cases = self.expand()
        missing = []
        for name, values in self.grid.items():
            seen = {repr(c[name]) for c in kept_cases}
            absent = [f"{v:g}" if isinstance(v, float) else excerpt(str(v)) for v in values if repr(v) not in seen]
            if absent:
                more = f" and {len(absent) - WARNING_VALUES:,} more" if len(absent) > WARNING_VALUES else ""
                missing.append(f"{excerpt(name)} = {', '.join(absent[:WARNING_VALUES])}{more}")
        return missing


def _plain(value):
    """Python scalars (numpy's become int/float/bool), for TOML-like values, JSON and Parquet."""
    if isinstance(value, np.generic):
        return value.item()
    return value


def _grid_values(name: str, spec) -> list:
    if isinstance(spec, list):
        if not spec:
            raise SweepError(f"[grid] '{excerpt(name)}': empty list")
        return [_plain(v) for v in spec]
    if isinstance(spec, dict) and len(spec) == 1:
        (kind, args), = spec.items()
        if kind in ("linspace", "geomspace") and isinstance(args, list) and len(args) == 3:
            return _spaced_values(name, kind, *args)
    raise SweepError(f"[grid] '{excerpt(name)}': expected a list of values, {{ linspace = [a, b, n] }} or "
                     f"{{ geomspace = [a, b, n] }}, got {shown(spec)}")


def _spaced_values(name: str, kind: str, a, b, n) -> list:
    """The values of { linspace = [a, b, n] } or { geomspace = [a, b, n] }."""
    _finite_numbers(f"[grid] '{excerpt(name)}': {kind}", [a, b])
    if not _is_count(n):
        raise SweepError(f"[grid] '{excerpt(name)}': {kind} = [start, stop, count], count a positive integer")
    over_limit(f"[grid] '{excerpt(name)}': {kind} count", n, MAX_SWEEP_CASES, " values", SweepError)
    if kind == "geomspace" and not (a > 0 and b > 0):
        raise SweepError(f"[grid] '{excerpt(name)}': geomspace needs positive bounds")
    return [float(v) for v in getattr(np, kind)(float(a), float(b), n)]


def _is_count(value) -> bool:
    """A positive integer (a bool is none)."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 1


def _finite_numbers(where: str, values: list) -> None:
    """Grid and distribution bounds: numbers a case could be given, refused here, not case by case."""
    for value in values:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise SweepError(f"{where}: {shown(value)} is not a finite number")


# (the kinds it applies to, whether their [a, b] are wrong, what is said after "[random] 'name': "), in
# this order, once the arguments are a list of the right length and, but for choice, finite numbers
_DISTRIBUTION_REFUSALS = [
    (("normal",), lambda args: args[1] < 0,
     lambda kind, args: f"normal = [mean, std] needs std >= 0, got {args[1]:g}"),
    (("loguniform",), lambda args: not (args[0] > 0 and args[1] > 0),
     lambda kind, args: "loguniform needs positive bounds"),
    (("integers",), lambda args: not all(isinstance(v, int) and not isinstance(v, bool) for v in args),
     lambda kind, args: "integers needs integer bounds"),
    (("uniform", "loguniform", "integers"), lambda args: not args[0] <= args[1],
     lambda kind, args: f"{kind} = [{args[0]:g}, {args[1]:g}] needs low <= high"),
    (("uniform",), lambda args: not math.isfinite(args[1] - args[0]),   # numpy draws low + width * u
     lambda kind, args: f"uniform = [{args[0]:g}, {args[1]:g}] are {args[1] - args[0]:g} apart: their width must be a "
                        f"finite number"),
]


def _check_distribution(name: str, spec) -> dict:
    if not (isinstance(spec, dict) and len(spec) == 1 and next(iter(spec)) in DISTRIBUTIONS):
        raise SweepError(f"[random] '{excerpt(name)}': expected one of {{ uniform = [a, b] }}, {{ loguniform = [a, b] }}, "
                         f"{{ normal = [mean, std] }}, {{ integers = [low, high] }}, {{ choice = [values] }}; got {shown(spec)}")
    (kind, args), = spec.items()
    if not isinstance(args, list) or (kind != "choice" and len(args) != 2) or not args:
        raise SweepError(f"[random] '{excerpt(name)}': {kind} needs " + ("a non-empty list" if kind == "choice" else "[a, b]"))
    if kind != "choice":
        _finite_numbers(f"[random] '{excerpt(name)}': {kind}", args)
    for kinds, wrong, message in _DISTRIBUTION_REFUSALS:
        if kind in kinds and wrong(args):
            raise SweepError(f"[random] '{excerpt(name)}': " + message(kind, args))
    return spec


def draw(name: str, spec: dict, n: int, seed: int) -> list:
    """n draws of one parameter from its own stream (seed, crc32(name)): prefix-stable in n."""
    rng = np.random.default_rng([seed, zlib.crc32(name.encode())])
    (kind, args), = spec.items()
    if kind == "uniform":
        values = rng.uniform(args[0], args[1], n)
    elif kind == "loguniform":
        values = np.exp(rng.uniform(math.log(args[0]), math.log(args[1]), n))
    elif kind == "normal":
        values = rng.normal(args[0], args[1], n)
    elif kind == "integers":
        values = rng.integers(args[0], args[1], n, endpoint=True)
    else:
        return [_plain(args[i]) for i in rng.integers(0, len(args), n)]
    return [_plain(v) for v in values]


def load_sweep(path: pathlib.Path | str) -> Sweep:
    path = pathlib.Path(path)
    raw = read_toml(path, SweepError)
    try:
        _check_tables(raw)
        grid, random = _parameters(raw)
        cases, samples, seed = _counts(raw)
        _check_times(raw)
        name, description = _name_and_description(raw, path)
        sweep = Sweep(path=path, name=name, description=description, cases_limit=cases, seed=seed, samples=samples,
                      stop_time=raw.get("stop_time"), metrics_from_s=raw.get("metrics_from_s"), grid=grid,
                      random=random, raw=raw)
        _check_size(sweep)
    except SweepError as exc:
        raise SweepError(f"{path}: {exc}") from None
    return sweep


def _check_tables(raw: dict) -> None:
    unknown = set(raw) - TOP_KEYS
    if unknown:
        raise SweepError(f"unknown key(s) {[excerpt(key) for key in sorted(unknown)[:5]]}"
                         f"{did_you_mean(sorted(unknown)[0], sorted(TOP_KEYS))}; allowed: {sorted(TOP_KEYS)}")
    for key in ("grid", "random"):
        if not isinstance(raw.get(key, {}), dict):
            raise SweepError(f"'{key}' must be a table ([{key}])")


def _parameters(raw: dict) -> tuple:
    """({name: grid values}, {name: distribution}) of [grid] and [random]."""
    grid = {name: _grid_values(name, spec) for name, spec in _flatten_names(raw.get("grid", {})).items()}
    random = {name: _check_distribution(name, spec) for name, spec in _flatten_names(raw.get("random", {})).items()}
    both = set(grid) & set(random)
    if both:
        raise SweepError(f"parameter(s) {sorted(both)} both in [grid] and [random]")
    if not grid and not random:
        raise SweepError("nothing to sweep: give a [grid] and/or a [random] table")
    for name in list(grid) + list(random):
        parse_name(name)
    return grid, random


def _counts(raw: dict) -> tuple:
    """(cases, samples, seed)."""
    cases = raw.get("cases")
    if cases is not None and not _is_count(cases):
        raise SweepError("'cases' must be a positive integer")
    samples = raw.get("samples")
    if samples is not None and not _is_count(samples):
        raise SweepError("'samples' must be a positive integer")
    if samples is not None:   # every random parameter draws `samples` values up front
        over_limit("'samples'", samples, MAX_SWEEP_CASES, " draws per grid point", SweepError)
    seed = raw.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise SweepError("'seed' must be a non-negative integer")
    return cases, samples, seed


def _check_times(raw: dict) -> None:
    for key in ("stop_time", "metrics_from_s"):
        value = raw.get(key, 0.0)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (0 <= value < math.inf):
            raise SweepError(f"'{key}' must be a finite number >= 0, got {shown(value)}")
    if raw.get("stop_time", 1.0) == 0:
        raise SweepError("'stop_time' must be positive: every case ends there")
    check_metrics_window(raw.get("metrics_from_s"), raw.get("stop_time"))


def _name_and_description(raw: dict, path: pathlib.Path) -> tuple:
    name = raw.get("name", path.stem)
    if not isinstance(name, str) or not name.replace("_", "").replace("-", "").isalnum():
        raise SweepError("'name' must be a string of letters, digits, '_' and '-' (it names the result files)")
    description = raw.get("description", "")
    if not isinstance(description, str):
        raise SweepError(f"'description' must be a string, got {shown(description)}")
    too_long("'description'", len(description), MAX_DESCRIPTION_CHARS, error=SweepError)
    return name, description


def _check_size(sweep: Sweep) -> None:
    """Refuses a sweep that would run more than MAX_SWEEP_CASES cases, or draw more values than that."""
    if sweep.cases_limit is not None:
        over_limit("'cases'", sweep.cases_limit, MAX_SWEEP_CASES, " cases", SweepError)
    elif sweep.full_size > MAX_SWEEP_CASES:
        raise SweepError(f"grid points x samples = {sweep.full_size:,} cases is over the limit of {MAX_SWEEP_CASES:,} "
                         "cases; set 'cases' to run the first of them")


def _flatten_names(table: dict, prefix: str = "") -> dict:
    """Unquoted dotted keys (controller.azimuth.kp = [...]) make nested tables: join them back,
    stopping at a value spec (a list, or a one-key table naming a grid or distribution kind)."""
    flat = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and not (len(value) == 1 and next(iter(value)) in DISTRIBUTIONS | {"linspace", "geomspace"}):
            flat.update(_flatten_names(value, name + "."))
        else:
            flat[name] = value
    return flat


def parse_name(name: str) -> tuple[str, list]:
    """(section, path): section one of FLAT_SECTIONS, NESTED_SECTIONS, 'stop_time' or 'fmu' (a bare
    FMU name, resolved against the FMU by names.resolve_names); path the key (flat) or list of keys
    (nested)."""
    head, _, rest = name.partition(".")
    if name == "stop_time":
        return "stop_time", []
    if head in FLAT_SECTIONS:
        if not rest:
            raise SweepError(f"'{excerpt(name)}': give the variable, e.g. {head}.gear1.k_s")
        return head, [rest]
    if head in NESTED_SECTIONS:
        if not rest:
            raise SweepError(f"'{excerpt(name)}': give the key, e.g. {head}.<key>")
        return head, [int(k) if k.isdigit() else k for k in rest.split(".")]
    return "fmu", [name]


def _set_nested(table, path: list, value, name: str):
    node = table
    for key in path[:-1]:
        if isinstance(node, list):
            if not (isinstance(key, int) and key < len(node)):
                raise SceneError(f"'{excerpt(name)}': no item {key} in the list")
            node = node[key]
        else:
            node = node.setdefault(key, {})
    last = path[-1]
    if isinstance(node, list):
        if not (isinstance(last, int) and last < len(node)):
            raise SceneError(f"'{excerpt(name)}': no item {last} in the list")
    elif not isinstance(node, dict):
        raise SceneError(f"'{excerpt(name)}': {'.'.join(map(str, path[:-1]))} is not a table")
    node[last] = value


def check_metrics_window(from_s: float | None, stop_time: float | None, whose: str = "stop_time",
                         error: type = SweepError) -> None:
    """Refuses a metrics window [from_s, end] that starts at or after the stop time of the runs
    (`whose` says which stop time): its metrics would be those of another window. A sweep's and a
    tuning's own stop_time, and that of each case (the scene's, or a swept one)."""
    if from_s is not None and stop_time is not None and not from_s < stop_time:
        raise error(f"'metrics_from_s' = {from_s:g} must be below {whose} = {stop_time:g}: the metrics are over "
                    f"[metrics_from_s, stop time]")


def check_cases_window(from_s: float | None, scenes, error: type = SweepError) -> None:
    """check_metrics_window for the stop time of each case's scene (None: a case refused already)."""
    for index, scene in enumerate(scenes):
        if scene is not None:
            check_metrics_window(from_s, scene.stop_time, f"the stop time of case {index}", error)


def apply_case(scene: Scene, resolved: dict, case: dict, stop_time: float | None = None) -> Scene:
    """The scene with the case's values (and the sweep's stop_time) put in; validated (SceneError)."""
    changes: dict = {}
    if stop_time is not None:
        changes["stop_time"] = float(stop_time)
    for name, value in case.items():
        section, path = resolved[name]
        if section == "stop_time":
            changes["stop_time"] = positive("stop_time", value)
        elif section in FLAT_SECTIONS:
            table = changes.setdefault(section, dict(getattr(scene, section)))
            if section == "initial":
                # beta_deg replaces the scene's beta (which load_scene made of its beta_deg), and the other
                # way round: the same angle in both units would be refused
                name_in_other_unit = path[0].removesuffix("_deg") if path[0].endswith("_deg") else path[0] + "_deg"
                if f"initial.{name_in_other_unit}" not in case:
                    table.pop(name_in_other_unit, None)
            table[path[0]] = value
        else:
            attr = NESTED_SECTIONS[section]
            if attr not in changes:
                changes[attr] = copy.deepcopy(getattr(scene, attr) or ({} if section != "target" else NO_TARGET))
            _set_nested(changes[attr], path, value, name)
    return scene.with_changes(**changes)


def canonical(value) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=_plain)


def scene_hash(scene: Scene) -> str:
    """Of the scene's content (its parsed TOML: comments and layout do not count)."""
    return hashlib.sha256(canonical(scene.raw).encode()).hexdigest()[:12]


def case_key(scene_digest: str, sweep: Sweep, case: dict) -> str:
    """Stable id of a case: its parameter values, the scene's content and the sweep's stop time and
    metrics window (not the FMU: a rebuilt FMU keeps the rows; see --redo)."""
    payload = {"scene": scene_digest, "stop_time": sweep.stop_time, "metrics_from_s": sweep.metrics_from_s,
               "case": {k: _plain(v) for k, v in case.items()}}
    return hashlib.sha256(canonical(payload).encode()).hexdigest()[:16]
