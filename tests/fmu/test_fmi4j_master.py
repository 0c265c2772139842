"""The FMU under FMI4j, the JVM's FMI library (Maven Central `info.laht.fmi4j:fmi-import` 0.38.0),
compared with our fmpy master.

`tests/fmu/masters/fmi4j/` is a small Java master (one class, `Fmi4jMaster`) over FMI4j's co-simulation
API; a module fixture builds it with Maven into `<build dir>/fmi4j-master` and each test runs it in
its own JVM. FMI4j loads `Gimbal2Axis.so` through its JNI bridge (`libfmi4j-import.so`, C++, shipped
in the jar), and every call below goes straight through it to the FMU:

- `Fmu.from(file).asCoSimulationFmu().newInstance(name, false, false)`: fmi2Instantiate, not visible,
  logging off, with FMI4j's own logger (it prints the FMU's messages on stdout).
- `setupExperiment(0, 0, 0)`: fmi2SetupExperiment(toleranceDefined = false, 0, startTime 0,
  stopTimeDefined = false, 0): FMI4j defines the tolerance only if > 0 and the stop time only if
  > start, so this is exactly fmpy's `setupExperiment(startTime=0.0)`. A defined tolerance would
  replace the FMU's default `solver.rtol` (here START sets `solver.rtol`, which wins anyway).
- `writeReal(vrs, values)` of the start values in one fmi2SetReal, then fmi2EnterInitializationMode
  and fmi2ExitInitializationMode, as `gimbal2axis.fmu.simulate` does.
- Each step k: `writeReal` of the inputs (the rolling base), `doStep(k * h, h)`, `readReal` of the
  outputs. FMI4j 0.38 keeps no clock of its own: `CoSimulationSlave.doStep(t, h)` hands t and h to
  fmi2DoStep unchanged. The harness passes t = k * h, the double `gimbal2axis.fmu.simulate` passes, and the
  constant h (0.001 is 0.001 at every step, unlike libcosim's integer-nanosecond clock, see
  test_other_masters.py). FMI4j always passes noSetFMUStatePriorToCurrentPoint = fmi2True, as fmpy
  does by default (the FMU ignores the flag).
- FMI4j widens value references to Java longs and narrows them back to fmi2ValueReference in its
  bridge; it reads and writes doubles as they are.

Same FMU, same calls with the same arguments, same inputs: the outputs must agree with fmpy to the
last bit, and do. Every double crosses the process boundary as a hexadecimal literal (Python's
`float.hex`/`float.fromhex`, Java's `Double.toHexString`/`Double.parseDouble`), so no decimal
conversion stands between the two runs.

FMU state: `getFMUstate()` / `setFMUstate(s)` / `freeFMUstate(s)` in a rollback: run to
t1 = K h, save, run on to the end, restore, replay the steps from K with the same inputs; the replay
must repeat the first pass bit for bit. FMI4j's bridge calls fmi2GetFMUstate(c, &state) with `state`
an uninitialised local (the standard's "*FMUstate == NULL: allocate a new state" is not honoured),
so the FMU finds whatever the stack held where the standard allows a previous state to reuse: it
must not take that for one of its own states, let alone dereference it. FMI4j ignores the status of fmi2GetFMUstate;
the harness checks it through `getLastStatus()`.
"""
from __future__ import annotations

import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

from gimbal2axis.fmu import simulate
from test_other_masters import OUTPUTS, SCENES, START, STOP_TIME, as_matrix, assert_bitwise_equal

pytestmark = pytest.mark.skipif(
    os.environ.get("GIMBAL_SANITIZED") == "1",
    reason="the sanitizer pass LD_PRELOADs libasan into every child process: a JVM under ASan is not "
           "meaningful (it handles SIGSEGV and maps memory its own way); fmpy covers the sanitized FMU")

HARNESS = pathlib.Path(__file__).resolve().parent / "masters" / "fmi4j"
ROLLBACK_STEP = 200  # of 500 steps of 1 ms: save the state at t1 = 0.2 s


@pytest.fixture(scope="module")
def fmi4j_master(build_dir) -> list:
    """The command that runs the harness (`java ... Fmi4jMaster`), built by Maven: offline when the
    local repository already holds everything, else online (a failed download fails, not skips)."""
    java, mvn = shutil.which("java"), shutil.which("mvn")
    if java is None or mvn is None:
        pytest.skip("the FMI4j master needs a JDK (java) and Maven (mvn) on PATH")
    out = build_dir / "fmi4j-master"
    maven = [mvn, "-q", "-B", "-f", str(HARNESS / "pom.xml"), f"-Dharness.build.directory={out}", "package"]
    built = subprocess.run([*maven, "-o"], capture_output=True, text=True, timeout=300)
    if built.returncode != 0:
        built = subprocess.run(maven, capture_output=True, text=True, timeout=600)
    if built.returncode != 0:
        pytest.fail(f"Maven could not build the FMI4j master ({' '.join(maven)}):\n{built.stdout}{built.stderr}")
    classpath = [str(out / "classes"), *(out / "classpath.txt").read_text().strip().split(os.pathsep)]
    # Serial GC and C1 only: short runs, where the JVM's start-up is most of the time.
    return [java, "-XX:+UseSerialGC", "-XX:TieredStopAtLevel=1", "-cp", os.pathsep.join(classpath), "Fmi4jMaster"]


def run_fmi4j(master: list, fmu_path: pathlib.Path, workdir: pathlib.Path, step: float, n_steps: int,
              start_values: dict, inputs, rollback_at: int | None = None) -> dict:
    """Runs the harness; returns {pass: (steps, outputs)}: pass 0 the run, pass 1 the replay after the
    rollback (its first row is read right after fmi2SetFMUstate, at the saved time)."""
    out = workdir / "outputs.csv"
    arguments = ["--fmu", str(fmu_path), "--step", step.hex(), "--steps", str(n_steps),
                 "--outputs", ",".join(OUTPUTS), "--out", str(out)]
    for name, value in start_values.items():
        arguments += ["--start", f"{name}={float(value).hex()}"]
    if inputs is not None:
        # The values set before the step starting at t_k = k * step, as gimbal2axis.fmu.simulate sets them.
        rows = [inputs(k * step) for k in range(n_steps)]
        names = list(rows[0])
        table = workdir / "inputs.csv"
        table.write_text("\n".join([",".join(names)] + [",".join(float(row[n]).hex() for n in names) for row in rows]) + "\n")
        arguments += ["--inputs", str(table)]
    if rollback_at is not None:
        arguments += ["--rollback-at", str(rollback_at)]
    # A JVM that dies in native code writes hs_err_pid*.log; FMI4j extracts its bridge into java.io.tmpdir:
    # both into the test's own directory.
    jvm_options = [f"-XX:ErrorFile={workdir / 'hs_err_pid%p.log'}", f"-Djava.io.tmpdir={workdir}"]
    run = subprocess.run([master[0], *jvm_options, *master[1:], *arguments], cwd=workdir,
                         capture_output=True, text=True, timeout=120)
    if run.returncode != 0:
        crash = "".join(path.read_text(errors="replace") for path in workdir.glob("hs_err_pid*.log"))
        frames = [line for line in crash.splitlines() if line.startswith(("# Problematic frame", "# C  ", "C  [", "j  "))]
        pytest.fail(f"the FMI4j master exited with status {run.returncode}\nstderr:\n{run.stderr}\n"
                    f"stdout (the FMU's log):\n{run.stdout}" + ("\nJVM crash report:\n" + "\n".join(frames[:12]) if crash else ""))
    lines = out.read_text().splitlines()
    assert lines[0] == "pass,step," + ",".join(OUTPUTS)
    passes: dict = {}
    for line in lines[1:]:
        fields = line.split(",")
        passes.setdefault(int(fields[0]), []).append((int(fields[1]), [float.fromhex(v) for v in fields[2:]]))
    result = {}
    for number, rows in passes.items():
        steps = [k for k, _ in rows]
        assert steps == list(range(steps[0], steps[0] + len(steps))), f"pass {number}: steps out of order"
        result[number] = np.array([values for _, values in rows])
    return result


def fmpy_reference(gimbal_fmu, scene: str, step: float, n_steps: int) -> np.ndarray:
    inputs = SCENES[scene]
    return as_matrix(simulate(gimbal_fmu, n_steps * step, step, start_values=START, outputs=OUTPUTS,
                              inputs=None if inputs is None else (lambda t, _latest: inputs(t))))


@pytest.mark.parametrize("step", [1e-3, 1e-2], ids=["h1ms", "h10ms"])
@pytest.mark.parametrize("scene", SCENES)
def test_fmi4j_matches_fmpy_bitwise(fmi4j_master, fmu_path, gimbal_fmu, tmp_path, scene, step):
    n_steps = int(round(STOP_TIME / step))
    got = run_fmi4j(fmi4j_master, fmu_path, tmp_path, step, n_steps, START, SCENES[scene])
    assert set(got) == {0}
    assert_bitwise_equal(got[0], fmpy_reference(gimbal_fmu, scene, step, n_steps), "FMI4j")


@pytest.mark.parametrize("scene", SCENES)
def test_fmi4j_fmu_state_rollback_replays_bitwise(fmi4j_master, fmu_path, gimbal_fmu, tmp_path, scene):
    """Save at t1 = 0.2 s, run to 0.5 s, restore, replay 0.2 .. 0.5 s: both passes equal fmpy's run."""
    step = 1e-3
    n_steps = int(round(STOP_TIME / step))
    got = run_fmi4j(fmi4j_master, fmu_path, tmp_path, step, n_steps, START, SCENES[scene], rollback_at=ROLLBACK_STEP)
    assert set(got) == {0, 1}
    first, replay = got[0], got[1]
    assert_bitwise_equal(first, fmpy_reference(gimbal_fmu, scene, step, n_steps), "FMI4j (before the rollback)")
    # Row 0 of the replay: the outputs right after fmi2SetFMUstate, those of step ROLLBACK_STEP - 1.
    repeated = first[ROLLBACK_STEP - 1:]
    assert replay.shape == repeated.shape
    for j, name in enumerate(OUTPUTS):
        differ = np.flatnonzero(replay[:, j] != repeated[:, j])
        assert differ.size == 0, (
            f"FMI4j: after fmi2SetFMUstate, {name} differs from the first pass at {differ.size} steps, first at "
            f"step {ROLLBACK_STEP - 1 + differ[0]}: {replay[differ[0], j]!r} vs {repeated[differ[0], j]!r}")
