"""The FMI 3.0 FMU (build/Gimbal2Axis-fmi3.fmu) under fmpy: Co-Simulation bit for bit the FMI 2.0
FMU's for the same calls (with and without Event Mode, steps of 1 ms and 0.7 ms, fixed and moving
base), Model Exchange agreeing with FMI 2.0's, Enumerations through fmi3GetInt64/fmi3SetInt64, FMU
states, refusals, and the package: only fmi3* exported, the C++ runtime linked in."""
from __future__ import annotations

import math
import os
import pathlib
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.validation import validate_fmu

from gimbal2axis.fmu import simulate

# The sanitizer pass's FMU links the sanitizer runtimes dynamically and has no Windows binary; a build
# from sources/ uses fmpy's flags: these run in the release pass.
release_only = pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                  reason="the sanitizer build's package is not the shipped one; the release pass runs it")

OUTPUTS = ["alpha", "alpha_m", "beta", "beta_m", "i_R1", "i_R2", "theta_b2", "T_E2", "los.omega[1]"]


@pytest.fixture(scope="module")
def fmu3(build_dir, tmp_path_factory):
    path = build_dir / "Gimbal2Axis-fmi3.fmu"
    assert path.is_file(), f"{path} is missing: the build did not package it"
    md = read_model_description(str(path))
    unzipdir = extract(str(path), str(tmp_path_factory.mktemp("fmi3")))
    return path, md, unzipdir


def slave(fmu3, name="cs", log=None, event_mode=False):
    path, md, unzipdir = fmu3
    instance = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipdir, modelIdentifier="Gimbal2Axis",
                         instanceName=name)
    logger = None
    if log is not None:
        def logger(environment, status, category, message):
            log.append((int(status), category.decode(), message.decode()))
    instance.instantiate(eventModeUsed=event_mode, logMessage=logger, loggingOn=log is not None)
    return instance


def vr(fmu3, name):
    return next(v.valueReference for v in fmu3[1].modelVariables if v.name == name)


def carrier(t):
    return {"base.gamma": 0.05 * math.sin(3.0 * t), "base.gamma_dot": 0.15 * math.cos(3.0 * t),
            "base.gamma_ddot": -0.45 * math.sin(3.0 * t), "u_R1": 6.0 * math.copysign(1.0, math.sin(40 * t)),
            "u_R2": -3.0}


def run_fmi3(fmu3, start, step, stop, inputs, event_mode=False, start_time=0.0):
    s = slave(fmu3, event_mode=event_mode)
    try:
        float_start = {k: v for k, v in start.items() if not isinstance(v, bool)}
        s.setFloat64([vr(fmu3, k) for k in float_start], list(float_start.values()))
        booleans = {k: v for k, v in start.items() if isinstance(v, bool)}
        if booleans:
            s.setBoolean([vr(fmu3, k) for k in booleans], list(booleans.values()))
        s.enterInitializationMode(startTime=start_time)
        s.exitInitializationMode()
        if event_mode:
            s.updateDiscreteStates()
            s.enterStepMode()
        out = [vr(fmu3, n) for n in OUTPUTS]
        rows = [s.getFloat64(out)]
        for k in range(int(round(stop / step))):
            t = k * step
            values = inputs(t)
            s.setFloat64([vr(fmu3, n) for n in values], list(values.values()))
            if event_mode and k % 7 == 3:  # an importer's event iteration in between: nothing to update
                s.enterEventMode()
                s.updateDiscreteStates()
                s.enterStepMode()
            event, terminate, early, last = s.doStep(currentCommunicationPoint=start_time + t, communicationStepSize=step)
            assert not event and not terminate and not early
            assert last == pytest.approx(start_time + t + step, abs=1e-12 * max(1.0, start_time) + 1e-12)
            rows.append(s.getFloat64(out))
        s.terminate()
        return np.array(rows)
    finally:
        s.freeInstance()


@pytest.mark.parametrize("step", [1e-3, 7e-4])
@pytest.mark.parametrize("base", ["fixed", "moving"])
@pytest.mark.parametrize("event_mode", [False, True])
def test_co_simulation_equals_fmi_2_bit_for_bit(gimbal_fmu, fmu3, step, base, event_mode):
    start = {"beta": 0.3, "beta_m": 18.0}
    if base == "fixed":
        start["base.fixed"] = True
        inputs = lambda t: {"u_R1": 6.0 * math.copysign(1.0, math.sin(40 * t)), "u_R2": -3.0}  # noqa: E731
    else:
        inputs = carrier
    stop = 0.21
    fmi3 = run_fmi3(fmu3, start, step, stop, inputs, event_mode)
    fmi2 = simulate(gimbal_fmu, stop, step, start, lambda t, _: inputs(t), outputs=OUTPUTS)
    matrix2 = np.column_stack([fmi2[n] for n in OUTPUTS])
    assert fmi3.shape == matrix2.shape
    assert np.array_equal(fmi3, matrix2)


def test_a_late_start_time_changes_no_bit(gimbal_fmu, fmu3):
    """Steps of 1 ms from a start time of 1.7e9 s (doubles 2.4e-7 s apart there): the instance
    integrates each step size on its own clock, so the FMI 3.0 run equals the FMI 2.0 run from 0."""
    start = {"beta": 0.5, "base.fixed": True}
    inputs = lambda t: {"u_R1": 12.0 if int(round(t / 1e-3)) // 25 % 2 == 0 else -12.0}  # noqa: E731
    late = run_fmi3(fmu3, start, 1e-3, 0.3, inputs, start_time=1.7e9)
    fmi2 = simulate(gimbal_fmu, 0.3, 1e-3, start, lambda t, _: inputs(t), outputs=OUTPUTS)
    assert np.array_equal(late, np.column_stack([fmi2[n] for n in OUTPUTS]))


def test_model_exchange_agrees_with_fmi_2(gimbal_fmu, fmu3, build_dir):
    start = {"beta": 0.3, "u_R1": 6.0, "u_R2": -3.0}
    out = ["alpha", "beta", "events.total"]
    me3 = simulate_fmu(str(fmu3[0]), fmi_type="ModelExchange", stop_time=0.3, output_interval=1e-3,
                       relative_tolerance=1e-9, start_values=start, output=out)
    me2 = simulate_fmu(str(build_dir / "Gimbal2Axis.fmu"), fmi_type="ModelExchange", stop_time=0.3, output_interval=1e-3,
                       relative_tolerance=1e-9, start_values=start, output=out)
    assert me3["events.total"][-1] == me2["events.total"][-1] > 0
    assert abs(me3["alpha"][-1] - me2["alpha"][-1]) < 1e-9 and abs(me3["beta"][-1] - me2["beta"][-1]) < 1e-9


def test_enumerations_are_int64_and_other_types_are_refused(fmu3):
    log = []
    s = slave(fmu3, log=log)
    try:
        gear = vr(fmu3, "gear1.model")
        assert gear >= 1000  # an Integer's reference, 1000 + its FMI 2.0 one
        s.setInt64([gear], [1])  # before initialization, as a structural parameter is
        s.enterInitializationMode(startTime=0.0)
        assert s.getInt64([gear]) == [1]
        with pytest.raises(FMICallException):
            s.getInt32([gear])
        assert any("gear1.model is an Enumeration" in m for _, _, m in log)
        with pytest.raises(FMICallException):
            s.getFloat32([0])
        assert any("fmi3GetFloat32: value reference 0: the model has no variable of this type" in m for _, _, m in log)
        with pytest.raises(FMICallException):
            s.setFloat64([vr(fmu3, "beta")], [float("nan")])
        assert any("fmi3SetFloat64: beta = nan refused" in m for _, _, m in log)
        with pytest.raises(FMICallException):
            s.setFloat64([vr(fmu3, "event_indicators[1]")], [0.0])
        steps = vr(fmu3, "solver.steps")
        assert steps >= 1000 and s.getInt32([steps]) == [0]
        s.exitInitializationMode()
        assert s.getFloat64([vr(fmu3, "time")]) == [0.0]
        count = fmu3[1].numberOfEventIndicators
        indicators = [vr(fmu3, f"event_indicators[{k}]") for k in range(1, count + 1)]
        assert s.getFloat64(indicators + [vr(fmu3, "time")]) == [1.0] * count + [0.0]  # Co-Simulation: no indicator
    finally:
        s.freeInstance()


def test_fmu_states_replay_and_refuse_the_other_fmi_version(gimbal_fmu, fmu3):
    log = []
    s = slave(fmu3, log=log)
    try:
        s.setFloat64([vr(fmu3, "beta")], [0.3])
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        u = vr(fmu3, "u_R1")
        out = [vr(fmu3, n) for n in OUTPUTS]
        for k in range(20):
            s.setFloat64([u], [8.0 if k % 5 else -8.0])
            s.doStep(k * 1e-3, 1e-3)
        state = s.getFMUState()
        blob = s.serializeFMUState(state)

        def tail():
            rows = []
            for k in range(20, 40):
                s.setFloat64([u], [8.0 if k % 5 else -8.0])
                s.doStep(k * 1e-3, 1e-3)
                rows.append(s.getFloat64(out))
            return np.array(rows)

        first = tail()
        copy = s.deserializeFMUState(blob)
        s.setFMUState(copy)
        assert np.array_equal(tail(), first)
        s.freeFMUState(state)
        s.freeFMUState(copy)
        # A state of the FMI 2.0 binary is refused by name.
        fmi2 = gimbal_fmu.instantiate("fmi2")
        try:
            fmi2.setupExperiment(startTime=0.0)
            fmi2.enterInitializationMode()
            fmi2.exitInitializationMode()
            fmi2_state = fmi2.getFMUstate()
            fmi2_blob = bytes(fmi2.serializeFMUstate(fmi2_state))
            fmi2.freeFMUstate(fmi2_state)
        finally:
            fmi2.freeInstance()
        with pytest.raises(FMICallException):
            s.deserializeFMUState(fmi2_blob)
        assert any("this FMU's other FMI version" in m for _, _, m in log)
    finally:
        s.freeInstance()


def test_state_machine_refusals_name_the_function(fmu3):
    log = []
    s = slave(fmu3, log=log)
    try:
        with pytest.raises(FMICallException):
            s.doStep(0.0, 1e-3)
        assert any("fmi3DoStep is not allowed in state 'instantiated'" in m for _, _, m in log)
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        with pytest.raises(FMICallException):
            s.enterEventMode()
        assert any("eventModeUsed = false" in m for _, _, m in log)
        with pytest.raises(FMICallException):
            s.doStep(0.5, 1e-3)
        assert any("does not match the FMU's time" in m for _, _, m in log)
    finally:
        s.freeInstance()
    path, md, unzipdir = fmu3
    model = FMU3Model(guid=md.instantiationToken, unzipDirectory=unzipdir, modelIdentifier="Gimbal2Axis", instanceName="me")
    model.instantiate()
    try:
        model.enterInitializationMode(startTime=0.0)
        model.exitInitializationMode()
        with pytest.raises(FMICallException):  # Model Exchange has no step mode
            model.fmi3EnterStepMode(model.component)
    finally:
        model.freeInstance()


@release_only
def test_the_package(fmu3):
    path = fmu3[0]
    assert validate_fmu(str(path)) == []
    names = zipfile.ZipFile(path).namelist()
    assert "binaries/x86_64-linux/Gimbal2Axis.so" in names and "modelDescription.xml" in names
    binary = str(pathlib.Path(fmu3[2]) / "binaries" / "x86_64-linux" / "Gimbal2Axis.so")
    nm = shutil.which("nm")
    exported = subprocess.run([nm, "-D", "--defined-only", binary], capture_output=True, text=True).stdout.split()
    symbols = [s for s in exported[2::3]]
    assert symbols and all(s.startswith("fmi3") for s in symbols), [s for s in symbols if not s.startswith("fmi3")][:5]
    assert len(symbols) == 75  # every function of fmi3Functions.h
    needed = subprocess.run(["ldd", binary], capture_output=True, text=True).stdout
    assert "libstdc++" not in needed and "libgcc_s" not in needed and "sundials" not in needed


@release_only
def test_the_windows_binary_exports_fmi3_only_and_imports_system_libraries(fmu3):
    names = zipfile.ZipFile(fmu3[0]).namelist()
    objdump = shutil.which("x86_64-w64-mingw32-objdump")
    if "binaries/x86_64-windows/Gimbal2Axis.dll" not in names:
        assert objdump is None, "mingw-w64 is installed but the FMU lacks binaries/x86_64-windows"
        pytest.skip("built without mingw-w64: no x86_64-windows binary")
    dll = pathlib.Path(fmu3[2]) / "binaries" / "x86_64-windows" / "Gimbal2Axis.dll"
    table = subprocess.run([objdump, "-p", str(dll)], capture_output=True, text=True, check=True).stdout
    exports = [line.split()[-1] for line in table.splitlines() if line.strip().startswith("[") and "fmi" in line]
    assert len(exports) == 75 and all(name.startswith("fmi3") for name in exports)
    imports = sorted(line.split(":")[1].strip() for line in table.splitlines() if "DLL Name" in line)
    assert imports == ["KERNEL32.dll", "msvcrt.dll"]


@pytest.mark.parametrize("event_mode", [False, True])
def test_early_return_stops_at_each_mode_change_and_continues_the_same_solution(gimbal_fmu, fmu3, event_mode):
    """With earlyReturnAllowed, fmi3DoStep ends right after the first mode change in the step (at the
    event's time, which events.last_time confirms); the importer continues from there and, the inputs
    left as the step carried them, gets the solution of steps without early return (to the
    integrator's tolerance: the remaining steps end where the master's sums say) and the same events."""
    path, md, unzipdir = fmu3
    start = {"beta": 0.3, "beta_m": 18.0, "solver.rtol": 1e-10}
    inputs = carrier
    step, stop = 1e-3, 0.12
    reference = run_fmi3(fmu3, start, step, stop, inputs)
    s = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipdir, modelIdentifier="Gimbal2Axis", instanceName="early")
    s.instantiate(eventModeUsed=event_mode, earlyReturnAllowed=True)
    try:
        s.setFloat64([vr(fmu3, k) for k in start], list(start.values()))
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        if event_mode:
            s.updateDiscreteStates()
            s.enterStepMode()
        out = [vr(fmu3, n) for n in OUTPUTS]
        last_event = vr(fmu3, "events.last_time")
        rows, early_returns = [s.getFloat64(out)], 0
        for k in range(int(round(stop / step))):
            t, end = k * step, (k + 1) * step
            values = inputs(t)
            s.setFloat64([vr(fmu3, n) for n in values], list(values.values()))
            now = t
            while True:
                event, terminate, early, reached = s.doStep(currentCommunicationPoint=now, communicationStepSize=end - now)
                assert not terminate
                if not early:
                    break
                early_returns += 1
                assert now < reached < end and event == event_mode
                assert s.getFloat64([last_event]) == [reached]  # it stopped at the mode change
                if event_mode:
                    s.enterEventMode()
                    assert s.updateDiscreteStates()[0] is False
                    s.enterStepMode()
                now = reached
            rows.append(s.getFloat64(out))
        events = s.getInt32([vr(fmu3, "events.total")])[0]
    finally:
        s.freeInstance()
    assert 10 < early_returns <= events  # several changes at one instant are one early return
    result = np.array(rows)
    scale = np.maximum(1.0, np.max(np.abs(reference), axis=0))
    assert np.max(np.abs(result - reference) / scale) < 1e-7


@release_only
def test_the_sources_build_with_fmpy_and_give_the_shipped_binarys_bits(fmu3, tmp_path):
    """sources/ with buildDescription.xml (FMI 3.0's replacement of <SourceFiles>): fmpy builds the
    binary from them alone, and it gives the shipped binary's results."""
    from fmpy.build import build_platform_binary

    with zipfile.ZipFile(fmu3[0]) as archive:
        members = [n for n in archive.namelist() if not n.startswith("binaries/")]
        archive.extractall(tmp_path / "fmu", members=members)
    assert (tmp_path / "fmu" / "sources" / "buildDescription.xml").is_file()
    build_platform_binary(str(tmp_path / "fmu"))
    assert (tmp_path / "fmu" / "binaries" / "x86_64-linux" / "Gimbal2Axis.so").is_file()
    start = {"beta": 0.3, "beta_m": 18.0}
    built = (fmu3[0], fmu3[1], str(tmp_path / "fmu"))
    rebuilt = run_fmi3(built, start, 1e-3, 0.05, carrier)
    shipped = run_fmi3(fmu3, start, 1e-3, 0.05, carrier)
    assert np.max(np.abs(rebuilt - shipped)) <= 1e-9 * max(1.0, float(np.max(np.abs(shipped))))


@pytest.mark.parametrize("scene", ["fixed_base", "rolling_base"])
def test_ecos_a_second_host_runs_the_fmi_3_fmu_bit_for_bit(gimbal_fmu, fmu3, scene):
    """ecos (ecospy, a host independent of fmpy, on its own FMI 3.0 loader) co-simulates the FMI 3.0
    FMU; its results are the FMI 2.0 FMU's under fmpy, to the last bit. (ecos skips the Enumeration
    variables it does not support: the structural selectors keep their defaults here.)"""
    from test_other_masters import OUTPUTS as ECOS_OUTPUTS, SCENES, START, run_ecos

    inputs = SCENES[scene]
    got = run_ecos(str(fmu3[0]), 1e-3, 100, START, inputs)
    ref = simulate(gimbal_fmu, 0.1, 1e-3, start_values=START, outputs=ECOS_OUTPUTS,
                   inputs=None if inputs is None else (lambda t, _latest: inputs(t)))
    ref = np.column_stack([ref[n][1:] for n in ECOS_OUTPUTS])
    assert got.shape == ref.shape and np.array_equal(got, ref)


def test_a_host_without_arrays_records_every_variable(gimbal_fmu, fmu3, tmp_path):
    """ecos reads every Float64 as one value and its CSV writer records all variables by default, locals
    too: the FMU must have no array among them (docs/fmi_interfaces.md). With the 36 event indicators
    as one array each of its reads failed and the file held zeros; as 36 scalars it records the run:
    the angles are fmpy's (FMI 2.0 FMU) to the CSV's 6 decimals, every indicator 1 (Co-Simulation)."""
    from test_other_masters import START, import_ecospy

    import_ecospy()
    from ecospy import EcosSimulation, EcosSimulationStructure

    steps = 50
    structure = EcosSimulationStructure()
    structure.add_model("gimbal", str(fmu3[0]))
    assert structure.add_parameter_set("start", {f"gimbal::{n}": float(v) for n, v in START.items()})
    simulation = EcosSimulation(structure=structure, step_size=1e-3)
    structure.free()
    result = tmp_path / "ecos.csv"
    try:
        simulation.add_csv_writer(str(result))
        assert simulation.init(parameter_set="start")
        simulation.step(steps)
        simulation.terminate()
    finally:
        simulation.free()
    header, *rows = [line.split(", ") for line in result.read_text().splitlines()]
    columns = {name.removeprefix("gimbal::").rsplit("[", 1)[0]: j for j, name in enumerate(header)}  # "...[REAL]"
    table = np.array(rows, dtype=float)
    assert table.shape == (steps + 1, len(header))
    indicators = [f"event_indicators[{k}]" for k in range(1, 37)]
    assert set(indicators) <= set(columns)
    assert np.all(table[1:, [columns[name] for name in indicators]] == 1.0)
    ref = simulate(gimbal_fmu, steps * 1e-3, 1e-3, start_values=START, outputs=["alpha", "beta", "alpha_m"])
    for name in ("alpha", "beta", "alpha_m"):
        assert np.max(np.abs(table[:, columns[name]] - ref[name])) < 1e-6, name
    assert np.ptp(ref["alpha"]) > 1e-3   # the run moves: a file of start values would not pass
