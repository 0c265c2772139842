"""Scene files: loading and validation.

A scene is a TOML file (comments allowed). Top level: name (the title of the plot; default the
file's name), description, stop_time [s], step_size [s] (communication step), output_interval [s]
(CSV rows; default every step). The result files are named after the scene file, not after `name`
(scenes/x.toml -> x.csv, x.png), so a copy of a scene never overwrites the original's results. Tables:

  [fidelity]      structural parameters of the FMU (gear1.model, gear2.model, motor1.model,
                  motor2.model, dry_friction, base.fixed); absent = the FMU's defaults (full model)
  [parameters]    any FMU parameter by its name, SI units
  [imbalance]     payload_offset_mm, azimuth_housing_offset_mm: [x, y, z] in mm, the centre of mass
                  of the payload from point b in frame 2 (body2.d_bd) and of the azimuth housing in
                  frame 1 (body1.d_bc); merged into the parameters (one table per parameter)
  [initial]       start values of the FMU's states (alpha, beta_m, i_R1, ...), SI units; an angle
                  also as NAME_deg in degrees (beta_deg = 30), not both; alpha and beta within half a
                  turn; a rotor angle/rate not given follows its load through the gear (alpha_m = N1 alpha)
  [base_motion]   type = "fixed" | "sinusoids" | "sea_state" | "recorded" (base_motion.py)
  [target]        azimuth_deg, elevation_deg: the fixed inertial direction the line of sight should
                  hold (geometry.py); start_on_target = true starts the gimbal pointing at it; or
                  type = "earth_point" | "flyby" | "track", a moving target (gimbal2axis/target/spec.py,
                  docs/targets.md)
  [controller]    type = "none" | "pid" | "state_feedback" | "python", delay_steps (default 1)
                  (controllers.py)
  [sensors]       encoders, a datasheet gyro, direct or indirect stabilization, IMU noise (sensors.py)
  [requirements]  los_rms_max_mrad, los_final_max_mrad, from_s: line-of-sight bounds the run must meet
  [test]          stop_time: the shortened end time the test suite runs the scene to
  [plot]          optional: panel name = [recorded signal names], replaces the default panels
  [analysis]      optional: psd_resolution_hz, isolation_resolution_hz and [analysis.bands] of the
                  line-of-sight error's spectrum (analysis.py, docs/jitter.md)

Units: a key ending in _deg is in degrees (_deg_s degrees per second, _mm millimetres), a key without a
unit suffix in SI units, angles in radians, as the FMU's names are. An angle in radians beyond what
can be meant (a start angle beyond half a turn) is refused with the value in degrees too, since it is
most likely degrees given without the suffix.

Validation has two levels: `load_scene` checks everything a file alone can say (each value's type,
finiteness and range, by its key); `check_against_fmu` checks the FMU variable names, causalities and
types (the FMU's model description is the truth). Names are looked up with close-match suggestions,
and what the user wrote is quoted as a bounded excerpt (errors.excerpt).
A scene that runs, but likely not as meant (no controller, a motor the controller leaves at 0 V, a
moving-base model with no base motion), loads with a SceneWarning per finding (Python's warnings
module, so it shows on stderr; the list is also Scene.warnings).
"""
from __future__ import annotations

import math
import pathlib
import warnings
from dataclasses import dataclass, field

import numpy as np

from . import analysis, geometry
from .base_motion import INPUTS as BASE_INPUT_NAMES, Recorded, make_base_motion
from .controllers import make_controller
from .drives import other_drive_columns, scene_drives
from .parameters import parameter_value
from .. import target as moving_targets
from ..target import spec as target_spec_table
from ..errors import (SceneError, SceneWarning, boolean, check_keys, did_you_mean, excerpt, is_number_text, number,
                      positive, shown)
from ..fmu import FIDELITY, FMU, enumeration_items
from ..limits import (read_toml, MAX_DELAY_STEPS, MAX_DESCRIPTION_CHARS, MAX_PLOT_PANELS, MAX_PLOT_SIGNALS, MAX_TITLE_CHARS,
                      over_limit, steps_of, too_long)
from .sensors import Sensors
from .setpoints import target_direction

TOP_KEYS = {"name", "description", "stop_time", "step_size", "output_interval", "fidelity", "parameters",
            "imbalance", "initial", "base_motion", "target", "controller", "sensors", "requirements", "test",
            "plot", "analysis"}

# [initial] angles that may be given in degrees as NAME_deg; the FMU's own names are radians.
ANGLE_STATES = ("alpha", "beta", "alpha_m", "beta_m", "theta_b1", "theta_b2")
# The load angles have no end stops (no bounds in model_core/include/gimbal/real_variables.def): a start
# beyond half a turn is the same pose as one within it, so a value beyond pi rad is degrees without the
# suffix, not a pose.
HALF_TURN_ANGLES = ("alpha", "beta")

# The angle between two directions is at most pi rad: a line-of-sight bound above holds for any run (and
# a plot's log axis drawn up to 1e300 overflows its tick labels).
LARGEST_LOS_ERROR_MRAD = 1000.0 * math.pi

# [imbalance]: a centre-of-mass offset in millimetres -> the FMU's vector parameter (metres, frame of
# its body; docs/physics.md section 1).
IMBALANCE = {"payload_offset_mm": "body2.d_bd", "azimuth_housing_offset_mm": "body1.d_bc"}


@dataclass
class Scene:
    path: pathlib.Path
    name: str                 # the scene file's stem: names the result files and the FMU instance
    title: str                # the file's `name`: the title of the plot
    description: str
    stop_time: float
    step_size: float
    output_interval: float
    fidelity: dict
    parameters: dict
    initial: dict
    base_motion_spec: dict
    target_spec: dict | None
    controller_spec: dict
    sensors_spec: dict
    requirements: dict
    test: dict
    plot: dict
    analysis_spec: dict = field(default_factory=dict)
    raw: dict = field(repr=False, default_factory=dict)
    warnings: list = field(repr=False, default_factory=list)

    @property
    def n_steps(self) -> int:
        return int(round(self.stop_time / self.step_size))

    @property
    def target(self):
        """Unit vector of the target in G, or None: the kernel's (setpoints.target_direction), whose
        bits the controller FMU computes from the same angles. None for a moving target too
        (moving_target)."""
        if self.target_spec is None or "type" in self.target_spec:
            return None
        return target_direction(math.radians(self.target_spec["azimuth_deg"]),
                                math.radians(self.target_spec["elevation_deg"]))

    @property
    def moving_target(self):
        """The target.motion.MovingTarget of a [target] with a type (earth_point, flyby, track), else None."""
        if self.target_spec is None or "type" not in self.target_spec:
            return None
        cache = self.__dict__.setdefault("_moving_target", {})
        # the gimbal moves with the base motion and its lever arm d_ab (target.motion.GimbalMotion)
        key = repr((sorted(self.target_spec.items(), key=str), self.base_motion_spec,
                    target_spec_table.lever_arm(self.parameters), self.step_size))
        if key not in cache:
            cache.clear()
            cache[key] = target_spec_table.build(self.target_spec, self.path.parent, self.base_motion(),
                                                 self.parameters, self.step_size)
        return cache[key]

    @property
    def delay_steps(self) -> int:
        return int(self.controller_spec.get("delay_steps", 1))

    @property
    def analysis(self) -> analysis.AnalysisSettings:
        """The [analysis] settings (defaults without the table)."""
        return analysis.parse(self.analysis_spec, self.step_size)

    def base_motion(self):
        return make_base_motion(self.base_motion_spec, self.path.parent)

    def controller(self, u_limit=(math.inf, math.inf)):
        target = self.target if self.moving_target is None else self.moving_target
        return make_controller(self.controller_spec, target, u_limit, base_dir=self.path.parent)

    def sensors(self):
        return Sensors(self.sensors_spec)

    def with_changes(self, **changes) -> "Scene":
        """A copy with top-level fields replaced (e.g. stop_time, controller_spec), re-validated."""
        import dataclasses
        scene = dataclasses.replace(self, **changes)
        _validate(scene)
        return scene


def _table(raw: dict, key: str, flatten: bool = False) -> dict:
    value = raw.get(key, {})
    if not isinstance(value, dict):
        raise SceneError(f"'{key}' must be a table ([{key}]), got {shown(value)}")
    return _flatten(value) if flatten else value


def _scalar_values(where: str, table: dict) -> dict:
    """[parameters] and [fidelity] hold numbers and true/false (the FMU's Real, Integer, Enumeration
    and Boolean variables): anything else is refused by its key before the FMU is opened."""
    for name, value in table.items():
        if isinstance(value, bool) or (isinstance(value, (int, float)) and math.isfinite(value)):
            continue
        if isinstance(value, list):   # an FMU vector is one scalar variable per component
            hint = f' (one value per FMU variable: "{excerpt(name)}[1]" = ..., "{excerpt(name)}[2]" = ...)'
        elif isinstance(value, str):
            hint = " (a string: write the number without quotes)" if is_number_text(value) else \
                " (an Enumeration such as gear1.model by its integer value)"
        else:
            hint = ""
        raise SceneError(f"{where}.{excerpt(name)} must be a finite number or true/false, got {shown(value)}{hint}")
    return table



def initial_in_radians(initial: dict) -> dict:
    """[initial] with every NAME_deg turned into the FMU's NAME in radians; refuses an angle given both
    ways and a load angle beyond half a turn (with the value in degrees, the likely mistake)."""
    values = {}
    for name, value in initial.items():
        where = f"initial.{excerpt(name)}"
        value = number(where, value)
        base = name[:-len("_deg")] if name.endswith("_deg") else None
        if base in ANGLE_STATES:
            if base in initial:
                raise SceneError(f"initial.{base} and initial.{name} are the same angle (radians, degrees): give one")
            if base in HALF_TURN_ANGLES and abs(value) > 180.0:
                raise SceneError(f"{where} = {value:g} deg is beyond ±180 deg: a start angle beyond half a turn is "
                                 f"the same pose as {math.remainder(value, 360.0):g} deg")
            values[base] = math.radians(value)
            continue
        if name in HALF_TURN_ANGLES and abs(value) > math.pi:
            raise SceneError(f"{where} = {value:g} rad ({math.degrees(value):.0f} deg) is beyond ±{math.pi:.4f} rad "
                             f"(half a turn); a bare angle is in radians: did you mean {name}_deg = {value:g}?")
        values[name] = value
    return values


def _flatten(table: dict, prefix: str = "") -> dict:
    """FMU names have dots; unquoted in TOML (gear1.eta = 1e-3) they make nested tables: join them back."""
    flat = {}
    for key, value in table.items():
        if isinstance(value, dict):
            flat.update(_flatten(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def _imbalance_parameters(table: dict, parameters: dict) -> dict:
    """The FMU parameters (SI) of an [imbalance] table; a parameter also in [parameters] is refused,
    since one of the two would win without a word."""
    check_keys("imbalance", table, set(IMBALANCE))
    values = {}
    for key, vector in IMBALANCE.items():
        if key not in table:
            continue
        offset = table[key]
        if not (isinstance(offset, list) and len(offset) == 3):
            raise SceneError(f"imbalance.{key} must be [x, y, z] in mm, got {shown(offset)}")
        for component, value in enumerate(offset, start=1):
            name = f"{vector}[{component}]"
            if name in parameters:
                raise SceneError(f"imbalance.{key} and [parameters] '{name}' both set {name}: "
                                 "give the centre of mass in one table only")
            values[name] = number(f"imbalance.{key}[{component - 1}]", value) / 1000.0
    return values


def load_scene(path: pathlib.Path | str) -> Scene:
    """Reads and validates a scene file (everything but the FMU variable names)."""
    path = pathlib.Path(path)
    raw = read_toml(path)
    try:
        check_keys("top level", raw, TOP_KEYS)
        for key in ("stop_time", "step_size"):
            if key not in raw:
                raise SceneError(f"missing required key '{key}'")
        title = raw.get("name", path.stem)
        if not isinstance(title, str) or not title.strip():
            raise SceneError(f"'name' (the title of the plot) must be a non-empty string, got {shown(title)}")
        too_long("'name' (the title of the plot)", len(title), MAX_TITLE_CHARS)
        description = raw.get("description", "")
        if not isinstance(description, str):
            raise SceneError(f"'description' must be a string, got {shown(description)}")
        too_long("'description'", len(description), MAX_DESCRIPTION_CHARS)
        step = positive("step_size", raw["step_size"])
        target = raw.get("target")
        if target is not None and target_spec_table.kind_of(_table(raw, "target")) != "direction":
            target = target_spec_table.parse(target)
        elif target is not None:
            target = {key: value for key, value in _table(raw, "target").items() if key != "type"}
            check_keys("target", target, {"azimuth_deg", "elevation_deg", "start_on_target"})
            target = {"azimuth_deg": number("target.azimuth_deg", target.get("azimuth_deg", 0.0)),
                      "elevation_deg": number("target.elevation_deg", target.get("elevation_deg", 0.0)),
                      "start_on_target": boolean("target.start_on_target", target.get("start_on_target", False))}
        parameters = _scalar_values("parameters", _table(raw, "parameters", True))
        parameters.update(_imbalance_parameters(_table(raw, "imbalance"), parameters))
        scene = Scene(path=path, name=path.stem, title=title, description=description,
                      stop_time=positive("stop_time", raw["stop_time"]), step_size=step,
                      output_interval=positive("output_interval", raw.get("output_interval", step)),
                      fidelity=_scalar_values("fidelity", _table(raw, "fidelity", True)), parameters=parameters,
                      initial=_table(raw, "initial", True), base_motion_spec=_table(raw, "base_motion"),
                      target_spec=target, controller_spec=_table(raw, "controller"),
                      sensors_spec=_table(raw, "sensors"), requirements=_table(raw, "requirements"),
                      test=_table(raw, "test"), plot=_table(raw, "plot"),
                      analysis_spec=_table(raw, "analysis"), raw=raw)
        _validate(scene)
        # as written in the file; a run shortened later (--stop-time, a sweep) may end before from_s
        if scene.requirements.get("from_s", 0.0) >= scene.stop_time:
            raise SceneError(f"requirements.from_s = {scene.requirements['from_s']:g} s is not before stop_time = "
                             f"{scene.stop_time:g} s: the bounds would hold over no time")
        analysis.check_window(scene.analysis, scene.stop_time, float(scene.requirements.get("from_s", 0.0)))
    except SceneError as exc:
        raise SceneError(f"{path}: {exc}") from None
    for message in scene.warnings:
        # stacklevel 1: one registry entry per message, so loading a scene twice warns once
        warnings.warn(SceneWarning(f"{path}: {message}"))
    return scene


def _validate(scene: Scene) -> None:
    """Refuses what a scene cannot be run with, in this order: its time grid, its tables of FMU values,
    its target, its controller and base motion, its requirements, [test] and [plot]; keeps the
    warnings of a scene that runs, but probably not as meant (scene.warnings)."""
    _validate_grid(scene)
    _validate_values(scene)
    _validate_target(scene)
    found = _validate_controller(scene)
    _validate_base_motion(scene)
    scene.controller()
    scene.warnings = found
    scene.sensors()
    _validate_requirements(scene)
    _validate_outputs(scene)


def _validate_grid(scene: Scene) -> None:
    """stop_time, step_size and output_interval: a whole number of steps each."""
    # again here: with_changes (a sweep, --stop-time) brings values load_scene has not seen
    for key in ("stop_time", "step_size", "output_interval"):
        positive(key, getattr(scene, key))
    steps_of("stop_time", scene.stop_time, scene.step_size)
    # the steps between two recorded rows: a stride the streamed record counts in 64-bit integers
    steps_of("output_interval", scene.output_interval, scene.step_size)
    if scene.n_steps < 1:
        raise SceneError(f"stop_time = {scene.stop_time:g} s is shorter than one step (step_size = "
                         f"{scene.step_size:g} s): the run would have no step")
    if abs(scene.n_steps * scene.step_size - scene.stop_time) > 1e-9 * scene.stop_time:
        raise SceneError(f"stop_time = {scene.stop_time:g} s must be a whole number of steps of step_size = "
                         f"{scene.step_size:g} s")
    ratio = scene.output_interval / scene.step_size
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise SceneError(f"output_interval = {scene.output_interval:g} s must be a whole multiple of step_size = "
                         f"{scene.step_size:g} s")


def _validate_values(scene: Scene) -> None:
    """[fidelity] switches the FMU has, [initial] in radians, no variable set in two tables."""
    unknown = sorted(set(scene.fidelity) - set(FIDELITY))
    if unknown:
        raise SceneError(f"[fidelity]: unknown switch {shown(unknown[0])}{did_you_mean(unknown[0], FIDELITY)}; "
                         f"known: {', '.join(FIDELITY)}")
    # whether each is a state: check_against_fmu
    scene.initial = initial_in_radians(scene.initial)
    overlap = sorted(set(scene.fidelity) & set(scene.parameters))
    if overlap:
        # start_values would let [parameters] win without a word
        raise SceneError(f"{', '.join(repr(n) for n in overlap)} set in both [fidelity] and [parameters]: "
                         "set each FMU variable in one table only")


def _validate_target(scene: Scene) -> None:
    if scene.moving_target is not None:
        target_spec_table.check_run(scene.moving_target, scene.stop_time)
    elif scene.target_spec is not None:
        elevation = number("target.elevation_deg", scene.target_spec["elevation_deg"])
        if not -90.0 <= elevation <= 90.0:
            raise SceneError(f"target.elevation_deg = {elevation:g} is outside [-90, 90] deg (0 = horizon, "
                             f"90 = straight up); the direction behind is azimuth_deg + 180 with elevation "
                             f"{math.copysign(180.0, elevation) - elevation:g}")


def _validate_controller(scene: Scene) -> list[str]:
    """The delay and the built-in controllers' gains (_check_controller); returns the warnings found,
    also of a base motion the FMU is not set for."""
    delay = scene.controller_spec.get("delay_steps", 1)
    if not isinstance(delay, int) or isinstance(delay, bool) or delay < 0:
        raise SceneError("[controller] delay_steps must be an integer >= 0 (1 = a one-sample delay: the voltage "
                         "computed at t_k is applied over [t_k+1, t_k+2])")
    # the master keeps the commands of the last delay_steps steps in memory
    over_limit("[controller] delay_steps", delay, MAX_DELAY_STEPS, " steps")
    found = _check_controller(scene.controller_spec)
    if not scene.base_motion_spec and scene.fidelity.get("base.fixed") is not True:
        setting = "= false" if "base.fixed" in scene.fidelity else "is not set (the FMU's default is false)"
        found.append(f"no [base_motion] while [fidelity] base.fixed {setting}: the base stays still, but the FMU "
                     "runs its moving-base model; for a fixed base say [base_motion] type = \"fixed\" and "
                     "\"base.fixed\" = true, for a moving one give the motion")
    return found


def _validate_base_motion(scene: Scene) -> None:
    motion = scene.base_motion()
    if scene.fidelity.get("base.fixed") is True and not motion.fixed:
        raise SceneError("[fidelity] base.fixed = true needs a fixed base: [base_motion] type = 'fixed'")
    if isinstance(motion, Recorded) and (motion.t_start > 0 or motion.t_end < scene.stop_time):
        raise SceneError(f"[base_motion] the recording covers [{motion.t_start:g}, {motion.t_end:g}] s, "
                         f"not [0, {scene.stop_time:g}] s")


def _validate_requirements(scene: Scene) -> None:
    check_keys("requirements", scene.requirements, {"los_rms_max_mrad", "los_final_max_mrad", "from_s"})
    for key, value in scene.requirements.items():
        positive(f"requirements.{key}", value) if key != "from_s" else number("requirements.from_s", value)
        if key != "from_s" and value > LARGEST_LOS_ERROR_MRAD:
            raise SceneError(f"requirements.{key} = {value:g} mrad can never fail: a line-of-sight error is at most "
                             f"half a turn ({LARGEST_LOS_ERROR_MRAD:.1f} mrad)")
    if scene.requirements.get("from_s", 0.0) < 0:
        raise SceneError(f"requirements.from_s = {scene.requirements['from_s']:g} s must be >= 0 (the bounds hold "
                         "from then to the end of the run)")
    if scene.requirements and scene.target_spec is None:
        raise SceneError("[requirements] on the line of sight need a [target]")


def _validate_outputs(scene: Scene) -> None:
    """[test], [plot] and [analysis.bands]."""
    check_keys("test", scene.test, {"stop_time"})
    if "stop_time" in scene.test:
        positive("test.stop_time", scene.test["stop_time"])
    over_limit("[plot]: the number of panels", len(scene.plot), MAX_PLOT_PANELS)
    for panel, names in scene.plot.items():
        if not (isinstance(names, list) and all(isinstance(n, str) for n in names)):
            raise SceneError(f"[plot] {excerpt(panel)} must be a list of signal names, got {shown(names)}")
        over_limit(f"[plot] {excerpt(panel)}: the number of signals", len(names), MAX_PLOT_SIGNALS)
    settings = scene.analysis
    if settings.bands and scene.target_spec is None:
        raise SceneError("[analysis.bands] of the line-of-sight error need a [target]")


AXIS_MOTOR = {"azimuth": "u_R1", "elevation": "u_R2"}
PID_GAINS = ("kp", "ki", "kd", "k_gyro", "k_ff")
WHY_NOT_NEGATIVE = {
    "kp": "a negative gain pushes the axis away from its set point",
    "ki": "a negative gain integrates the axis away from its set point",
    "kd": "a negative gain feeds the error's rate back with the wrong sign",
    "k_gyro": "negative rate feedback undamps the axis",
    "k_ff": "the feed-forward cancels the motor's back-emf (k_ff = N k_emf); a negative one adds to it",
    "k_acc": "the feed-forward gives the torque of the set point's acceleration; a negative one opposes it",
    "d_filter_s": "it is the time constant of the derivative filter",
    "i_limit_V": "it bounds |ki * integral|",
}


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check_controller(spec: dict) -> list[str]:
    """Refuses gains of the wrong sign in the built-in controllers; returns warnings for a scene
    without a controller and for motors a controller leaves at 0 V. Values that are not numbers
    are left to the controller's own checks (make_controller), which run next. A "python"
    controller's options are its own business."""
    if "type" not in spec:
        where = "no [controller]" if not spec else "[controller] has no type"
        return [f"{where}: the gimbal runs open loop, both motors at 0 V (say [controller] type = \"none\" "
                "if that is the point)"]
    if spec["type"] == "pid":
        return _check_pid(spec)
    if spec["type"] == "state_feedback":
        return _check_state_feedback(spec)
    return []


def _check_pid(spec: dict) -> list[str]:
    found = []
    for axis in AXIS_MOTOR:
        table = spec.get(axis)
        if table is None:
            found.append(f"[controller] type = \"pid\" has no [controller.{axis}] table: the {axis} motor "
                         f"({AXIS_MOTOR[axis]}) gets 0 V")
            continue
        if not isinstance(table, dict):
            raise SceneError(f"[controller] '{axis}' must be a table ([controller.{axis}]), got {shown(table)}")
        for key, why in WHY_NOT_NEGATIVE.items():
            value = table.get(key, 0.0)
            if _is_number(value) and value < 0:
                raise SceneError(f"controller.{axis}.{key} = {value:g} is negative: {why}")
        if all(table.get(key, 0.0) == 0 for key in PID_GAINS):
            found.append(f"[controller.{axis}] has no nonzero gain ({', '.join(PID_GAINS)}): the {axis} "
                         f"motor ({AXIS_MOTOR[axis]}) gets 0 V")
    return found


def _check_state_feedback(spec: dict) -> list[str]:
    found = []
    K, ki = spec.get("K"), spec.get("ki", [0.0, 0.0])
    if not (isinstance(ki, list) and len(ki) == 2):
        raise SceneError(f"controller.ki must be [ki of u_R1, ki of u_R2], got {shown(ki)}")
    if not (isinstance(K, list) and len(K) == 2 and all(isinstance(row, list) and len(row) == 4 for row in K)):
        return found
    for i, axis in enumerate(AXIS_MOTOR):
        if _state_feedback_axis_is_zero(K, ki, i, axis):
            found.append(f"[controller] K[{i}] and ki[{i}] are all zero: the {axis} motor ({AXIS_MOTOR[axis]}) "
                         "gets 0 V")
    return found


def _state_feedback_axis_is_zero(K: list, ki: list, i: int, axis: str) -> bool:
    """Refuses gains of row i (the motor of `axis`) that push the axis away; True when the row is all zero."""
    motor = AXIS_MOTOR[axis]
    # u = -K x: the gains of an axis's own angle error and rate must be >= 0 to pull it back
    for j, what in ((i, "angle error"), (2 + i, "rate")):
        if _is_number(K[i][j]) and K[i][j] < 0:
            raise SceneError(f"controller.K[{i}][{j}] = {K[i][j]:g} ({motor} per {axis} {what}) is negative: "
                             f"u = -K x then pushes the {axis} away from its set point")
    if _is_number(ki[i]) and ki[i] < 0:
        raise SceneError(f"controller.ki[{i}] = {ki[i]:g} ({motor}) is negative: {WHY_NOT_NEGATIVE['ki']}")
    return all(k == 0 for k in K[i]) and ki[i] == 0


def check_against_fmu(scene: Scene, fmu: FMU) -> None:
    """Refuses FMU variable names the FMU does not have, wrong causalities and wrong value types."""
    try:
        _check_values(scene, fmu)
        _check_plot(scene, fmu)
    except SceneError as exc:
        raise SceneError(f"{scene.path}: {exc}") from None


def _check_values(scene: Scene, fmu: FMU) -> None:
    """[fidelity], [parameters] and [initial]: variables of the FMU, of the right causality and type."""
    parameters = [name for name, v in fmu.variables.items() if v.causality in ("parameter", "structuralParameter")]
    for where, table in (("fidelity", scene.fidelity), ("parameters", scene.parameters)):
        for name in table:   # named here with the close matches, before fmu.check quotes it whole
            if not fmu.has(name):
                hint = did_you_mean(name, parameters) or "; is the FMU older than the scene?"
                raise SceneError(f"[{where}] '{excerpt(name)}' is not a variable of {fmu.path} (its "
                                 f"modelDescription.xml is the truth){hint}")
    fmu.check("fidelity", scene.fidelity, {"parameter", "structuralParameter"})
    fmu.check("parameters", scene.parameters, {"parameter", "structuralParameter"})
    for name in scene.initial:
        if name not in fmu.states:
            raise SceneError(f"[initial]: '{excerpt(name)}' is not a state (states: {fmu.states})"
                             f"{did_you_mean(name, fmu.states + [a + '_deg' for a in ANGLE_STATES])}")
    fmu.check("initial", scene.initial, {"output", "local"})


def _check_plot(scene: Scene, fmu: FMU) -> None:
    """[plot]: signals a run records, of the motors' drives as the scene sets them."""
    names = {n for names in scene.plot.values() for n in names}
    drives = scene_drives(scene, fmu)
    recorded_inputs = set(BASE_INPUT_NAMES) | {drive.applied for drive in drives}
    for drive in drives:
        for name, instead in other_drive_columns(drive).items():
            if name in names:
                raise SceneError(f"[plot] '{name}': motor{drive.motor} is in {drive.kind} drive (motor{drive.motor}"
                                 f".drive), so its record has '{instead}' instead ({drive.unit}; "
                                 f"docs/scenes.md, \"Current-commanded drives\")")
    for name in sorted(names):
        if fmu.has(name) and name not in DERIVED_SIGNALS and (
                fmu.variables[name].type not in ("Real", "Integer", "Enumeration") or
                (fmu.variables[name].causality == "input" and name not in recorded_inputs)):
            raise SceneError(f"[plot] '{excerpt(name)}' is an FMU {fmu.variables[name].causality} of type "
                             f"{fmu.variables[name].type} that a run does not record: a plot draws Real, "
                             f"Integer and Enumeration variables the FMU computes, and the runner's signals")
        if not fmu.has(name) and name not in DERIVED_SIGNALS:
            raise SceneError(f"[plot] '{excerpt(name)}' is neither an FMU variable nor a signal of the runner "
                             f"({sorted(DERIVED_SIGNALS)}){did_you_mean(name, list(fmu.variables) + sorted(DERIVED_SIGNALS))}")


# What a run with a moving target adds (master/results.py): the target's direction and range in G, the
# pointing command on the carrier (inverse kinematics) with its rates and accelerations.
TRACKING_SIGNALS = ("target_azimuth", "target_elevation", "target_range", "alpha_cmd", "beta_cmd", "alpha_cmd_dot",
                    "beta_cmd_dot", "alpha_cmd_ddot", "beta_cmd_ddot")
DERIVED_SIGNALS = {"u_R1", "u_R2", "u_R1_cmd", "u_R2_cmd", "u_R1_asked", "u_R2_asked",
                   "i_R1_ctrl", "i_R2_ctrl", "i_R1_asked", "i_R2_asked",
                   "alpha_ref", "beta_ref", "alpha_error", "beta_error", "los_error",
                   "los_azimuth", "los_elevation", "heave", "los_error_xel", "los_error_el",
                   "base.omega2[1]", "base.omega2[2]", "base.omega2[3]"} | set(TRACKING_SIGNALS) | {f"base.{n}" for n in (
                       "delta", "psi", "gamma", "delta_dot", "psi_dot", "gamma_dot",
                       "delta_ddot", "psi_ddot", "gamma_ddot")}


def check_run_length(scene: Scene, t_end: float) -> None:
    """Refuses a run to t_end (a --stop-time beyond the scene's) that a recorded target or carrier
    track does not cover; the scene's own stop_time is checked when it loads."""
    if scene.moving_target is not None:
        try:
            target_spec_table.check_run(scene.moving_target, t_end)
        except SceneError as exc:
            raise SceneError(f"{scene.path}: {exc}") from None


def start_values(scene: Scene, fmu: FMU, base_row0: np.ndarray, base_row_eps: np.ndarray | None = None,
                 eps: float = 1e-6) -> dict:
    """All values to set before initialization: fidelity, parameters, initial state; rotors follow
    their loads when not given; start_on_target points the gimbal at the target for the base
    attitude at t = 0 (and gives it the rates that keep it there, from base_row_eps at t = eps)."""
    initial = dict(scene.initial)
    if scene.target_spec is not None and scene.target_spec["start_on_target"]:
        for name, value in _on_target(scene, base_row0, base_row_eps, eps).items():
            initial.setdefault(name, value)
    runner_starts_rotors = {}
    for axis, (load, rotor) in enumerate([("alpha", "alpha_m"), ("beta", "beta_m")], start=1):
        runner_starts_rotors.update(_rotor_start(scene, fmu, initial, axis, load, rotor))
    values = dict(scene.fidelity)
    values.update(scene.parameters)
    values.update(runner_starts_rotors)
    values.update(initial)
    return values


def _on_target(scene: Scene, base_row0: np.ndarray, base_row_eps: np.ndarray | None, eps: float) -> dict:
    """The joint angles (and rates) that point at the target at t = 0: toward a moving target by the
    pointing command; toward a fixed one by its angles at t = 0 and t = eps (rates only with base_row_eps)."""
    if scene.moving_target is not None:
        rows = np.asarray(base_row0, dtype=float).reshape(1, -1)
        command = moving_targets.pointing(scene.moving_target, [0.0], rows[:, 0:3], rows[:, 3:6], rows[:, 6:9])
        return {name: float(getattr(command, name)[0]) for name in ("alpha", "beta", "alpha_dot", "beta_dot")}
    a0, b0 = geometry.gimbal_angles_for(scene.target, *base_row0[:3])
    angles = {"alpha": a0, "beta": b0}
    if base_row_eps is not None:
        a1, b1 = geometry.gimbal_angles_for(scene.target, *base_row_eps[:3], alpha_near=a0)
        angles.update({"alpha_dot": (a1 - a0) / eps, "beta_dot": (b1 - b0) / eps})
    return angles


def _rotor_start(scene: Scene, fmu: FMU, initial: dict, axis: int, load: str, rotor: str) -> dict:
    """Where the rotor of gear `axis` starts, into `initial` (as the scene gives it, else N times its load);
    returns {gear<j>.start: as_given} when the FMU's own rule would not keep that."""
    gear_model = parameter_value(scene, fmu, f"gear{axis}.model")
    if gear_model == 0:   # rigid gear: the FMU has no rotor state of its own
        return {}
    ratio = float(parameter_value(scene, fmu, f"gear{axis}.N"))
    if load in initial and rotor not in initial:
        initial[rotor] = ratio * initial[load]
    if load + "_dot" in initial and rotor + "_dot" not in initial:
        initial[rotor + "_dot"] = ratio * initial[load + "_dot"]
    # The runner has decided where the rotor starts (as the scene gives it, else N times its load).
    # The FMU's default rule (gear<j>.start = in_mesh_unless_given) keeps that too, except for a
    # rotor value of 0 whose value in mesh is not 0: then the runner asks for as_given, unless the
    # scene chooses the rule itself. Only then: libcosim cannot set an Enumeration (gimbal2axis system).
    rule = f"gear{axis}.start"
    if not fmu.has(rule) or rule in scene.parameters:
        return {}

    def start(name):
        return float(initial[name]) if name in initial else float(fmu.start(name))
    backlash = start(f"theta_b{axis}") if gear_model == 2 else 0.0
    moved_angle = start(rotor) == 0.0 and ratio * (start(load) + backlash) != 0.0
    moved_rate = start(rotor + "_dot") == 0.0 and ratio * start(load + "_dot") != 0.0
    return {rule: gear_start_item(fmu, rule, "as_given")} if moved_angle or moved_rate else {}


def gear_start_item(fmu: FMU, name: str, item: str) -> int:
    """The value of the item named `item` of the Enumeration parameter `name` (gear<j>.start)."""
    values = {label: value for value, label in enumeration_items(fmu.variable(name)).items()}
    return values[item]
