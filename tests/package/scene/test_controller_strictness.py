"""A user controller is code the scene names, held to what it returns, and blamed for what it raises
(issue 34):

- only a .py file the scene names is loaded (`module = "subprocess"` is refused before anything is
  built), and its class is checked (a class defined in that file, with callable reset and step)
  before it is instantiated;
- an exception in the user's code names the exception, the class, the user's file, line and
  function, on one line (the traceback behind `gimbal2axis run --traceback`); a run that fails
  part-way keeps its record (exit 3), in the single run, the streamed run and the lockstep batch;
- step() must return exactly two finite real numbers; the clamp to +-U_L is recorded
  (u_R1_asked beside u_R1_cmd) and counted in the summary, for built-in controllers too, with the
  compiled loop's records equal to the Python loop's.
"""
import json
import math
import pathlib
import subprocess
import sys

import numpy as np
import pyarrow.parquet as pq
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.cli.failures import EXIT_ERROR, EXIT_FAILED_PARTIAL
from gimbal2axis.master.lockstep import run_lockstep
from gimbal2axis.scene.controllers import ControllerError

from support.scenes import cheap_scene

RUN = [sys.executable, "-m", "gimbal2axis", "run"]

# A controller whose helper method raises part-way (a KeyError two calls deep in the user's file).
RAISES_IN_HELPER = '''\
class OneValue:
    batch = BATCH

    def __init__(self):
        self.gains = {"kp": 1.0}

    def reset(self, context):
        self.h = context.step_size

    def gain(self, t):
        if t > 0.0205:
            return self.gains["missing_key"]
        return self.gains["kp"]

    def step(self, t, m):
        return (self.gain(t) * 0.1, 0.0)
'''
HELPER_LINE = 1 + RAISES_IN_HELPER.splitlines().index('            return self.gains["missing_key"]')

# A controller that asks for far more than the motors' voltage limit on the azimuth.
GREEDY = '''\
class Greedy:
    def reset(self, context):
        self.limit = context.u_limit

    def step(self, t, m):
        return (1e6, 0.5 * self.limit[1])
'''

# Writes a file when it is built: a class refused before instantiation must leave no file.
BUILT_MARKER = '''\
import pathlib

class Marks:
    def __init__(self, marker):
        pathlib.Path(marker).write_text("built")
'''


def write_scene(tmp_path, controller: str, code: str | None = None, file_name: str = "my_controller.py",
                stop_time: float = 0.05) -> pathlib.Path:
    if code is not None:
        (tmp_path / file_name).write_text(code)
    path = tmp_path / "strict.toml"
    # A cheap gimbal on a fixed base: what these tests need is the controller's plumbing, not physics.
    path.write_text(cheap_scene(stop_time, name="strict") + "[controller]\n" + controller + "\n")
    return path


def python_controller(class_name: str, file_name: str = "my_controller.py", key: str = "file", extra: str = ""):
    return f'type = "python"\n{key} = "{file_name}"\nclass = "{class_name}"\n{extra}'


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


def cli(*args, cwd):
    return subprocess.run([*RUN, *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=600)


def one_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    return lines[0]


# -- nothing runs that the user did not name as code ---------------------------------------------


def test_a_module_that_is_not_a_file_is_refused_before_anything_is_built(tmp_path, fmu_path):
    marker = tmp_path / "shell_ran"
    scene = write_scene(tmp_path, 'type = "python"\nmodule = "subprocess"\nclass = "Popen"\n'
                                  f'options = {{ args = ["touch", "{marker}"] }}')
    with pytest.raises(SceneError, match="module = 'subprocess' is not a .py file: a user controller is a Python "
                                         "file, given as a path relative to the scene"):
        load_scene(scene)
    done = cli(scene.name, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    assert done.returncode == EXIT_ERROR
    assert "is not a .py file" in one_line(done.stderr)
    assert not marker.exists() and not (tmp_path / "out" / "strict.csv").exists()


@pytest.mark.parametrize("code, class_name, message", [
    ("from subprocess import Popen\n", "Popen", "class 'Popen' is imported into"),
    (BUILT_MARKER + "Alias = 3\n", "Alias", "'Alias' in"),
    (BUILT_MARKER, "Marks", "has no method reset()"),
    (BUILT_MARKER + "    def reset(self, context):\n        pass\n    step = 3\n", "Marks", "has no method step()"),
])
def test_a_class_that_is_not_a_controller_is_refused_before_it_is_built(tmp_path, code, class_name, message):
    marker = tmp_path / "built"
    scene = write_scene(tmp_path, python_controller(class_name, extra=f'options = {{ marker = "{marker}" }}'),
                        code)
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    assert message in str(error.value) and "my_controller.py" in str(error.value)
    assert "gimbal_user_controller" not in str(error.value)   # the user's file, not a generated module name
    assert not marker.exists()


def test_the_file_key_and_the_older_module_key_name_the_same_file(tmp_path, fmu):
    results = []
    for key in ("file", "module"):
        scene = write_scene(tmp_path, python_controller("Greedy", key=key), GREEDY)
        results.append(run(load_scene(scene), fmu).signals["alpha"])
    assert np.array_equal(*results)
    both = python_controller("Greedy") + '\nmodule = "my_controller.py"'
    with pytest.raises(SceneError, match="both file and module"):
        load_scene(write_scene(tmp_path, both, GREEDY))


# -- errors that name the user's culprit ---------------------------------------------------------


def test_a_controller_raising_inside_a_helper_is_named_with_its_file_and_line(tmp_path, fmu_path):
    scene = write_scene(tmp_path, python_controller("OneValue"), RAISES_IN_HELPER.replace("BATCH", "False"))
    out = tmp_path / "out"
    done = cli(scene.name, "--fmu", fmu_path, "--out", out, "--quiet", cwd=tmp_path)
    assert done.returncode == EXIT_FAILED_PARTIAL, done.stderr
    message = one_line(done.stderr)
    assert message.startswith("gimbal2axis run: error: strict: OneValue (my_controller.py): step() raised "
                              "KeyError: 'missing_key' at t = 0.021 s "
                              f"(my_controller.py:{HELPER_LINE}, in gain)"), message
    assert "FMU" not in message
    status = json.loads((out / "strict_run.json").read_text())
    assert status["partial"] is True and status["recorded_until_s"] == pytest.approx(0.020)
    # the traceback on request, after the one-line error
    done = cli(scene.name, "--fmu", fmu_path, "--out", out, "--quiet", "--traceback", cwd=tmp_path)
    assert done.returncode == EXIT_FAILED_PARTIAL
    lines = done.stderr.splitlines()
    assert lines[0] == message and lines[1] == "Traceback (most recent call last):"
    assert f'my_controller.py", line {HELPER_LINE}, in gain' in done.stderr and lines[-1] == "KeyError: 'missing_key'"


def test_a_reset_that_raises_is_refused_in_one_line_with_the_traceback_on_request(tmp_path, fmu_path):
    code = RAISES_IN_HELPER.replace("BATCH", "False").replace("self.h = context.step_size",
                                                               "self.h = context.step_size / context.missing")
    line = 1 + code.splitlines().index("        self.h = context.step_size / context.missing")
    scene = write_scene(tmp_path, python_controller("OneValue"), code)
    done = cli(scene.name, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", cwd=tmp_path)
    assert done.returncode == EXIT_ERROR   # nothing recorded: refused, not partial
    assert one_line(done.stderr) == ("gimbal2axis run: error: strict: OneValue (my_controller.py): reset() raised "
                                     "AttributeError: 'ControllerContext' object has no attribute 'missing' at "
                                     f"t = 0 s (my_controller.py:{line}, in reset)")
    done = cli(scene.name, "--fmu", fmu_path, "--out", tmp_path / "out", "--quiet", "--traceback", cwd=tmp_path)
    assert done.returncode == EXIT_ERROR
    assert done.stderr.splitlines()[1] == "Traceback (most recent call last):"
    assert f'my_controller.py", line {line}, in reset' in done.stderr


def test_the_library_and_the_lockstep_batch_name_the_same_culprit(tmp_path, fmu):
    scalar = load_scene(write_scene(tmp_path, python_controller("OneValue"),
                                    RAISES_IN_HELPER.replace("BATCH", "False")))
    with pytest.raises(ControllerError) as error:
        run(scalar, fmu)
    assert f"my_controller.py:{HELPER_LINE}, in gain" in str(error.value) and "KeyError" in error.value.details
    partial = run(scalar, fmu, keep_partial=True)
    assert partial.stopped.kind == "failed" and partial.stopped.reason == str(error.value)
    assert partial.stopped.details == error.value.details
    # the batch form (numpy in, numpy out) fails every case of the batch with the same words
    batch_dir = tmp_path / "batch"
    batch_dir.mkdir()
    batch = load_scene(write_scene(batch_dir, python_controller("OneValue"), RAISES_IN_HELPER.replace(
        "BATCH", "True").replace("return (self.gain(t) * 0.1, 0.0)", "return (self.gain(t) * 0.1 + 0 * m.alpha, 0 * m.alpha)")))
    outcomes = run_lockstep([batch, batch], fmu)
    for outcome in outcomes:
        assert isinstance(outcome, ControllerError), outcome
        assert str(outcome).startswith("strict: OneValue (")
        assert f"my_controller.py:{HELPER_LINE}, in gain)" in str(outcome) and "at t = 0.021 s" in str(outcome)


# -- strict, explicit outputs --------------------------------------------------------------------


@pytest.mark.parametrize("returned, shown", [
    ("(1.0, 2.0, 3.0)", "returned (1.0, 2.0, 3.0); it must return (u_R1, u_R2), two finite numbers"),
    ("('1.0', 2.0)", "returned ('1.0', 2.0); the voltages must be numbers"),
    ("(True, 0.0)", "returned (True, 0.0); the voltages must be numbers"),
    ("(None, 0.0)", "returned (None, 0.0); the voltages must be numbers"),
    ("None", "returned None; it must return (u_R1, u_R2)"),
    ("np.zeros(3)", "returned an array of shape (3,); it must return (u_R1, u_R2)"),
    ("(math.inf, 0.0)", "returned (inf, 0.0): the voltages must be finite"),
    ("[0.0, math.nan]", "returned (0.0, nan): the voltages must be finite"),
])
def test_outputs_that_are_not_two_finite_numbers_are_refused(tmp_path, fmu, returned, shown):
    code = (f"import math\nimport numpy as np\nclass Odd:\n    def reset(self, context):\n        pass\n"
            f"    def step(self, t, m):\n        return {returned} if t > 0.0105 else (0.0, 0.0)\n")
    scene = load_scene(write_scene(tmp_path, python_controller("Odd"), code))
    with pytest.raises(ControllerError) as error:
        run(scene, fmu)
    assert str(error.value).startswith("strict: Odd (") and f"step() at t = 0.011 s {shown}" in str(error.value)


@pytest.mark.parametrize("returned", ["(1.0, 2.0)", "[1, 2]", "np.array([1.0, 2.0])", "(np.float32(1.0), 2)"])
def test_two_real_numbers_in_any_sequence_are_taken(tmp_path, fmu, returned):
    code = (f"import numpy as np\nclass Fine:\n    def reset(self, context):\n        pass\n"
            f"    def step(self, t, m):\n        return {returned}\n")
    result = run(load_scene(write_scene(tmp_path, python_controller("Fine"), code)), fmu)
    assert result.signals["u_R1_cmd"][-1] == 1.0 and result.signals["u_R2_cmd"][-1] == 2.0


def test_the_clamp_is_recorded_and_counted(tmp_path, fmu_path, fmu):
    scene = write_scene(tmp_path, python_controller("Greedy"), GREEDY)
    limit = fmu.start("motor1.U_L")
    result = run(load_scene(scene), fmu)
    s = result.signals
    assert np.all(s["u_R1_asked"] == 1e6) and np.all(s["u_R1_cmd"] == limit)   # asked beside applied
    assert np.array_equal(s["u_R2_asked"], s["u_R2_cmd"])                      # within the limit
    steps = len(s["time"])
    assert f"voltage clamped on {steps:,} of {steps:,} steps (azimuth), max asked 1e+06 V" in result.summary()
    assert "(elevation)" not in result.summary()
    # the command line: the summary line and the CSV's and Parquet's columns
    out = tmp_path / "out"
    done = cli(scene.name, "--fmu", fmu_path, "--out", out, cwd=tmp_path)   # not --quiet: the summary line
    assert done.returncode == 0, done.stderr
    assert f"voltage clamped on {steps:,} of {steps:,} steps (azimuth), max asked 1e+06 V" in done.stdout
    table = pq.read_table(out / "strict.parquet")
    assert np.array_equal(table.column("u_R1_asked").to_numpy(), s["u_R1_asked"])
    assert np.array_equal(table.column("u_R1_cmd").to_numpy(), s["u_R1_cmd"])
    header = (out / "strict.csv").read_text().splitlines()[0]
    assert "u_R1_asked" in header and "u_R2_asked" in header


@pytest.mark.parametrize("controller", [
    'type = "pid"\n[controller.azimuth]\nkp = 1e5\nreference = { type = "step", from_deg = 0.0, to_deg = 10.0, at_s = 0.01 }\n'
    '[controller.elevation]\nkp = 10.0\nreference = { type = "constant", value_deg = 0.0 }',
    'type = "state_feedback"\nK = [[1e5, 0, 0, 0], [0, 10.0, 0, 0]]\n'
    'reference = { type = "step", from_deg = 0.0, to_deg = 10.0, at_s = 0.01 }',
])
def test_a_built_in_controllers_clamp_is_recorded_alike_by_both_loops(tmp_path, fmu, controller):
    scene = load_scene(write_scene(tmp_path, controller))
    compiled, python = run(scene, fmu, compiled=True), run(scene, fmu, compiled=False)
    assert compiled.loop == "compiled" and python.loop == "python"
    for name, values in compiled.signals.items():
        assert np.array_equal(values, python.signals[name], equal_nan=True), name
    s = compiled.signals
    clamped = s["u_R1_asked"] != s["u_R1_cmd"]
    limit = fmu.start("motor1.U_L")
    assert clamped.any() and np.all(np.abs(s["u_R1_cmd"][clamped]) == limit)
    assert np.all(np.abs(s["u_R1_asked"][clamped]) > limit)
    assert f"voltage clamped on {np.count_nonzero(clamped):,} of {len(clamped):,} steps (azimuth)" in \
        compiled.summary()
    assert compiled.voltage_clamp.summary() == python.voltage_clamp.summary()
