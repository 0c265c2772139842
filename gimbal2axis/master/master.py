"""The co-simulation master: one FMU2Slave, fixed communication steps, the controller with the
zero-order-hold delay of the voltages.

At each communication point t_k the master reads the FMU's outputs, lets the sensors measure and
the controller compute u_k from them, and then steps the FMU over [t_k, t_{k+1}] with
  - the voltages u_{k-d} (d = delay_steps, default 1: the voltage computed from the sensors at t_k
    is applied over [t_{k+1}, t_{k+2}]; before the first command is due, 0 V), held constant;
  - the base inputs at t_k (attitude, rates, accelerations, v_a, a_a), exact values of the base
    motion; the FMU extrapolates them inside the step with constant acceleration (docs/physics.md,
    section 2).
With a fixed base the base inputs are never set (they stay 0).
"""
from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass

import numpy as np

from . import compiled_loop
from ..scene.base_motion import INPUTS as BASE_INPUTS
from ..errors import FMUCallFailed, SceneError  # FMUCallFailed: also importable from here, as before
from ..fmu import FMU
from ..scene.controllers import AXES, ControllerError
from ..progress import Progress
from ..scene.drives import command_columns, command_signals, scene_drives
from .results import RunResult
from ..scene.scene import Scene, check_against_fmu, check_run_length, parameter_value, start_values

# How a run ended before its stop time (Stop.kind), in the words of the summary line.
STOP_KINDS = {"failed": "failed", "interrupted": "interrupted (SIGINT)", "terminated": "terminated (SIGTERM)"}


@dataclass(frozen=True)
class Stop:
    """Why and where a run ended before its stop time; its record ends at `time` (the last
    communication point whose outputs, sensors and controller output were all recorded)."""
    kind: str       # a key of STOP_KINDS
    time: float     # s
    reason: str     # one line
    details: str | None = None   # a user controller's traceback (gimbal2axis run --traceback), else None


class StopRequest:
    """Asks a running loop to end, keeping what it recorded: `request(kind, reason)` is seen at the
    next step of the Python loop or at the next chunk boundary of the compiled loop (CHUNK_STEPS
    steps, a few tens of milliseconds).

    A signal handler calls `signal_received`: while the run steps (`stepping`), the first signal
    only asks; a repeated one, or one in any other phase (preparing, the metrics, the plots, the
    files), raises at once (errors.Interrupted, Terminated), so that no phase can ignore Ctrl-C.
    Inside `shield()` (a file being written whole) a signal only asks, and whoever holds the
    shield looks at `kind` after it."""

    def __init__(self):
        self.kind, self.reason = None, None
        self.stepping, self.shields, self.signals = False, 0, 0
        self.phase = "running"   # what the run was doing, for the message of a signal that ends it

    def request(self, kind: str, reason: str) -> None:
        if kind not in STOP_KINDS:
            raise ValueError(f"unknown stop kind {kind!r}")
        self.kind, self.reason = kind, reason

    def signal_received(self, kind: str, reason: str) -> None:
        self.signals += 1
        if self.kind is None or self.kind == "failed":
            self.request(kind, reason)
        if self.shields == 0 and (self.signals > 1 or not self.stepping):
            self.raise_stop()

    def raise_stop(self) -> None:
        """Raises the exception of the signal asked for (after a shield, or at a phase's start)."""
        from ..errors import Interrupted, Terminated

        if self.kind == "terminated":
            raise Terminated(self.reason)
        if self.kind == "interrupted":
            raise Interrupted(self.reason)

    @contextlib.contextmanager
    def shield(self):
        self.shields += 1
        try:
            yield self
        finally:
            self.shields -= 1


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


# Recorded besides the states (FMU.states, from the model description).
OTHER_REAL_OUTPUTS = ["T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "los.omega[3]"]


def real_outputs(fmu: FMU) -> list[str]:
    """The Real outputs a run records: the FMU's states, then the gear torques and the payload gyro."""
    return fmu.states + [name for name in OTHER_REAL_OUTPUTS if fmu.has(name)]
# Recorded after the modes: the number of mode changes.
EVENT_OUTPUTS = ["events.total"]


def mode_outputs(fmu: FMU, scene: Scene | None = None) -> list[str]:
    """The Integer outputs a run records besides the counters: the switching elements' modes, as the FMU
    declares them (FMU.mode_outputs, from model_core/include/gimbal/switching_elements.def), then
    EVENT_OUTPUTS. An element switched on by a parameter is recorded only in a scene that switches it on
    (without a scene: all), so that a scene without it records what it did before the element existed."""
    def switched_on(switch):
        return switch is None or scene is None or bool(parameter_value(scene, fmu, switch))
    return [mode.name for mode in fmu.mode_outputs if switched_on(mode.switch)] + EVENT_OUTPUTS


class Plan:
    """Everything a run is decided by before the FMU starts: the time grid, the base motion of the
    whole run (evaluated once, vectorised), the controller, the sensors, what is recorded and the
    preallocated arrays the loop fills: the FMU reads its inputs from row k of `inputs` (base columns
    filled up front) and writes its outputs into row k of the records, through raw pointers."""

    def __init__(self, scene: Scene, fmu: FMU, stop_time: float | None, controller):
        check_against_fmu(scene, fmu)
        self.scene, self.h = scene, scene.step_size
        self.t_end = scene.stop_time if stop_time is None else stop_time
        self.n = int(round(self.t_end / self.h))
        check_run_length(scene, self.t_end)
        self.motion = scene.base_motion()
        check_memory(scene, fmu, self)
        self.times = np.arange(self.n + 1) * self.h
        self.base = self.motion.sample(self.times)
        self.drives = scene_drives(scene, fmu)
        self.controller = controller or scene.controller(tuple(drive.limit for drive in self.drives))
        self.sensors = scene.sensors()
        self.delay = scene.delay_steps
        # What the IMU measures (the sensors' noise of the whole run drawn here), and from it the
        # built-in controllers' set points of the whole run.
        self.measured_attitude = self.sensors.prepare(self.base, self.h)
        self.controller.prepare(self.times, self.h, self.measured_attitude, self.base[:, 3:6],
                                **moving_target_accelerations(scene, self.base))

        choose_records(self, fmu)

        self.rec_real = np.zeros((self.n + 1, len(self.real_names)))
        self.rec_mode = np.zeros((self.n + 1, len(self.mode_names)), dtype=np.int32)
        self.inputs = np.zeros((self.n + 1, len(self.input_vrs)))
        if not self.motion.fixed:
            self.inputs[:, 2:] = self.base
        # lists: appending costs less than writing a numpy row; u_asked: the controller's outputs before its clamp
        self.u_cmd, self.refs, self.u_asked = [], [], []
        self.k = 0                      # the step reached (for the message of a failure)
        self.rows = 0                   # communication points recorded whole (rows 0 .. rows - 1)


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
    from .streaming import available_memory, size_text

    needed, available = memory_needed(fmu, plan.n + 1), available_memory()
    if available is not None and needed > available:
        raise SceneError(f"{scene.name}: a run of {plan.n + 1:,} points ({plan.t_end:g} s at {plan.h:g} s) held in "
                         f"memory needs {size_text(needed)}, {size_text(available)} is available; shorten it, or "
                         f"run it with `gimbal2axis run`, which writes it to disk as it goes")


def choose_records(plan, fmu: FMU) -> None:
    """What a run records and sets, on `plan` (a Plan or a streaming.StreamPlan): the outputs' names
    and value references, the columns the sensors read, the inputs' value references."""
    plan.real_names = real_outputs(fmu) + [name for drive in plan.drives if drive.kind == "current"
                                           for name in drive.amplifier_outputs if fmu.has(name)]
    plan.mode_names = [name for name in mode_outputs(fmu, plan.scene)
                       if fmu.has(name) and fmu.variables[name].type in ("Integer", "Enumeration")]
    # an FMU variable the scene's [plot] names is recorded too (a solver counter, a parameter, an output
    # the runner leaves out), so that the plot draws what was asked (check_against_fmu refuses the rest)
    for name in sorted({n for names in plan.scene.plot.values() for n in names}):
        if not fmu.has(name) or name in plan.real_names or name in plan.mode_names or name in BASE_INPUTS:
            continue
        kind = fmu.variables[name].type
        if kind == "Real" and fmu.variables[name].causality != "input":
            plan.real_names.append(name)
        elif kind in ("Integer", "Enumeration"):
            plan.mode_names.append(name)
    for needed in ("alpha", "beta", "los.omega[1]", "los.omega[2]", "los.omega[3]", "alpha_dot", "beta_dot"):
        if needed not in plan.real_names:
            raise SceneError(f"{fmu.path} has no output '{needed}', which the sensors need")
    plan.real_vrs = [fmu.vr(name) for name in plan.real_names]
    plan.mode_vrs = [fmu.vr(name) for name in plan.mode_names]
    plan.i_alpha, plan.i_beta = plan.real_names.index("alpha"), plan.real_names.index("beta")
    plan.i_gyro = [plan.real_names.index(f"los.omega[{j}]") for j in (1, 2, 3)]
    plan.i_joint_rates = [plan.real_names.index(name) for name in ("alpha_dot", "beta_dot")]
    plan.input_vrs = [fmu.vr(drive.input_name) for drive in plan.drives] + ([] if plan.motion.fixed else
                                                                            [fmu.vr(b) for b in BASE_INPUTS])


def initialize(slave, scene: Scene, fmu: FMU, plan: Plan) -> None:
    """Set-up and initialization: start values, the first inputs (0 V, the base at t = 0)."""
    slave.setupExperiment(startTime=0.0, stopTime=plan.t_end)
    base_eps = plan.motion.sample(np.array([1e-6]))[0]
    fmu.set_values(slave, start_values(scene, fmu, plan.base[0], base_eps))
    slave.enterInitializationMode()
    slave.setReal(plan.input_vrs, [0.0, 0.0] + ([] if plan.motion.fixed else plan.base[0].tolist()))
    slave.exitInitializationMode()


def step_loop(slave, plan: Plan, bar: Progress, stop: StopRequest | None = None) -> None:
    """The communication steps: outputs at t_k, sensors, controller, the delayed voltage, one step.
    Locals only inside the loop: it is the master's whole per-step cost. Ends early, before reading
    the outputs at t_k, when `stop` is requested. plan.rows: the points recorded whole (one per
    controller output), also when a call or the controller raises."""
    calls = RawCalls(slave)
    vr_arrays = [np.array(vrs, dtype=np.uint32) for vrs in (plan.real_vrs, plan.mode_vrs, plan.input_vrs)]
    (real_refs, mode_refs, input_refs), (real_count, mode_count, input_count) = \
        [a.ctypes.data for a in vr_arrays], [len(a) for a in vr_arrays]
    rec_real, rec_mode, inputs = plan.rec_real, plan.rec_mode, plan.inputs
    real_row, real_stride = rec_real.ctypes.data, rec_real.strides[0]
    mode_row, mode_stride = rec_mode.ctypes.data, rec_mode.strides[0]
    input_row, input_stride = inputs.ctypes.data, inputs.strides[0]
    component = slave.component
    get_real, get_integer, set_real, do_step = calls.get_real, calls.get_integer, calls.set_real, calls.do_step
    measure, controller = plan.sensors.measure, plan.controller
    h, n, delay = plan.h, plan.n, plan.delay
    # Python floats: reading them per step costs less than indexing numpy rows
    attitude_rows, rate_rows = plan.measured_attitude.tolist(), plan.base[:, 3:6].tolist()
    i_alpha, i_beta, i_gyro, (i_alpha_dot, i_beta_dot) = plan.i_alpha, plan.i_beta, plan.i_gyro, plan.i_joint_rates
    u_cmd, refs, u_asked = plan.u_cmd, plan.refs, plan.u_asked
    zero = (0.0, 0.0)
    stop = stop or StopRequest()   # nobody can ask: one attribute read per step all the same
    try:
        for k in range(n + 1):
            if stop.kind is not None:
                break
            plan.k = k
            t = k * h
            if get_real(component, real_refs, real_count, real_row + k * real_stride) > 1:
                raise FMUCallFailed("fmi2GetReal")
            if mode_count and get_integer(component, mode_refs, mode_count, mode_row + k * mode_stride) > 1:
                raise FMUCallFailed("fmi2GetInteger")
            y = rec_real[k].tolist()
            alpha, beta, gyro = measure(k, y[i_alpha], y[i_beta], [y[i] for i in i_gyro], y[i_alpha_dot],
                                        y[i_beta_dot])
            u = controller(t, h, alpha, beta, gyro, attitude_rows[k], rate_rows[k], step=k)
            u_cmd.append(u)
            refs.append(controller.reference)
            u_asked.append(controller.asked)
            applied = u if delay == 0 else (u_cmd[k - delay] if k >= delay else zero)
            if k == n:
                break
            inputs[k, 0], inputs[k, 1] = applied
            if set_real(component, input_refs, input_count, input_row + k * input_stride) > 1:
                raise FMUCallFailed("fmi2SetReal")
            if do_step(component, t, h, 1) > 1:
                raise FMUCallFailed("fmi2DoStep")
            if k % 256 == 0:
                bar.update((k + 1) * h)
    finally:
        plan.rows = len(u_cmd)


# Steps of the compiled loop between progress updates and looks at a StopRequest: about 40 ms of
# the ship scene, so Ctrl-C or SIGTERM is answered at once to a person.
CHUNK_STEPS = 4096


def compiled_step_loop(slave, plan: Plan, bar: Progress, stop: StopRequest | None = None) -> None:
    """step_loop for the built-in controllers, compiled (compiled_loop.py): the same results. Ends
    at a chunk boundary when `stop` is requested (the FMU has then made the step after the last
    recorded point, whose outputs are not recorded)."""
    loop = compiled_loop.CompiledLoop(slave, RawCalls(slave), plan)
    try:
        for first in range(0, plan.n + 1, CHUNK_STEPS):
            if stop is not None and stop.kind is not None:
                break
            last = min(first + CHUNK_STEPS - 1, plan.n)
            loop.run(first, last)
            plan.rows = last + 1
            bar.update(min(last + 1, plan.n) * plan.h)
    except FMUCallFailed as failure:
        # the outputs at the failed step were recorded unless reading them is what failed
        plan.rows = plan.k + (failure.function in ("fmi2SetReal", "fmi2DoStep"))
        raise
    finally:
        plan.u_cmd, plan.refs, plan.u_asked = loop.u_cmd, loop.refs, loop.u_asked


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


def failure_message(scene: Scene, plan: Plan, exc: Exception, log: list | None) -> str:
    """The message of a run stopped by `exc` at step plan.k, with the FMU's last log messages."""
    if isinstance(exc, ControllerError):   # the user's controller raised or returned nonsense: its culprit
        return f"{scene.name}: {exc}"
    if isinstance(exc, SceneError):
        return str(exc)
    if not isinstance(exc, FMUCallFailed) and not type(exc).__module__.startswith("fmpy"):
        # neither the FMU nor the user's code (a ControllerError, above): the runner's own sensors or loop
        return f"{scene.name}: the scene runner failed at t = {plan.k * plan.h:.6g} s: {type(exc).__name__}: {exc}"
    details = "; ".join(map(str, (log or [])[-5:])) or "no log message"
    return f"{scene.name}: the FMU failed at t = {plan.k * plan.h:.6g} s ({exc}): {details}"


class ClampCount:
    """How often the controller's commands were clamped (voltages to +-U_L, current commands to
    +-i_L: scene/drives.py), per axis, accumulated over a run (or its chunks): the steps whose applied
    command differs from what the controller asked, of all steps, and the largest |command| asked on
    that axis."""

    def __init__(self, drives=None):
        self.clamped, self.steps, self.max_asked = [0, 0], 0, [0.0, 0.0]
        self.kinds = [("voltage", "V") if drive is None or drive.kind == "voltage" else ("current command", "A")
                      for drive in (drives or (None, None))]

    def add(self, asked: np.ndarray, commanded: np.ndarray) -> None:
        """`asked`, `commanded`: (rows, 2), the controller's outputs before and after the clamp."""
        self.steps += len(asked)
        for axis in (0, 1):
            self.clamped[axis] += int(np.count_nonzero(asked[:, axis] != commanded[:, axis]))
            if len(asked):
                self.max_asked[axis] = max(self.max_asked[axis], float(np.max(np.abs(asked[:, axis]))))

    def summary(self) -> str | None:
        """"voltage clamped on 1,234 of 60,000 steps (azimuth), max asked 1e+06 V; ..." ("current command
        clamped ..., max asked 12 A" for a motor in current drive) or None when nothing was clamped."""
        parts = [f"{self.kinds[axis][0]} clamped on {self.clamped[axis]:,} of {self.steps:,} steps ({AXES[axis]}), "
                 f"max asked {self.max_asked[axis]:.4g} {self.kinds[axis][1]}" for axis in (0, 1) if self.clamped[axis]]
        return "; ".join(parts) or None


def clamp_count(signals: dict) -> ClampCount:
    """The ClampCount of a run's recorded signals (recorded_signals), each axis by the columns of its drive."""
    drives = [command_columns(signals, motor) for motor in (1, 2)]
    count = ClampCount(drives)
    count.add(np.column_stack([signals[drive.asked] for drive in drives]),
              np.column_stack([signals[drive.commanded] for drive in drives]))
    return count


def failure_error(message: str, exc: Exception) -> SceneError:
    """The SceneError of a failed run with `message` (failure_message); a ControllerError, keeping
    the traceback of the user's exception, when the user's controller is the culprit."""
    return ControllerError(message, exc.details) if isinstance(exc, ControllerError) else SceneError(message)


def recorded_signals(plan: Plan, rows: int | None = None) -> dict:
    """'time' and one array per signal; row k: outputs at t_k, the voltage applied over
    [t_k, t_k+1], the controller's output at t_k, the base inputs at t_k. `rows`: only the first
    rows (a run that ended early), default all."""
    rows = plan.n + 1 if rows is None else rows
    u_cmd = np.array(plan.u_cmd, dtype=float).reshape(-1, 2)[:rows]
    refs = np.array(plan.refs, dtype=float).reshape(-1, 2)[:rows]
    u_asked = np.array(plan.u_asked, dtype=float).reshape(-1, 2)[:rows]
    # Applied over [t_k, t_k+1]: the command of `delay` steps before (0 V until the first is due).
    u_applied = np.zeros_like(u_cmd)
    u_applied[plan.delay:] = u_cmd[:len(u_cmd) - plan.delay]
    times = plan.times[:rows]
    signals = {"time": times}
    signals.update({name: plan.rec_real[:rows, j] for j, name in enumerate(plan.real_names)})
    signals.update({name: plan.rec_mode[:rows, j].astype(float) for j, name in enumerate(plan.mode_names)})
    signals.update(command_signals(plan.drives, u_applied, u_cmd, u_asked))
    signals.update({"alpha_ref": refs[:, 0], "beta_ref": refs[:, 1]})
    signals.update({name: plan.base[:rows, j] for j, name in enumerate(BASE_INPUTS)})
    signals["heave"] = plan.motion.position(times)[:, 2]
    return signals


def run(scene: Scene, fmu: FMU, progress: bool = False, stop_time: float | None = None,
        controller=None, slave=None, log: list | None = None, compiled: bool | None = None,
        keep_partial: bool = False, stop: StopRequest | None = None) -> RunResult:
    """Runs `scene` (to `stop_time` if given) and returns the recorded signals (recorded_signals),
    with line-of-sight signals added.

    `slave` (with the `log` list its logger appends to, from `fmu.instantiate(name, log)`): reuse this
    instance instead of instantiating a fresh one; it is reset first (fmi2Reset: back to the start
    values, state 'instantiated'), the log is cleared, and the instance is left alive for the next run.
    `compiled`: which loop (choose_loop); the result's `loop` says which ran.

    A run that fails in its loop (the FMU refuses a call, the controller raises) raises SceneError
    with the message of where and why, unless `keep_partial`: then it returns what it recorded up to
    the last whole communication point, with `result.stopped` (a Stop) saying where and why. `stop`:
    a StopRequest that ends the run early the same way (a signal handler's). A run that recorded no
    point at all raises SceneError either way. `result.stopped` is None for a whole run."""
    plan = Plan(scene, fmu, stop_time, controller)
    loop = choose_loop(plan.controller, compiled)
    owned = slave is None
    if owned:
        log = []
        slave = fmu.instantiate(scene.name, log)
    else:
        if log is not None:
            log.clear()
        slave.reset()
    bar = Progress(plan.t_end, enabled=progress)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    stopped = None
    try:
        try:
            initialize(slave, scene, fmu, plan)
            plan.controller.start(plan.h, scene.name)
        except ControllerError as exc:   # the user's reset() raised
            raise failure_error(failure_message(scene, plan, exc, log), exc) from None
        except SceneError:
            raise
        except Exception as exc:   # refused at initialization: the scene, not the run
            raise SceneError(failure_message(scene, plan, exc, log)) from None
        try:
            (compiled_step_loop if loop == "compiled" else step_loop)(slave, plan, bar, stop)
        except Exception as exc:   # a refused FMI call, fmpy raising on fmi2Error / fmi2Discard, the controller
            message = failure_message(scene, plan, exc, log)
            if not keep_partial or plan.rows == 0:
                raise failure_error(message, exc) from None
            stopped = Stop("failed", (plan.rows - 1) * plan.h, message, getattr(exc, "details", None))
        if stopped is None and plan.rows < plan.n + 1:
            if plan.rows == 0:
                raise SceneError(f"{scene.name}: {stop.reason} before the first communication point: nothing "
                                 "recorded")
            stopped = Stop(stop.kind, (plan.rows - 1) * plan.h, f"{scene.name}: {stop.reason}")
        bar.close(complete=stopped is None)
        if stopped is None:
            slave.terminate()
    finally:
        if owned:
            slave.freeInstance()
    wall, loop_cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    end = plan.t_end if stopped is None else stopped.time
    signals = recorded_signals(plan, plan.rows)
    result = RunResult(scene, signals, wall, end)
    result.voltage_clamp = clamp_count(signals)
    result.loop_cpu_time = loop_cpu  # set-up, initialization and the loop; not the base motion's evaluation
    result.loop = loop
    result.stopped = stopped
    result.requested_stop_time = plan.t_end
    return result
