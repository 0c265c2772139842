"""The FMU under two more independent FMI 2.0 masters, compared with our fmpy master.

- libcosim (DNV's Open Simulation Platform) through `libcosimpy`,
- ecos through `ecospy`, both in-process and with the FMU in a child `proxyfmu` process
  (`proxyfmu://localhost?file=...`), the server that ships with ecospy.

Same FMU, same start values, same inputs, same communication steps: the outputs must agree to the
last bit. They do, once "same communication steps" is taken literally:

- ecos keeps time as a double and passes the constant step `h` (0.001 is 0.001) to every
  `fmi2DoStep`, exactly like `gimbal2axis.fmu.simulate`: bit-identical results.
- libcosim keeps time as integer nanoseconds and converts each step to a double as
  `to_double_duration(d, t) = double(t + d) - double(t)` (`cosim/time.hpp`), with
  `double(t) = t_ns / 1e9`. So the step it passes varies in the last bits: for h = 1 ms,
  0.001 for the first 8 steps, then 0.00099999999999999915, 0.0010000000000000009, ... (8 distinct
  values over 0.5 s). The FMU integrates from its own time to `time + communicationStepSize`, so
  CVODE's stop times move by an ulp, its step-size sequence changes, and the two runs are two
  different error-controlled solutions: they differ at the level of the integration error, not of
  round-off. Driving fmpy with libcosim's clock (the same doubles for every step) gives bit-identical
  results again; that is asserted below. The comparison with the plain fixed-step `simulate` needs a
  tolerance (see `test_libcosim_agrees_with_fixed_step_simulate`).

The time check of the FMU (currentCommunicationPoint within 1e-12 relative of its own time) passes
under both masters: libcosim's t_k = k h_ns / 1e9 and ecos's t += h stay within a few ulps of the
FMU's accumulated time.
"""
from __future__ import annotations

import os
import pathlib
import shutil
import stat

import numpy as np
import pytest

from gimbal2axis.fmu import simulate

START = {"solver.rtol": 1e-9, "gear2.eta": 1e-4, "beta": 0.3, "beta_m": 18.0,
         "u_R1": 2.0, "u_R2": -1.5}  # constant voltages, held by every master from initialization on
OUTPUTS = ["alpha", "beta", "i_R1", "i_R2", "theta_b2", "T_E2", "los.omega[1]"]
STOP_TIME = 0.5
GAMMA_DOT = 0.1  # rad/s, the rolling base of the second scene


def rolling_base(t: float) -> dict:
    """Base inputs set before the step starting at t: a constant roll rate, attitude consistent with it."""
    return {"base.gamma": GAMMA_DOT * t, "base.gamma_dot": GAMMA_DOT}


SCENES = {"fixed_base": None, "rolling_base": rolling_base}


def as_matrix(result: dict) -> np.ndarray:
    """(steps, outputs) after each step, from a `simulate` result (which also holds the initial point)."""
    return np.column_stack([result[n][1:] for n in OUTPUTS])


def fmpy_on_schedule(fmu, times: list, start_values: dict, inputs) -> np.ndarray:
    """`gimbal2axis.fmu.simulate`, but with given communication points: step k goes from times[k] with
    step size times[k+1] - times[k] (what libcosim passes)."""
    slave = fmu.instantiate("fmpy_schedule")
    try:
        slave.setupExperiment(startTime=times[0])
        fmu.set_values(slave, start_values)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        rows = []
        for t0, t1 in zip(times[:-1], times[1:]):
            if inputs is not None:
                fmu.set_values(slave, inputs(t0))
            slave.doStep(currentCommunicationPoint=t0, communicationStepSize=t1 - t0)
            rows.append(fmu.get_values(slave, OUTPUTS))
        slave.terminate()
    finally:
        slave.freeInstance()
    return np.array(rows)


def assert_bitwise_equal(got: np.ndarray, ref: np.ndarray, master: str) -> None:
    assert got.shape == ref.shape
    for j, name in enumerate(OUTPUTS):
        differ = np.flatnonzero(got[:, j] != ref[:, j])
        assert differ.size == 0, (
            f"{master}: {name} differs from fmpy at {differ.size} steps, first at step {differ[0]}: "
            f"{got[differ[0], j]!r} vs {ref[differ[0], j]!r}")


# ----------------------------------------------------------------------------------------------------
# libcosim (libcosimpy)

def libcosim_clock(step_ns: int, n_steps: int) -> list:
    """libcosim's communication points as doubles: integer nanoseconds / 1e9 (std::chrono's
    duration_cast<duration<double>> divides the count by the period's denominator)."""
    return [(k * step_ns) / 1e9 for k in range(n_steps + 1)]


def run_libcosim(fmu_path: pathlib.Path, step_ns: int, n_steps: int, start_values: dict, inputs) -> np.ndarray:
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_size=step_ns)
    slave = CosimLocalSlave(fmu_path=str(fmu_path), instance_name="gimbal")
    index = execution.add_local_slave(slave)
    assert index >= 0
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    # Set before fmi2SetupExperiment and again in initialization mode, like fmpy's start values.
    for name, value in start_values.items():
        assert execution.real_initial_value(index, vr[name], float(value)), name
    observer = CosimObserver.create_last_value()
    assert execution.add_observer(observer)
    override = CosimManipulator.create_override()
    assert execution.add_manipulator(override)
    times = libcosim_clock(step_ns, n_steps)
    out_vrs = [vr[n] for n in OUTPUTS]
    rows = []
    for k in range(n_steps):
        if inputs is not None:
            values = inputs(times[k])
            assert override.slave_real_values(index, [vr[n] for n in values], [float(v) for v in values.values()])
        assert execution.step(1), f"libcosim step {k} failed"
        rows.append(observer.last_real_values(index, out_vrs))
    status = execution.status()
    assert status.current_time == n_steps * step_ns
    return np.array(rows)


@pytest.mark.parametrize("step_ns", [1_000_000, 10_000_000], ids=["h1ms", "h10ms"])
@pytest.mark.parametrize("scene", SCENES)
def test_libcosim_matches_fmpy_bitwise_on_libcosims_clock(fmu_path, gimbal_fmu, scene, step_ns):
    n_steps = int(round(STOP_TIME * 1e9 / step_ns))
    got = run_libcosim(fmu_path, step_ns, n_steps, START, SCENES[scene])
    ref = fmpy_on_schedule(gimbal_fmu, libcosim_clock(step_ns, n_steps), START, SCENES[scene])
    assert_bitwise_equal(got, ref, "libcosim")


@pytest.mark.parametrize("step_ns", [1_000_000, 10_000_000], ids=["h1ms", "h10ms"])
@pytest.mark.parametrize("scene", SCENES)
def test_libcosim_agrees_with_fixed_step_simulate(fmu_path, gimbal_fmu, scene, step_ns):
    """Against the plain `simulate` (h = 0.001 every step) the runs are two solutions at rtol = 1e-9.

    Measured worst differences, relative to each signal's range over 0.5 s (1 ms and 10 ms steps, both
    scenes): angles 1e-9..1.4e-7, currents and gyro rate up to 5e-7, T_E2 up to 6.5e-6. The shaft torque
    T_E2 = k_s (beta_m/N - beta - theta_b) + c_s (...) is k_s = 2e4 N.m/rad times a difference of angles
    of ~0.3 rad, so an rtol-sized angle error (1e-9 * 0.3 rad) is already ~6e-6 N.m on a ~1 N.m range.
    Tolerances: 1e-5 of the range (>= 20x the worst measured), 1e-4 for T_E2 (15x).
    """
    h = step_ns / 1e9  # the double 0.001 or 0.01
    n_steps = int(round(STOP_TIME / h))
    times = libcosim_clock(step_ns, n_steps)
    steps = {t1 - t0 for t0, t1 in zip(times[:-1], times[1:])}
    assert len(steps) > 1 and h in steps  # libcosim's step sizes are not all the double h
    got = run_libcosim(fmu_path, step_ns, n_steps, START, SCENES[scene])
    inputs = SCENES[scene]
    ref = as_matrix(simulate(gimbal_fmu, STOP_TIME, h, start_values=START, outputs=OUTPUTS,
                             inputs=None if inputs is None else (lambda t, _latest: inputs(t))))
    worst = np.max(np.abs(got - ref), axis=0) / np.max(np.abs(ref), axis=0)
    tolerance = np.array([1e-4 if name == "T_E2" else 1e-5 for name in OUTPUTS])
    assert np.all(worst <= tolerance), dict(zip(OUTPUTS, worst))


# ----------------------------------------------------------------------------------------------------
# ecos (ecospy), in-process and through its proxyfmu child process

def import_ecospy():
    try:
        return pytest.importorskip("ecospy")  # skips only if the package is not installed
    except OSError as error:  # installed, but its libecosc.so does not load
        pytest.fail(f"ecospy is installed but its native library does not load ({error}); "
                    "it needs Debian's libtbb12 (libtbb.so.12)")


@pytest.fixture(scope="module")
def proxyfmu_on_path(tmp_path_factory):
    """ecos starts the child with `system("proxyfmu ...")`, found through PATH (ecospy prepends its
    `binaries` folder). The ecospy 0.7.2 wheel ships `binaries/proxyfmu` without the executable bit
    (mode 644 in the wheel), so `sh` says "proxyfmu: Permission denied": put an executable copy first
    on PATH, without touching the installed package."""
    ecospy = import_ecospy()
    server = pathlib.Path(ecospy.__file__).parent / "binaries" / "proxyfmu"
    assert server.is_file(), f"{server} is missing from the ecospy package"
    with pytest.MonkeyPatch.context() as patch:
        if not os.access(server, os.X_OK):
            directory = tmp_path_factory.mktemp("proxyfmu")
            copy = directory / "proxyfmu"
            shutil.copyfile(server, copy)
            copy.chmod(copy.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
            patch.setenv("PATH", f"{directory}{os.pathsep}{os.environ.get('PATH', '')}")
        yield


def run_ecos(uri: str, step: float, n_steps: int, start_values: dict, inputs) -> np.ndarray:
    import_ecospy()
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    structure.add_model("gimbal", uri)
    # Applied in initialization mode (after fmi2SetupExperiment and fmi2EnterInitializationMode).
    assert structure.add_parameter_set("start", {f"gimbal::{n}": float(v) for n, v in start_values.items()}), \
        EcosLib.get_last_error()
    simulation = EcosSimulation(structure=structure, step_size=step)
    structure.free()
    try:
        assert simulation.init(parameter_set="start"), EcosLib.get_last_error()
        rows = []
        for k in range(n_steps):
            if inputs is not None:
                for name, value in inputs(k * step).items():  # the times gimbal2axis.fmu.simulate uses
                    simulation.set_real(f"gimbal::{name}", float(value))
            simulation.step(1)
            rows.append([simulation.get_real(f"gimbal::{n}") for n in OUTPUTS])
        assert simulation.get_time() == pytest.approx(n_steps * step, rel=1e-12)
        simulation.terminate()
    finally:
        simulation.free()  # with proxyfmu: frees the remote instance and joins the child process
    return np.array(rows)


def ecos_versus_fmpy(uri, gimbal_fmu, scene, step):
    n_steps = int(round(STOP_TIME / step))
    inputs = SCENES[scene]
    got = run_ecos(uri, step, n_steps, START, inputs)
    ref = as_matrix(simulate(gimbal_fmu, n_steps * step, step, start_values=START, outputs=OUTPUTS,
                             inputs=None if inputs is None else (lambda t, _latest: inputs(t))))
    assert_bitwise_equal(got, ref, f"ecos ({uri.split(':')[0] if '://' in uri else 'in-process'})")


@pytest.mark.parametrize("step", [1e-3, 1e-2], ids=["h1ms", "h10ms"])
@pytest.mark.parametrize("scene", SCENES)
def test_ecos_in_process_matches_fmpy_bitwise(fmu_path, gimbal_fmu, scene, step):
    ecos_versus_fmpy(str(fmu_path), gimbal_fmu, scene, step)


@pytest.mark.parametrize("scene", SCENES)
def test_ecos_proxyfmu_child_process_matches_fmpy_bitwise(fmu_path, gimbal_fmu, proxyfmu_on_path, scene):
    ecos_versus_fmpy(f"proxyfmu://localhost?file={fmu_path}", gimbal_fmu, scene, 1e-3)
