"""A Model Exchange host for the tests, on fmpy's FMU2Model and its CVode wrapper (or a forward Euler
step): the inputs are functions of time applied at every instant the host sets (fmpy's own
simulate_fmu sets them only where it looks for roots, so the right-hand side sees inputs up to one
internal step old), input discontinuities are time events, and every event iteration is counted.

`simulate_model_exchange(fmu, stop_time, ...)` returns {'time': ..., name: ...} at the output points
(after the event iteration where one falls on them) and a record of the event iterations.
"""
from __future__ import annotations

import ctypes
from typing import Callable, Iterable

import numpy as np

from fmpy.fmi2 import FMU2Model

InputFunction = Callable[[float], dict]


class ModelExchangeInstance:
    """One initialized FMU2Model with the value references of the gimbal2axis FMU wrapper."""

    def __init__(self, fmu, start_values: dict, inputs: InputFunction | None, start_time: float = 0.0,
                 log: list | None = None, name: str = "me"):
        md = fmu.model_description
        self.fmu = fmu
        self.model = FMU2Model(guid=md.guid, unzipDirectory=fmu.unzipdir,
                               modelIdentifier=md.modelExchange.modelIdentifier, instanceName=name)
        callbacks = None
        if log is not None:
            from gimbal2axis.fmu.fmu import _capturing_callbacks
            callbacks = _capturing_callbacks(self.model, log)
        self.model.instantiate(callbacks=callbacks, loggingOn=log is not None)
        self.nx = md.numberOfContinuousStates
        self.nz = md.numberOfEventIndicators
        self.inputs = inputs
        self.model.setupExperiment(startTime=start_time)
        fmu.set_values(self.model, start_values)
        self.model.enterInitializationMode()
        if inputs is not None:
            fmu.set_values(self.model, inputs(start_time))
        self.model.exitInitializationMode()
        self.time = start_time
        self.event_calls: list[int] = []   # fmi2NewDiscreteStates calls of each event iteration
        self.next_event_time = None
        self.event_iteration(repeats=0)
        self.model.enterContinuousTimeMode()

    def set_time(self, t: float) -> None:
        self.model.setTime(t)
        if self.inputs is not None:
            self.fmu.set_values(self.model, self.inputs(t))

    def event_iteration(self, repeats: int = 0) -> bool:
        """fmi2NewDiscreteStates until it needs no more (and `repeats` more times, as a naive host
        would); returns whether the continuous states changed."""
        calls, changed = 0, False
        while True:
            info = self.model.newDiscreteStates()
            calls += 1
            assert calls <= 100, "the event iteration does not end"
            changed = changed or bool(info[3])
            self.next_event_time = info[5] if info[4] else None
            if not info[0]:
                break
        for _ in range(repeats):
            info = self.model.newDiscreteStates()
            assert not info[0] and not info[3], "a repeated fmi2NewDiscreteStates changed the states or asked for more"
        self.event_calls.append(calls)
        return changed

    def values(self, names: Iterable[str]) -> list:
        return self.fmu.get_values(self.model, names)

    def free(self) -> None:
        self.model.terminate()
        self.model.freeInstance()


def simulate_model_exchange(fmu, stop_time: float, start_values: dict | None = None,
                            inputs: InputFunction | None = None, input_events: Iterable[float] = (),
                            outputs: Iterable[str] = ("alpha", "beta"), output_interval: float = 1e-3,
                            solver: str = "CVode", rtol: float = 1e-10, euler_step: float | None = None,
                            repeats: int = 0, log: list | None = None) -> dict:
    """`inputs(t)` gives the inputs at t (right-continuous: at an input event, the values after it)."""
    outputs = list(outputs)
    instance = ModelExchangeInstance(fmu, start_values or {}, inputs, log=log)
    model = instance.model
    nx, nz = instance.nx, instance.nz
    x = np.zeros(nx)
    dx = np.zeros(nx)
    z = np.zeros(nz)
    px = x.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
    pdx = dx.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
    pz = z.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
    events = sorted(t for t in input_events if 0.0 < t < stop_time)
    n_out = int(round(stop_time / output_interval))
    times = np.arange(n_out + 1) * output_interval
    record = np.empty((n_out + 1, len(outputs)))
    record[0] = instance.values(outputs)
    state_events = 0
    try:
        if solver == "CVode":
            from fmpy.sundials import CVodeSolver

            cvode = CVodeSolver(nx=nx, nz=nz, get_x=model.getContinuousStates, set_x=model.setContinuousStates,
                                get_dx=model.getDerivatives, get_z=model.getEventIndicators,
                                get_nominals=model.getNominalsOfContinuousStates, set_time=instance.set_time,
                                input=_NoInput(), startTime=0.0, maxStep=stop_time / 50, relativeTolerance=rtol,
                                maxNumSteps=100000)
        t = 0.0
        k_out = 1
        while k_out <= n_out:
            target = times[k_out]
            next_events = [e for e in events if e > t + 1e-14]
            if next_events and next_events[0] < target - 1e-14:
                target = next_events[0]
            if instance.next_event_time is not None and instance.next_event_time < target:
                target = instance.next_event_time
            if solver == "CVode":
                state_event, _, t_reached = cvode.step(t, target)
            else:
                # Forward Euler with a fixed step; events are seen at the end of the step.
                state_event = False
                model.getEventIndicators(pz, nz)
                before = z.copy()
                t_reached = t
                while t_reached < target - 1e-14:
                    h = min(euler_step, target - t_reached)
                    model.getContinuousStates(px, nx)
                    model.getDerivatives(pdx, nx)
                    x[:] += h * dx
                    t_reached = t_reached + h
                    instance.set_time(t_reached)
                    model.setContinuousStates(px, nx)
                    model.getEventIndicators(pz, nz)
                    if np.any((before > 0) != (z > 0)):
                        state_event = True
                        break
                    before[:] = z
            t = t_reached
            instance.set_time(t)
            input_event = any(abs(t - e) <= 1e-12 for e in events)
            time_event = instance.next_event_time is not None and t >= instance.next_event_time - 1e-14
            if state_event or input_event or time_event:
                state_events += bool(state_event)
                model.enterEventMode()
                instance.set_time(t)
                instance.event_iteration(repeats)
                model.enterContinuousTimeMode()
                if solver == "CVode":
                    cvode.reset(t)
            if abs(t - times[k_out]) <= 1e-12:
                record[k_out] = instance.values(outputs)
                k_out += 1
    finally:
        instance.free()
    result = {"time": times, "event_calls": np.array(instance.event_calls), "state_events": state_events}
    result.update({name: record[:, j] for j, name in enumerate(outputs)})
    return result


class _NoInput:
    """CVodeSolver applies inputs in its root function: ours are applied with the time instead."""

    def apply(self, time, continuous=True, discrete=True, after_event=False):
        pass
