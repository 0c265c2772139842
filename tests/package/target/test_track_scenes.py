"""Runs with a moving target (gimbal2axis/target, scenes/track_*.toml), short: the inverse kinematics
at every sample of a run on a moving carrier (forward kinematics of the commanded angles points at
the target to 1e-12 rad), the built-in controllers' set points following it in both loops with the
same bits, the tracking metrics, files and plots, and the scene's refusals of what cannot be right."""
import math
import pathlib

import numpy as np
import pytest

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.master import run_scene_file
from gimbal2axis.scene import geometry
from gimbal2axis.scene.controller_fmu import controller_fmu_parameters

REPO = pathlib.Path(__file__).resolve().parents[3]
SCENES = REPO / "scenes"


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


def near_keyhole_flyby():
    """The keyhole scene with its closest approach 0.6 s in, on its rolling ship."""
    scene = load_scene(SCENES / "track_flyby_keyhole.toml")
    return scene.with_changes(target_spec={**scene.target_spec, "closest_approach_s": 0.6})


@pytest.mark.parametrize("name", ["track_coastal_point", "track_recorded_boat", "flyby_near_the_keyhole"])
def test_forward_kinematics_of_the_command_points_at_the_target_at_every_sample(name, fmu):
    scene = near_keyhole_flyby() if name.startswith("flyby") else load_scene(SCENES / f"{name}.toml")
    result = run(scene, fmu, stop_time=1.0)
    s = result.signals
    attitude = [s[f"base.{n}"] for n in ("delta", "psi", "gamma")]
    assert np.ptp(attitude[2]) > 0   # the carrier rolls
    los = geometry.los_direction(result.signal("alpha_cmd"), result.signal("beta_cmd"), *attitude)
    target = scene.moving_target.direction(s["time"])
    assert np.max(geometry.angle_between(los, target)) < 1e-12
    # the built-in controller's set points are that command (the IMU here measures the attitude exactly)
    assert np.max(np.abs(s["alpha_ref"] - result.signal("alpha_cmd"))) < 1e-12
    assert np.max(np.abs(s["beta_ref"] - result.signal("beta_cmd"))) < 1e-12
    # and the line-of-sight error is the angle to the target where it is at each sample
    assert np.array_equal(s["los_error"], geometry.angle_between(
        geometry.los_direction(s["alpha"], s["beta"], *attitude), target))
    # the command's rates are the derivatives of its angles along the run (differences over 2 steps)
    h = scene.step_size
    for angle in ("alpha_cmd", "beta_cmd"):
        values, rates = result.signal(angle), result.signal(f"{angle}_dot")
        assert np.allclose((values[2:] - values[:-2]) / (2 * h), rates[1:-1], rtol=1e-3, atol=1e-6)


def test_both_loops_give_the_same_bits_with_a_moving_target(fmu):
    scene = near_keyhole_flyby()
    python = run(scene, fmu, stop_time=0.3, compiled=False)
    compiled = run(scene, fmu, stop_time=0.3, compiled=True)
    for signal, values in python.signals.items():
        assert np.array_equal(values, compiled.signals[signal], equal_nan=True), signal


def test_the_keyhole_is_counted_and_its_rates_reported(fmu_path, tmp_path):
    scene_path = tmp_path / "keyhole.toml"
    text = (SCENES / "track_flyby_keyhole.toml").read_text()
    scene_path.write_text(text.replace("closest_approach_s = 15.0", "closest_approach_s = 1.0"))
    result, csv_path, _ = run_scene_file(scene_path, fmu_path, tmp_path, stop_time=2.0, stream=True)
    metrics = result.tracking_metrics().as_dict()
    # 10 m beside, 300 m below the aircraft: the command asks v / d = 12 rad/s and more (the roll), the
    # azimuth drive reaches a fraction of it and the line of sight leaves the 5 mrad beam
    assert metrics["keyhole_asked_rate_max"] > 12.0
    assert metrics["keyhole_achieved_rate_max"] < 0.5 * metrics["keyhole_asked_rate_max"]
    assert 0.0 < metrics["time_lost_near_keyhole_s"] <= metrics["time_near_keyhole_s"]
    assert metrics["keyhole_current_max"] > 0.0
    assert metrics["keyhole_asked_voltage_max"] > 24.0   # beyond the motor's 24 V: clamped
    assert "near the keyhole" in result.summary() and "off target" in result.summary()
    header = csv_path.read_text().splitlines()[0].split(",")
    for column in ("alpha_cmd [rad]", "alpha_cmd_dot [rad/s]", "alpha_cmd_ddot [rad/s2]", "target_range [m]",
                   "target_elevation [rad]"):
        assert column in header
    tracking_png = tmp_path / "keyhole_tracking.png"
    assert tracking_png.read_bytes()[:4] == b"\x89PNG" and tracking_png.stat().st_size > 20_000
    # the record held in memory gives the same figures as the streamed one
    in_memory, _, _ = run_scene_file(scene_path, fmu_path, tmp_path / "memory", stop_time=2.0)
    assert in_memory.tracking_metrics().as_dict() == pytest.approx(metrics)


def test_a_fixed_direction_stays_the_default(tmp_path):
    ship = load_scene(SCENES / "ship_stabilization.toml")
    assert ship.target_spec == {"azimuth_deg": 30.0, "elevation_deg": 5.0, "start_on_target": True}
    assert ship.moving_target is None and len(ship.target) == 3
    path = tmp_path / "direction.toml"
    path.write_text('stop_time = 0.01\nstep_size = 1e-3\n[base_motion]\ntype = "fixed"\n[fidelity]\n'
                    '"base.fixed" = true\n[controller]\ntype = "none"\n[target]\ntype = "direction"\nazimuth_deg = 30.0\n'
                    'elevation_deg = 5.0\nstart_on_target = true\n')
    assert load_scene(path).target_spec == ship.target_spec


def write(tmp_path, target: str, extra: str = "", name: str = "scene.toml") -> pathlib.Path:
    path = tmp_path / name
    path.write_text(f'stop_time = 1.0\nstep_size = 1e-3\n[base_motion]\ntype = "fixed"\n[fidelity]\n'
                    f'"base.fixed" = true\n[target]\n{target}\n{extra}')
    return path


TRACK_HEADER = "time,latitude_deg,longitude_deg,altitude_m\n"
GOOD_ROWS = "".join(f"{t:.1f},59.9,10.6,5.0\n" for t in (-1.0, 0.0, 0.5, 1.0, 2.0))
CARRIER = "[target.carrier]\nlatitude_deg = 59.8\nlongitude_deg = 10.5\n"


@pytest.mark.parametrize("target, extra, track, message", [
    ('type = "earth_pint"', "", None, r"target.type must be one of .*did you mean 'earth_point'"),
    ('type = "flyby"\naltitude_m = 300.0\nspeed_m_s = 100.0\nheading_deg = 0.0\nclosest_approach_m = 10.0\n'
     'closest_aproach_s = 1.0', "", None, r"unknown key\(s\) \['closest_aproach_s'\].*did you mean 'closest_approach_s'"),
    ('type = "flyby"\naltitude_m = 300.0\nspeed_m_s = 100.0\nheading_deg = 0.0\nclosest_approach_m = 10.0', "", None,
     "needs closest_approach_s"),
    ('type = "earth_point"\nlatitude_deg = 59.9\nlongitude_deg = 10.6', "", None, "needs the carrier's position"),
    ('type = "earth_point"\nlatitude_deg = 59.9\nlongitude_deg = 10.6\nnorth_m = 5.0', CARRIER, None, "not both"),
    ('type = "earth_point"\nlatitude_deg = 99.0\nlongitude_deg = 10.6', CARRIER, None, r"outside \[-90, 90\]"),
    ('type = "earth_point"\nnorth_m = 1000.0\nbeam_width_mrad = -1.0', CARRIER, None, "beam_width_mrad must be positive"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, TRACK_HEADER + GOOD_ROWS.replace("0.5,59.9", "0.5,59,9"), 
     r"line 4 \(data row 3\) has 5 cells, the header 4"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, TRACK_HEADER + GOOD_ROWS.replace("0.5,59.9", "0.5,N59.9"),
     r"line 4 \(data row 3\), column 'latitude_deg' is not a number: 'N59.9'"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, TRACK_HEADER + GOOD_ROWS.replace("1.0,59.9", "0.2,59.9"),
     r"'time' must increase strictly, but line 5 has 0.2 after 0.5"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, TRACK_HEADER + GOOD_ROWS.replace("2.0,59.9", "1.02,59.9"),
     r"covers \[-1, 1.02\] s, not \[-0.05, 1.05\] s"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, "t,lat,lon\n1,2,3\n", "not a recorded track: .* no 'time' column"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, "time;latitude_deg\n", "semicolons"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, "time,x_m\n0,1\n1,1\n2,1\n3,1\n",
     "a track needs time and either latitude_deg"),
    ('type = "track"\nfile = "boat.csv"', CARRIER, "time,x_m\n0,1\n", "1 data rows; a cubic spline needs at least 4"),
])
def test_what_cannot_be_right_is_refused_naming_the_key_or_the_line(tmp_path, target, extra, track, message):
    if track is not None:
        (tmp_path / "boat.csv").write_text(track)
    with pytest.raises(SceneError, match=message):
        load_scene(write(tmp_path, target, extra))


def test_a_good_track_loads_and_the_controller_fmu_points_at_it_through_its_target_inputs(tmp_path):
    (tmp_path / "boat.csv").write_text("# a comment line\n" + TRACK_HEADER + GOOD_ROWS)
    scene = load_scene(write(tmp_path, 'type = "track"\nfile = "boat.csv"',
                             CARRIER + '[controller]\ntype = "pid"\nreference = "target"\n'
                             '[controller.azimuth]\nkp = 1.0\n[controller.elevation]\nkp = 1.0\n'))
    assert scene.moving_target.kind == "track" and scene.target is None
    values = controller_fmu_parameters(scene, (10.0, 10.0))
    # the target's position comes in through the inputs (tests/package/system/test_system_target.py), not as a direction
    assert values["target.moving"] is True and "target.azimuth" not in values


def test_a_local_north_east_down_point_is_where_it_says(tmp_path):
    # 1 km north, 100 m up (down_m = -100) from the carrier's start, the carrier still on course 0:
    # 5.71 deg up (less the Earth's curvature: 1000^2 / (2 R) = 0.08 m, 0.08 mrad) straight ahead
    scene = load_scene(write(tmp_path, 'type = "earth_point"\nnorth_m = 1000.0\ndown_m = -100.0',
                             CARRIER + '[controller]\ntype = "none"\n'))
    u = scene.moving_target.direction([0.0])[:, 0]
    assert math.atan2(-u[0], u[1]) == pytest.approx(0.0, abs=1e-9)
    assert math.atan2(u[2], math.hypot(u[0], u[1])) == pytest.approx(math.atan2(100.0, 1000.0), abs=1e-9)


def test_the_pid_feeds_the_command_forward_toward_a_moving_target():
    """The kernel's PID toward a moving target, by hand: u = kp e - k_gyro (w - w_on_track) + k_ff r' +
    k_acc r'', w the gyro's rate about the axis (the cross-elevation rate over cos(beta) for the
    azimuth), w_on_track the line of sight's rate on track; a fixed target's set points carry none."""
    from gimbal2axis.scene.controllers import PID

    scene = near_keyhole_flyby()
    gains = {"kp": 300.0, "k_gyro": 7.0, "k_ff": 4.8, "k_acc": 0.18}
    spec = {"type": "pid", "reference": "target", "azimuth": gains, "elevation": {**gains, "k_ff": 2.4, "k_acc": 0.16}}
    controller = PID(spec, scene.moving_target, (1e9, 1e9))
    times = np.arange(3) * 0.2
    attitude, rates = np.array([[0.01, 0.02, -0.03]] * 3), np.array([[0.001, -0.002, 0.003]] * 3)
    accelerations = np.array([[0.0005, 0.0, -0.001]] * 3)
    controller.prepare(times, 0.2, attitude, rates, accelerations)
    points = controller.set_points
    assert points.accelerations.shape == points.gyro_rates.shape == (3, 2)
    k, alpha, beta, gyro = 2, 0.3, 0.9, (0.01, -0.02, 0.05)
    u = controller(0.4, 0.2, alpha, beta, gyro, attitude[k], rates[k], step=k)
    alpha_ref = points.values[k, 0] + 2 * math.pi * round((alpha - points.values[k, 0]) / (2 * math.pi))
    on_track = points.gyro_rates[k]
    expected = (300.0 * (alpha_ref - alpha) - 7.0 * ((gyro[2] - on_track[1]) / max(math.cos(beta), 0.2))
                + 4.8 * points.rates[k, 0] + 0.18 * points.accelerations[k, 0],
                300.0 * (points.values[k, 1] - beta) - 7.0 * (gyro[0] - on_track[0]) + 2.4 * points.rates[k, 1]
                + 0.16 * points.accelerations[k, 1])
    assert u == pytest.approx(expected, rel=1e-12)
    assert np.all(points.gyro_rates != 0) and np.all(points.accelerations != 0)
    fixed = PID(spec, load_scene(SCENES / "ship_stabilization.toml").target, (1e9, 1e9))
    fixed.prepare(times, 0.2, attitude, rates, accelerations)
    assert fixed.set_points.accelerations is None and not fixed.state.set_points.gyro_rates


def test_a_negative_acceleration_gain_is_refused(tmp_path):
    text = (SCENES / "track_flyby_keyhole.toml").read_text().replace("k_acc = 0.18", "k_acc = -0.18")
    path = tmp_path / "negative.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match="controller.azimuth.k_acc = -0.18 is negative"):
        load_scene(path)


def test_a_run_longer_than_the_recorded_track_is_refused_before_it_starts(fmu):
    scene = load_scene(SCENES / "track_recorded_boat.toml")
    with pytest.raises(SceneError, match=r"covers \[-2, 94\] s, not \[-0.05, 100.05\] s"):
        run(scene, fmu, stop_time=100.0)


def test_the_controller_outside_a_run_points_at_the_target_where_it_is(fmu):
    # called without a prepared run (a notebook, a user's own loop): the set points come from the
    # target at that time, as the prepared ones do
    scene = near_keyhole_flyby()
    controller = scene.controller((24.0, 24.0))
    controller(0.6, 1e-3, 0.0, 1.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    command = scene.moving_target.kinematics([0.6])[0][:, 0]
    assert controller.reference[1] == pytest.approx(math.atan2(command[2], math.hypot(command[0], command[1])),
                                                    abs=1e-12)
