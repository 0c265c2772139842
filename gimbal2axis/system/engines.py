"""Running a written system in the engines users have: libcosim (its OSP system structure, or its
SSP archive) and FMPy's SSP support (the SSP archive). Each returns the recorded outputs of one
component at every communication point after the first, t_1 to t_n, as {name: array} with "time"."""
from __future__ import annotations

import pathlib
import zipfile

import numpy as np

from ..errors import SceneError


class ParameterNotApplied(SceneError):
    """An engine instantiated a system without a value the system binds: a binding the importer lost
    (a name it resolved to another variable or to none) would otherwise run the FMU's default silently."""


def _same(intended, read) -> bool:
    if isinstance(intended, bool):
        return bool(read) == intended
    return float(read) == float(intended)


def check_read_back(component: str, intended: dict, read: dict) -> int:
    """Refuses (ParameterNotApplied) the first bound value of `component` that the engine does not hold
    after instantiation, naming the component, the variable and both values; the number checked."""
    for name, value in intended.items():
        if name not in read:
            raise ParameterNotApplied(f"{component}: the bound value {name} = {value!r} names no variable the engine "
                                      f"can read back: the FMU runs without it")
        if not _same(value, read[name]):
            raise ParameterNotApplied(f"{component}: {name} is {read[name]!r} after instantiation, but the system "
                                      f"binds {value!r}")
    return len(intended)


def _libcosim_read_back(execution, intended: dict):
    """Starts observing the bound variables; returns the check to call after the first step, which
    compares each with its value at libcosim's initialization (step 0: before any step changes an
    output such as the gimbal's angles)."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimObserver import CosimObserver

    observer = CosimObserver.create_time_series()
    last = CosimObserver.create_last_value()
    execution.add_observer(observer)
    execution.add_observer(last)
    plan = {}
    for component, values in intended.items():
        index = execution.slave_index_from_instance_name(component)
        variables = {v.name.decode(): v for v in execution.slave_variables(index)}
        plan[component] = (index, variables)
        for name in values:
            variable = variables.get(name)
            if variable is not None and variable.type != CosimVariableType.BOOLEAN.value:
                observer.start_time_series(index, variable.reference, CosimVariableType(variable.type))

    def check() -> None:
        for component, values in intended.items():
            index, variables = plan[component]
            read = {}
            for name in values:
                variable = variables.get(name)
                if variable is None:
                    continue
                if variable.type == CosimVariableType.BOOLEAN.value:   # parameters: unchanged by a step
                    read[name] = last.last_boolean_values(index, [variable.reference])[0]
                    continue
                # (times, steps, values) from step 0; libcosimpy 0.0.6 returns nothing when asked for one
                _, steps, samples = (observer.time_series_real_samples if variable.type == CosimVariableType.REAL.value
                                     else observer.time_series_integer_samples)(index, variable.reference, 0, 2)
                if steps and steps[0] == 0:
                    read[name] = samples[0]
            check_read_back(component, values, read)
    return check


def _run_execution(execution, component: str, outputs: list, steps: int, intended: dict) -> dict:
    """`steps` steps of libcosim's base step; the outputs of `component` after each. Every value of
    `intended` ({component: {variable: value}}) is read back after initialization first."""
    from libcosimpy.CosimObserver import CosimObserver

    index = execution.slave_index_from_instance_name(component)
    references = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    missing = [name for name in outputs if name not in references]
    if missing:
        raise KeyError(f"{component} has no variables {missing}")
    check = _libcosim_read_back(execution, intended)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    vrs = [references[name] for name in outputs]
    rows, times = [], []
    for k in range(1, steps + 1):   # libcosim initializes in the first step: values from t_1 on
        if not execution.step(1):
            raise RuntimeError(f"libcosim: step {k} failed")
        if k == 1:
            check()
        rows.append(observer.last_real_values(index, vrs))
        times.append(execution.status().current_time * 1e-9)
    table = np.array(rows)
    return {"time": np.array(times), **{name: table[:, j] for j, name in enumerate(outputs)}}


def structure_initial_values(structure: pathlib.Path) -> dict:
    """{simulator: {variable: value}} of an OSP system structure's <InitialValues>."""
    import xml.etree.ElementTree as ET

    from .osp import NAMESPACE

    ns = f"{{{NAMESPACE}}}"
    values = {}
    for simulator in ET.parse(structure).getroot().iter(ns + "Simulator"):
        own = values.setdefault(simulator.get("name"), {})
        for initial in simulator.iter(ns + "InitialValue"):
            [element] = list(initial)
            kind, value = element.tag.split("}")[-1], element.get("value")
            parse = {"Real": float, "Integer": int}.get(kind, lambda text: text in ("true", "1"))
            own[initial.get("variable")] = parse(value)
    return values


def run_libcosim(structure: pathlib.Path, component: str, outputs: list, steps: int,
                 intended: dict | None = None) -> dict:
    """libcosim on <structure> (OspSystemStructure.xml): `steps` fixed steps of its base step. The values
    `intended` ({component: {variable: value}}; by default the structure's own <InitialValues>) are read
    back after initialization: one libcosim does not hold is refused (ParameterNotApplied)."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.ERROR)
    intended = structure_initial_values(structure) if intended is None else intended
    return _run_execution(CosimExecution.from_osp_config_file(str(structure)), component, outputs, steps, intended)


def run_libcosim_ssp(archive: pathlib.Path, component: str, outputs: list, steps: int,
                     intended: dict | None = None) -> dict:
    """libcosim's SSP loader on <archive> (.ssp): the step it takes is the one the archive states (the
    `com.opensimulationplatform` annotation of the DefaultExperiment; no step is passed here), the
    components, connections and parameter sets the archive's. The loader applies a parameter set only
    to parameters and inputs and leaves out, with a warning, the start value of any other variable:
    the gimbal's angles and rates (outputs with initial="exact", which the ship scene points at the
    target). Those values, read from the same parameter sets, go in through libcosim's own initial
    values, as the OSP structure's <InitialValues> do. The values `intended` ({component: {variable:
    value}}; by default the archive's parameter sets, less the Enumerations libcosim ignores) are read
    back after initialization: one libcosim does not hold is refused (ParameterNotApplied)."""
    from libcosimpy.CosimEnums import CosimVariableCausality, CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from fmpy.ssp.ssd import read_ssv

    from .ssp import archive_parameters, parameter_file

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
    if intended is None:
        intended = {name: {variable: value for variable, value in values.items()
                           if variable not in _fmu_enumerations(archive, name)}
                    for name, values in archive_parameters(archive).items()}
    return _run_execution(execution, component, outputs, steps, intended)


def _fmu_enumerations(archive: pathlib.Path, component: str) -> set:
    """The Enumeration variables of a component's FMU in the archive (libcosim neither sets nor lists them)."""
    import xml.etree.ElementTree as ET

    from fmpy import read_model_description

    from .ssp import SSD

    with zipfile.ZipFile(archive) as contents:
        root = ET.fromstring(contents.read("SystemStructure.ssd"))
        source = next(c.get("source") for c in root.iter(f"{{{SSD}}}Component") if c.get("name") == component)
        with contents.open(source) as fmu:
            variables = read_model_description(fmu).modelVariables
    return {v.name for v in variables if v.type == "Enumeration"}


def _fmpy_read_back(archive: pathlib.Path, parameters, intended: dict) -> None:
    """Instantiates the archive's components as FMPy's simulate_ssp does (its own functions, the same
    parameter set), reads every value of `intended` back and frees them: one FMPy does not hold after
    initialization is refused (ParameterNotApplied)."""
    import shutil

    from fmpy import extract
    from fmpy.ssp.simulation import add_path, find_components, free_fmu, get_value, instantiate_fmu
    from fmpy.ssp.ssd import read_ssd

    system = read_ssd(str(archive)).system
    add_path(system)
    folder = extract(str(archive))
    try:
        for component in find_components(system):
            if component.name not in intended:
                continue
            instantiate_fmu(component, folder, 0.0, None, parameters)
            try:
                read = {name: get_value(component, name) for name in intended[component.name]
                        if name in component.variables}
            finally:
                free_fmu(component)
            check_read_back(component.name, intended[component.name], read)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _refuse_unknown_names(archive: pathlib.Path, bound: dict) -> None:
    """A bound name that is no variable of its component's FMU is a value lost (FMPy would stop on it
    with a bare KeyError)."""
    import xml.etree.ElementTree as ET

    from fmpy import read_model_description

    from .ssp import SSD

    with zipfile.ZipFile(archive) as contents:
        root = ET.fromstring(contents.read("SystemStructure.ssd"))
        for element in root.iter(f"{{{SSD}}}Component"):
            with contents.open(element.get("source")) as fmu:
                known = {v.name: v for v in read_model_description(fmu).modelVariables}
            values = bound.get(element.get("name"), {})
            check_read_back(element.get("name"), values, {name: values[name] for name in values if name in known})


def run_fmpy_ssp(archive: pathlib.Path, component: str, outputs: list, step: float, stop_time: float,
                 intended: dict | None = None) -> dict:
    """FMPy's SSP simulation of <archive> with the components' parameter sets (resources/<component>.ssv):
    FMPy (0.3) applies no binding of the archive itself but one parameter set given to it, whose names
    are <component>.<variable>. The values `intended` ({component: {variable: value}}; by default the
    archive's parameter sets) are read back from FMPy's instantiation first (ParameterNotApplied)."""
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import ParameterSet, read_ssd, read_ssv

    from .ssp import archive_parameters, parameter_file

    bound = archive_parameters(archive)
    _refuse_unknown_names(archive, bound)

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
    parameter_set = ParameterSet(name="start values", parameters=parameters)
    _fmpy_read_back(archive, parameter_set, bound if intended is None else intended)
    result = simulate_ssp(str(archive), stop_time=stop_time, step_size=step, parameter_set=parameter_set)
    prefix = f"{component}."
    # FMPy labels a row with the time its step started; its values are those at the step's end
    return {"time": result["time"] + step, **{name: result[prefix + name] for name in outputs}}
