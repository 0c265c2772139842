"""The FMU allocates nothing inside doStep after the first (docs/benchmarks.md, "FMI overhead and memory").

A real-time rig cannot afford the allocator's worst case, and a mode change is where an allocation
hides: a callback that captured too much once allocated at every mode decision. The native benchmark
driver (benchmarks/bench_driver.cpp) interposes malloc and its family and counts the calls made inside
fmi2DoStep; each case below must change modes (backlash, friction, clamps), or it could not fail.
"""
import json
import subprocess

import pytest

BODY_FRICTION = {"body1.T_din": 0.05, "body1.T_max": 0.08, "body2.T_din": 0.04, "body2.T_max": 0.06}
CASES = {
    "automatic (default)": ({}, {}),
    "Dormand-Prince": ({"--method": "5"}, {}),
    "RODAS4": ({"--method": "6"}, {}),
    "real time, 2 substeps": ({"--method": "7"}, {"solver.substeps": 2}),
    "automatic, friction on every body": ({}, BODY_FRICTION),
    "automatic, stiff chattering gears": ({}, {"gear1.k_s": 1e8, "gear2.k_s": 1e8}),
    "CVODE BDF": ({"--method": "0"}, {}),
}


@pytest.fixture(scope="module")
def bench(build_dir):
    path = build_dir / "benchmarks" / "gimbal_bench"
    if not path.is_file():
        pytest.skip("gimbal_bench is not built (sanitizer builds leave it out: their allocator is not malloc's)")
    return path


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_do_step_does_not_allocate(bench, build_dir, case):
    options, parameters = CASES[case]
    so = build_dir / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    command = [str(bench), "--fmu", str(so), "--duration", "0.3", "--json"]
    for option, value in options.items():
        command += [option, value]
    for name, value in parameters.items():
        command += ["--set", f"{name}={value}"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    result = json.loads(done.stdout)
    assert result["failure"] == "", result["failure"]
    assert result["events"] >= 5, f"{case}: only {result['events']} mode changes, the case tests nothing"
    assert result["dostep_allocations"] == 0, "\n".join(result["allocation_sites"])
