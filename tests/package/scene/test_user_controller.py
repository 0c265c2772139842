"""A controller of the user's own in a scene: `[controller] type = "python"` with module, class and
options. The plumbing is checked by re-implementing the built-in PID as a user class: the run must
equal the built-in one bit for bit (same measurements, delay, saturation and records)."""
import pathlib

import numpy as np
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run

REPO = pathlib.Path(__file__).resolve().parents[3]

EXAMPLE = REPO / "examples" / "user_controller.toml"

PID_AS_USER_CLASS = '''
from gimbal2axis.scene.controllers import PID

class PIDAsUser:
    """The built-in PID behind the user interface."""
    def __init__(self, **spec):
        self.spec = spec
        self.resets = 0

    def reset(self, context):
        self.resets += 1
        self.h = context.step_size
        self.pid = PID(self.spec, context.target, context.u_limit)

    def step(self, t, m):
        u = self.pid(t, self.h, m.alpha, m.beta, m.gyro, m.base_attitude, m.base_rates)
        self.reference = self.pid.reference
        return u
'''


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


def scene_with_controller(tmp_path, controller_table: str, module_text: str | None = None, stop_time=0.5):
    """The example scene with another [controller] table (and a module next to it)."""
    text = EXAMPLE.read_text()
    head, tail = text.split("[controller]", 1)
    tail = tail[tail.index("[requirements]"):]
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(head + controller_table + "\n" + tail)
    if module_text is not None:
        (tmp_path / "user_module.py").write_text(module_text)
    return load_scene(scene_file).with_changes(stop_time=stop_time)


def test_the_example_controller_stabilizes_the_line_of_sight(fmu):
    scene = load_scene(EXAMPLE)
    result = run(scene.with_changes(stop_time=scene.test.get("stop_time", 3.0)), fmu)
    assert result.requirement_failures() == []
    assert result.los_metrics()["rms"] * 1e3 < scene.requirements["los_rms_max_mrad"]
    limit = [fmu.start("motor1.U_L"), fmu.start("motor2.U_L")]
    for axis, name in enumerate(("u_R1", "u_R2")):
        assert np.all(np.abs(result.signals[name]) <= limit[axis])
    assert np.all(np.isfinite(result.signals["alpha_ref"][1:]))


def pid_tables(reference: str) -> tuple[str, str]:
    """The scene's PID as a built-in table and as the user class's options."""
    built_in = f"""[controller]
type = "pid"
delay_steps = 1
reference = {reference}
[controller.azimuth]
kp = 400.0
ki = 8000.0
k_gyro = 8.0
k_ff = 4.8
[controller.elevation]
kp = 400.0
ki = 8000.0
k_gyro = 8.0
k_ff = 2.4
"""
    user = f"""[controller]
type = "python"
delay_steps = 1
module = "user_module.py"
class = "PIDAsUser"
options = {{ reference = {reference}, azimuth = {{ kp = 400.0, ki = 8000.0, k_gyro = 8.0, k_ff = 4.8 }}, elevation = {{ kp = 400.0, ki = 8000.0, k_gyro = 8.0, k_ff = 2.4 }} }}
"""
    return built_in, user


STEP_REFERENCE = '{ type = "step", from_deg = 30.0, to_deg = 31.0, at_s = 0.1 }'


def test_a_user_class_gives_the_built_in_controllers_run_bit_for_bit(tmp_path, fmu):
    # Step references: the user class computes them as the built-in one does, so every signal of
    # the two runs (measurements, delay, saturation, records) must agree to the bit.
    pid_table, user_table = pid_tables(STEP_REFERENCE)
    built_in = run(scene_with_controller(tmp_path, pid_table), fmu)
    user_scene = scene_with_controller(tmp_path, user_table, PID_AS_USER_CLASS)
    controller = user_scene.controller((fmu.start("motor1.U_L"), fmu.start("motor2.U_L")))
    user = run(user_scene, fmu, controller=controller)
    assert built_in.loop == "compiled" and user.loop == "python"
    for name, values in built_in.signals.items():
        # what was asked: the built-in PID's output before its clamp; the user class returns the PID's
        # clamped output, which is what it asks of the runner
        expected = built_in.signals[name.replace("_asked", "_cmd")] if name.endswith("_asked") else values
        assert np.array_equal(expected, user.signals[name], equal_nan=True), name
    # reset() before every run: a second run with the same controller object starts afresh.
    again = run(user_scene, fmu, controller=controller)
    assert controller.user.resets == 2
    assert np.array_equal(again.signals["beta"], user.signals["beta"])


def test_a_user_class_tracking_the_target_gets_the_measured_base_attitude(tmp_path, fmu):
    # reference "target": the set points come from the measured base attitude the user's step()
    # receives. The built-in PID evaluates them vectorised for the whole run, the user class step by
    # step with scalar functions: the set points agree to an ulp; their rates (the feed-forward),
    # differences over 1e-6 s of attitude, to the rounding of that difference (~1e-10 rad/s), which
    # the loop passes on to voltages, currents and rates at that level.
    pid_table, user_table = pid_tables('"target"')
    built_in = run(scene_with_controller(tmp_path, pid_table), fmu)
    user = run(scene_with_controller(tmp_path, user_table, PID_AS_USER_CLASS), fmu)
    for name, atol in (("alpha_ref", 1e-15), ("beta_ref", 1e-15), ("alpha", 1e-11), ("beta", 1e-11),
                       ("alpha_dot", 1e-8), ("beta_dot", 1e-8), ("i_R1", 1e-8), ("i_R2", 1e-8), ("u_R1", 1e-7),
                       ("u_R2", 1e-7)):
        np.testing.assert_allclose(user.signals[name], built_in.signals[name], rtol=0, atol=atol, err_msg=name)
    # without the base attitude the user's set points would be off by the ship's motion
    assert np.ptp(built_in.signals["alpha_ref"]) > 1e-3


@pytest.mark.parametrize("table, module, message", [
    ('type = "python"\nmodule = "missing.py"\nclass = "X"', None, "controller file"),
    ('type = "python"\nmodule = "user_module.py"\nclass = "Absent"', "class Other: pass\n",
     "has no class 'Absent' (classes defined there: Other)"),
    ('type = "python"\nmodule = "user_module.py"\nclass = "NoStep"',
     "class NoStep:\n    def reset(self, context): pass\n", "has no method step()"),
    ('type = "python"\nmodule = "user_module.py"\nclass = "C"\noptions = { gain = 1.0 }',
     "class C:\n    def __init__(self): pass\n    def reset(self, context): pass\n    def step(self, t, m): pass\n",
     "the options (gain) do not fit its __init__"),
    ('type = "python"\nmodule = "user_module.py"\nclass = "C"', "import not_a_module_anywhere\n",
     "user_module.py: loading raised ModuleNotFoundError: No module named 'not_a_module_anywhere' ("),
    ('type = "python"\nclass = "C"', None, "needs file = '<controller file>.py'"),
])
def test_a_broken_user_controller_is_refused_with_a_message(tmp_path, fmu, table, module, message):
    with pytest.raises(SceneError) as error:
        scene_with_controller(tmp_path, "[controller]\n" + table, module)
    assert message in str(error.value)


@pytest.mark.parametrize("returned, message", [
    ("(math.nan, 0.0)", "must be finite"),
    ("1.0", "must return (u_R1, u_R2)"),
])
def test_a_user_controller_returning_nonsense_stops_the_run_naming_it(tmp_path, fmu, returned, message):
    module = f"import math\nclass Bad:\n    def reset(self, context): pass\n    def step(self, t, m): return {returned}\n"
    scene = scene_with_controller(tmp_path, '[controller]\ntype = "python"\nmodule = "user_module.py"\nclass = "Bad"',
                                  module)
    with pytest.raises(SceneError) as error:
        run(scene, fmu)
    assert "Bad (" in str(error.value) and "step() at t = 0 s returned" in str(error.value)
    assert message in str(error.value)
