"""The compiled communication loop (c_kernel/src/master_loop.c) against the Python loop
(master.step_loop): for every built-in controller, sensor model and delay, the two runs must agree
to the bit in every recorded signal; and a failing FMU call must stop both with the same message.

Both loops call the kernel's controllers and sensors (the Python one through ctypes), so what this
compares is the loops themselves: the records, the set point rows, the delay and zero-order hold, the
state carried from step to step, the failure handling. The controllers' and sensors' equations are
checked against independent references in tests/c_kernel/test_kernel.py."""
import pathlib

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.master import compiled_loop
from gimbal2axis.scene.drives import command_columns

SCENES = REPO / "scenes"
NOISY_SENSORS = {"encoder_resolution_deg": 0.001, "gyro_noise_deg_s": 0.02, "imu_attitude_noise_deg": 0.01, "seed": 3}
SINE = {"type": "sine", "offset_deg": 2.0, "amplitude_deg": 3.0, "frequency_hz": 2.0}
DATASHEET_GYRO = {"angle_random_walk_deg_rt_h": 0.5, "bias_instability_deg_h": 20.0, "bias_correlation_time_s": 50.0,
                  "rate_random_walk_deg_h_rt_h": 30.0, "bias_deg_h": [10.0, -5.0, 3.0], "scale_factor_error_ppm": 800.0,
                  "misalignment_mrad": [1.0, -0.5, 0.3, 2.0, -1.0, 0.5], "bandwidth_hz": 150.0, "damping": 0.6,
                  "quantization_deg_s": 0.002, "delay_samples": 2}
EVERY_SENSOR_TERM = {**NOISY_SENSORS, "encoder_offset_deg": [0.01, -0.02], "gyro": DATASHEET_GYRO}
PID_WITH_EVERY_TERM = {
    "type": "pid", "delay_steps": 2,
    "azimuth": {"kp": 300.0, "ki": 3000.0, "kd": 2.0, "d_filter_s": 0.002, "i_limit_V": 3.0, "k_gyro": 4.0,
                "k_ff": 4.8, "reference": SINE},
    "elevation": {"kp": 300.0, "ki": 3000.0, "kd": 1.0, "k_gyro": 4.0, "reference": {"type": "ramp",
                  "start_deg": 0.0, "rate_deg_s": 20.0, "start_s": 0.05}},
}


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


def variant(name: str):
    """(scene, stop time) of the variants below."""
    if name.endswith(".toml"):
        scene = load_scene(SCENES / name)
        return scene, min(scene.stop_time, 1.0)
    ship = load_scene(SCENES / "ship_stabilization.toml")
    pointing = load_scene(SCENES / "pointing_step.toml")
    if name == "ship_with_noisy_sensors":
        return ship.with_changes(sensors_spec=NOISY_SENSORS), 1.0
    if name == "ship_with_every_sensor_term":
        return ship.with_changes(sensors_spec=EVERY_SENSOR_TERM), 1.0
    if name == "ship_indirect_with_every_sensor_term_and_encoder_differences":
        return ship.with_changes(sensors_spec={**EVERY_SENSOR_TERM, "stabilization": "indirect",
                                               "joint_rate": "encoder_difference"}), 1.0
    if name == "ship_indirect_with_a_tachometer":
        return ship.with_changes(sensors_spec={**EVERY_SENSOR_TERM, "stabilization": "indirect"}), 1.0
    if name == "ship_undelayed":
        return ship.with_changes(controller_spec={**ship.controller_spec, "delay_steps": 0}), 0.5
    if name == "state_feedback_encoder_rates_on_the_ship":
        spec = {**pointing.controller_spec, "rate_source": "encoder", "reference": "target"}
        spec.pop("azimuth"), spec.pop("elevation")
        return ship.with_changes(controller_spec=spec, sensors_spec=NOISY_SENSORS), 1.0
    if name == "pid_with_every_term_saturating":
        return pointing.with_changes(controller_spec=PID_WITH_EVERY_TERM,
                                     parameters={**pointing.parameters, "motor1.U_L": 6.0}), 0.6
    if name == "constant_voltages":
        return pointing.with_changes(controller_spec={"type": "none", "voltage_V": [1.5, -0.7]}), 0.3
    raise KeyError(name)


VARIANTS = sorted(p.name for p in SCENES.glob("*.toml")) + [
    "ship_with_noisy_sensors", "ship_with_every_sensor_term",
    "ship_indirect_with_every_sensor_term_and_encoder_differences", "ship_indirect_with_a_tachometer", "ship_undelayed", "state_feedback_encoder_rates_on_the_ship",
    "pid_with_every_term_saturating", "constant_voltages"]


def test_the_compiled_loop_is_built():
    # the package's install builds it (pyproject.toml); without it every scene silently runs the slower loop
    assert compiled_loop.available() is None


@pytest.mark.parametrize("name", VARIANTS)
def test_the_compiled_loop_gives_the_python_loops_bits(name, fmu):
    scene, stop_time = variant(name)
    python = run(scene, fmu, stop_time=stop_time, compiled=False)
    compiled = run(scene, fmu, stop_time=stop_time, compiled=True)
    assert (python.loop, compiled.loop) == ("python", "compiled")
    assert python.signals.keys() == compiled.signals.keys()
    for signal, values in python.signals.items():
        assert np.array_equal(values, compiled.signals[signal], equal_nan=True), signal
    if scene.controller_spec.get("type", "none") != "none":   # a loop that was closed
        # the commands of either drive (a voltage u_R<j>, a current command i_R<j>_cmd: scene/drives.py)
        for motor in (1, 2):
            assert np.ptp(python.signals[command_columns(python.signals, motor).applied]) > 0


def test_the_default_is_the_compiled_loop_for_built_in_controllers(fmu):
    scene, _ = variant("ship_stabilization.toml")
    assert run(scene, fmu, stop_time=0.01).loop == "compiled"


def test_a_failing_step_stops_both_loops_with_the_same_message(fmu):
    # one internal step per communication step cannot follow the ship: the FMU discards a step
    scene, _ = variant("ship_stabilization.toml")
    scene = scene.with_changes(parameters={**scene.parameters, "solver.max_steps": 1})
    messages = []
    for compiled in (False, True):
        with pytest.raises(SceneError) as failure:
            run(scene, fmu, stop_time=0.5, compiled=compiled)
        messages.append(str(failure.value))
    assert messages[0] == messages[1]
    assert "the FMU failed at t = " in messages[0] and "fmi2DoStep" in messages[0]
