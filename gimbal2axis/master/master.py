"""A scene run held in memory (run): the sweeps, the reports, the tests and the linearization's
operating point take its record whole. The loop is the stepper's (stepper.py: the communication
points, the controller with the zero-order-hold delay of its commands), here on one chunk, the whole
run, into a MemorySink; `gimbal2axis run` streams the record to disk instead (streaming.py).

The names the package had here before the loop moved to stepper.py and the plan to plan.py are kept
importable from here.
"""
from __future__ import annotations

import time

from ..errors import FMUCallFailed
from ..fmu import FMU
from ..progress import Progress
from ..scene.scene import Scene
from .plan import Plan, initialize, real_outputs
from .results import RunResult, clamp_count
from .stepper import MemorySink, choose_loop, start, step_run
from .stopping import STOP_KINDS, Stop, StopRequest

# importable from here, as before the loop and the plan moved out
__all__ = ["FMUCallFailed", "Plan", "STOP_KINDS", "Stop", "StopRequest", "choose_loop", "initialize", "real_outputs",
           "run"]

def _instance(scene: Scene, fmu: FMU, slave, log: list | None):
    """(slave, log, owned): a fresh instance, or `slave` reset (its log cleared) for this run."""
    if slave is None:
        log = []
        return fmu.instantiate(scene.name, log), log, True
    if log is not None:
        log.clear()
    slave.reset()
    return slave, log, False


def run(scene: Scene, fmu: FMU, progress: bool = False, stop_time: float | None = None,
        controller=None, slave=None, log: list | None = None, compiled: bool | None = None,
        keep_partial: bool = False, stop: StopRequest | None = None) -> RunResult:
    """Runs `scene` (to `stop_time` if given) and returns the recorded signals (Plan.chunk_signals),
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
    slave, log, owned = _instance(scene, fmu, slave, log)
    bar = Progress(plan.t_end, enabled=progress)
    sink = MemorySink()
    wall0, cpu0 = time.perf_counter(), time.process_time()
    try:
        start(slave, scene, fmu, plan, log)
        stopped = step_run(scene, plan, slave, log, loop, sink, stop or StopRequest(), bar, keep_partial)
    finally:
        if owned:
            slave.freeInstance()
    wall, loop_cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    signals = sink.signals()
    result = RunResult(scene, signals, wall, plan.t_end if stopped is None else stopped.time)
    result.voltage_clamp = clamp_count(signals)
    result.loop_cpu_time = loop_cpu  # set-up, initialization and the loop; not the base motion's evaluation
    result.loop = loop
    result.stopped = stopped
    result.requested_stop_time = plan.t_end
    return result
