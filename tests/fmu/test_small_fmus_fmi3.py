"""The ship-motion and controller FMUs for FMI 3.0 (build/Gimbal2Axis-ShipMotion-fmi3.fmu,
build/Gimbal2Axis-Controller-fmi3.fmu): the small FMUs' one FMI 3.0 face
(fmu_src/fmi_layer/fmi3_functions.c) over the same model tables as their FMI 2.0 twins. Driven by
fmpy, each gives its twin's outputs bit for bit (the ship motion in sea-state and recorded mode, the
controller in the closed loop of tests/fmu/test_controller_fmu.py, both run by the FMI 2.0 tests' own
functions through an adapter), validates, takes and restores FMU states (also serialized, also in
another instance) with the same continuation, and refuses a repeated or skipped step, a NaN, an
unknown value reference, a call in the wrong state and a foreign or altered FMU state with an
error naming the culprit, never a crash. Their sources/ build into binaries with the shipped ones'
bits, and the binaries export only fmi3* functions."""
import os
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from gimbal2axis import load_scene
from gimbal2axis.fmu import FMU
from gimbal2axis.scene.base_motion import INPUTS
from gimbal2axis.scene.controller_fmu import controller_fmu_parameters
from gimbal2axis.scene.ship_motion_fmu import recording_parameters, ship_motion_fmu_parameters
from conftest import REPO_ROOT
from test_controller_fmu import coupled_run, u_limits, variants
from test_ship_motion_fmu import (RECORDED_SCENE, SHIP_SCENE, bits, irregular_times, recorded_columns, run_fmu,
                                  run_recorded_fmu, write_recording)

TWINS = {"ship_motion": ("Gimbal2Axis-ShipMotion.fmu", "Gimbal2Axis-ShipMotion-fmi3.fmu"),
         "controller": ("Gimbal2Axis-Controller.fmu", "Gimbal2Axis-Controller-fmi3.fmu")}
FMI2_TYPES = {"Float64": "Real", "Int32": "Integer", "Boolean": "Boolean", "String": "String"}


class Fmi3Slave:
    """An FMU3Slave answering the FMI 2.0 calls the FMI 2.0 tests make (setupExperiment, getReal,
    doStep ...), so that their runs drive the FMI 3.0 FMU unchanged."""

    def __init__(self, slave: FMU3Slave):
        self.slave = slave
        self.experiment = {"startTime": 0.0, "stopTime": None}

    def setupExperiment(self, startTime=0.0, stopTime=None, tolerance=None):
        self.experiment = {"startTime": startTime, "stopTime": stopTime}

    def enterInitializationMode(self):
        self.slave.enterInitializationMode(**self.experiment)

    def doStep(self, currentCommunicationPoint, communicationStepSize, noSetFMUStatePriorToCurrentPoint=True):
        self.slave.doStep(currentCommunicationPoint, communicationStepSize)

    def __getattr__(self, name):
        for fmi2, fmi3 in (("Real", "Float64"), ("Integer", "Int32")):
            if name.endswith(fmi2) and name[:3] in ("get", "set"):
                return getattr(self.slave, name[:3] + fmi3)
        return getattr(self.slave, name)


class Fmi3Twin:
    """The FMI 3.0 FMU with what the FMI 2.0 tests use of gimbal2axis.fmu.FMU: vr, set_values,
    instantiate (a Fmi3Slave)."""

    def __init__(self, path, workdir):
        self.path = path
        self.model_description = read_model_description(str(path))
        self.unzipdir = extract(str(path), unzipdir=str(workdir))
        self.variables = {v.name: v for v in self.model_description.modelVariables}

    def vr(self, name: str) -> int:
        return self.variables[name].valueReference

    def set_values(self, slave, values: dict) -> None:
        for name, value in values.items():
            setter = getattr(slave, "set" + FMI2_TYPES[self.variables[name].type])
            setter([self.vr(name)], [value])

    def instantiate(self, name: str = "instance", log: list | None = None, **flags) -> Fmi3Slave:
        slave = FMU3Slave(guid=self.model_description.instantiationToken, unzipDirectory=self.unzipdir,
                          modelIdentifier=self.model_description.coSimulation.modelIdentifier, instanceName=name)
        logger = None
        if log is not None:
            def logger(environment, status, category, message):
                log.append((int(status), category.decode(), message.decode()))
        slave.instantiate(logMessage=logger, loggingOn=log is not None, **flags)
        return Fmi3Slave(slave)


@pytest.fixture(scope="module")
def twins(build_dir, tmp_path_factory):
    """{name: (the FMI 2.0 FMU, the FMI 3.0 FMU)}."""
    opened = {}
    for name, files in TWINS.items():
        for file in files:
            if not (build_dir / file).is_file():
                pytest.fail(f"{build_dir / file} is missing: the build did not package it")
        opened[name] = (FMU(build_dir / files[0]), Fmi3Twin(build_dir / files[1], tmp_path_factory.mktemp(name)))
    yield opened
    for fmi2, _ in opened.values():
        fmi2.close()


def ship_parameters():
    return ship_motion_fmu_parameters(load_scene(SHIP_SCENE))


# ---------------------------------------------------------------- the same outputs as the FMI 2.0 twin

def test_ship_motion_in_a_sea_state_equals_fmi_2_bit_for_bit(twins):
    fmi2, fmi3 = twins["ship_motion"]
    expected = run_fmu(fmi2, ship_parameters(), 1e-3, 3000, start_time=0.25)
    outputs = run_fmu(fmi3, ship_parameters(), 1e-3, 3000, start_time=0.25)
    assert np.count_nonzero(expected) > expected.size // 2, "the sea must move the ship"
    np.testing.assert_array_equal(bits(outputs), bits(expected))


def test_ship_motion_of_a_recording_equals_fmi_2_bit_for_bit(twins, tmp_path):
    fmi2, fmi3 = twins["ship_motion"]
    step, steps = 1e-3, 2000
    write_recording(tmp_path / "motion.csv", recorded_columns("radians", irregular_times(steps * step, 200, 3)))
    scene_path = tmp_path / "scene.toml"
    scene_path.write_text(RECORDED_SCENE.format(stop_time=steps * step, step=step))
    values = recording_parameters(load_scene(scene_path))
    expected = run_recorded_fmu(fmi2, values, step, steps, stop_time=steps * step)
    outputs = run_recorded_fmu(fmi3, values, step, steps, stop_time=steps * step)
    assert np.count_nonzero(expected[:, INPUTS.index("base.gamma")]) > steps // 2
    np.testing.assert_array_equal(bits(outputs), bits(expected))


@pytest.mark.parametrize("variant", ["gyro axes, quantization and delay", "state feedback"])
def test_the_controller_in_the_closed_loop_equals_fmi_2_bit_for_bit(twins, gimbal_fmu, variant):
    fmi2, fmi3 = twins["controller"]
    scene = variants(load_scene(REPO_ROOT / "scenes" / "ship_stabilization.toml"))[variant]
    expected = coupled_run(scene, gimbal_fmu, fmi2, controller_first=False)
    outputs = coupled_run(scene, gimbal_fmu, fmi3, controller_first=False)
    assert np.max(np.abs(expected["u_R1"])) > 0.1, "the loop must have done something"
    for name in ("alpha", "beta", "u_R1", "u_R2", "set_points"):
        np.testing.assert_array_equal(bits(outputs[name]), bits(expected[name]), err_msg=name)


# ---------------------------------------------------------------- the package

@pytest.mark.parametrize("name", TWINS)
def test_the_fmu_validates_and_names_its_variables_as_fmi_2(twins, name):
    fmi2, fmi3 = twins[name]
    assert validate_fmu(str(fmi3.path)) == []
    md2, md3 = fmi2.model_description, fmi3.model_description
    assert md3.fmiVersion == "3.0" and md3.instantiationToken == md2.guid
    assert md3.coSimulation.modelIdentifier == md2.coSimulation.modelIdentifier
    assert md3.coSimulation.canGetAndSetFMUstate and md3.coSimulation.canSerializeFMUstate   # fmpy's names
    base = {"Float64": 0, "Int32": 1000, "Boolean": 2000, "String": 3000}
    described = [(v.name, FMI2_TYPES[v.type], v.valueReference - base[v.type], v.causality, v.variability,
                  v.unit, v.start, v.min, v.max) for v in md3.modelVariables if v.causality != "independent"]
    assert described == [(v.name, v.type, v.valueReference, v.causality, v.variability, v.unit, v.start, v.min,
                          v.max) for v in md2.modelVariables]
    assert [u.variable.name for u in md3.outputs] == [u.variable.name for u in md2.outputs]
    time = next(v for v in md3.modelVariables if v.causality == "independent")   # FMI 3.0 requires one
    assert (time.name, time.valueReference, time.unit) == ("time", 4000, "s")
    with zipfile.ZipFile(fmi3.path) as archive:
        names = set(archive.namelist())
    identifier = md3.coSimulation.modelIdentifier
    expected = {f"binaries/x86_64-linux/{identifier}.so", "sources/buildDescription.xml"}
    if os.environ.get("GIMBAL_SANITIZED") != "1":   # the sanitizer build makes no win64 binary
        expected.add(f"binaries/x86_64-windows/{identifier}.dll")
    assert expected <= names


@pytest.mark.parametrize("name", TWINS)
def test_the_shared_object_exports_only_fmi3_functions(twins, name):
    _, fmi3 = twins[name]
    identifier = fmi3.model_description.coSimulation.modelIdentifier
    so = os.path.join(fmi3.unzipdir, "binaries", "x86_64-linux", identifier + ".so")
    symbols = subprocess.run(["nm", "-D", "--defined-only", so], capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in symbols.splitlines() if line.split()[1] in "TDBR"}
    assert exported and all(symbol.startswith("fmi3") for symbol in exported), sorted(exported)
    assert "fmi3DoStep" in exported and "fmi3GetFMUState" in exported


# ---------------------------------------------------------------- FMU states

def started(fmi3, name, log=None):
    """An instance in step mode: the ship scene's sea (ship motion) or the controller's start values."""
    slave = fmi3.instantiate(name, log)
    if name == "ship_motion":
        fmi3.set_values(slave, ship_parameters())
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def controller_inputs(fmi3, k):
    """Deterministic inputs of step k for the controller (its Float64 inputs)."""
    inputs = [v for v in fmi3.model_description.modelVariables if v.causality == "input"]
    return [v.valueReference for v in inputs], [0.01 * np.sin(0.37 * k + j) for j in range(len(inputs))]


def advance(fmi3, name, slave, first: int, steps: int, h: float = 1e-3) -> np.ndarray:
    """Steps first .. first + steps - 1 (the controller's inputs set before each), the outputs after each."""
    outputs = [u.variable.valueReference for u in fmi3.model_description.outputs]
    rows = []
    for k in range(first, first + steps):
        if name == "controller":
            slave.setFloat64(*controller_inputs(fmi3, k))
        slave.doStep(k * h, h)
        rows.append(slave.getFloat64(outputs))
    return np.array(rows)


@pytest.mark.parametrize("name", TWINS)
def test_an_fmu_state_restored_gives_the_same_continuation(twins, name):
    _, fmi3 = twins[name]
    slave = started(fmi3, name)
    advance(fmi3, name, slave, 0, 300)
    state = slave.getFMUState()
    serialized = slave.serializeFMUState(state)
    first = advance(fmi3, name, slave, 300, 500)
    slave.setFMUState(state)
    again = advance(fmi3, name, slave, 300, 500)
    np.testing.assert_array_equal(bits(again), bits(first))
    other = started(fmi3, name)   # another instance, from the bytes, with other parameters before
    restored = other.deserializeFMUState(serialized)
    other.setFMUState(restored)
    np.testing.assert_array_equal(bits(advance(fmi3, name, other, 300, 500)), bits(first))
    for instance, taken in ((slave, state), (other, restored)):
        instance.freeFMUState(taken)
        instance.terminate()
        instance.freeInstance()


def test_an_fmu_state_of_another_fmu_or_altered_is_refused(twins):
    ship, controller = twins["ship_motion"][1], twins["controller"][1]
    log = []
    slave = started(controller, "controller", log)
    ship_slave = started(ship, "ship_motion")
    foreign = ship_slave.serializeFMUState(ship_slave.getFMUState())
    with pytest.raises(FMICallException):
        slave.deserializeFMUState(foreign)
    assert log[-1][0] == 3 and log[-1][2].startswith("fmi3DeserializeFMUState: the ") and "refused" in log[-1][2]
    own = bytearray(slave.serializeFMUState(slave.getFMUState()))
    own[len(own) // 2] ^= 0x10
    with pytest.raises(FMICallException):
        slave.deserializeFMUState(bytes(own))
    assert "checksum" in log[-1][2], log[-1]
    for instance in (slave, ship_slave):
        instance.freeInstance()


# ---------------------------------------------------------------- refusals

def refused(log, call, expected: str):
    """`call` raises, and the last message logged is the error `expected` (its start)."""
    with pytest.raises(FMICallException):
        call()
    assert log and log[-1][0] == 3 and log[-1][1] == "logStatusError", log
    assert log[-1][2].startswith(expected), log[-1]


@pytest.mark.parametrize("name", TWINS)
def test_a_repeated_or_skipped_step_is_refused(twins, name):
    _, fmi3 = twins[name]
    log = []
    slave = started(fmi3, name, log)
    h = 1.0 / 64.0
    slave.doStep(0.0, h)
    refused(log, lambda: slave.doStep(0.0, h),
            "fmi3DoStep: currentCommunicationPoint = 0 does not match the FMU's time 0.015625")
    refused(log, lambda: slave.doStep(2 * h, h),
            "fmi3DoStep: currentCommunicationPoint = 0.03125 does not match the FMU's time 0.015625")
    slave.doStep(h, h)   # the right point still steps
    slave.freeInstance()


@pytest.mark.parametrize("name", TWINS)
def test_bad_values_references_and_states_are_refused_naming_them(twins, name):
    _, fmi3 = twins[name]
    md = fmi3.model_description
    settable = next(v for v in md.modelVariables if v.type == "Float64" and v.causality in ("parameter", "input"))
    log = []
    slave = fmi3.instantiate(name, log)
    refused(log, lambda: slave.doStep(0.0, 1e-3), "fmi3DoStep is not allowed in state 'instantiated'")
    refused(log, lambda: slave.setFloat64([settable.valueReference], [float("nan")]),
            f"fmi3SetFloat64: {settable.name} = nan")
    refused(log, lambda: slave.getInt32([0]), "fmi3GetInt32 is not allowed in state 'instantiated'")
    slave.enterInitializationMode()
    floats = 1 + max(v.valueReference for v in md.modelVariables if v.type == "Float64" and v.name != "time")
    refused(log, lambda: slave.getFloat64([floats]), f"fmi3GetFloat64: value reference {floats} is not a Float64")
    refused(log, lambda: slave.getInt32([0]), "fmi3GetInt32: value reference 0 is not an Int32 variable")
    refused(log, lambda: slave.getFloat64([0, 1], nValues=1), "fmi3GetFloat64: nValues = 1")
    refused(log, lambda: slave.getFloat32([0]), "fmi3GetFloat32: value reference 0: the model has no variable")
    slave.exitInitializationMode()
    refused(log, lambda: slave.slave.enterEventMode(), "fmi3EnterEventMode: hasEventMode is false")
    refused(log, lambda: slave.slave.setFMUState(None), "fmi3SetFMUState: argument FMUState is a null pointer")
    slave.freeInstance()


def test_what_the_fmus_do_not_offer_is_refused_at_instantiation(twins):
    _, fmi3 = twins["controller"]
    log = []
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmi3.instantiate("events", log, eventModeUsed=True)
    assert log[-1][2] == "fmi3InstantiateCoSimulation: eventModeUsed is true, but hasEventMode is false"


# ---------------------------------------------------------------- sources/

release_only = pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                  reason="the sanitizer build's package is not the shipped one; the release pass runs it")


def controller_run(fmu, steps: int, h: float = 1e-3) -> np.ndarray:
    """The controller's outputs over `steps` steps of deterministic inputs (FMI 2.0 calls, either version)."""
    slave = fmu.instantiate("controller")
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    md = fmu.model_description
    inputs = [v.valueReference for v in md.modelVariables if v.causality == "input"]
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    rows = []
    for k in range(steps):
        slave.setReal(inputs, [0.01 * np.sin(0.37 * k + j) for j in range(len(inputs))])
        slave.doStep(k * h, h)
        rows.append(slave.getReal(outputs))
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


@release_only
@pytest.mark.parametrize("name", TWINS)
@pytest.mark.parametrize("version", [2, 3])
def test_the_sources_build_with_fmpy_and_give_the_shipped_binarys_bits(twins, name, version, tmp_path):
    """sources/ alone (listed in <SourceFiles> for FMI 2.0, in sources/buildDescription.xml for FMI 3.0)
    builds with fmpy into a binary whose outputs are the shipped binary's, bit for bit."""
    from fmpy.build import build_platform_binary

    shipped = twins[name][version - 2]
    unzipped = tmp_path / "fmu"
    with zipfile.ZipFile(shipped.path) as archive:
        archive.extractall(unzipped, members=[n for n in archive.namelist() if not n.startswith("binaries/")])
    build_platform_binary(str(unzipped))
    identifier = shipped.model_description.coSimulation.modelIdentifier
    folder = "linux64" if version == 2 else "x86_64-linux"
    assert (unzipped / "binaries" / folder / f"{identifier}.so").is_file()
    rebuilt = tmp_path / shipped.path.name
    with zipfile.ZipFile(rebuilt, "w") as archive:
        for path in unzipped.rglob("*"):
            if path.is_file():
                archive.write(path, path.relative_to(unzipped).as_posix())
    built = Fmi3Twin(rebuilt, tmp_path / "built") if version == 3 else FMU(rebuilt)
    try:
        if name == "ship_motion":
            expected, outputs = (run_fmu(fmu, ship_parameters(), 1e-3, 500) for fmu in (shipped, built))
        else:
            expected, outputs = (controller_run(fmu, 300) for fmu in (shipped, built))
    finally:
        if version == 2:
            built.close()
    assert np.count_nonzero(expected) > 0
    np.testing.assert_array_equal(bits(outputs), bits(expected))
