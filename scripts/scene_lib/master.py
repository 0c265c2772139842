"""The co-simulation master: one FMU2Slave, fixed communication steps, the controller with the
zero-order-hold delay of the voltages.

At each communication point t_k the master reads the FMU's outputs, lets the sensors measure and
the controller compute u_k from them, and then steps the FMU over [t_k, t_{k+1}] with
  - the voltages u_{k-d} (d = delay_steps, default 1: the voltage computed from the sensors at t_k
    is applied over [t_{k+1}, t_{k+2}]; before the first command is due, 0 V), held constant;
  - the base inputs at t_k (attitude, rates, accelerations, v_a, a_a), exact values of the base
    motion; the FMU extrapolates them inside the step with constant acceleration (INTERFACE.md).
With a fixed base the base inputs are never set (they stay 0).
"""
from __future__ import annotations

import math
import time

import numpy as np

from .base_motion import INPUTS as BASE_INPUTS
from .errors import SceneError
from .fmu import FMU, STATES
from .progress import Progress
from .results import RunResult
from .scene import Scene, check_against_fmu, parameter_value, start_values

class FMUCallFailed(Exception):
    def __init__(self, function: str):
        super().__init__(f"{function} returned fmi2Discard or fmi2Error")


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


REAL_OUTPUTS = STATES + ["T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "los.omega[3]"]
MODE_OUTPUTS = ["gear1.contact", "gear2.contact", "motor1.limited", "motor2.limited", "body1.stick_slip",
                "rotor1.stick_slip", "body2.stick_slip", "rotor2.stick_slip", "events.total"]


def run(scene: Scene, fmu: FMU, progress: bool = False, stop_time: float | None = None,
        controller=None, slave=None, log: list | None = None) -> RunResult:
    """Runs `scene` (to `stop_time` if given) and returns the recorded signals ('time' and one array
    per signal, sampled at every communication point (row k: outputs at t_k, the voltage applied
    over [t_k, t_{k+1}], the controller output computed at t_k, the base inputs at t_k), with line-of-sight signals added.

    `slave` (with the `log` list its logger appends to, from `fmu.instantiate(name, log)`): reuse this
    instance instead of instantiating a fresh one; it is reset first (fmi2Reset: back to the start
    values, state 'instantiated'), the log is cleared, and the instance is left alive for the next run."""
    check_against_fmu(scene, fmu)
    h = scene.step_size
    t_end = scene.stop_time if stop_time is None else stop_time
    n = int(round(t_end / h))
    times = np.arange(n + 1) * h
    motion = scene.base_motion()
    base = motion.sample(times)
    base_rows = base.tolist()
    u_limit = tuple(float(parameter_value(scene, fmu, f"motor{j}.U_L")) for j in (1, 2))
    controller = controller or scene.controller(u_limit)
    sensors = scene.sensors()
    delay = scene.delay_steps

    real_names = [n_ for n_ in REAL_OUTPUTS if fmu.has(n_)]
    mode_names = [n_ for n_ in MODE_OUTPUTS if fmu.has(n_) and fmu.variables[n_].type == "Integer"]
    for needed in ("alpha", "beta", "los.omega[1]", "los.omega[2]", "los.omega[3]"):
        if needed not in real_names:
            raise SceneError(f"{fmu.path} has no output '{needed}', which the sensors need")
    real_vrs = [fmu.vr(n_) for n_ in real_names]
    mode_vrs = [fmu.vr(n_) for n_ in mode_names]
    i_alpha, i_beta = real_names.index("alpha"), real_names.index("beta")
    i_gyro = [real_names.index(f"los.omega[{j}]") for j in (1, 2, 3)]
    input_vrs = [fmu.vr("u_R1"), fmu.vr("u_R2")] + ([] if motion.fixed else [fmu.vr(b) for b in BASE_INPUTS])

    # Everything the loop touches is preallocated: the FMU reads its inputs from row k of `inputs`
    # (base columns filled for the whole run up front) and writes its outputs into row k of the
    # records, through raw pointers; Python only runs the sensors and the controller.
    rec_real = np.zeros((n + 1, len(real_names)))
    rec_mode = np.zeros((n + 1, len(mode_names)), dtype=np.int32)
    inputs = np.zeros((n + 1, len(input_vrs)))
    if not motion.fixed:
        inputs[:, 2:] = base
    u_cmd, refs = [], []  # lists: appending costs less than writing a numpy row

    owned = slave is None
    if owned:
        log = []
        slave = fmu.instantiate(scene.name, log)
    else:
        if log is not None:
            log.clear()
        slave.reset()
    bar = Progress(t_end, enabled=progress)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    k = 0
    try:
        slave.setupExperiment(startTime=0.0, stopTime=t_end)
        base_eps = motion.sample(np.array([1e-6]))[0]
        fmu.set(slave, start_values(scene, fmu, base[0], base_eps))
        slave.enterInitializationMode()
        slave.setReal(input_vrs, [0.0, 0.0] + ([] if motion.fixed else base_rows[0]))
        slave.exitInitializationMode()
        calls = RawCalls(slave)
        vr_arrays = [np.array(vrs, dtype=np.uint32) for vrs in (real_vrs, mode_vrs, input_vrs)]
        (real_refs, mode_refs, input_refs), (real_count, mode_count, input_count) = \
            [a.ctypes.data for a in vr_arrays], [len(a) for a in vr_arrays]
        real_row, real_stride = rec_real.ctypes.data, rec_real.strides[0]
        mode_row, mode_stride = rec_mode.ctypes.data, rec_mode.strides[0]
        input_row, input_stride = inputs.ctypes.data, inputs.strides[0]
        component = slave.component
        get_real, get_integer, set_real, do_step = calls.get_real, calls.get_integer, calls.set_real, calls.do_step
        measure = sensors.measure
        controller.start(h, scene.name)
        zero = (0.0, 0.0)
        for k in range(n + 1):
            t = k * h
            if get_real(component, real_refs, real_count, real_row + k * real_stride) > 1:
                raise FMUCallFailed("fmi2GetReal")
            if mode_count and get_integer(component, mode_refs, mode_count, mode_row + k * mode_stride) > 1:
                raise FMUCallFailed("fmi2GetInteger")
            y = rec_real[k].tolist()
            row = base_rows[k]
            u = controller(t, h, *measure(y[i_alpha], y[i_beta], [y[i] for i in i_gyro], row[:3], row[3:6]))
            u_cmd.append(u)
            refs.append(controller.reference)
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
        bar.close()
        slave.terminate()
    except SceneError:
        raise
    except Exception as exc:   # a refused FMI call, or fmpy raising on fmi2Error / fmi2Discard
        details = "; ".join((log or [])[-5:]) or "no log message"
        raise SceneError(f"{scene.name}: the FMU failed at t = {k * h:.6g} s ({exc}): {details}") from None
    finally:
        if owned:
            slave.freeInstance()
    wall, loop_cpu = time.perf_counter() - wall0, time.process_time() - cpu0

    u_cmd, refs = np.array(u_cmd, dtype=float).reshape(-1, 2), np.array(refs, dtype=float).reshape(-1, 2)
    # Applied over [t_k, t_k+1]: the command of `delay` steps before (0 V until the first is due).
    u_applied = np.zeros_like(u_cmd)
    u_applied[delay:] = u_cmd[:len(u_cmd) - delay]
    signals = {"time": times}
    signals.update({name: rec_real[:, j] for j, name in enumerate(real_names)})
    signals.update({name: rec_mode[:, j].astype(float) for j, name in enumerate(mode_names)})
    signals.update({"u_R1": u_applied[:, 0], "u_R2": u_applied[:, 1], "u_R1_cmd": u_cmd[:, 0],
                    "u_R2_cmd": u_cmd[:, 1], "alpha_ref": refs[:, 0], "beta_ref": refs[:, 1]})
    signals.update({name: base[:, j] for j, name in enumerate(BASE_INPUTS)})
    signals["heave"] = motion.position(times)[:, 2]
    result = RunResult(scene, signals, wall, t_end)
    result.loop_cpu_time = loop_cpu  # set-up, initialization and the loop; not the base motion's evaluation
    return result
