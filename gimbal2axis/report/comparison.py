"""A comparison file (TOML) and its runs: one scene, every gyro grade under every stabilization
scheme, with the same sea, seed and encoders.

  title = "Gyro grade and stabilization scheme on the ship"
  description = "..."
  scene = "../scenes/ship_stabilization.toml"   # relative to this file
  stop_time = 30.0                              # optional: shortens the scene's run
  schemes = ["direct", "indirect"]              # default: both
  repeats = 5                                   # optional: runs per case, the sensors' seed + 0, 1, ...
  [sensors]                                     # optional: over the scene's [sensors] in every run
  encoder_resolution_deg = 0.0007
  [analysis]                                    # optional: replaces the scene's [analysis]
  bands = { sea = [0.0, 1.0], loop = [1.0, 20.0], high = [20.0, 500.0] }
  [grades.fog]                                  # one table per grade: a [sensors.gyro] datasheet
  label = "tactical FOG"                        # optional: its name in the page
  angle_random_walk_deg_rt_h = 0.05
  ...
"""
from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError, check_keys, positive
from ..limits import read_toml
from ..master import run
from ..scene import load_scene
from ..scene.gyro import GyroModel
from ..scene.sensors import SCHEMES, Sensors

KEYS = {"title", "description", "scene", "stop_time", "schemes", "repeats", "sensors", "analysis", "grades"}
MAX_REPEATS = 100


@dataclass
class Case:
    grade: str       # the grade's key in the file
    label: str       # its name in the page
    scheme: str      # direct or indirect
    scene: object    # the scene with this case's sensors

    @property
    def name(self) -> str:
        return f"{self.label}, {self.scheme}"


@dataclass
class Comparison:
    path: pathlib.Path
    title: str
    description: str
    scene: object
    stop_time: float
    cases: list
    repeats: int = 1   # runs per case, each with its own sensor noise (seed + 0, 1, ...)


def _grade_cases(scene, grades: dict, schemes: list, common: dict, analysis: dict | None) -> list[Case]:
    cases = []
    for key, table in grades.items():
        if not isinstance(table, dict):
            raise SceneError(f"grades.{key} must be a table ([grades.{key}]) of a gyro's datasheet")
        gyro = {k: v for k, v in table.items() if k != "label"}
        label = str(table.get("label", key))
        for scheme in schemes:
            GyroModel(gyro, where=f"grades.{key}")   # a wrong datasheet refused by its name in this file
            sensors = {**scene.sensors_spec, **common, "gyro": gyro, "stabilization": scheme}
            Sensors(sensors)   # and the shared sensors, before any run
            changes = {"sensors_spec": sensors}
            if analysis is not None:
                changes["analysis_spec"] = analysis
            cases.append(Case(key, label, scheme, scene.with_changes(**changes)))
    return cases


def load_comparison(path: pathlib.Path | str) -> Comparison:
    """Reads and checks a comparison file; SceneError naming the file and the key otherwise."""
    path = pathlib.Path(path)
    raw = read_toml(path)
    try:
        check_keys("comparison", raw, KEYS)
        if "scene" not in raw or "grades" not in raw:
            raise SceneError("needs scene = \"<scene file>\" and at least one [grades.<name>] table")
        scene = load_scene((path.parent / str(raw["scene"])).resolve())
        stop_time = _stop_time(raw, scene)
        schemes, common, grades = _schemes(raw), _common_sensors(raw), _grades(raw)
        analysis = raw.get("analysis")
        repeats = raw.get("repeats", 1)
        if isinstance(repeats, bool) or not isinstance(repeats, int) or not 1 <= repeats <= MAX_REPEATS:
            raise SceneError(f"repeats must be an integer in [1, {MAX_REPEATS}], got {repeats!r}")
        cases = _grade_cases(scene, grades, schemes, common, analysis)
        if scene.target_spec is None:
            raise SceneError(f"the scene {scene.path.name} has no [target]: there is no line-of-sight error to compare")
    except SceneError as exc:
        raise SceneError(f"{path}: {exc}") from None
    return Comparison(path, str(raw.get("title", path.stem)), str(raw.get("description", "")), scene, stop_time, cases,
                      repeats)


def _stop_time(raw: dict, scene) -> float:
    """The runs' end: within the scene's, on one of its steps."""
    stop_time = positive("stop_time", raw.get("stop_time", scene.stop_time))
    if stop_time > scene.stop_time * (1 + 1e-12):
        raise SceneError(f"stop_time {stop_time:g} is after the scene's ({scene.stop_time:g} s)")
    steps = stop_time / scene.step_size
    if abs(steps - round(steps)) > 1e-9 * max(steps, 1.0):
        raise SceneError(f"stop_time {stop_time:g} is not a whole number of the scene's steps ({scene.step_size:g} s)")
    return stop_time


def _schemes(raw: dict) -> list:
    schemes = raw.get("schemes", list(SCHEMES))
    if not isinstance(schemes, list) or not schemes or any(s not in SCHEMES for s in schemes):
        raise SceneError(f"schemes must be a non-empty list of {', '.join(repr(s) for s in SCHEMES)}, got {schemes!r}")
    return schemes


def _common_sensors(raw: dict) -> dict:
    common = raw.get("sensors", {})
    if not isinstance(common, dict) or "gyro" in common or "stabilization" in common:
        raise SceneError("[sensors] must be a table of the sensors shared by every case (without gyro, which "
                         "the grades give, and stabilization, which schemes gives)")
    return common


def _grades(raw: dict) -> dict:
    grades = raw["grades"]
    if not isinstance(grades, dict) or not grades:
        raise SceneError("[grades] must hold at least one [grades.<name>] table")
    return grades


def repeat_scene(case: Case, repeat: int):
    """The case's scene with its sensors' seed moved on by `repeat` (0: as given)."""
    if repeat == 0:
        return case.scene
    sensors = dict(case.scene.sensors_spec)
    sensors["seed"] = int(sensors.get("seed", 0)) + repeat
    return case.scene.with_changes(sensors_spec=sensors)


def run_comparison(comparison: Comparison, fmu, progress: bool = True) -> list:
    """(case, [RunResult of each repeat]) of every case, in the file's order."""
    return [(case, [run(repeat_scene(case, r), fmu, stop_time=comparison.stop_time, progress=progress)
                    for r in range(comparison.repeats)]) for case in comparison.cases]


def run_metrics(result) -> dict:
    metrics = result.los_metrics()
    values = {"los_rms_mrad": metrics["rms"] * 1e3, "los_max_mrad": metrics["max"] * 1e3}
    for name, spectrum in result.los_spectra().items():
        values[f"{name}_std_mrad"] = math.sqrt(float(spectrum.psd.sum() * spectrum.resolution)) * 1e3
        values[f"{name}_mean_mrad"] = spectrum.mean * 1e3
    values.update({f"band_{band}_mrad": value * 1e3 for band, value in result.band_rms().items()})
    return values


def table_rows(results: list) -> list[dict]:
    """One row per case: the line-of-sight error's RMS (total, per axis, per band) and maximum, mrad,
    each the mean over the case's repeats; los_rms_spread_mrad is the RMS's standard deviation over
    them (0 with one run): differences between cases smaller than a few spreads say nothing."""
    rows = []
    for case, runs in results:
        per_run = [run_metrics(result) for result in runs]
        row = {"case": case.name, "grade": case.label, "scheme": case.scheme, "runs": len(runs)}
        for key in per_run[0]:
            row[key] = float(np.mean([m[key] for m in per_run]))
            if key == "los_rms_mrad":
                spread = float(np.std([m[key] for m in per_run], ddof=1)) if len(per_run) > 1 else 0.0
                row["los_rms_spread_mrad"] = spread
        rows.append(row)
    return rows
