"""The FMI 3.0 FMU under a second, independent FMI 3.0 host: fmi-rs (CATIA-Systems, a Rust
implementation of FMI with its own loader, model-description reader and simulation loops, separate
from fmpy's Python code). tests/fmu/fmi_rs_host is a small command-line program over its library, built
here with cargo into the build directory.

- Co-Simulation with Event Mode and early return allowed (fmi-rs handles the early returns and the
  event iterations itself): the values at the communication points equal the FMI 2.0 FMU's under
  fmpy to rounding, with the same event count.
- Model Exchange with fmi-rs' forward Euler and its own event handling: every output physical (the
  current limits and the backlash play hold), first-order convergence to the Co-Simulation
  reference as the step halves.
- fmi-rs' validation of both model descriptions (FMI 2.0 and 3.0), a second validator beside fmpy's."""
from __future__ import annotations

import csv
import os
import pathlib
import subprocess
import time

import numpy as np
import pytest

from gimbal2axis.fmu import simulate
from test_fmi_sim_master import find_cargo

pytestmark = pytest.mark.skipif(
    os.environ.get("GIMBAL_SANITIZED") == "1",
    reason="the sanitizer pass LD_PRELOADs libasan into every child process, cargo and rustc included; the "
           "release pass runs these tests")

REPO = pathlib.Path(__file__).resolve().parents[2]
BUILD_TIMEOUT_S = 900  # a cold build takes about 3 minutes on 2 cores
# gear2.start = as_given (2): beta_m stays at 0, the elevation gear twisted by 0.3 rad on purpose (its
# impacts make the run rich in events).
START = {"base.fixed": True, "beta": 0.3, "u_R1": 6.0, "u_R2": -3.0, "gear2.start": 2}
STOP, INTERVAL = 0.2, 1e-3
LOAD_ANGLES = ["alpha", "beta"]
ANGLES = ["alpha", "alpha_m", "beta", "beta_m"]


@pytest.fixture(scope="module")
def fmi_rs_host(build_dir) -> pathlib.Path:
    target = build_dir / "fmi-rs-host"
    cargo = find_cargo()
    if cargo is None:
        pytest.skip("cargo is not installed: the fmi-rs host is a Rust program built with cargo")
    command = [cargo, "build", "--release", "--locked", "--manifest-path",
               str(REPO / "tests" / "fmu" / "fmi_rs_host" / "Cargo.toml"), "--target-dir", str(target)]
    # Unoptimized: the build takes far less CPU, the runs last a fraction of a second either way, and
    # Rust keeps IEEE semantics at every level (the doubles passed to the FMU are the same).
    environment = dict(os.environ, CARGO_PROFILE_RELEASE_OPT_LEVEL="0")
    started = time.monotonic()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=BUILD_TIMEOUT_S, env=environment)
    except subprocess.TimeoutExpired:
        pytest.fail(f"`{' '.join(command)}` did not finish in {BUILD_TIMEOUT_S} s")
    binary = target / "release" / "gimbal-fmi-rs-host"
    if done.returncode != 0 or not binary.is_file():
        pytest.fail(f"`{' '.join(command)}` failed with exit code {done.returncode} after "
                    f"{time.monotonic() - started:.0f} s:\n{done.stderr[-4000:]}")
    return binary


def run_host(host: pathlib.Path, fmu: pathlib.Path, out: pathlib.Path, interface: str, euler_step: float = 0.0) -> dict:
    values = [f"{name}={str(value).lower() if isinstance(value, bool) else repr(value)}" for name, value in START.items()]
    command = [str(host), str(fmu), str(out), interface, repr(STOP), repr(INTERVAL), repr(euler_step)] + values
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, f"{' '.join(command)}\n{done.stderr[-4000:]}"
    with out.open(newline="") as file:
        rows = list(csv.DictReader(file))
    booleans = {"true": 1.0, "false": 0.0}
    return {name: np.array([booleans[row[name]] if row[name] in booleans else float(row[name]) for row in rows])
            for name in rows[0]}


def at_communication_points(result: dict) -> dict:
    """The last row at each communication point (fmi-rs also records the points of events)."""
    n = int(round(STOP / INTERVAL))
    rows = []
    for k in range(n + 1):
        matches = np.flatnonzero(np.abs(result["time"] - k * INTERVAL) <= 1e-9)
        assert matches.size > 0, f"no row at t = {k * INTERVAL}"
        rows.append(matches[-1])
    return {name: values[rows] for name, values in result.items()}


@pytest.fixture(scope="module")
def reference(gimbal_fmu):
    """Co-Simulation of the FMI 2.0 FMU under fmpy: at the default tolerance (the same solution the
    FMI 3.0 FMU's Co-Simulation computes) and at a tight one (for Model Exchange)."""
    outputs = ANGLES + ["events.total"]
    default = simulate(gimbal_fmu, STOP, INTERVAL, START, None, outputs)
    tight = simulate(gimbal_fmu, STOP, INTERVAL, dict(START, **{"solver.rtol": 1e-10, "solver.atol": 1e-12}), None,
                     outputs)
    return default, tight


def test_co_simulation_with_event_mode_and_early_return_equals_fmi2(fmi_rs_host, build_dir, reference, tmp_path):
    default, _ = reference
    result = run_host(fmi_rs_host, build_dir / "Gimbal2Axis-fmi3.fmu", tmp_path / "cs.csv", "cs")
    points = at_communication_points(result)
    assert result["time"].size > points["time"].size  # early returns at mode changes were recorded
    assert default["events.total"][-1] > 50
    assert points["events.total"][-1] == default["events.total"][-1]
    for name in ANGLES:
        # Early returns restart the integrator at the events the Co-Simulation step locates anyway:
        # the same solution, measured 4e-14 on a 10-15 rad rotor angle.
        np.testing.assert_allclose(points[name], default[name], rtol=1e-12, atol=1e-12, err_msg=name)


def test_model_exchange_with_forward_euler_stays_physical_and_converges(fmi_rs_host, build_dir, gimbal_fmu, reference,
                                                                        tmp_path):
    _, tight = reference
    errors = []
    for euler_step in (2e-5, 1e-5, 5e-6):
        result = run_host(fmi_rs_host, build_dir / "Gimbal2Axis-fmi3.fmu", tmp_path / f"me_{euler_step}.csv", "me",
                          euler_step)
        for name in ["alpha", "beta", "i_R1", "i_R2", "theta_b1", "theta_b2"]:
            assert np.all(np.isfinite(result[name])), name
        for axis in (1, 2):
            assert np.max(np.abs(result[f"i_R{axis}"])) <= gimbal_fmu.start(f"motor{axis}.i_L"), axis
            assert np.max(np.abs(result[f"theta_b{axis}"])) <= gimbal_fmu.start(f"gear{axis}.eta"), axis
        assert result["events.total"][-1] > 50
        points = at_communication_points(result)
        errors.append(max(np.max(np.abs(points[name] - tight[name])) for name in LOAD_ANGLES))
    # Forward Euler is of order 1: halving the step halves the error (measured 6.2e-3, 3.0e-3, 1.5e-3).
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 1.6) & (ratios < 2.5)), (errors, ratios)
    assert errors[-1] < 5e-3, errors


def test_both_model_descriptions_pass_fmi_rs_validation(fmi_rs_host, build_dir, tmp_path):
    """fmi-rs' own checks of the model descriptions (value references, causality/variability/initial
    combinations, dependencies, units, naming), a second validator beside fmpy's: no problem in either
    FMU; a duplicated value reference in a copy is reported (the validator does run)."""
    import zipfile

    fmi3 = tmp_path / "fmi3.xml"
    with zipfile.ZipFile(build_dir / "Gimbal2Axis-fmi3.fmu") as fmu:
        fmi3.write_bytes(fmu.read("modelDescription.xml"))
    for description in (build_dir / "fmu_staging" / "modelDescription.xml", fmi3):
        done = subprocess.run([str(fmi_rs_host), "validate", str(description)], capture_output=True, text=True,
                              timeout=60)
        assert done.returncode == 0 and done.stdout == "", f"{description}:\n{done.stdout}{done.stderr}"
    broken = tmp_path / "broken.xml"
    text = fmi3.read_text()
    assert 'valueReference="103"' in text
    broken.write_text(text.replace('valueReference="103"', 'valueReference="104"', 1))
    done = subprocess.run([str(fmi_rs_host), "validate", str(broken)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 1 and "Duplicate value reference: 104" in done.stdout
