"""A small FMI 2.0 co-simulation master over fmpy, shared by the tests.

It runs the FMU with fixed communication steps, lets a callback set inputs before each step (the
controller with its zero-order hold lives here, in the master), and records outputs.
"""
from __future__ import annotations

import pathlib
import shutil
import tempfile
from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

STATE_NAMES = ["alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot",
               "i_R1", "i_R2", "theta_b1", "theta_b2"]


@dataclass
class LoadedFMU:
    """An extracted FMU, reusable for many instances."""
    path: pathlib.Path
    unzipdir: str
    model_description: object
    vr: dict = field(default_factory=dict)
    types: dict = field(default_factory=dict)

    @classmethod
    def load(cls, path: pathlib.Path) -> "LoadedFMU":
        md = read_model_description(str(path))
        unzipdir = extract(str(path), unzipdir=tempfile.mkdtemp(prefix="gimbal_fmu_"))
        return cls(path, unzipdir, md, {v.name: v.valueReference for v in md.modelVariables},
                   {v.name: v.type for v in md.modelVariables})

    def set_values(self, slave: FMU2Slave, values: dict) -> None:
        """Sets Real, Integer and Boolean variables by name."""
        by_type = {"Real": ({}, slave.setReal, float), "Integer": ({}, slave.setInteger, int),
                   "Boolean": ({}, slave.setBoolean, bool)}
        for name, value in values.items():
            by_type[self.types[name]][0][self.vr[name]] = value
        for selected, setter, cast in by_type.values():
            if selected:
                setter(list(selected), [cast(v) for v in selected.values()])

    def get_values(self, slave: FMU2Slave, names: list) -> list:
        """Reads Real and Integer variables by name, as floats, in the order given."""
        reals = [n for n in names if self.types[n] == "Real"]
        integers = [n for n in names if self.types[n] == "Integer"]
        values = dict(zip(reals, slave.getReal([self.vr[n] for n in reals]) if reals else []))
        values.update(zip(integers, slave.getInteger([self.vr[n] for n in integers]) if integers else []))
        return [float(values[n]) for n in names]

    def cleanup(self) -> None:
        shutil.rmtree(self.unzipdir, ignore_errors=True)

    def instantiate(self, name: str = "instance", log: list | None = None, logging_on: bool = False) -> FMU2Slave:
        """A new instance; with `log`, every message the FMU logs is appended to it as (status, category, text)."""
        slave = FMU2Slave(guid=self.model_description.guid, unzipDirectory=self.unzipdir,
                          modelIdentifier=self.model_description.coSimulation.modelIdentifier, instanceName=name)
        slave.instantiate(callbacks=None if log is None else _capturing_callbacks(slave, log), loggingOn=logging_on)
        return slave


def _capturing_callbacks(slave: FMU2Slave, log: list):
    from fmpy import fmi2

    # fmpy's native logger proxy keeps one process-wide target, so it is not used here: the FMU only
    # ever passes fully formatted messages, with '%' escaped as the format-string contract requires.
    def logger(environment, instance_name, status, category, message):
        log.append((int(status), category.decode(), message.decode().replace("%%", "%")))

    callbacks = fmi2.fmi2CallbackFunctions()
    callbacks.logger = fmi2.fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2.defaultCallbacks.allocateMemory
    callbacks.freeMemory = fmi2.defaultCallbacks.freeMemory
    slave._capturing_callbacks = callbacks  # must outlive the instance
    return callbacks


InputFunction = Callable[[float, dict], dict]


def simulate(fmu: LoadedFMU, stop_time: float, step_size: float, start_values: dict | None = None,
             inputs: InputFunction | None = None, outputs: Iterable[str] = STATE_NAMES,
             instance_name: str = "instance") -> dict:
    """Runs one simulation; returns {'time': array, name: array, ...} sampled at every communication point.

    Start values and inputs may be Real, Integer or Boolean; outputs Real or Integer (returned as floats).

    `inputs(t, latest_outputs)` returns the input values to hold over the step starting at t.
    """
    outputs = list(outputs)
    slave = fmu.instantiate(instance_name)
    try:
        slave.setupExperiment(startTime=0.0)
        fmu.set_values(slave, start_values or {})
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        n_steps = int(round(stop_time / step_size))
        record = np.empty((n_steps + 1, len(outputs)))
        record[0] = fmu.get_values(slave, outputs)
        times = np.arange(n_steps + 1) * step_size
        latest = dict(zip(outputs, record[0]))
        for k in range(n_steps):
            t = k * step_size
            if inputs is not None:
                values = inputs(t, latest)
                fmu.set_values(slave, values or {})
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=step_size)
            record[k + 1] = fmu.get_values(slave, outputs)
            latest = dict(zip(outputs, record[k + 1]))
        slave.terminate()
    finally:
        slave.freeInstance()
    result = {"time": times}
    result.update({name: record[:, j] for j, name in enumerate(outputs)})
    return result
