"""The compiled communication loop (native/master_loop.c) for the built-in controllers, through ctypes.

It does what master.step_loop does with a built-in controller, with the same arithmetic: the tests
check both give the same bits. A scene with a user controller (type "python") runs the Python loop;
so does everything when the extension was not built (`available()` says why).
"""
from __future__ import annotations

import ctypes

import numpy as np

from .. import native
from ..scene.controllers import PID, Controller, Replay, StateFeedback

_pointer, _long, _double, _int = ctypes.c_void_p, ctypes.c_long, ctypes.c_double, ctypes.c_int


class _AxisPid(ctypes.Structure):
    _fields_ = [(name, _double) for name in ("kp", "ki", "kd", "k_gyro", "k_ff", "d_filter_s", "i_limit",
                                             "u_limit", "integral", "e_prev", "derivative")] + \
               [("has_prev", _int), ("saturated", _int)]


class _MasterLoop(ctypes.Structure):
    _fields_ = [("component", _pointer), ("get_real", _pointer), ("get_integer", _pointer), ("set_real", _pointer),
                ("do_step", _pointer), ("real_vrs", _pointer), ("mode_vrs", _pointer), ("input_vrs", _pointer),
                ("real_count", _long), ("mode_count", _long), ("input_count", _long),
                ("rec_real", _pointer), ("rec_mode", _pointer), ("inputs", _pointer), ("u_cmd", _pointer),
                ("refs", _pointer), ("h", _double), ("n", _long), ("delay", _long),
                ("i_alpha", _long), ("i_beta", _long), ("i_gyro", _long * 3),
                ("encoder_resolution", _double), ("gyro_noise", _pointer),
                ("setpoint", _pointer), ("setpoint_rate", _pointer), ("unwrap", _int * 2),
                ("kind", _int), ("voltage", _double * 2), ("u_limit", _double * 2), ("axis", _AxisPid * 2),
                ("gain", (_double * 4) * 2), ("state_ki", _double * 2), ("state_integral", _double * 2),
                ("prev_angle", _double * 2), ("rate_from_encoder", _int), ("has_prev_angle", _int), ("replayed", _pointer),
                ("failed_step", _long), ("failed_call", _int)]


FAILED_CALLS = {1: "fmi2GetReal", 2: "fmi2GetInteger", 3: "fmi2SetReal", 4: "fmi2DoStep"}


def available() -> str | None:
    """None when the compiled loop can be used, else why not."""
    loaded = native.library()
    if loaded is None:
        return native.why_not()
    if loaded.gimbal_master_loop_struct_size() != ctypes.sizeof(_MasterLoop):
        return "the compiled loop's MasterLoop struct does not match compiled_loop.py (rebuild: pip install -e .)"
    return None


def supports(controller) -> bool:
    return type(controller) in (Controller, PID, StateFeedback, Replay)


class CompiledLoop:
    """One run's loop state; `run(first, last)` steps k = first .. last like master.step_loop."""

    def __init__(self, slave, calls, plan):
        self.library = native.library()
        self.plan = plan   # keeps every array the struct points into alive
        controller, sensors = plan.controller, plan.sensors
        self.vr_arrays = [np.array(vrs, dtype=np.uint32) for vrs in (plan.real_vrs, plan.mode_vrs, plan.input_vrs)]
        self.u_cmd = np.zeros((plan.n + 1, 2))
        self.refs = np.full((plan.n + 1, 2), np.nan)
        m = self.loop = _MasterLoop()
        m.component = slave.component
        for name in ("get_real", "get_integer", "set_real", "do_step"):
            setattr(m, name, ctypes.cast(getattr(calls, name), _pointer).value)
        m.real_vrs, m.mode_vrs, m.input_vrs = (a.ctypes.data for a in self.vr_arrays)
        m.real_count, m.mode_count, m.input_count = (len(a) for a in self.vr_arrays)
        m.rec_real, m.rec_mode, m.inputs = plan.rec_real.ctypes.data, plan.rec_mode.ctypes.data, plan.inputs.ctypes.data
        m.u_cmd, m.refs = self.u_cmd.ctypes.data, self.refs.ctypes.data
        m.h, m.n, m.delay = plan.h, plan.n, plan.delay
        m.i_alpha, m.i_beta = plan.i_alpha, plan.i_beta
        m.i_gyro[:] = plan.i_gyro
        m.encoder_resolution = float(sensors.resolution)
        m.gyro_noise = None if sensors.gyro_noise_table is None else sensors.gyro_noise_table.ctypes.data
        m.u_limit[:] = controller.u_limit
        if type(controller) is Controller:
            m.kind, m.voltage[:] = 0, controller.voltage
            return
        if type(controller) is Replay:
            m.kind, m.replayed = 3, controller.voltages.ctypes.data
            return
        points = controller.set_points
        m.setpoint, m.setpoint_rate = points.values.ctypes.data, points.rates.ctypes.data
        m.unwrap[:] = points.unwrap
        if isinstance(controller, PID):
            m.kind = 1
            for axis, pid in zip(m.axis, controller.axes):
                axis.kp, axis.ki, axis.kd, axis.k_gyro, axis.k_ff = pid.kp, pid.ki, pid.kd, pid.k_gyro, pid.k_ff
                axis.d_filter_s, axis.i_limit, axis.u_limit = pid.tau, pid.i_limit, pid.u_limit
                axis.integral, axis.derivative, axis.saturated = pid.integral, pid.d, pid.saturated
                axis.has_prev = pid.e_prev is not None
                axis.e_prev = pid.e_prev or 0.0
        else:
            m.kind = 2
            for i in range(2):
                m.gain[i][:] = controller.K[i]
            m.state_ki[:] = controller.ki
            m.state_integral[:] = controller.integral
            m.rate_from_encoder = controller.rate_source == "encoder"
            m.has_prev_angle = controller.prev is not None
            if controller.prev is not None:
                m.prev_angle[:] = controller.prev

    def run(self, first: int, last: int) -> None:
        failed = self.library.gimbal_master_loop(ctypes.addressof(self.loop), first, last)
        self.plan.k = self.loop.failed_step
        if failed:
            from .master import FMUCallFailed
            raise FMUCallFailed(FAILED_CALLS.get(failed, f"call {failed}"))
