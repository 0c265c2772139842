"""N cases of a user controller class with `batch = True`, stepped together (lockstep): one FMU
instance and one plan.Plan per case (its own base motion, sensors, records and delay), one call
of the user's step() for all of them per communication point.

Per communication point t_k: each case's outputs are read into its records and its sensors measure
(the stepper's calls of a point, stepper.point_calls, as a single run's Python loop makes them); the
measurements are stacked (alpha, beta: (N,); gyro, base_attitude, base_rates: (N, 3)); the user's
step(t, measurements) returns (N, 2) voltages; then, case by case, the voltage (saturated at the
case's +-U_L) goes into its record, the delayed one into its inputs, and its FMU takes the step.

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
from ..errors import FMUCallFailed, SceneError, StopSignal
from .plan import Plan, initialize
from .results import RunResult, clamp_count
from .stepper import RawCalls, failure_error, failure_message, point_calls
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
    """One case of the batch: its plan, its instance, the stepper's calls of a point on them, and its
    last measurements (what the batch's arrays hold for it once it has dropped out)."""

    def __init__(self, index, position, scene, fmu, plan, u_limit):
        self.index, self.position = index, position   # in the scenes given; in the batch's arrays
        self.scene, self.fmu, self.plan, self.u_limit = scene, fmu, plan, u_limit
        self.slave = self.log = None
        self.error = None      # the SceneError once failed
        self.measured = (0.0, 0.0, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])

    def take_instance(self, instance) -> None:
        """`instance`: the (slave, log) to reuse, reset first (its log cleared); None: a fresh one."""
        if instance is None:
            self.log = []
            self.slave = self.fmu.instantiate(self.scene.name, self.log)
            return
        self.slave, self.log = instance
        self.log.clear()
        self.slave.reset()

    def result(self, wall: float, cpu: float, count: int) -> RunResult:
        """The case's RunResult, with its share of the batch's times."""
        self.flush()
        signals = self.plan.chunk_signals(self.plan.n + 1)
        result = RunResult(self.scene, signals, wall / count, self.plan.t_end)
        result.voltage_clamp = clamp_count(signals)
        result.loop_cpu_time = cpu / count   # the batch's set-up and loop, shared out evenly
        result.loop = "lockstep"
        result.batch_size = count
        return result

    def start(self) -> bool:
        """Initializes the instance; False (the case failed) when it refuses."""
        try:
            initialize(self.slave, self.scene, self.fmu, self.plan)
            self.read, self.store, self.apply, self.flush = point_calls(self.slave, RawCalls(self.slave), self.plan,
                                                                        measure_ideal=False)
        except Exception as exc:   # SceneError too
            self.fail(exc)
            return False
        return True

    def measure(self, k: int) -> bool:
        """Reads the outputs at t_k and measures them; False (the case failed) when the FMU refuses."""
        try:
            self.measured = self.read(k, k)
        except FMUCallFailed as exc:
            self.fail(exc)
            return False
        return True

    def step(self, k: int, u1: float, u2: float, reference, label: str, t: float) -> bool:
        """Records the batch's voltages for this case (saturated at its +-U_L) and, before the last point,
        steps its FMU with the delayed ones; False (the case failed) for voltages that are not finite or
        an FMU that refuses."""
        if not (math.isfinite(u1) and math.isfinite(u2)):
            self.fail(controllers.ControllerError(f"{label}: step() at t = {t:.6g} s returned ({u1}, {u2}): "
                                                  "the voltages must be finite"))
            return False
        limit1, limit2 = self.u_limit
        self.store((min(max(u1, -limit1), limit1), min(max(u2, -limit2), limit2)), tuple(reference), (u1, u2))
        if k == self.plan.n:
            return True
        try:
            self.apply(k, k)
        except FMUCallFailed as exc:
            self.fail(exc)
            return False
        return True

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
    cases = _planned_cases(scenes, fmu, outcomes)
    if not cases:
        return outcomes
    owned = instances is None
    wall0, cpu0 = time.perf_counter(), time.process_time()
    try:
        for case in cases:
            case.take_instance(None if owned else instances[case.index])
        _run(cases)
    finally:
        if owned:
            for case in cases:
                if case.slave is not None:
                    case.slave.freeInstance()
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    for case in cases:
        outcomes[case.index] = case.error if case.error is not None else case.result(wall, cpu, len(cases))
    return outcomes


def _planned_cases(scenes: list, fmu, outcomes: list) -> list:
    """A _Case per scene whose plan could be made; the SceneError of the others into `outcomes`."""
    cases = []
    for i, scene in enumerate(scenes):
        try:
            plan = Plan(scene, fmu, None, controllers.Controller())   # the placeholder is never called
            u_limit = tuple(drive.limit for drive in plan.drives)
        except SceneError as exc:
            outcomes[i] = exc
            continue
        cases.append(_Case(i, len(cases), scene, fmu, plan, u_limit))
    return cases


class _Batch:
    """The user's batch object for the cases, and its call per communication point."""

    def __init__(self, cases: list):
        first = cases[0].scene
        spec = first.controller_spec
        cls, self.path = controllers.load_user_class(spec, first.path.parent)
        self.label = controllers.class_label(cls, self.path)
        options = merge_options([case.scene.controller_spec.get("options", {}) for case in cases])
        self.user = controllers.build_user(cls, self.label, self.path, options)
        self.count = len(cases)
        u_limit = tuple(_per_case([case.u_limit[j] for case in cases]) for j in (0, 1))
        target = None if first.target is None else _per_case([case.scene.target for case in cases])
        self.context = controllers.ControllerContext(first.step_size, u_limit, target,
                                                     int(spec.get("delay_steps", 1)), first.name, cases=len(cases))

    def reset(self) -> None:
        try:
            self.user.reset(self.context)
        except StopSignal:
            raise
        except BaseException as exc:   # sys.exit, a KeyboardInterrupt of its own: the code's failure
            raise controllers.user_exception(self.label, "reset()", exc, self.path, 0.0) from None

    def step(self, t: float, cases: list) -> tuple[list, list]:
        """The voltages and set points, (N, 2) lists, of the user's step() for the cases' measurements."""
        rows, array = [case.measured for case in cases], np.array
        m = controllers.Measurements(array([r[0] for r in rows]), array([r[1] for r in rows]),
                                     array([r[2] for r in rows]), array([r[3] for r in rows]),
                                     array([r[4] for r in rows]))
        try:
            returned = self.user.step(t, m)
        except StopSignal:
            raise
        except BaseException as exc:
            raise controllers.user_exception(self.label, "step()", exc, self.path, t) from None
        return (controllers.batch_voltages(self.label, t, returned, self.count).tolist(),
                controllers.batch_reference(self.label, self.user, self.count).tolist())


def _fail_all(alive: list, exc: Exception):
    for case in alive:
        case.fail(exc)
    alive.clear()


def _run(cases: list) -> None:
    """Initialization and the communication steps of the cases; failures go to case.error."""
    alive = [case for case in cases if case.start()]
    if not alive:
        return
    try:
        batch = _Batch(cases)
        batch.reset()
    except Exception as exc:   # a SceneError as it is; others as master.run reports them, at t = 0
        return _fail_all(alive, exc)
    h, n = cases[0].plan.h, cases[0].plan.n
    for k in range(n + 1):
        t = k * h
        alive = [case for case in alive if case.measure(k)]
        if not alive:
            return
        try:
            voltages, references = batch.step(t, cases)
        except Exception as exc:
            return _fail_all(alive, exc)
        alive = [case for case in alive
                 if case.step(k, *voltages[case.position], references[case.position], batch.label, t)]
    for case in alive:
        try:
            case.slave.terminate()
        except Exception as exc:
            case.fail(exc)
