"""The compiled communication loop (c_kernel/src/master_loop.c) for the built-in controllers,
through ctypes.

It does what stepper.Stepper.python_steps does with a built-in controller, with the same kernel for the
controller and the sensors: the tests check both loops give the same bits. A scene with a user
controller (type "python") runs the Python loop; so does everything when the kernel was not built
(`available()` says why).
"""
from __future__ import annotations

import ctypes

from .. import native
from ..errors import FMUCallFailed
from ..scene.controllers import PID, Controller, Replay, StateFeedback


def available() -> str | None:
    """None when the compiled loop can be used, else why not."""
    return native.why_not()


def supports(controller) -> bool:
    return type(controller) in (Controller, PID, StateFeedback, Replay)


class CompiledLoop:
    """One run's loop state; `run(first, last)` steps k = first .. last like stepper.Stepper.python_steps,
    on the plan's tables (point_at_chunk before each chunk)."""

    def __init__(self, slave, calls, plan):
        self.library = native.kernel()
        self.plan = plan   # keeps every array the struct points into alive
        m = self.loop = native.struct("GimbalMasterLoop")()
        m.component = slave.component
        for name in ("get_real", "get_integer", "set_real", "do_step"):
            setattr(m, name, ctypes.cast(getattr(calls, name), ctypes.c_void_p).value)
        m.real_vrs, m.mode_vrs, m.input_vrs = (a.ctypes.data for a in plan.vr_arrays)
        m.real_count, m.mode_count, m.input_count = (len(a) for a in plan.vr_arrays)
        m.h, m.n, m.delay = plan.h, plan.n, plan.delay
        m.i_alpha, m.i_beta = plan.i_alpha, plan.i_beta
        m.i_gyro[:] = plan.i_gyro
        m.i_alpha_dot, m.i_beta_dot = plan.i_joint_rates
        m.sensors = plan.sensors.state
        # A copy: the run leaves the controller object's own state as it was (as before the run).
        m.controller = plan.controller.state

    def point_at_chunk(self, first: int, plan) -> None:
        """Before each chunk (a run held in memory has one, first = 0): the kernel indexes every table by
        the run's step k, so each table of the chunk whose row 0 is step `first` is given as the address
        its row 0 of the run would have (sensors.SensorStream's _shifted); the commands' table starts
        `delay` rows earlier, with the commands of the chunk before (the delayed voltage reads them).
        The sensors' and controller's running states stay the loop's own."""
        from ..scene.sensors import _shifted

        m = self.loop
        m.rec_real, m.rec_mode, m.inputs = (_shifted(a, first) for a in (plan.rec_real, plan.rec_mode, plan.inputs))
        m.u_cmd = _shifted(plan.u_cmd, first - plan.delay)
        m.refs = _shifted(plan.refs, first)
        m.u_asked = _shifted(plan.u_asked, first)
        source = plan.sensors.state
        m.sensors.gyro_noise, m.sensors.carrier_rate = source.gyro_noise, source.carrier_rate
        m.sensors.gyro.error = source.gyro.error
        m.controller.set_points.values = plan.controller.state.set_points.values
        m.controller.set_points.rates = plan.controller.state.set_points.rates
        m.controller.set_points.accelerations = plan.controller.state.set_points.accelerations
        m.controller.set_points.gyro_rates = plan.controller.state.set_points.gyro_rates

    def run(self, first: int, last: int) -> None:
        failed = self.library.gimbal_master_loop(ctypes.addressof(self.loop), first, last)
        self.plan.k = self.loop.failed_step
        if failed:
            name = self.library.gimbal_master_loop_call_name(failed)
            raise FMUCallFailed(name.decode() if name else f"call {failed}")
