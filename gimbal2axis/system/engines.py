"""Running a written system in the engines users have: libcosim (its OSP system structure, or its
SSP archive) and FMPy's SSP support (the SSP archive). Each returns the recorded outputs of one
component at every communication point after the first, t_1 to t_n, as {name: array} with "time"."""
from __future__ import annotations

import pathlib
import zipfile

import numpy as np


def _run_execution(execution, component: str, outputs: list, steps: int) -> dict:
    """`steps` steps of libcosim's base step; the outputs of `component` after each."""
    from libcosimpy.CosimObserver import CosimObserver

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


def run_libcosim(structure: pathlib.Path, component: str, outputs: list, steps: int) -> dict:
    """libcosim on <structure> (OspSystemStructure.xml): `steps` fixed steps of its base step."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.ERROR)
    return _run_execution(CosimExecution.from_osp_config_file(str(structure)), component, outputs, steps)


def run_libcosim_ssp(archive: pathlib.Path, component: str, outputs: list, steps: int) -> dict:
    """libcosim's SSP loader on <archive> (.ssp): the step it takes is the one the archive states (the
    `com.opensimulationplatform` annotation of the DefaultExperiment; no step is passed here), the
    components, connections and parameter sets the archive's. The loader applies a parameter set only
    to parameters and inputs and leaves out, with a warning, the start value of any other variable:
    the gimbal's angles and rates (outputs with initial="exact", which the ship scene points at the
    target). Those values, read from the same parameter sets, go in through libcosim's own initial
    values, as the OSP structure's <InitialValues> do."""
    from libcosimpy.CosimEnums import CosimVariableCausality, CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from fmpy.ssp.ssd import read_ssv

    from .ssp import parameter_file

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_ssp_file(str(archive))
    applied = (CosimVariableCausality.PARAMETER.value, CosimVariableCausality.INPUT.value)
    with zipfile.ZipFile(archive) as contents:
        files = set(contents.namelist())
    for info in execution.slave_infos():
        name = info.name.decode()
        if parameter_file(name) not in files:
            continue
        variables = {v.name.decode(): v for v in execution.slave_variables(info.index)}
        for parameter in read_ssv(str(archive), resource=parameter_file(name)).parameters:
            variable = variables.get(parameter.name)
            if variable is None or variable.causality in applied:
                continue   # applied by the loader, or a type libcosim ignores (Enumerations)
            if variable.type != CosimVariableType.REAL.value:
                raise ValueError(f"{name}.{parameter.name}: a start value libcosim's SSP loader leaves out")
            execution.real_initial_value(info.index, variable.reference, float(parameter.value))
    return _run_execution(execution, component, outputs, steps)


def run_fmpy_ssp(archive: pathlib.Path, component: str, outputs: list, step: float, stop_time: float) -> dict:
    """FMPy's SSP simulation of <archive> with the components' parameter sets (resources/<component>.ssv):
    FMPy (0.3) applies no binding of the archive itself but one parameter set given to it, whose names
    are <component>.<variable>."""
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import ParameterSet, read_ssd, read_ssv

    from .ssp import parameter_file

    names = [element.name for element in read_ssd(str(archive)).system.elements]
    with zipfile.ZipFile(archive) as contents:
        files = set(contents.namelist())
    parameters = []
    for name in names:
        if parameter_file(name) not in files:
            continue
        for parameter in read_ssv(str(archive), resource=parameter_file(name)).parameters:
            parameter.name = f"{name}.{parameter.name}"
            # FMPy (0.3) sets a Boolean to `value != 0.0`, and the SSV's value is the text "true" or
            # "false": both would come out true. Numbers keep its test meaningful.
            if parameter.type == "Boolean":
                parameter.value = 1.0 if parameter.value in ("true", "1") else 0.0
            parameters.append(parameter)
    result = simulate_ssp(str(archive), stop_time=stop_time, step_size=step,
                          parameter_set=ParameterSet(name="start values", parameters=parameters))
    prefix = f"{component}."
    # FMPy labels a row with the time its step started; its values are those at the step's end
    return {"time": result["time"] + step, **{name: result[prefix + name] for name in outputs}}
