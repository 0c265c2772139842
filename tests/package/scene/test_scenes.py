"""Scenes (scenes/*.toml) and the scene runner (gimbal2axis run, gimbal2axis/)."""
import math
import pathlib

import numpy as np
import pytest

from gimbal2axis import FMU, SceneError, check_against_fmu, load_scene, run, run_scene_file
from gimbal2axis.scene import geometry
from gimbal2axis.scene.base_motion import INPUTS, make_base_motion

REPO = pathlib.Path(__file__).resolve().parents[3]

SCENES = sorted((REPO / "scenes").glob("*.toml"))
REQUIRED = {"free_swing", "pointing_step", "ship_stabilization", "backlash_limit_cycle", "stick_slip_slow_tracking"}


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


def write_scene(tmp_path, text: str, name: str = "scene.toml") -> pathlib.Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_required_scenes_exist():
    assert REQUIRED <= {p.stem for p in SCENES}


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_scene_loads_and_validates(path, fmu):
    scene = load_scene(path)
    assert scene.name == path.stem
    check_against_fmu(scene, fmu)


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_scene_runs_and_writes_csv_and_png(path, fmu_path, tmp_path):
    scene = load_scene(path)
    stop = float(scene.test.get("stop_time", min(scene.stop_time, 0.3)))
    result, csv_path, png_path = run_scene_file(path, fmu_path, tmp_path, stop_time=stop)
    header = csv_path.read_text().splitlines()[0].split(",")
    # the motor commands by each motor's drive: a voltage, or a current command to the FMU's amplifier
    current = {int(j) for j in ("1", "2") if int(scene.fidelity.get(f"motor{j}.drive", 0)) == 1}
    commands = [label for j in (1, 2) for label in (
        (f"i_R{j}_cmd [A]", f"i_R{j}_ctrl [A]", f"amplifier{j}.u [V]") if j in current else (f"u_R{j} [V]", f"u_R{j}_cmd [V]"))]
    for column in ("time [s]", "alpha [rad]", "beta [rad]", "i_R1 [A]", "i_R2 [A]", "theta_b1 [rad]",
                   "los.omega[1] [rad/s]", "base.gamma [rad]", "los_error [rad]", *commands):
        assert column in header
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1, ndmin=2)
    assert data[-1, 0] == pytest.approx(stop)
    assert np.all(np.isfinite(data[:, header.index("alpha [rad]")]))
    assert png_path.stat().st_size > 10_000 and png_path.read_bytes()[:4] == b"\x89PNG"
    # the line-of-sight bounds the scene states hold on the shortened run too (when it reaches their window)
    assert result.requirement_failures() == [], result.summary()
    assert "real time" in result.summary()


def test_unknown_fmu_variable_is_refused_with_a_clear_message(tmp_path, fmu):
    path = write_scene(tmp_path, 'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\n[parameters]\n"gear1.stiffness" = 1.0\n')
    with pytest.raises(SceneError, match=r"'gear1.stiffness' is not a variable of .*Gimbal2Axis.fmu"):
        check_against_fmu(load_scene(path), fmu)


def test_scene_errors_name_the_culprit(tmp_path, fmu):
    cases = {
        'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\nstep = 2\n': "unknown key",
        'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\n[controller]\ntype = "pid"\n[controller.azimuth]\nkpp = 1\n':
            "kpp",
        'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\n[base_motion]\ntype = "sinusoids"\nroll = {amplitude_deg = 1}\n':
            "period_s",
        'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\n[fidelity]\n"gear3.model" = 0\n': "gear3.model",
        'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\n[fidelity]\n"base.fixed" = true\n[base_motion]\n'
        'type = "sinusoids"\nroll = {amplitude_deg = 1, period_s = 5}\n': "base.fixed = true needs a fixed base",
    }
    for text, message in cases.items():
        with pytest.raises(SceneError, match=message):
            load_scene(write_scene(tmp_path, text))
    path = write_scene(tmp_path, 'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\n[parameters]\n"solver.max_steps" = 1.5\n')
    with pytest.raises(SceneError, match="Integer"):
        check_against_fmu(load_scene(path), fmu)
    # the states are the FMU's (its model description's outputs with initial="exact"), so checked against it
    path = write_scene(tmp_path, 'name = "x"\nstop_time = 0.01\nstep_size = 1e-3\n[initial]\nomega = 1.0\n')
    with pytest.raises(SceneError, match=r"\[initial\]: 'omega' is not a state \(states: \['alpha'"):
        check_against_fmu(load_scene(path), fmu)


DELAY_SCENE = """
name = "delay"
stop_time = 0.1
step_size = 1e-3
[parameters]
g = 0.0                  # nothing moves before the step
[controller]
type = "pid"
delay_steps = {delay}
[controller.azimuth]
kp = 50.0
ki = 100.0
k_gyro = 1.0
reference = {{ type = "step", from_deg = 0.0, to_deg = 1.0, at_s = 0.05 }}
[controller.elevation]
kp = 30.0
kd = 0.5
reference = {{ type = "step", to_deg = -0.5, at_s = 0.07 }}
"""


def test_one_sample_zero_order_hold_delay(tmp_path, fmu):
    scene = load_scene(write_scene(tmp_path, DELAY_SCENE.format(delay=1)))
    s = run(scene, fmu).signals
    # the voltage applied over [t_k, t_k+1] is the controller output computed from the sensors at t_k-1
    assert np.all(s["u_R1"][0] == 0.0) and s["u_R2"][0] == 0.0
    np.testing.assert_array_equal(s["u_R1"][1:], s["u_R1_cmd"][:-1])
    np.testing.assert_array_equal(s["u_R2"][1:], s["u_R2_cmd"][:-1])
    # ... and those outputs are what a fresh controller computes from the recorded sensors
    controller = scene.controller((24.0, 24.0))
    h = scene.step_size
    for k, t in enumerate(s["time"]):
        gyro = [s["los.omega[1]"][k], s["los.omega[2]"][k], s["los.omega[3]"][k]]
        u = controller(t, h, s["alpha"][k], s["beta"][k], gyro, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        assert u == (s["u_R1_cmd"][k], s["u_R2_cmd"][k])
    # the FMU really gets it one step late: the step command at t_50 drives current only after t_51
    k_step = 50
    assert s["u_R1_cmd"][k_step - 1] == 0.0 and s["u_R1_cmd"][k_step] > 0.0
    assert s["i_R1"][k_step + 1] == 0.0 and s["i_R1"][k_step + 2] > 0.0
    undelayed = run(load_scene(write_scene(tmp_path, DELAY_SCENE.format(delay=0))), fmu).signals
    np.testing.assert_array_equal(undelayed["u_R1"], undelayed["u_R1_cmd"])
    assert undelayed["i_R1"][k_step] == 0.0 and undelayed["i_R1"][k_step + 1] > 0.0


def test_line_of_sight_geometry():
    np.testing.assert_allclose(geometry.los_direction(0.0, 0.0, 0.0, 0.0, 0.0), [0.0, 1.0, 0.0], atol=1e-15)
    for psi in (0.3, -1.2, 2.5):   # a pure base yaw turns the line of sight about z_G
        np.testing.assert_allclose(geometry.los_direction(0.0, 0.0, 0.0, psi, 0.0),
                                   [-math.sin(psi), math.cos(psi), 0.0], atol=1e-15)
        # ... exactly like the azimuth angle does
        np.testing.assert_allclose(geometry.los_direction(psi, 0.0, 0.0, 0.0, 0.0),
                                   geometry.los_direction(0.0, 0.0, 0.0, psi, 0.0), atol=1e-15)
    # elevation lifts it towards z_G (up); a pure roll about y_0 leaves a level line of sight alone
    np.testing.assert_allclose(geometry.los_direction(0.0, 0.4, 0.0, 0.0, 0.0), [0.0, math.cos(0.4), math.sin(0.4)])
    np.testing.assert_allclose(geometry.los_direction(0.0, 0.0, 0.0, 0.0, 0.3), [0.0, 1.0, 0.0], atol=1e-15)
    # pitch (about x_G) raises it
    np.testing.assert_allclose(geometry.los_direction(0.0, 0.0, 0.2, 0.0, 0.0), [0.0, math.cos(0.2), math.sin(0.2)])
    rng = np.random.default_rng(3)
    for _ in range(50):
        alpha, beta, delta, psi, gamma = rng.uniform(-1.2, 1.2, 5)
        # the element-wise form equals GT0 Rz(alpha) Rx(beta) e_y with GT0 = Rx(delta) Rz(psi) Ry(gamma)
        matrix = geometry.base_to_inertial(delta, psi, gamma) @ geometry.rz(alpha) @ geometry.rx(beta) @ [0, 1, 0]
        np.testing.assert_allclose(geometry.los_direction(alpha, beta, delta, psi, gamma), matrix, atol=1e-15)
        # inverse kinematics points exactly at the target; the error angle is the angle between them
        az, el = rng.uniform(-3, 3), rng.uniform(-1.2, 1.2)
        a, b = geometry.gimbal_angles_for(tuple(geometry.target_direction(az, el)), delta, psi, gamma)
        assert geometry.los_error(a, b, delta, psi, gamma, az, el) < 1e-12
        assert geometry.los_error(a, b + 1e-4, delta, psi, gamma, az, el) == pytest.approx(1e-4, rel=1e-6)
    assert geometry.los_error(0.3, 0.1, 0.0, 0.0, 0.0, 0.3, 0.1) < 1e-15   # level base: alpha = az, beta = el


def _assert_derivative(t, q, q_dot, rtol):
    h = t[1] - t[0]
    fd = (q[2:] - q[:-2]) / (2 * h)
    scale = max(np.max(np.abs(q_dot)), 1e-12)
    np.testing.assert_allclose(fd, q_dot[1:-1], atol=rtol * scale)


@pytest.mark.parametrize("spec", [
    {"type": "sinusoids", "roll": {"amplitude_deg": 5.0, "period_s": 8.0, "phase_deg": 30.0},
     "pitch": [{"amplitude_deg": 2.0, "frequency_hz": 0.2}, {"amplitude_deg": 0.5, "period_s": 3.0}],
     "yaw": {"amplitude_deg": 1.0, "period_s": 11.0, "offset_deg": 20.0}, "heave": {"amplitude_m": 1.0, "period_s": 7.0},
     "velocity_m_s": [0.0, 5.0, 0.0]},
    {"type": "sea_state", "seed": 4, "components": 80,
     "roll": {"significant_amplitude_deg": 6.0, "peak_period_s": 9.0},
     "pitch": {"significant_amplitude_deg": 2.0, "peak_period_s": 7.0, "gamma": 1.0},
     "yaw": {"significant_amplitude_deg": 1.0, "peak_period_s": 12.0},
     "heave": {"significant_amplitude_m": 1.5, "peak_period_s": 8.0}},
], ids=["sinusoids", "sea_state"])
def test_analytic_base_motion_rates_are_the_derivatives_of_its_angles(spec, tmp_path):
    motion = make_base_motion(spec, tmp_path)
    t = np.arange(0.0, 30.0, 1e-3)
    x = motion.sample(t)
    for i in range(3):   # angle -> rate -> acceleration
        _assert_derivative(t, x[:, i], x[:, 3 + i], 1e-6)
        _assert_derivative(t, x[:, 3 + i], x[:, 6 + i], 1e-5)
    position = motion.position(t)
    for i in range(3):   # position of point a -> v_a -> a_a
        _assert_derivative(t, position[:, i], x[:, 9 + i], 1e-6)
        _assert_derivative(t, x[:, 9 + i], x[:, 12 + i], 1e-5)
    assert np.any(x[:, 2] != 0) and np.any(x[:, 11] != 0)


def test_sea_state_has_the_stated_significant_amplitude_and_is_reproducible(tmp_path):
    spec = {"type": "sea_state", "seed": 11, "components": 200,
            "roll": {"significant_amplitude_deg": 4.0, "peak_period_s": 8.0}}
    t = np.arange(0.0, 3000.0, 0.1)
    roll = make_base_motion(spec, tmp_path).sample(t)[:, 2]
    assert 2 * np.degrees(np.std(roll)) == pytest.approx(4.0, rel=0.05)
    np.testing.assert_array_equal(roll[:100], make_base_motion(spec, tmp_path).sample(t[:100])[:, 2])
    other = make_base_motion(dict(spec, seed=12), tmp_path).sample(t[:100])[:, 2]
    assert not np.allclose(roll[:100], other)


def test_recorded_base_motion_interpolates_consistently(tmp_path):
    t = np.arange(0.0, 10.0, 0.02)
    roll, z = 0.05 * np.sin(0.8 * t), 0.7 * np.sin(0.6 * t)
    np.savetxt(tmp_path / "motion.csv", np.column_stack([t, roll, z]), delimiter=",", header="time,gamma,z", comments="")
    motion = make_base_motion({"type": "recorded", "file": "motion.csv"}, tmp_path)
    tt = np.arange(0.5, 9.5, 1e-3)
    x = motion.sample(tt)
    np.testing.assert_allclose(x[:, 2], 0.05 * np.sin(0.8 * tt), atol=1e-7)
    np.testing.assert_allclose(x[:, 5], 0.04 * np.cos(0.8 * tt), atol=1e-6)
    np.testing.assert_allclose(x[:, 11], 0.42 * np.cos(0.6 * tt), atol=1e-5)
    _assert_derivative(tt, x[:, 5], x[:, 8], 1e-4)


def test_stabilization_loop_reduces_the_line_of_sight_error(fmu):
    scene = load_scene(REPO / "scenes" / "ship_stabilization.toml")
    on = run(scene, fmu, stop_time=4.0).los_metrics(from_s=1.0)
    off_scene = scene.with_changes(controller_spec={"type": "none"})
    off = run(off_scene, fmu, stop_time=4.0).los_metrics(from_s=1.0)
    assert on["rms"] < 1e-3                       # well under a milliradian
    assert on["rms"] < off["rms"] / 20, (on, off)  # the open gimbal drifts with the ship


def test_surge_runs_along_the_bow_the_axis_the_ship_rolls_about():
    # roll is gamma, a turn about y_0: the bow points along y, so surge moves point a along y_G and
    # sway along x_G (the FMU's base.v_a[1..3] are the x, y, z components in G)
    wave = {"amplitude_m": 0.5, "period_s": 4.0}
    t = np.arange(101) * 0.01
    surge = make_base_motion({"type": "sinusoids", "surge": wave}, REPO).sample(t)
    sway = make_base_motion({"type": "sinusoids", "sway": wave}, REPO).sample(t)
    velocity = [INPUTS.index(f"base.v_a[{j}]") for j in (1, 2, 3)]
    assert np.all(surge[:, velocity[0]] == 0.0) and np.ptp(surge[:, velocity[1]]) > 0.1
    assert np.all(sway[:, velocity[1]] == 0.0) and np.ptp(sway[:, velocity[0]]) > 0.1
    roll = make_base_motion({"type": "sinusoids", "roll": {"amplitude_deg": 5.0, "period_s": 8.0}}, REPO).sample(t)
    assert np.ptp(roll[:, INPUTS.index("base.gamma")]) > 0.01   # roll drives gamma, the turn about y_0
