"""N cases of a user controller class with `batch = True`, stepped together (lockstep): one FMU
instance and one master.Plan per case (its own base motion, sensors, records and delay), one call
of the user's step() for all of them per communication point.

Per communication point t_k: each case's outputs are read into its records through raw calls on
preallocated arrays (as in master.step_loop) and its sensors measure; the measurements are stacked
(alpha, beta: (N,); gyro, base_attitude, base_rates: (N, 3)); the user's step(t, measurements)
returns (N, 2) voltages; then, case by case, the voltage (saturated at the case's +-U_L) goes into
its record, the delayed one into its inputs, and its FMU takes the step.

Cases run together when they share what the loop's one clock and the class's one object need
(batch_key): the class, the step size, the number of steps, the delay, whether there is a target,
and the options that are not numbers. Everything else may differ per case: parameters, fidelity
(each case has its own instance), base motion, sensors, target direction and numeric options.

Options: a numeric option whose values differ between the cases reaches the class as a numpy array
of shape (N,) (the cases' values in order); options equal in all cases stay as given (numpy
broadcasting makes the two alike in arithmetic). reset(context) is called once, with
context.cases = N; context.u_limit is a pair of (N,) arrays and context.target an (N, 3) array
where the cases differ in them, else as in a single run.

A case whose FMU call fails, or whose voltages are not finite, ends as failed with the message a
single run (master.run) gives (the voltages before the clamp recorded as u_R1_asked, u_R2_asked), and drops out: its instance takes no more steps and its row of the
arrays passed to step() keeps its last measurements (its voltages are ignored). An exception in
the user's step() or reset(), or voltages of the wrong shape, fail all cases still running.
Results: per case a RunResult as master.run returns it (loop = 'lockstep'), or the SceneError.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..scene import controllers
from ..errors import SceneError, StopSignal
from .master import (FMUCallFailed, Plan, RawCalls, clamp_count, failure_error, failure_message, initialize,
                     recorded_signals)
from .results import RunResult
from ..scene.scene import Scene


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def user_class(scene: Scene):
    """The scene's user controller class if it has `batch = True`, else None."""
    spec = scene.controller_spec
    if spec.get("type") != "python":
        return None
    cls, _ = controllers.load_user_class(spec, scene.path.parent)
    return cls if getattr(cls, "batch", False) is True else None


def batch_key(scene: Scene):
    """What cases must share to run in one lockstep batch, or None if the scene's controller is not
    a batch class (a class that cannot be loaded: None too, the single run reports it)."""
    try:
        cls = user_class(scene)
    except SceneError:
        return None
    if cls is None:
        return None
    spec = scene.controller_spec
    options = spec.get("options", {})
    if not isinstance(options, dict):
        return None
    shared = tuple(sorted((k, "<number>" if _is_number(v) else repr(v)) for k, v in options.items()))
    return (cls.__module__, cls.__qualname__, str(scene.path.parent), scene.step_size, scene.n_steps,
            scene.delay_steps, scene.target is None, shared)


def merge_options(option_tables: list) -> dict:
    """The keyword arguments of the batch object: per option, its value if all cases agree, else
    a numpy array of the cases' values (numbers only)."""
    merged = {}
    for key in option_tables[0]:
        values = [table[key] for table in option_tables]
        if all(v == values[0] and type(v) is type(values[0]) for v in values):
            merged[key] = values[0]
        elif all(_is_number(v) for v in values):
            merged[key] = np.array(values)
        else:
            raise SceneError(f"[controller] option {key!r} differs between the cases of a batch and is not a number")
    return merged


def _per_case(values: list):
    """A pair/vector of the cases: as given if all equal, else stacked (first axis: the cases)."""
    first = values[0]
    if all(v == first for v in values):
        return first
    return np.array(values, dtype=float)


class _Case:
    """One case of the batch: its plan, its instance and the raw pointers its loop uses."""

    def __init__(self, index, position, scene, fmu, plan, u_limit):
        self.index, self.position = index, position   # in the scenes given; in the batch's arrays
        self.scene, self.fmu, self.plan, self.u_limit = scene, fmu, plan, u_limit
        self.slave = self.log = None
        self.error = None      # the SceneError once failed

    def wire(self):
        plan = self.plan
        calls = RawCalls(self.slave)
        self.get_real, self.get_integer = calls.get_real, calls.get_integer
        self.set_real, self.do_step = calls.set_real, calls.do_step
        self.vr_arrays = [np.array(v, dtype=np.uint32) for v in (plan.real_vrs, plan.mode_vrs, plan.input_vrs)]
        (self.real_refs, self.mode_refs, self.input_refs) = [a.ctypes.data for a in self.vr_arrays]
        self.real_count, self.mode_count, self.input_count = [len(a) for a in self.vr_arrays]
        self.real_row, self.real_stride = plan.rec_real.ctypes.data, plan.rec_real.strides[0]
        self.mode_row, self.mode_stride = plan.rec_mode.ctypes.data, plan.rec_mode.strides[0]
        self.input_row, self.input_stride = plan.inputs.ctypes.data, plan.inputs.strides[0]
        self.component = self.slave.component
        self.attitude_rows, self.rate_rows = plan.measured_attitude.tolist(), plan.base[:, 3:6].tolist()

    def fail(self, exc: Exception):
        """Ends the case with the SceneError of `exc` (a ControllerError, naming the scene, when the
        user's class is the culprit)."""
        if isinstance(exc, controllers.ControllerError):
            self.error = failure_error(failure_message(self.scene, self.plan, exc, self.log), exc)
        elif isinstance(exc, SceneError):
            self.error = exc
        else:
            self.error = SceneError(failure_message(self.scene, self.plan, exc, self.log))


def run_lockstep(scenes: list, fmu, instances: list | None = None) -> list:
    """Runs the scenes (cases of one batch_key) in lockstep; returns per scene a RunResult or the
    SceneError that ended it. `instances`: one (slave, log) per scene to reuse (reset first with
    fmi2Reset, logs cleared; an instance that will not reset raises: the caller may retry on fresh
    ones), else fresh instances are made and freed."""
    keys = {batch_key(scene) for scene in scenes}
    if len(keys) != 1 or None in keys:
        raise ValueError("run_lockstep needs scenes of one batch class that share batch_key()")
    outcomes: list = [None] * len(scenes)
    cases = []
    for i, scene in enumerate(scenes):
        try:
            plan = Plan(scene, fmu, None, controllers.Controller())   # the placeholder is never called
            u_limit = tuple(drive.limit for drive in plan.drives)
        except SceneError as exc:
            outcomes[i] = exc
            continue
        cases.append(_Case(i, len(cases), scene, fmu, plan, u_limit))
    if not cases:
        return outcomes
    owned = instances is None
    wall0, cpu0 = time.perf_counter(), time.process_time()
    try:
        for case in cases:
            if owned:
                case.log = []
                case.slave = fmu.instantiate(case.scene.name, case.log)
            else:
                case.slave, case.log = instances[case.index]
                case.log.clear()
                case.slave.reset()
        _run(cases)
    finally:
        if owned:
            for case in cases:
                if case.slave is not None:
                    case.slave.freeInstance()
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    for case in cases:
        if case.error is not None:
            outcomes[case.index] = case.error
            continue
        signals = recorded_signals(case.plan)
        result = RunResult(case.scene, signals, wall / len(cases), case.plan.t_end)
        result.voltage_clamp = clamp_count(signals)
        result.loop_cpu_time = cpu / len(cases)   # the batch's set-up and loop, shared out evenly
        result.loop = "lockstep"
        result.batch_size = len(cases)
        outcomes[case.index] = result
    return outcomes


def _make_user(cases: list):
    first = cases[0].scene
    spec = first.controller_spec
    cls, path = controllers.load_user_class(spec, first.path.parent)
    label = controllers.class_label(cls, path)
    options = merge_options([case.scene.controller_spec.get("options", {}) for case in cases])
    user = controllers.build_user(cls, label, path, options)
    u_limit = tuple(_per_case([case.u_limit[j] for case in cases]) for j in (0, 1))
    target = None if first.target is None else _per_case([case.scene.target for case in cases])
    context = controllers.ControllerContext(first.step_size, u_limit, target, int(spec.get("delay_steps", 1)),
                                            first.name, cases=len(cases))
    return user, label, path, context


def _fail_all(alive: list, exc: Exception):
    for case in alive:
        case.fail(exc)
    alive.clear()


def _run(cases: list) -> None:
    """Initialization and the communication steps of the cases; failures go to case.error."""
    alive = []
    for case in cases:
        try:
            initialize(case.slave, case.scene, case.fmu, case.plan)
            case.wire()
            alive.append(case)
        except Exception as exc:   # SceneError too
            case.fail(exc)
    if not alive:
        return
    try:
        user, label, path, context = _make_user(cases)
        try:
            user.reset(context)
        except StopSignal:
            raise
        except BaseException as exc:   # sys.exit, a KeyboardInterrupt of its own: the code's failure
            raise controllers.user_exception(label, "reset()", exc, path, 0.0) from None
    except Exception as exc:   # a SceneError as it is; others as master.run reports them, at t = 0
        return _fail_all(alive, exc)
    first = cases[0].plan
    h, n, delay, count = first.h, first.n, first.delay, len(cases)
    zero = (0.0, 0.0)
    rows = [[0.0, 0.0, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]] for _ in cases]  # last measurements
    # Per case the locals of its loop in one tuple (unpacking costs less than attribute look-ups).
    slots = [(case, case.plan, case.component, case.get_real, case.real_refs, case.real_count, case.real_row,
              case.real_stride, case.get_integer, case.mode_refs, case.mode_count, case.mode_row, case.mode_stride,
              case.set_real, case.input_refs, case.input_count, case.input_row, case.input_stride, case.do_step,
              case.plan.rec_real, case.plan.inputs, None if case.plan.sensors.ideal else case.plan.sensors.measure,
              case.plan.i_alpha, case.plan.i_beta, case.plan.i_gyro, case.plan.i_joint_rates, case.attitude_rows,
              case.rate_rows,
              case.plan.u_cmd, case.plan.refs, case.u_limit[0], case.u_limit[1], rows[case.position],
              case.plan.u_asked)
             for case in alive]
    isfinite, array, Measurements = math.isfinite, np.array, controllers.Measurements
    for k in range(n + 1):
        t = k * h
        failed = []
        for slot in slots:
            (case, plan, component, get_real, real_refs, real_count, real_row, real_stride, get_integer, mode_refs,
             mode_count, mode_row, mode_stride, _, _, _, _, _, _, rec_real, _, measure, i_alpha, i_beta, (g1, g2, g3),
             (i_alpha_dot, i_beta_dot), attitude_rows, rate_rows, _, _, _, _, row, _) = slot
            plan.k = k
            if get_real(component, real_refs, real_count, real_row + k * real_stride) > 1:
                case.fail(FMUCallFailed("fmi2GetReal"))
                failed.append(slot)
                continue
            if mode_count and get_integer(component, mode_refs, mode_count, mode_row + k * mode_stride) > 1:
                case.fail(FMUCallFailed("fmi2GetInteger"))
                failed.append(slot)
                continue
            y = rec_real[k].tolist()
            if measure is None:
                row[0], row[1], row[2] = y[i_alpha], y[i_beta], [y[g1], y[g2], y[g3]]
            else:
                row[0], row[1], row[2] = measure(k, y[i_alpha], y[i_beta], [y[g1], y[g2], y[g3]], y[i_alpha_dot],
                                                 y[i_beta_dot])
            row[3], row[4] = attitude_rows[k], rate_rows[k]
        if failed:
            slots = [slot for slot in slots if slot not in failed]
        if not slots:
            return
        m = Measurements(array([r[0] for r in rows]), array([r[1] for r in rows]), array([r[2] for r in rows]),
                         array([r[3] for r in rows]), array([r[4] for r in rows]))
        try:
            try:
                returned = user.step(t, m)
            except StopSignal:
                raise
            except BaseException as exc:
                raise controllers.user_exception(label, "step()", exc, path, t) from None
            voltages = controllers.batch_voltages(label, t, returned, count).tolist()
            references = controllers.batch_reference(label, user, count).tolist()
        except Exception as exc:
            return _fail_all([slot[0] for slot in slots], exc)
        failed = []
        for slot in slots:
            (case, plan, component, _, _, _, _, _, _, _, _, _, _, set_real, input_refs, input_count, input_row,
             input_stride, do_step, _, inputs, _, _, _, _, _, _, _, u_cmd, refs, limit1, limit2, _, u_asked) = slot
            position = case.position
            u1, u2 = voltages[position]
            if not (isfinite(u1) and isfinite(u2)):
                case.fail(controllers.ControllerError(f"{label}: step() at t = {t:.6g} s returned ({u1}, {u2}): "
                                                      "the voltages must be finite"))
                failed.append(slot)
                continue
            u = (min(max(u1, -limit1), limit1), min(max(u2, -limit2), limit2))
            u_cmd.append(u)
            refs.append(tuple(references[position]))
            u_asked.append((u1, u2))
            if k == n:
                continue
            applied = u if delay == 0 else (u_cmd[k - delay] if k >= delay else zero)
            inputs[k, 0], inputs[k, 1] = applied
            if set_real(component, input_refs, input_count, input_row + k * input_stride) > 1:
                case.fail(FMUCallFailed("fmi2SetReal"))
                failed.append(slot)
            elif do_step(component, t, h, 1) > 1:
                case.fail(FMUCallFailed("fmi2DoStep"))
                failed.append(slot)
        if failed:
            slots = [slot for slot in slots if slot not in failed]
    for slot in slots:
        case = slot[0]
        try:
            case.slave.terminate()
        except Exception as exc:
            case.fail(exc)
