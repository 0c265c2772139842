"""The FMU as a master sees it, for the scene runner, the sweeps and the tests: extracted once,
variables by name (the model description is the truth: names it does not have are refused),
typed setters and getters, a fresh FMU2Slave per run whose log messages can be collected; and
`simulate`, a plain fixed-step master with a callback for the inputs (the tests' master)."""
from __future__ import annotations

import math
import pathlib
import shutil
import tempfile
import zipfile
from typing import Callable, Iterable, NamedTuple

import numpy as np

from ..errors import SceneError, excerpt

# The structural switches a scene's [fidelity] table takes: the scene format's vocabulary, checked when
# a scene file is loaded (before any FMU is opened); check_against_fmu then checks each against the
# model description. The states, by contrast, are read from the model description (FMU.states).
FIDELITY = ["gear1.model", "gear2.model", "motor1.model", "motor2.model", "dry_friction", "base.fixed", "motor1.drive",
            "motor2.drive"]


def state_names(model_description) -> list[str]:
    """The model's states, in the model description's order: the outputs with a start value that sets
    the initial state, initial="exact", or "approx" for the rotors, which gear<j>.start may put in mesh
    with their loads instead (the core holds that rule: kStartState in variable_groups.hpp)."""
    return [v.name for v in model_description.modelVariables
            if v.causality == "output" and v.initial in ("exact", "approx")]

_CASTS = {"Real": float, "Integer": int, "Boolean": bool}   # the types set and read by name


def value_type(variable) -> str:
    """The FMI function family a variable is set and read with: an Enumeration (the structural
    selectors gear1.model, ..., solver.method) goes through fmi2SetInteger/fmi2GetInteger."""
    return "Integer" if variable.type == "Enumeration" else variable.type


def enumeration_items(variable) -> dict:
    """{value: item name} of an Enumeration variable ({} for other types)."""
    if variable.type != "Enumeration" or variable.declaredType is None:
        return {}
    return {int(item.value): item.name for item in variable.declaredType.items}


class LogEntry(NamedTuple):
    """One message the FMU logged: its fmi2Status (0 OK, 1 warning, 2 discard, 3 error, 4 fatal),
    category and text; str() gives '[category] text'."""
    status: int
    category: str
    text: str

    def __str__(self) -> str:
        return f"[{self.category}] {self.text}"


class ModeOutput(NamedTuple):
    """An Integer output that shows a switching element's mode, and the Boolean parameter that switches
    the element on (None: always on)."""
    name: str
    element: str
    switch: str | None


def mode_outputs(path: pathlib.Path) -> list[ModeOutput]:
    """The mode outputs the FMU declares, in the order a run records them: its model description's
    <VendorAnnotations><Tool name="gimbal2axis"><ModeOutputs>, written by the generator from the switching
    elements' one declaration (model_core/include/gimbal/switching_elements.def). None for an FMU without it."""
    import xml.etree.ElementTree as ElementTree
    import zipfile

    with zipfile.ZipFile(path) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    return [ModeOutput(node.get("name"), node.get("element"), node.get("switch"))
            for node in root.iterfind("VendorAnnotations/Tool[@name='gimbal2axis']/ModeOutputs/ModeOutput")]


class FMU:
    """An extracted FMU, reusable for many instances; a context manager that removes the extracted
    files on exit (or call close()).

    variables      {name: fmpy ModelVariable} of the model description (`model_description`)
    states         the names of the states (outputs with initial="exact" or "approx"), in the description's order
    mode_outputs   the switching elements' mode outputs (ModeOutput), from the model description
    vr(name)       the value reference; variable(name) the ModelVariable; has(name), start(name)
    check(...)     validates scene values (names, causalities, types) before a run
    set_values(slave, {name: value})   Real, Integer (and Enumeration) and Boolean, each with the setter of its type
    get_values(slave, [names])         Real, Integer (and Enumeration) and Boolean, as floats, in the order given
    instantiate(name, log, logging_on) a new FMU2Slave; the FMU's messages go to `log` as LogEntry

    A name the model description does not have is refused with a SceneError naming it and the FMU.
    """

    def __init__(self, path: pathlib.Path | str, workdir: pathlib.Path | str | None = None):
        import xml.etree.ElementTree as ElementTree

        from fmpy import extract, read_model_description

        self.path = pathlib.Path(path)
        if not self.path.is_file():
            raise SceneError(f"{self.path}: no such FMU (build it: cmake --build build, or bash scripts/setup.sh)")
        try:
            self.model_description = read_model_description(str(self.path))
            self.variables = {v.name: v for v in self.model_description.modelVariables}
            self.states = state_names(self.model_description)
            self.mode_outputs = mode_outputs(self.path)
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, ElementTree.ParseError) as exc:
            # a truncated download, a file being rebuilt, something else named .fmu
            raise SceneError(f"{self.path}: not a readable FMU ({type(exc).__name__}: {excerpt(exc)})") from None
        # what an instance loads (binaries/, resources/, the model description), not the FMU's sources
        # and documentation: 300 files whose writing was a fifth of a 60-s run's time
        unzipdir = tempfile.mkdtemp(prefix="gimbal_fmu_", dir=workdir)
        try:
            self.unzipdir = extract(str(self.path), unzipdir=unzipdir,
                                    include=lambda name: not name.startswith(("sources/", "documentation/")))
        except (OSError, zipfile.BadZipFile) as exc:
            shutil.rmtree(unzipdir, ignore_errors=True)
            raise SceneError(f"{self.path}: cannot extract the FMU ({type(exc).__name__}: {excerpt(exc)})") from None

    def close(self) -> None:
        shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def variable(self, name: str):
        v = self.variables.get(name)
        if v is None:
            raise SceneError(f"'{name}' is not a variable of {self.path} (its modelDescription.xml is the truth)")
        return v

    def vr(self, name: str) -> int:
        return self.variable(name).valueReference

    def start(self, name: str):
        v = self.variable(name)
        if v.start is None:
            return None
        return {"Real": float, "Integer": int, "Boolean": lambda s: str(s).lower() in ("true", "1")}[value_type(v)](v.start)

    def has(self, name: str) -> bool:
        return name in self.variables

    def check(self, where: str, values: dict, causalities: set) -> None:
        """Refuses names the FMU does not have, of the wrong causality, or values of the wrong type."""
        for name, value in values.items():
            v = self.variables.get(name)
            if v is None:
                raise SceneError(f"[{where}] '{name}' is not a variable of {self.path} (its modelDescription.xml "
                                 f"is the truth; is the FMU older than the scene?)")
            if v.causality not in causalities:
                raise SceneError(f"[{where}] '{name}' has causality '{v.causality}', expected {sorted(causalities)}")
            if v.type == "Enumeration":
                _check_enumeration(where, name, v, value)
                continue
            ok = _TYPE_CHECKS.get(v.type, lambda value: False)(value)
            if not ok:
                raise SceneError(f"[{where}] '{name}' is {v.type} in the FMU; got {value!r}")

    def _by_type(self, names: Iterable[str]) -> dict:
        """{type: [(name, value reference), ...]} for Real, Integer and Boolean, in the order given;
        Enumeration variables are with the Integer ones (set and read as integers)."""
        groups = {t: [] for t in _CASTS}
        for name in names:
            v = self.variable(name)
            if value_type(v) not in groups:
                raise SceneError(f"'{name}' is a {v.type} variable of {self.path}: only Real, Integer, Enumeration "
                                 f"and Boolean variables are set and read by name")
            groups[value_type(v)].append((name, v.valueReference))
        return groups

    def set_values(self, slave, values: dict) -> None:
        """Sets Real, Integer and Boolean variables by name, one call of the setter of each type."""
        setters = {"Real": slave.setReal, "Integer": slave.setInteger, "Boolean": slave.setBoolean}
        for type_, selected in self._by_type(values).items():
            if selected:
                cast = _CASTS[type_]
                setters[type_]([vr for _, vr in selected], [cast(values[name]) for name, _ in selected])

    def get_values(self, slave, names: Iterable[str]) -> list:
        """Reads Real, Integer and Boolean variables by name, as floats, in the order given."""
        names = list(names)
        getters = {"Real": slave.getReal, "Integer": slave.getInteger, "Boolean": slave.getBoolean}
        values = {}
        for type_, selected in self._by_type(names).items():
            if selected:
                values.update(zip((name for name, _ in selected), getters[type_]([vr for _, vr in selected])))
        return [float(values[name]) for name in names]

    def instantiate(self, name: str = "instance", log: list | None = None, logging_on: bool = False):
        """A new FMU2Slave (state 'instantiated'); with `log`, every message the FMU logs is appended to
        it as a LogEntry."""
        from fmpy.fmi2 import FMU2Slave

        slave = FMU2Slave(guid=self.model_description.guid, unzipDirectory=self.unzipdir,
                          modelIdentifier=self.model_description.coSimulation.modelIdentifier, instanceName=name)
        slave.instantiate(callbacks=None if log is None else _capturing_callbacks(slave, log), loggingOn=logging_on)
        return slave


def _capturing_callbacks(slave, log: list):
    from fmpy import fmi2

    # fmpy's native logger proxy keeps one process-wide target, so it is not used here: the FMU only
    # ever passes fully formatted messages, with '%' escaped as the format-string contract requires.
    def logger(environment, instance_name, status, category, message):
        log.append(LogEntry(int(status), category.decode(), message.decode().replace("%%", "%")))

    callbacks = fmi2.fmi2CallbackFunctions()
    callbacks.logger = fmi2.fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2.defaultCallbacks.allocateMemory
    callbacks.freeMemory = fmi2.defaultCallbacks.freeMemory
    slave._capturing_callbacks = callbacks  # must outlive the instance
    return callbacks


InputFunction = Callable[[float, dict], dict]


def simulate(fmu: FMU, stop_time: float, step_size: float, start_values: dict | None = None,
             inputs: InputFunction | None = None, outputs: Iterable[str] | None = None,
             instance_name: str = "instance") -> dict:
    """Runs one simulation with fixed communication steps on a fresh instance; returns
    {'time': array, name: array, ...} sampled at every communication point.

    Start values and inputs may be Real, Integer or Boolean; outputs too (returned as floats).

    `inputs(t, latest_outputs)` returns the input values to hold over the step starting at t.
    """
    outputs = list(fmu.states if outputs is None else outputs)
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


# {FMI type: whether a scene's value fits it} (an Enumeration: _check_enumeration, by its items)
_TYPE_CHECKS = {
    "Real": lambda value: isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value),
    "Integer": lambda value: isinstance(value, int) and not isinstance(value, bool),
    "Boolean": lambda value: isinstance(value, bool),
}


def _check_enumeration(where: str, name: str, variable, value) -> None:
    """An Enumeration is given by the integer of one of its items."""
    items = enumeration_items(variable)
    listed = ", ".join(f"{k} ({n})" for k, n in sorted(items.items()))
    if not isinstance(value, int) or isinstance(value, bool):
        raise SceneError(f"[{where}] '{name}' is an Enumeration in the FMU, given by its integer value: "
                         f"{listed}; got {value!r}")
    if value not in items:
        raise SceneError(f"[{where}] '{name}' = {value} is none of its values: {listed}")
