"""The co-simulation master: one FMU2Slave, fixed communication steps, the controller with the
seed's zero-order-hold delay (section 2.5).

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

    rec_real = np.empty((n + 1, len(real_names)))
    rec_mode = np.empty((n + 1, len(mode_names)))
    u_cmd = np.empty((n + 1, 2))
    u_applied = np.empty((n + 1, 2))
    refs = np.empty((n + 1, 2))

    owned = slave is None
    if owned:
        log = []
        slave = fmu.instantiate(scene.name, log)
    else:
        if log is not None:
            log.clear()
        slave.reset()
    bar = Progress(t_end, enabled=progress)
    wall0 = time.perf_counter()
    k = 0
    try:
        slave.setupExperiment(startTime=0.0, stopTime=t_end)
        base_eps = motion.sample(np.array([1e-6]))[0]
        fmu.set(slave, start_values(scene, fmu, base[0], base_eps))
        slave.enterInitializationMode()
        slave.setReal(input_vrs, [0.0, 0.0] + ([] if motion.fixed else base_rows[0]))
        slave.exitInitializationMode()
        get_real, set_real, do_step = slave.getReal, slave.setReal, slave.doStep
        get_int = slave.getInteger if mode_vrs else (lambda vrs: [])
        zero = (0.0, 0.0)
        for k in range(n + 1):
            y = get_real(real_vrs)
            rec_real[k] = y
            rec_mode[k] = get_int(mode_vrs)
            row = base_rows[k]
            u = controller(k * h, h, *sensors.measure(y[i_alpha], y[i_beta], [y[i] for i in i_gyro], row[:3], row[3:6]))
            u_cmd[k] = u
            refs[k] = controller.reference
            applied = u if delay == 0 else (u_cmd[k - delay] if k >= delay else zero)
            u_applied[k] = applied
            if k == n:
                break
            set_real(input_vrs, [applied[0], applied[1]] + ([] if motion.fixed else row))
            do_step(currentCommunicationPoint=k * h, communicationStepSize=h)
            if k % 64 == 0:
                bar.update((k + 1) * h)
        bar.close()
        slave.terminate()
    except SceneError:
        raise
    except Exception as exc:   # fmpy raises on fmi2Error / fmi2Discard
        details = "; ".join((log or [])[-5:]) or "no log message"
        raise SceneError(f"{scene.name}: the FMU failed at t = {k * h:.6g} s ({exc}): {details}") from None
    finally:
        if owned:
            slave.freeInstance()
    wall = time.perf_counter() - wall0

    signals = {"time": times}
    signals.update({name: rec_real[:, j] for j, name in enumerate(real_names)})
    signals.update({name: rec_mode[:, j] for j, name in enumerate(mode_names)})
    signals.update({"u_R1": u_applied[:, 0], "u_R2": u_applied[:, 1], "u_R1_cmd": u_cmd[:, 0],
                    "u_R2_cmd": u_cmd[:, 1], "alpha_ref": refs[:, 0], "beta_ref": refs[:, 1]})
    signals.update({name: base[:, j] for j, name in enumerate(BASE_INPUTS)})
    signals["heave"] = motion.position(times)[:, 2]
    return RunResult(scene, signals, wall, t_end)
