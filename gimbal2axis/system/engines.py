"""Running a written system in the engines users have: libcosim (its OSP system structure) and
FMPy's SSP support (its SSP archive). Each returns the recorded outputs of one component at every
communication point after the first, t_1 to t_n, as {name: array} with "time"."""
from __future__ import annotations

import pathlib

import numpy as np


def run_libcosim(structure: pathlib.Path, component: str, outputs: list, steps: int) -> dict:
    """libcosim on <structure> (OspSystemStructure.xml): `steps` fixed steps of its base step."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_osp_config_file(str(structure))
    index = execution.slave_index_from_instance_name(component)
    references = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    missing = [name for name in outputs if name not in references]
    if missing:
        raise KeyError(f"{component} has no variables {missing}")
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    vrs = [references[name] for name in outputs]
    rows, times = [], []
    for k in range(1, steps + 1):   # libcosim initializes in the first step: values from t_1 on
        if not execution.step(1):
            raise RuntimeError(f"libcosim: step {k} failed")
        rows.append(observer.last_real_values(index, vrs))
        times.append(execution.status().current_time * 1e-9)
    table = np.array(rows)
    return {"time": np.array(times), **{name: table[:, j] for j, name in enumerate(outputs)}}


def run_fmpy_ssp(archive: pathlib.Path, component: str, outputs: list, step: float, stop_time: float) -> dict:
    """FMPy's SSP simulation of <archive> with its parameter set (resources/parameters.ssv)."""
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import read_ssv

    parameters = read_ssv(str(archive), resource="resources/parameters.ssv")
    for parameter in parameters.parameters:
        # FMPy (0.3) sets a Boolean to `value != 0.0`, and the SSV's value is the text "true" or
        # "false": both would come out true. Numbers keep its test meaningful.
        if parameter.type == "Boolean":
            parameter.value = 1.0 if parameter.value in ("true", "1") else 0.0
    result = simulate_ssp(str(archive), stop_time=stop_time, step_size=step, parameter_set=parameters)
    prefix = f"{component}."
    # FMPy labels a row with the time its step started; its values are those at the step's end
    return {"time": result["time"] + step, **{name: result[prefix + name] for name in outputs}}
