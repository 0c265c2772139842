"""The FMU under fmi-sim, the command-line simulator of the Rust `rust-fmi` crates, compared with fmpy.

fmi-sim (crate `fmi-sim`, version pinned below, installed with cargo into the build directory by the
fixture) drives an FMI 2.0 co-simulation FMU like this (`src/sim/fmi2/cs.rs`, `src/sim/mod.rs`,
`src/sim/io.rs`, `src/sim/interpolation.rs` of the crate):

1. `fmi2Instantiate("inst1", visible = true, loggingOn = true)`.
2. One `fmi2SetReal` per `--init-values name=value`, in command-line order, before
   `fmi2SetupExperiment`. The string is cast to a double by Arrow (correctly rounded), so Python's
   `repr` round-trips. Then the input CSV's values at the start time (see 5).
3. `fmi2SetupExperiment(toleranceDefined, tolerance, startTime, stopTimeDefined = true, stopTime)`:
   the tolerance is defined only with `--tolerance` or a `tolerance` in `<DefaultExperiment>` (ours
   has none), the stop time always (`-f`). Then `fmi2EnterInitializationMode`,
   `fmi2ExitInitializationMode`.
4. For k = 0, 1, ...: t_k = startTime + k h (a product, not a running sum: for h = 1 ms, 491 of the
   500 points differ from the running sum), read every output (one `fmi2Get*` call each), set the
   inputs for t_k, stop once
   t_k >= stopTime, else `fmi2DoStep(t_k, h, noSetFMUStatePriorToCurrentPoint = true)`. Then
   `fmi2Terminate`. The communication step h is `--output-interval` (default: `stepSize` of
   `<DefaultExperiment>`); `--step` (whatever its help says), `-n` and `--print-all` are parsed but
   unused for co-simulation.
5. Inputs come from a CSV file with a `time` column and columns named like model inputs (other
   columns are ignored). Each continuous input is set by its own `fmi2SetReal`, in modelDescription
   order, to fmi-sim's linear interpolation: row i is the last with t_i < t, and the value is
   v_i + f (v_{i+1} - v_i) with f = (t - t_i) / (t_{i+1} - t_i). So the table is left-continuous:
   at a time listed twice (a jump), the value before the jump is held over the step starting there
   and the value after it from the next step on. Even at a breakpoint, t = t_{i+1}, the value is
   v_i + 1.0 (v_{i+1} - v_i), which may differ from v_{i+1} in the last bit. Past the last row it is
   the last value, by the same formula with f = 1.
6. The output CSV has a column per output (causality = "output") and `time`. Arrow writes doubles in
   their shortest round-trip form (lexical-core), so the CSV holds every bit: nothing is lost.

The fmpy reference (`fmpy_as_fmi_sim`) makes the same calls with the same doubles: the same start
values in the same order before `fmi2SetupExperiment`, the same tolerance and stop time, the same
k h, and the same interpolated inputs, computed operation by operation as fmi-sim does. The outputs
and the time column then agree to the last bit; that is asserted for every scene. The one argument
not copied is `visible = true`, which this FMU ignores.

For a fixed base, fmi-sim's calls differ from `gimbal2axis.fmu.simulate` only in where the start values
are set (before instead of after `fmi2SetupExperiment`, both in the instantiated state) and in
`loggingOn`; neither changes the solution, and the plain `simulate` agrees bit for bit too.
With inputs from a table, the interpolated values are not always the scene function's: for the
rolling base, base.gamma = v_i + f (v_{i+1} - v_i) differs from GAMMA_DOT t_k by one ulp at 106 of
the 501 points (h = 1 ms). A different input is a different problem, and the plain `simulate` fed
with GAMMA_DOT t_k differs from fmi-sim at round-off level (measured: at most 7e-12 of the signal's
range, on T_E2). Hence the reference takes its inputs through fmi-sim's interpolation instead.
"""
from __future__ import annotations

import csv
import os
import pathlib
import shutil
import subprocess
import time
from dataclasses import dataclass

import numpy as np
import pytest

from gimbal2axis.fmu import FMU, simulate
from test_other_masters import GAMMA_DOT, OUTPUTS, START, STOP_TIME, assert_bitwise_equal

pytestmark = pytest.mark.skipif(
    os.environ.get("GIMBAL_SANITIZED") == "1",
    reason="the sanitizer pass LD_PRELOADs libasan into every child process, cargo and rustc included, and "
           "would build fmi-sim a second time for its own build directory; the release pass runs these tests")

FMI_SIM_VERSION = "0.7.0"  # the newest on crates.io that builds (needs libclang for fmi-sys's bindgen)
INSTALL_TIMEOUT_S = 900  # a cold install takes 2-3 minutes on 2 cores

START_TIME = 0.0


@dataclass
class Scene:
    start_values: dict
    table: dict | None = None  # column name -> values; "time" first, as written to the input CSV
    tolerance: float | None = None  # fmi-sim's --tolerance, passed to fmi2SetupExperiment


def rolling_base_table() -> dict:
    """The rolling base of test_other_masters.py as a table, with breakpoints off the communication
    grid (every 30 ms), so fmi-sim interpolates between them at most communication points."""
    times = [0.03 * i for i in range(18)]  # up to 0.51 s, past the stop time
    return {"time": times, "base.gamma": [GAMMA_DOT * t for t in times], "base.gamma_dot": [GAMMA_DOT] * len(times)}


def voltage_profile_table() -> dict:
    """Motor 1 ramps up, holds, ramps down to a negative voltage; motor 2 reverses at 0.2 s (a jump:
    0.2 listed twice, and on the grid of both step sizes, so the left-continuity of the table shows)."""
    rows = [(0.0, 0.0, -1.5), (0.125, 4.0, -1.5), (0.2, 4.0, -1.5), (0.2, 4.0, 1.0), (0.3, 4.0, 1.0),
            (0.4375, -2.0, 1.0), (0.6, -2.0, 1.0)]
    return dict(zip(["time", "u_R1", "u_R2"], map(list, zip(*rows))))


WITHOUT_VOLTAGES = {n: v for n, v in START.items() if n not in ("u_R1", "u_R2")}
WITHOUT_RTOL = {n: v for n, v in START.items() if n != "solver.rtol"}

SCENES = {
    "fixed_base": Scene(START),
    "rolling_base_csv": Scene(START, rolling_base_table()),
    "voltage_profile_csv": Scene(WITHOUT_VOLTAGES, voltage_profile_table()),
    # No solver.rtol: the FMU integrates at the master's fmi2SetupExperiment tolerance instead of its
    # default 1e-6, so a tolerance lost on the way would show as a different solution.
    "master_tolerance": Scene(WITHOUT_RTOL, tolerance=1e-9),
}


# ----------------------------------------------------------------------------------------------------
# fmi-sim, installed once per build directory

def find_cargo() -> str | None:
    # rustup puts cargo in ~/.cargo/bin and adds it to PATH only through login-shell profiles.
    fallback = pathlib.Path.home() / ".cargo" / "bin" / "cargo"
    return shutil.which("cargo") or (str(fallback) if fallback.is_file() else None)


@pytest.fixture(scope="module")
def fmi_sim(build_dir) -> pathlib.Path:
    root = build_dir / f"fmi-sim-{FMI_SIM_VERSION}"
    binary = root / "bin" / "fmi-sim"
    if binary.is_file():
        return binary
    cargo = find_cargo()
    if cargo is None:
        pytest.skip("cargo is not installed: fmi-sim is a Rust program, installed from crates.io with cargo")
    command = [cargo, "install", "--locked", "--root", str(root), f"fmi-sim@{FMI_SIM_VERSION}"]
    # Unoptimized, the build takes a third of the CPU time (measured cold on 2 cores: 2 min instead of
    # 6, mostly Arrow), and the runs here last a tenth of a second either way. Rust never trades IEEE
    # semantics for speed (no fast-math, no fused multiply-add unless asked), so the doubles fmi-sim
    # passes are the same: the bitwise comparisons below pass with both builds.
    environment = dict(os.environ, CARGO_PROFILE_RELEASE_OPT_LEVEL="0")
    shown = f"CARGO_PROFILE_RELEASE_OPT_LEVEL=0 {' '.join(command)}"
    started = time.monotonic()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=INSTALL_TIMEOUT_S, env=environment)
    except subprocess.TimeoutExpired:
        pytest.fail(f"`{shown}` did not finish in {INSTALL_TIMEOUT_S} s")
    if done.returncode != 0 or not binary.is_file():
        hint = ("\nfmi-sys generates its FMI bindings with bindgen, which needs libclang: "
                "apt-get install libclang-dev" if "libclang" in done.stderr else "")
        pytest.fail(f"`{shown}` failed with exit code {done.returncode} after "
                    f"{time.monotonic() - started:.0f} s:\n{done.stderr[-4000:]}{hint}")
    return binary


def write_input_csv(path: pathlib.Path, table: dict) -> None:
    with path.open("w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(table)
        writer.writerows(zip(*[[repr(float(v)) for v in column] for column in table.values()]))


def run_fmi_sim(fmi_sim: pathlib.Path, fmu_path: pathlib.Path, workdir: pathlib.Path, scene: Scene,
                step: float) -> tuple[np.ndarray, np.ndarray]:
    """(time column, (points, OUTPUTS) matrix) of fmi-sim's output CSV, initial point included."""
    output = workdir / "out.csv"
    command = [str(fmi_sim), "--model", str(fmu_path), "--output-file", str(output)]
    if scene.table is not None:
        write_input_csv(workdir / "in.csv", scene.table)
        command += ["--input-file", str(workdir / "in.csv")]
    command += ["co-simulation", "-s", repr(START_TIME), "-f", repr(STOP_TIME), "--output-interval", repr(step)]
    for name, value in scene.start_values.items():
        command += ["--init-values", f"{name}={value!r}"]
    if scene.tolerance is not None:
        command += ["--tolerance", repr(scene.tolerance)]
    # It prints a line per communication point on stdout; only stderr says why a run failed.
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=300)
    assert done.returncode == 0, f"fmi-sim failed ({done.returncode}):\n{done.stderr[-4000:]}"
    with output.open(newline="") as file:
        rows = list(csv.DictReader(file))
    times = np.array([float(row["time"]) for row in rows])
    return times, np.array([[float(row[n]) for n in OUTPUTS] for row in rows])


# ----------------------------------------------------------------------------------------------------
# fmpy, making fmi-sim's calls

def fmi_sim_interpolation(times: list, values: list, t: float) -> float:
    """fmi-sim's `PreLookup::new` with `after_event = false` and `Linear::interpolate`, operation for
    operation (Rust does not contract a * b + c into a fused multiply-add, and neither does Python)."""
    row = 0
    for i in range(1, len(times)):
        if times[i] >= t:
            break
        row = i
    fraction = 1.0 if row == len(times) - 1 else (t - times[row]) / (times[row + 1] - times[row])
    index = min(row, len(times) - 2)
    return values[index] + fraction * (values[index + 1] - values[index])


def set_table_inputs(fmu: FMU, slave, table: dict, t: float) -> None:
    inputs = [v.name for v in fmu.model_description.modelVariables if v.causality == "input" and v.name in table]
    for name in inputs:  # one fmi2SetReal each, in modelDescription order
        slave.setReal([fmu.vr(name)], [fmi_sim_interpolation(table["time"], table[name], t)])


def fmpy_as_fmi_sim(fmu: FMU, scene: Scene, step: float) -> tuple[np.ndarray, np.ndarray]:
    """fmi-sim's calls, in its order (module docstring): (times, (points, OUTPUTS) matrix)."""
    log = []
    slave = fmu.instantiate("inst1", log=log, logging_on=True)
    try:
        for name, value in scene.start_values.items():
            fmu.set_values(slave, {name: value})
        if scene.table is not None:
            set_table_inputs(fmu, slave, scene.table, START_TIME)
        slave.setupExperiment(tolerance=scene.tolerance, startTime=START_TIME, stopTime=STOP_TIME)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        times, rows = [], []
        k = 0
        while True:
            t = START_TIME + k * step
            times.append(t)
            rows.append(fmu.get_values(slave, OUTPUTS))
            if scene.table is not None:
                set_table_inputs(fmu, slave, scene.table, t)
            if t >= STOP_TIME:
                break
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=step, noSetFMUStatePriorToCurrentPoint=True)
            k += 1
        slave.terminate()
    finally:
        slave.freeInstance()
    assert not [entry for entry in log if entry[0] > 1], log  # nothing above fmi2Warning
    return np.array(times), np.array(rows)


# ----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("step", [1e-3, 1e-2], ids=["h1ms", "h10ms"])
@pytest.mark.parametrize("scene", SCENES)
def test_fmi_sim_matches_fmpy_bitwise(fmi_sim, fmu_path, gimbal_fmu, tmp_path, scene, step):
    times, got = run_fmi_sim(fmi_sim, fmu_path, tmp_path, SCENES[scene], step)
    ref_times, ref = fmpy_as_fmi_sim(gimbal_fmu, SCENES[scene], step)
    assert np.array_equal(times, ref_times), "fmi-sim's communication points are not start + k h"
    assert_bitwise_equal(got, ref, "fmi-sim")


def test_fmi_sim_time_grid_is_a_product_not_a_running_sum(fmi_sim, fmu_path, tmp_path):
    step = 1e-3
    times, _ = run_fmi_sim(fmi_sim, fmu_path, tmp_path, SCENES["fixed_base"], step)
    n_steps = int(round(STOP_TIME / step))
    assert np.array_equal(times, START_TIME + np.arange(n_steps + 1) * step)
    assert not np.array_equal(times, np.concatenate([[START_TIME], START_TIME + np.cumsum(np.full(n_steps, step))]))


@pytest.mark.parametrize("step", [1e-3, 1e-2], ids=["h1ms", "h10ms"])
def test_fmi_sim_matches_plain_simulate_on_a_fixed_base(fmi_sim, fmu_path, gimbal_fmu, tmp_path, step):
    _, got = run_fmi_sim(fmi_sim, fmu_path, tmp_path, SCENES["fixed_base"], step)
    result = simulate(gimbal_fmu, STOP_TIME, step, start_values=START, outputs=OUTPUTS)
    assert_bitwise_equal(got, np.column_stack([result[n] for n in OUTPUTS]), "fmi-sim against simulate")


def test_fmi_sim_holds_a_jump_from_the_next_step_on(fmi_sim, fmu_path, gimbal_fmu, tmp_path):
    """The interpolation reproduced in the reference is fmi-sim's, not a guess that happens to agree:
    with the jump of motor 2's voltage at 0.2 s applied one step early (right-continuous table), the
    solutions part."""
    step = 1e-3
    scene = SCENES["voltage_profile_csv"]
    _, got = run_fmi_sim(fmi_sim, fmu_path, tmp_path, scene, step)
    table = dict(scene.table)
    jump = table["time"].index(0.2)
    table["time"] = table["time"][:jump] + [np.nextafter(0.2, 0.0)] + table["time"][jump + 1:]
    _, right_continuous = fmpy_as_fmi_sim(gimbal_fmu, Scene(scene.start_values, table), step)
    at_jump = int(round(0.2 / step))
    assert np.array_equal(got[:at_jump + 1], right_continuous[:at_jump + 1])
    # Over [0.2, 0.201] fmi-sim still applies -1.5 V: the reversal shows in i_R2 (~0.8 A) one step later.
    i_R2 = OUTPUTS.index("i_R2")
    assert abs(got[at_jump + 1, i_R2] - right_continuous[at_jump + 1, i_R2]) > 0.5


# ----------------------------------------------------------------------------------------------------
# Model Exchange: fmi-sim's forward Euler, a second host independent of fmpy's

def run_fmi_sim_model_exchange(fmi_sim: pathlib.Path, fmu_path: pathlib.Path, workdir: pathlib.Path,
                               start_values: dict, table: dict, stop_time: float, step: float) -> dict:
    """fmi-sim's `model-exchange` (forward Euler whose step is the output interval, events seen at the
    end of a step, left limits not printed): {name: array} of the values after each event handling."""
    output = workdir / f"me_{step!r}.csv"
    write_input_csv(workdir / "me_in.csv", table)
    command = [str(fmi_sim), "--model", str(fmu_path), "--output-file", str(output), "--input-file",
               str(workdir / "me_in.csv"), "model-exchange", "-s", "0.0", "-f", repr(stop_time),
               "--step", repr(step), "--output-interval", repr(step), "-n", "0"]
    for name, value in start_values.items():
        command += ["--init-values", f"{name}={value!r}"]
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=300)
    assert done.returncode == 0, f"fmi-sim failed ({done.returncode}):\n{done.stderr[-4000:]}"
    with output.open(newline="") as file:
        rows = list(csv.DictReader(file))
    return {name: np.array([float(row[name]) for row in rows]) for name in rows[0]}


def test_fmi_sim_model_exchange_stays_physical_and_converges(fmi_sim, fmu_path, gimbal_fmu, tmp_path):
    """The same FMU as Model Exchange under a second host: outputs finite and within their bounds at
    every point, and the Euler solution converging to the Co-Simulation reference at first order."""
    start = {"base.fixed": True, "beta": 0.3, "beta_m": 18.0}
    table = {"time": [0.0, 0.2], "u_R1": [6.0, 6.0], "u_R2": [-4.0, -4.0]}
    stop = 0.04
    reference = simulate(gimbal_fmu, stop, 1e-3, dict(start, **{"solver.rtol": 1e-10}),
                         lambda t, _: {"u_R1": 6.0, "u_R2": -4.0}, outputs=["alpha", "beta"])
    limits = {"i_R1": gimbal_fmu.start("motor1.i_L"), "i_R2": gimbal_fmu.start("motor2.i_L"),
              "theta_b1": gimbal_fmu.start("gear1.eta"), "theta_b2": gimbal_fmu.start("gear2.eta")}
    errors = []
    for step in (2e-5, 1e-5):
        me = run_fmi_sim_model_exchange(fmi_sim, fmu_path, tmp_path, start, table, stop, step)
        for name, values in me.items():
            assert np.all(np.isfinite(values)), name
        for name, limit in limits.items():
            assert np.max(np.abs(me[name])) <= limit, name
        assert me["events.total"][-1] > 0
        # The last row at each millisecond (after any event handling there).
        at_ms = {round(t * 1000): k for k, t in enumerate(me["time"]) if abs(t * 1000 - round(t * 1000)) < 1e-6}
        rows = [at_ms[k] for k in range(len(reference["time"]))]
        errors.append(max(np.max(np.abs(me[n][rows] - reference[n])) for n in ("alpha", "beta")))
    assert 1.5 < errors[0] / errors[1] < 2.6, errors
