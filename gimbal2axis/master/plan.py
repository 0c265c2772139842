"""What a run is decided by before the FMU starts (Plan): the time grid t_k = k h, the base motion,
the controller and its zero-order-hold delay, the sensors, what is recorded, and the tables the loops
fill. A run held in memory has one chunk, the whole run (Plan); a run streamed to disk has
tables of a chunk of rows, loaded one chunk after the other (StreamPlan): the same bits either way
(each of the base motion's, the sensors' and the set points' rows is computed alike in both).

Row k - first of the tables is the run's communication point k (first: the chunk's first point):
the outputs at t_k (rec_real, rec_mode), the inputs set for [t_k, t_k+1] (inputs: the applied
command, then the base inputs at t_k), the controller's output at t_k (u_cmd, after `delay` rows of
the commands before the chunk, which the delayed command reads back), its set point (refs) and what
it asked before its clamp (u_asked).
"""
from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..fmu import FMU
from ..scene.base_motion import INPUTS as BASE_INPUTS
from ..scene.drives import command_signals, scene_drives
from ..scene.scene import Scene, check_against_fmu, check_run_length, parameter_value, start_values
from .memory import available_memory, size_text

# Recorded besides the states (FMU.states, from the model description).
OTHER_REAL_OUTPUTS = ["T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "los.omega[3]"]
# Recorded after the modes: the number of mode changes.
EVENT_OUTPUTS = ["events.total"]
# The outputs the sensors read.
SENSED_OUTPUTS = ("alpha", "beta", "los.omega[1]", "los.omega[2]", "los.omega[3]", "alpha_dot", "beta_dot")


def real_outputs(fmu: FMU) -> list[str]:
    """The Real outputs a run records: the FMU's states, then the gear torques and the payload gyro."""
    return fmu.states + [name for name in OTHER_REAL_OUTPUTS if fmu.has(name)]


def mode_outputs(fmu: FMU, scene: Scene | None = None) -> list[str]:
    """The Integer outputs a run records besides the counters: the switching elements' modes, as the FMU
    declares them (FMU.mode_outputs, from model_core/include/gimbal/switching_elements.def), then
    EVENT_OUTPUTS. An element switched on by a parameter is recorded only in a scene that switches it on
    (without a scene: all), so that a scene without it records what it did before the element existed."""
    def switched_on(switch):
        return switch is None or scene is None or bool(parameter_value(scene, fmu, switch))
    return [mode.name for mode in fmu.mode_outputs if switched_on(mode.switch)] + EVENT_OUTPUTS


class Plan:
    """Everything a run is decided by before the FMU starts, with tables of the whole run (one chunk):
    the base motion of the whole run evaluated once, vectorised, the sensors' noise drawn and the set
    points made. The loops read the FMU's inputs from row k of `inputs` (base columns filled up front)
    and write its outputs into row k of the records, through raw pointers."""

    def __init__(self, scene: Scene, fmu: FMU, stop_time: float | None, controller, chunk_rows: int | None = None):
        check_against_fmu(scene, fmu)
        self.scene, self.h = scene, scene.step_size
        self.t_end = scene.stop_time if stop_time is None else stop_time
        self.n = int(round(self.t_end / self.h))
        check_run_length(scene, self.t_end)
        self.motion = scene.base_motion()
        self.chunk_rows = self.n + 1 if chunk_rows is None else min(chunk_rows, self.n + 1)
        if chunk_rows is None:
            check_memory(scene, fmu, self)
        self.drives = scene_drives(scene, fmu)
        self.controller = controller or scene.controller(tuple(drive.limit for drive in self.drives))
        self.sensors = scene.sensors()
        self.delay = scene.delay_steps
        choose_records(self, fmu)
        rows = self.chunk_rows
        self.rec_real = np.zeros((rows, len(self.real_names)))
        self.rec_mode = np.zeros((rows, len(self.mode_names)), dtype=np.int32)
        self.inputs = np.zeros((rows, len(self.input_vrs)))
        self.u_cmd = np.zeros((self.delay + rows, 2))
        self.refs = np.full((rows, 2), np.nan)
        self.u_asked = np.zeros((rows, 2))
        self.first = 0   # the run's point of the tables' row 0
        self.k = 0       # the step reached (for the message of a failure)
        self.rows = 0    # communication points recorded whole (the run's 0 .. rows - 1)
        if chunk_rows is None:
            self.load_chunk(0, rows)

    def base_rows(self, first: int, count: int) -> np.ndarray:
        return self.motion.sample(self.times)

    def measured_rows(self, first: int, base: np.ndarray) -> np.ndarray:
        """What the IMU measures (the sensors' noise of the whole run drawn here)."""
        return self.sensors.prepare(base, self.h)

    def heave_rows(self, first: int, count: int) -> np.ndarray:
        return self.motion.position(self.times[:count])[:, 2]

    def load_chunk(self, first: int, count: int) -> None:
        """Makes the inputs of the run's points first .. first + count - 1: the base motion, what the
        sensors measure of it, the controller's set points; the last `delay` commands carry over."""
        self.first, h = first, self.h
        if first > 0 and self.delay:
            self.u_cmd[:self.delay] = self.u_cmd[self.chunk_rows:self.chunk_rows + self.delay]
        self.refs[:] = np.nan
        self.times = np.arange(first, first + count) * h
        self.base = self.base_rows(first, count)
        if not self.motion.fixed:
            self.inputs[:count, 2:] = self.base
        self.measured_attitude = self.measured_rows(first, self.base)
        self.controller.prepare(self.times, h, self.measured_attitude, self.base[:, 3:6],
                                **moving_target_accelerations(self.scene, self.base))
        if first > 0:
            self._point_set_points_at(first)

    def _point_set_points_at(self, first: int) -> None:
        """The kernel's set point tables of this chunk, addressed by the run's step (a user controller
        has no kernel state)."""
        state = getattr(self.controller, "state", None)
        points = state.set_points if state is not None else None
        if points is None or not points.values:
            return
        points.values -= first * 2 * 8
        points.rates -= first * 2 * 8
        for name in ("accelerations", "gyro_rates"):   # a moving target's
            if getattr(points, name):
                setattr(points, name, getattr(points, name) - first * 2 * 8)

    def chunk_signals(self, count: int) -> dict:
        """'time' and one array per signal of the chunk's first `count` rows; row k: outputs at t_k, the
        command applied over [t_k, t_k+1], the controller's output at t_k, the base inputs at t_k. Views of
        the tables for a whole run, copies for a chunk (its tables are filled again by the next)."""
        own = np.copy if self.chunk_rows < self.n + 1 else np.asarray
        u_cmd = own(self.u_cmd[self.delay:self.delay + count])
        u_applied = self.u_cmd[:count].copy()   # the command of `delay` steps before, 0 until one is due
        u_applied[np.arange(self.first, self.first + count) < self.delay] = 0.0
        signals = {"time": self.times[:count]}
        signals.update({name: own(self.rec_real[:count, j]) for j, name in enumerate(self.real_names)})
        signals.update({name: self.rec_mode[:count, j].astype(float) for j, name in enumerate(self.mode_names)})
        signals.update(command_signals(self.drives, u_applied, u_cmd, own(self.u_asked[:count])))
        signals.update({"alpha_ref": own(self.refs[:count, 0]), "beta_ref": own(self.refs[:count, 1])})
        signals.update({name: self.base[:count, j] for j, name in enumerate(BASE_INPUTS)})
        signals["heave"] = self.heave_rows(self.first, count)
        return signals


class StreamPlan(Plan):
    """A Plan whose tables hold CHUNK_ROWS rows, loaded chunk by chunk (load_chunk, from the streamed
    run): the base motion, the sensors' noise (each random draw of Sensors.prepare from a generator
    placed at its start, scene/sensors.py SensorStream) and the set points of a chunk only."""

    def __init__(self, scene: Scene, fmu: FMU, stop_time: float | None, controller, chunk_rows: int):
        super().__init__(scene, fmu, stop_time, controller, chunk_rows)
        self.sensor_stream = self.sensors.stream(self.n + 1, self.h)

    def base_rows(self, first: int, count: int) -> np.ndarray:
        return self.motion.sample_rows(first, count, self.h)

    def measured_rows(self, first: int, base: np.ndarray) -> np.ndarray:
        return self.sensor_stream.rows(first, base)

    def heave_rows(self, first: int, count: int) -> np.ndarray:
        return self.motion.position_rows(first, count, self.h)[:, 2]


def moving_target_accelerations(scene: Scene, base) -> dict:
    """The base's angular accelerations for a controller's prepare(), as a keyword, with a moving
    target only (the command's accelerations); controllers that wrap another (an injection) take
    the fixed target's four arguments."""
    return {"accelerations": base[:, 6:9]} if scene.moving_target is not None else {}


def memory_needed(fmu: FMU, points: int) -> int:
    """Bytes a run held in memory takes at least for `points` communication points: per point the records (the
    outputs, the modes), the inputs and base motion, the times, the measured attitude, the set points,
    the commands, and the RunResult's columns (recorded and derived) made from them."""
    real = len(real_outputs(fmu))
    modes = sum(1 for name in mode_outputs(fmu) if fmu.has(name))
    plan = real + modes / 2 + (2 + len(BASE_INPUTS)) + len(BASE_INPUTS) + 1 + 3 + 4 + 4
    result = 1 + real + modes + 6 + len(BASE_INPUTS) + 1 + 10
    return int(points * (plan + result) * 8)


def check_memory(scene: Scene, fmu: FMU, plan) -> None:
    """Refuses (SceneError, one line) a run whose record cannot be held in the memory available, before
    anything is allocated (numpy would fail part-way with a traceback); `gimbal2axis run` streams the
    record to disk instead (streaming.py)."""
    needed, available = memory_needed(fmu, plan.n + 1), available_memory()
    if available is not None and needed > available:
        raise SceneError(f"{scene.name}: a run of {plan.n + 1:,} points ({plan.t_end:g} s at {plan.h:g} s) held in "
                         f"memory needs {size_text(needed)}, {size_text(available)} is available; shorten it, or "
                         f"run it with `gimbal2axis run`, which writes it to disk as it goes")


def choose_records(plan: Plan, fmu: FMU) -> None:
    """What a run records and sets, on `plan`: the outputs' names and value references, the columns the
    sensors read, the inputs' value references."""
    plan.real_names, plan.mode_names = recorded_names(plan.scene, fmu, plan.drives)
    plan.real_vrs = [fmu.vr(name) for name in plan.real_names]
    plan.mode_vrs = [fmu.vr(name) for name in plan.mode_names]
    plan.i_alpha, plan.i_beta = plan.real_names.index("alpha"), plan.real_names.index("beta")
    plan.i_gyro = [plan.real_names.index(f"los.omega[{j}]") for j in (1, 2, 3)]
    plan.i_joint_rates = [plan.real_names.index(name) for name in ("alpha_dot", "beta_dot")]
    plan.input_vrs = [fmu.vr(drive.input_name) for drive in plan.drives] + ([] if plan.motion.fixed else
                                                                            [fmu.vr(b) for b in BASE_INPUTS])
    # the loops pass these arrays' addresses to the FMU: they live as long as the plan
    plan.vr_arrays = [np.array(vrs, dtype=np.uint32) for vrs in (plan.real_vrs, plan.mode_vrs, plan.input_vrs)]


def recorded_names(scene: Scene, fmu: FMU, drives) -> tuple[list, list]:
    """The Real and the Integer outputs a run of `scene` records: real_outputs, a current drive's amplifier,
    mode_outputs, then what the scene's [plot] names besides (_add_plotted)."""
    real_names = real_outputs(fmu) + [name for drive in drives if drive.kind == "current"
                                      for name in drive.amplifier_outputs if fmu.has(name)]
    mode_names = [name for name in mode_outputs(fmu, scene)
                  if fmu.has(name) and fmu.variables[name].type in ("Integer", "Enumeration")]
    _add_plotted(scene, fmu, real_names, mode_names)
    for needed in SENSED_OUTPUTS:
        if needed not in real_names:
            raise SceneError(f"{fmu.path} has no output '{needed}', which the sensors need")
    return real_names, mode_names


def _add_plotted(scene: Scene, fmu: FMU, real_names: list, mode_names: list) -> None:
    """An FMU variable the scene's [plot] names is recorded too (a solver counter, a parameter, an output
    the runner leaves out), so that the plot draws what was asked (check_against_fmu refuses the rest)."""
    for name in sorted({n for names in scene.plot.values() for n in names}):
        if not fmu.has(name) or name in real_names or name in mode_names or name in BASE_INPUTS:
            continue
        kind = fmu.variables[name].type
        if kind == "Real" and fmu.variables[name].causality != "input":
            real_names.append(name)
        elif kind in ("Integer", "Enumeration"):
            mode_names.append(name)


def initialize(slave, scene: Scene, fmu: FMU, plan: Plan) -> None:
    """Set-up and initialization: start values, the first inputs (0 V, the base at t = 0)."""
    slave.setupExperiment(startTime=0.0, stopTime=plan.t_end)
    base_eps = plan.motion.sample(np.array([1e-6]))[0]
    fmu.set_values(slave, start_values(scene, fmu, plan.base[0], base_eps))
    slave.enterInitializationMode()
    slave.setReal(plan.input_vrs, [0.0, 0.0] + ([] if plan.motion.fixed else plan.base[0].tolist()))
    slave.exitInitializationMode()
