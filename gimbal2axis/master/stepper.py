"""The communication loop, once: a Plan's chunks stepped on one FMU instance, each chunk's record handed
to a sink (in memory: MemorySink; Parquet chunks: streaming.RecordSink).

At each communication point t_k = k h the stepper reads the FMU's outputs into the record, lets the
sensors measure and the controller compute u_k from them, and then steps the FMU over [t_k, t_{k+1}]
with
  - the command u_{k-d} (d = delay_steps, default 1: the command computed from the sensors at t_k is
    applied over [t_{k+1}, t_{k+2}]; before the first command is due, 0), held constant;
  - the base inputs at t_k (attitude, rates, accelerations, v_a, a_a), exact values of the base
    motion; the FMU extrapolates them inside the step with constant acceleration (docs/physics.md,
    section 2). With a fixed base the base inputs are never set (they stay 0).

Two ways to make a chunk's steps, the same bits: the Python loop (python_steps, over the per-point
calls of point_calls, which lockstep.py also uses for its cases), and for the built-in controllers
the compiled loop (compiled_loop.py, c_kernel/src/master_loop.c), the only fast path.
"""
from __future__ import annotations

import numpy as np

from ..errors import FMUCallFailed, SceneError, StopSignal
from ..scene.controllers import ControllerError
from . import compiled_loop
from .plan import initialize
from .stopping import Stop, StopRequest

# Steps of the compiled loop between progress updates and looks at a StopRequest: about 40 ms of
# the ship scene, so Ctrl-C or SIGTERM is answered at once to a person.
CHUNK_STEPS = 4096
# Steps of the Python loop between progress updates.
PROGRESS_STEPS = 256


class RawCalls:
    """The four functions of the loop, called through ctypes with plain addresses: fmpy's wrappers
    convert and check every argument, which costs more than the FMU's own step."""

    def __init__(self, slave):
        import ctypes

        status, pointer, size = ctypes.c_int, ctypes.c_void_p, ctypes.c_size_t
        array_call = ctypes.CFUNCTYPE(status, pointer, pointer, size, pointer)
        self.get_real = array_call(("fmi2GetReal", slave.dll))
        self.get_integer = array_call(("fmi2GetInteger", slave.dll))
        self.set_real = array_call(("fmi2SetReal", slave.dll))
        self.do_step = ctypes.CFUNCTYPE(status, pointer, ctypes.c_double, ctypes.c_double, ctypes.c_int)(
            ("fmi2DoStep", slave.dll))


def choose_loop(controller, compiled: bool | None) -> str:
    """'compiled' or 'python': `compiled` None takes the compiled loop where it can run this
    controller, True insists on it (an error says why it cannot), False takes the Python loop."""
    if compiled is False:
        return "python"
    why_not = compiled_loop.available()
    if why_not is None and not compiled_loop.supports(controller):
        why_not = f"the compiled loop runs the built-in controllers only, not {type(controller).__name__}"
    if why_not is None:
        return "compiled"
    if compiled:
        raise SceneError(why_not)
    return "python"


def point_calls(slave, calls: RawCalls, plan, measure_ideal: bool = True):
    """The calls of a communication point on the plan's current chunk (row = k - plan.first), closures
    over its tables' addresses (a local costs less than an attribute per step; the plan keeps the arrays
    alive, and the closures the plan):
      read(k, row) -> (alpha, beta, gyro, base attitude, base rates) as the controller sees them at t_k,
        the outputs read into the record first (FMUCallFailed when the FMU refuses);
      store(u, reference, asked): the controller's output at the chunk's next point, its set point, what
        it asked before its clamp (kept in lists: appending costs less than writing a numpy row);
      apply(k, row): the delayed command and the base inputs set, the step over [t_k, t_k+1] made;
      flush(): the commands stored into the plan's tables (u_cmd, refs, u_asked), before they are read.
    `measure_ideal` False: ideal sensors pass the outputs on without the kernel's call."""
    return (_reader(slave.component, calls, plan, measure_ideal),) + _commander(slave.component, calls, plan)


def _reader(component, calls: RawCalls, plan, measure_ideal: bool):
    """point_calls' read."""
    (real_refs, mode_refs), (real_count, mode_count) = \
        [a.ctypes.data for a in plan.vr_arrays[:2]], [len(a) for a in plan.vr_arrays[:2]]
    rec_real, get_real, get_integer = plan.rec_real, calls.get_real, calls.get_integer
    real_row, real_stride = rec_real.ctypes.data, rec_real.strides[0]
    mode_row, mode_stride = plan.rec_mode.ctypes.data, plan.rec_mode.strides[0]
    measure = None if plan.sensors.ideal and not measure_ideal else plan.sensors.measure
    # Python floats: reading them per step costs less than indexing numpy rows
    attitude_rows, rate_rows = plan.measured_attitude.tolist(), plan.base[:, 3:6].tolist()
    i_alpha, i_beta, (g1, g2, g3), (i_alpha_dot, i_beta_dot) = plan.i_alpha, plan.i_beta, plan.i_gyro, \
        plan.i_joint_rates

    def read(k, row):
        plan.k = k
        if get_real(component, real_refs, real_count, real_row + row * real_stride) > 1:
            raise FMUCallFailed("fmi2GetReal")
        if mode_count and get_integer(component, mode_refs, mode_count, mode_row + row * mode_stride) > 1:
            raise FMUCallFailed("fmi2GetInteger")
        y = rec_real[row].tolist()
        if measure is None:
            return y[i_alpha], y[i_beta], [y[g1], y[g2], y[g3]], attitude_rows[row], rate_rows[row]
        alpha, beta, gyro = measure(k, y[i_alpha], y[i_beta], [y[g1], y[g2], y[g3]], y[i_alpha_dot], y[i_beta_dot])
        return alpha, beta, gyro, attitude_rows[row], rate_rows[row]

    return read


def _commander(component, calls: RawCalls, plan):
    """point_calls' store, apply and flush."""
    input_refs, input_count = plan.vr_arrays[2].ctypes.data, len(plan.vr_arrays[2])
    inputs, set_real, do_step = plan.inputs, calls.set_real, calls.do_step
    input_row, input_stride = inputs.ctypes.data, inputs.strides[0]
    h, delay, zero = plan.h, plan.delay, (0.0, 0.0)
    commands, references, asked_commands = [], [], []   # the chunk's, from its row 0
    carried = plan.u_cmd[:delay].tolist()   # the last `delay` commands of the chunk before (0 before the first)

    def store(u, reference, asked):
        commands.append(u)
        references.append(reference)
        asked_commands.append(asked)

    def apply(k, row):
        if delay == 0:
            inputs[row, 0], inputs[row, 1] = commands[row]
        elif k < delay:
            inputs[row, 0], inputs[row, 1] = zero
        else:   # the command of step k - delay: of this chunk, or carried over from the one before
            inputs[row, 0], inputs[row, 1] = commands[row - delay] if row >= delay else carried[row]
        if set_real(component, input_refs, input_count, input_row + row * input_stride) > 1:
            raise FMUCallFailed("fmi2SetReal")
        if do_step(component, k * h, h, 1) > 1:
            raise FMUCallFailed("fmi2DoStep")

    def flush():
        count = len(commands)
        if count:
            plan.u_cmd[delay:delay + count] = commands
            plan.refs[:count] = references
            plan.u_asked[:count] = asked_commands

    return store, apply, flush


class Stepper:
    """One FMU instance stepped through a plan's chunks by the Python loop or, for a built-in
    controller, the compiled one (`loop`: choose_loop's answer)."""

    def __init__(self, slave, plan, loop: str):
        self.slave, self.plan, self.calls = slave, plan, RawCalls(slave)
        self.compiled = compiled_loop.CompiledLoop(slave, self.calls, plan) if loop == "compiled" else None

    def step_chunk(self, first: int, count: int, stop: StopRequest, bar, failures=Exception):
        """Steps the run's points first .. first + count - 1 (loading the chunk's inputs after the first);
        plan.rows: how many are recorded whole. Returns the exception of `failures` that ended it early
        (the FMU's refusal, the controller's exception, no memory), None when it ran whole or was asked to
        stop; a StopSignal raised inside (a repeated signal) is a stop while the run is `stepping`."""
        try:
            if first > 0:
                self.plan.load_chunk(first, count)
            steps = self.python_steps if self.compiled is None else self.compiled_steps
            steps(first, first + count - 1, stop, bar)
        except StopSignal:
            if not stop.stepping:
                raise
        except failures as exc:
            return exc
        return None

    def python_steps(self, first: int, last: int, stop: StopRequest, bar) -> None:
        """Locals only inside the loop: it is the Python runs' whole per-step cost. Ends early, before
        reading the outputs at t_k, when `stop` is requested."""
        plan = self.plan
        read, store, apply, flush = point_calls(self.slave, self.calls, plan)
        controller, h, n, offset = plan.controller, plan.h, plan.n, plan.first
        recorded = first
        try:
            for k in range(first, last + 1):
                if stop.kind is not None:
                    break
                row = k - offset
                alpha, beta, gyro, attitude, rates = read(k, row)
                u = controller(k * h, h, alpha, beta, gyro, attitude, rates, step=k)
                store(u, controller.reference, controller.asked)
                recorded = k + 1
                if k == n:
                    break
                apply(k, row)
                if k % PROGRESS_STEPS == 0:
                    bar.update((k + 1) * h)
        finally:
            flush()
            plan.rows = recorded

    def compiled_steps(self, first: int, last: int, stop: StopRequest, bar) -> None:
        """The compiled loop, CHUNK_STEPS at a time; ends at such a boundary when `stop` is requested (the
        FMU has then made the step after the last recorded point, whose outputs are not recorded)."""
        plan, loop = self.plan, self.compiled
        loop.point_at_chunk(first, plan)
        try:
            for start in range(first, last + 1, CHUNK_STEPS):
                if stop.kind is not None:
                    break
                end = min(start + CHUNK_STEPS - 1, last)
                loop.run(start, end)
                plan.rows = end + 1
                bar.update(min(end + 1, plan.n) * plan.h)
        except FMUCallFailed as failure:
            # the outputs at the failed step were recorded unless reading them is what failed
            plan.rows = plan.k + (failure.function in ("fmi2SetReal", "fmi2DoStep"))
            raise


class RecordWriteFailed(Exception):
    """Writing a chunk of the record failed (a full disk, a file system gone read-only)."""

    def __init__(self, cause: Exception, time_s: float):
        where = f"{cause.filename}: " if isinstance(cause, OSError) and cause.filename else ""
        text = cause.strerror if isinstance(cause, OSError) and cause.strerror else f"{type(cause).__name__}: {cause}"
        super().__init__(f"writing the record failed at t = {time_s:.6g} s: {where}{text}")


def failure_message(scene, plan, exc: BaseException, log: list | None) -> str:
    """The message of a run stopped by `exc` at step plan.k, with the FMU's last log messages."""
    if isinstance(exc, (ControllerError, RecordWriteFailed)):   # the user's controller, or the disk: its culprit
        return f"{scene.name}: {exc}"
    if isinstance(exc, SceneError):
        return str(exc)
    if not isinstance(exc, FMUCallFailed) and not type(exc).__module__.startswith("fmpy"):
        # neither the FMU nor the user's code (a ControllerError, above): the runner's own sensors or loop
        return f"{scene.name}: the scene runner failed at t = {plan.k * plan.h:.6g} s: {type(exc).__name__}: {exc}"
    details = "; ".join(map(str, (log or [])[-5:])) or "no log message"
    return f"{scene.name}: the FMU failed at t = {plan.k * plan.h:.6g} s ({exc}): {details}"


def failure_error(message: str, exc: BaseException) -> SceneError:
    """The SceneError of a failed run with `message` (failure_message); a ControllerError, keeping
    the traceback of the user's exception, when the user's controller is the culprit."""
    return ControllerError(message, exc.details) if isinstance(exc, ControllerError) else SceneError(message)


def start(slave, scene, fmu, plan, log: list | None) -> None:
    """Initializes the instance (plan.initialize) and starts the controller; a refusal raises SceneError
    (the scene's, not the run's: nothing is recorded)."""
    try:
        initialize(slave, scene, fmu, plan)
        plan.controller.start(plan.h, scene.name)
    except ControllerError as exc:   # the user's reset() raised
        raise failure_error(failure_message(scene, plan, exc, log), exc) from None
    except (SceneError, StopSignal):
        raise
    except Exception as exc:   # refused at initialization: the scene, not the run
        raise SceneError(failure_message(scene, plan, exc, log)) from None


class MemorySink:
    """The record held in memory: the chunks' signals (Plan.chunk_signals), joined at the end."""

    def __init__(self):
        self.parts = []

    def add(self, plan, first: int, recorded: int) -> BaseException | None:
        self.parts.append(plan.chunk_signals(recorded))
        return None

    def abandon(self, message: str) -> None:
        """The run failed before its first point: nothing to keep."""

    def signals(self) -> dict:
        if len(self.parts) == 1:
            return self.parts[0]
        return {name: np.concatenate([part[name] for part in self.parts]) for name in self.parts[0]}


def step_run(scene, plan, slave, log: list | None, loop: str, sink, stop: StopRequest, bar,
             keep_partial: bool = True) -> Stop | None:
    """Steps the started instance through the plan's chunks, each chunk's recorded points handed to
    `sink` (its add returns None, or the exception that kept it from keeping them: a StopSignal, or a
    RecordWriteFailed that fails the run). Returns None for a whole run (the instance terminated), else
    the Stop of a run that failed (with `keep_partial`) or was asked to stop: its record ends at the last
    point kept. Raises SceneError (sink.abandon first) when nothing was recorded, or the run failed
    without `keep_partial`. While `stop.stepping` (a streamed run under signal handlers) any exception
    fails the run with its record kept; else only an Exception does, and the others go through."""
    stepper = Stepper(slave, plan, loop)
    failures = BaseException if stop.stepping else Exception
    stopped = None
    for first in range(0, plan.n + 1, plan.chunk_rows):
        count = min(plan.chunk_rows, plan.n + 1 - first)
        failure = stepper.step_chunk(first, count, stop, bar, failures)
        if plan.rows > first:
            not_kept = sink.add(plan, first, plan.rows - first)
            if not_kept is not None:   # the record ends before this chunk
                plan.rows = first
                failure = failure or (None if isinstance(not_kept, StopSignal) else not_kept)
        stopped = _ended(scene, plan, log, sink, stop, failure, first + count, keep_partial)
        if stopped is not None:
            break
    bar.close(complete=stopped is None)
    if stopped is None:
        slave.terminate()
    return stopped


def _ended(scene, plan, log, sink, stop: StopRequest, failure, end: int, keep_partial: bool) -> Stop | None:
    """After the chunk of points up to `end` - 1: the Stop of a run that ends here, None if it goes on
    (or is whole)."""
    last = (plan.rows - 1) * plan.h
    if failure is not None:
        message = failure_message(scene, plan, failure, log)
        if plan.rows == 0 or not keep_partial:
            sink.abandon(message)
            raise failure_error(message, failure)
        return Stop("failed", last, message, getattr(failure, "details", None))
    if plan.rows == end and stop.kind is None:
        return None
    if plan.rows == 0:
        raise SceneError(f"{scene.name}: {stop.reason} before the first communication point: nothing recorded")
    if stop.kind is None:   # cannot be: a chunk ends short only when asked to stop
        raise AssertionError("a chunk ended short without a stop request")
    return Stop(stop.kind, last, f"{scene.name}: {stop.reason}")
