"""Checking a sweep's parameter names against the FMU and the scene before any case runs, and
suggesting the closest valid names for a misspelt one.

FMU names (bare, parameters., fidelity., initial.) are judged by the FMU's model description. For
paths into the scene's tables (controller., base_motion., ...) the scene's own validation is the
judge: every case sets every swept name, so a name is good when at least one case passes it. The
list of valid names below only feeds the suggestions: a key it does not know (say, one gimbal2axis.scene
adds later) is never refused for that.
"""
from __future__ import annotations

import difflib

from ..scene import base_motion, controllers, gyro, references, sensors
from ..errors import LONGEST_NAME_TO_MATCH, SceneError, excerpt, shown
from ..fmu import FIDELITY
from ..scene.scene import ANGLE_STATES, check_against_fmu

from .spec import FLAT_SECTIONS, NESTED_SECTIONS, SweepError, apply_case, parse_name

PARAMETER_CAUSALITIES = {"parameter", "structuralParameter"}
# Keys of [base_motion] and of its axis tables that gimbal2axis.scene checks inline (not exported).
BASE_MOTION_KEYS = {"type", "components", "seed", "file"}
BASE_AXIS_KEYS = {"significant_amplitude_deg", "significant_amplitude_m", "peak_period_s", "gamma", "components",
                  "amplitude_deg", "amplitude_m", "period_s", "frequency_hz", "phase_deg", "offset_deg"}
TARGET_KEYS = {"azimuth_deg", "elevation_deg", "start_on_target"}
LIST_KEYS = {"K", "ki", "voltage_V"}   # lists in [controller]: swept by item (controller.K.0.2)


def fmu_parameters(fmu) -> list[str]:
    return [name for name, v in fmu.variables.items() if v.causality in PARAMETER_CAUSALITIES]


def _leaf_paths(node, prefix: str) -> list[str]:
    """Dotted paths of the values in a scene table (list items by index, as the sweep names them)."""
    if isinstance(node, dict):
        return [p for key, value in node.items() for p in _leaf_paths(value, f"{prefix}.{key}")]
    if isinstance(node, list):
        return [p for i, value in enumerate(node) for p in _leaf_paths(value, f"{prefix}.{i}")]
    return [prefix]


def _reference_keys(prefix: str) -> list[str]:
    keys = {"type"} | set().union(*references.KINDS.values())
    return [f"{prefix}.reference.{k}" for k in sorted(keys)]


def valid_names(scene, fmu) -> list[str]:
    """Names a sweep could use with this scene and FMU: the vocabulary of the suggestions."""
    names = ["stop_time"] + _fmu_names(fmu)
    for section, attr in NESTED_SECTIONS.items():
        names += _leaf_paths(getattr(scene, attr) or {}, section)
    names += _controller_names() + _sensor_names()
    names += [f"target.{k}" for k in sorted(TARGET_KEYS)]
    names += _base_motion_names()
    return list(dict.fromkeys(names))


def _fmu_names(fmu) -> list[str]:
    parameters = fmu_parameters(fmu)
    return (parameters + [f"parameters.{p}" for p in parameters if p not in FIDELITY]
            + [f"fidelity.{f}" for f in FIDELITY] + [f"initial.{s}" for s in fmu.states]
            + [f"initial.{s}_deg" for s in fmu.states if s in ANGLE_STATES])


def _controller_names() -> list[str]:
    names = [f"controller.{k}" for k in sorted(controllers.CONTROLLER_KEYS - LIST_KEYS - {"options"})
             if k not in controllers.AXES]
    names += [f"controller.K.{i}.{j}" for i in range(2) for j in range(4)]
    names += [f"controller.{k}.{i}" for k in ("ki", "voltage_V") for i in range(2)]
    names += _reference_keys("controller")
    for axis in controllers.AXES:
        names += [f"controller.{axis}.{k}" for k in sorted(controllers.PID_KEYS) if k != "reference"]
        names += _reference_keys(f"controller.{axis}")
    return names


def _sensor_names() -> list[str]:
    return ([f"sensors.{k}" for k in sorted(sensors.KEYS - {"gyro", "encoder_offset_deg"})]
            + [f"sensors.encoder_offset_deg.{i}" for i in range(2)]
            + [f"sensors.gyro.{k}" for k in sorted(gyro.GYRO_KEYS)])


def _base_motion_names() -> list[str]:
    names = [f"base_motion.{k}" for k in sorted(BASE_MOTION_KEYS)]
    names += [f"base_motion.velocity_m_s.{i}" for i in range(3)]
    for axis in list(base_motion.ANGLE_AXES) + list(base_motion.TRANSLATION_AXES):
        names += [f"base_motion.{axis}.{k}" for k in sorted(BASE_AXIS_KEYS)]
    return names


def suggestions(name: str, candidates: list[str], n: int = 3) -> list[str]:
    """The closest candidates by spelling; failing those, the names beside it (same prefix)."""
    if len(name) > LONGEST_NAME_TO_MATCH:   # no name is that long; difflib would take long to say so
        return []
    close = difflib.get_close_matches(name, candidates, n=n, cutoff=0.6)
    if close:
        return close
    head = name.rpartition(".")[0]
    while head:
        siblings = [c for c in candidates if c.startswith(head + ".")]
        if siblings:
            return siblings[:8]
        head = head.rpartition(".")[0]
    return []


def did_you_mean(name: str, candidates: list[str]) -> str:
    close = [c for c in suggestions(name, candidates) if c != name]
    return f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""


def resolve_names(sweep, scene, fmu) -> tuple[dict, list[str]]:
    """(name -> (section, path), the valid names): bare FMU names resolved (structural switches to
    [fidelity], other parameters to [parameters]); names the FMU lacks, or that are not parameters,
    refused here, all of them in one message with the closest valid names."""
    candidates = valid_names(scene, fmu)
    resolved, problems = {}, []
    for name in sweep.parameters:
        section, path = parse_name(name)
        variable = name if section == "fmu" else path[0] if section in FLAT_SECTIONS else None
        if section == "fmu":
            section = "fidelity" if name in FIDELITY else "parameters"
            if not fmu.has(name):
                problems.append(f"'{excerpt(name)}' is neither a path into the scene (parameters., fidelity., initial., "
                                f"controller., base_motion., sensors., target., stop_time) nor a variable of "
                                f"{fmu.path.name}" + did_you_mean(name, candidates))
                continue
        resolved[name] = (section, path)
        problem = _variable_problem(name, section, variable, fmu, candidates) if variable is not None else None
        if problem:
            problems.append(problem)
    if problems:
        raise SweepError(f"{sweep.path}: " + "\n  ".join(["parameter names refused, no case was run:"] + problems))
    return resolved, candidates


def _variable_problem(name: str, section: str, variable: str, fmu, candidates: list[str]) -> str | None:
    """Why the FMU variable `variable` that `name` sets in `section` cannot be swept; None if it can."""
    v = fmu.variables.get(variable)
    if section == "initial":
        if variable.endswith("_deg") and variable.removesuffix("_deg") in ANGLE_STATES:
            variable = variable.removesuffix("_deg")   # the angle in degrees (load_scene converts it)
        if variable not in fmu.states:
            return (f"'{excerpt(name)}': '{excerpt(variable)}' is not a state of the FMU (states: {', '.join(fmu.states)})"
                    + did_you_mean(name, candidates))
        return None
    if v is None:
        return (f"'{excerpt(name)}': '{excerpt(variable)}' is not a variable of {fmu.path.name}"
                + did_you_mean(name, candidates))
    if v.causality not in PARAMETER_CAUSALITIES:
        hint = f"; its start value is swept as 'initial.{variable}'" if variable in fmu.states else ""
        what = f"'{excerpt(name)}'" if name == variable else f"'{excerpt(name)}': '{excerpt(variable)}'"
        return f"{what} is not a parameter of the FMU (causality {v.causality}){hint}"
    if section == "fidelity" and variable not in FIDELITY:
        return (f"'{excerpt(name)}': '{excerpt(variable)}' is not a structural switch ({', '.join(FIDELITY)}); "
                f"sweep it as 'parameters.{variable}'")
    return None


def _probe(scene, fmu, resolved, values: dict, stop_time):
    """The scene's (or FMU check's) refusal of these values alone, or None when accepted."""
    try:
        check_against_fmu(apply_case(scene, resolved, values, stop_time), fmu)
    except SceneError as exc:
        return str(exc)
    return None


def check_cases_accepted(scene, sweep, fmu, resolved: dict, cases: list, candidates: list[str]) -> None:
    """Every case sets every swept name, so one accepted case vouches for all the names. When the
    scene refuses every case, find the names it refuses on their own and say why, before running."""
    if not cases or any(case.scene is not None for case in cases):
        return
    where = f"{sweep.path}: " + ("the one case is" if len(cases) == 1 else f"all {len(cases)} cases are") + \
        " refused by the scene, so none was run"
    error = _probe(scene, fmu, resolved, {}, sweep.stop_time)
    if error is not None:
        raise SweepError(f"{where}: stop_time = {sweep.stop_time:g}: {error}")
    problems = [problem for name in sweep.parameters
                if (problem := _refused_alone(scene, fmu, resolved, sweep.stop_time, name, cases, candidates))]
    if not problems:   # refused only in combination: show the first case as it is
        problems.append(f"case 0 ({', '.join(f'{excerpt(k)} = {shown(v)}' for k, v in cases[0].values.items())}): "
                        f"{cases[0].error.removeprefix('invalid case: ')}")
    raise SweepError(where + ":\n  " + "\n  ".join(problems))


def _refused_alone(scene, fmu, resolved: dict, stop_time, name: str, cases: list, candidates: list[str]) -> str | None:
    """Why the scene refuses `name` on its own, when it refuses each of its first 3 values; else None."""
    values = list(dict.fromkeys(repr(case.values[name]) for case in cases))[:3]
    tried = {}
    for case in cases:
        key = repr(case.values[name])
        if key in values and key not in tried:
            try:
                tried[key] = _probe(scene, fmu, resolved, {name: case.values[name]}, stop_time)
            except (TypeError, ValueError, KeyError) as exc:
                tried[key] = f"{type(exc).__name__}: {exc}"
        if len(tried) == len(values):
            break
    if not all(error is not None for error in tried.values()):
        return None
    first = next(iter(tried.values()))
    if name in candidates:
        return f"'{excerpt(name)}' = {', '.join(excerpt(v) for v in values)} is refused: {first}"
    return f"'{excerpt(name)}' is not a name the scene accepts: {first}" + did_you_mean(name, candidates)
