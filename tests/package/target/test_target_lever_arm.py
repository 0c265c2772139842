"""The moving target seen from where the gimbal really is (issue 45, items 1 and 2): the carrier's
heave and the lever arm d_ab turned by its attitude move the gimbal from where [target.carrier]
places it, for the truth (target_azimuth, target_elevation, target_range, los_error) and for the
controller's command; the INS position error of [target] ins_position_error_m moves the command
only. Checked against an independent WGS 84 calculation through ECEF (pymap3d). And the keyhole
policy: an aircraft passing exactly overhead (the target on the azimuth axis) holds the azimuth
command, so the run ends with finite commands and the azimuth turning at what its drive can do."""
import math
import pathlib
import warnings

import numpy as np
import pymap3d
import pytest
from pymap3d.lox import loxodrome_direct

from gimbal2axis import FMU, SceneError, load_scene, run
from gimbal2axis.target import PointingCommand, pointing
from gimbal2axis.target.spec import DEFAULT_LEVER_ARM_M, LEVER_ARM_PARAMETERS, parse

SCENES = pathlib.Path(__file__).resolve().parents[3] / "scenes"
LEVER_ARM = (0.7, -1.5, 6.0)          # m, frame 0: a mast 6 m up, off the ship's reference point
HEAVE_M, HEAVE_PERIOD_S = 1.3, 2.0


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with FMU(fmu_path) as loaded:
        yield loaded


def heaving_coastal_scene(**target_changes):
    """track_coastal_point with a 1.3 m heave of 2 s (a quarter period in, the heave from the start is
    the full 1.3 m), a roll and a pitch, and the lever arm LEVER_ARM."""
    scene = load_scene(SCENES / "track_coastal_point.toml")
    motion = {"type": "sinusoids", "velocity_m_s": [0.0, 8.0, 0.0],
              "heave": {"amplitude_m": HEAVE_M, "period_s": HEAVE_PERIOD_S},
              "roll": {"amplitude_deg": 5.0, "period_s": 3.0, "phase_deg": 40.0},
              "pitch": {"amplitude_deg": 2.0, "period_s": 2.5},
              "yaw": {"amplitude_deg": 1.0, "period_s": 4.0}}
    parameters = {**scene.parameters, **dict(zip(LEVER_ARM_PARAMETERS, LEVER_ARM))}
    return scene.with_changes(base_motion_spec=motion, parameters=parameters,
                              target_spec={**scene.target_spec, **target_changes})


def rotation_gt0(delta, psi, gamma):
    """GT0 = Rx(delta) Rz(psi) Ry(gamma) (docs/physics.md (2.11)) as a matrix, for one sample."""
    cd, sd, cp, sp, cg, sg = (f(a) for a in (delta, psi, gamma) for f in (math.cos, math.sin))
    rx = np.array([[1, 0, 0], [0, cd, -sd], [0, sd, cd]])
    rz = np.array([[cp, -sp, 0], [sp, cp, 0], [0, 0, 1]])
    ry = np.array([[cg, 0, sg], [0, 1, 0], [-sg, 0, cg]])
    return rx @ rz @ ry


def independent_direction(scene, s):
    """The target's azimuth, elevation (in G) and range from the gimbal at each sample of record s,
    through ECEF: the carrier's reference on its rhumb line, the gimbal the recorded heave and the
    turned lever arm (less the level one: [target.carrier] places the gimbal on the carrier at rest)
    from it, the target's ECEF position less the gimbal's, turned into the carrier's east-north-up."""
    spec, carrier = scene.target_spec, scene.target_spec["carrier"]
    course = math.radians(carrier["course_deg"])
    c, s_ = math.cos(course), math.sin(course)
    g_to_enu = np.array([[c, s_, 0], [-s_, c, 0], [0, 0, 1]])
    target_ecef = np.array(pymap3d.geodetic2ecef(spec["latitude_deg"], spec["longitude_deg"], spec["altitude_m"]))
    d = np.array(LEVER_ARM)
    az, el, rng = [], [], []
    for k, t in enumerate(s["time"]):
        lat, lon = (float(x) for x in loxodrome_direct(carrier["latitude_deg"], carrier["longitude_deg"],
                                                       carrier["speed_m_s"] * t, carrier["course_deg"]))
        gt0 = rotation_gt0(s["base.delta"][k], s["base.psi"][k], s["base.gamma"][k])
        gimbal_g = np.array([0.0, 0.0, s["heave"][k]]) + gt0 @ d - d
        gimbal_ecef = np.array(pymap3d.enu2ecef(*(g_to_enu @ gimbal_g), lat, lon, carrier["altitude_m"]))
        enu = np.array(pymap3d.ecef2enuv(*(target_ecef - gimbal_ecef), lat, lon))
        x, y, z = g_to_enu.T @ enu
        az.append(math.atan2(-x, y))
        el.append(math.atan2(z, math.hypot(x, y)))
        rng.append(math.sqrt(x * x + y * y + z * z))
    return np.array(az), np.array(el), np.array(rng)


def test_the_lever_arm_default_is_the_fmus(fmu):
    assert tuple(fmu.start(name) for name in LEVER_ARM_PARAMETERS) == DEFAULT_LEVER_ARM_M


def test_the_target_seen_from_the_heaving_gimbal_on_its_lever_arm_as_through_ecef(fmu):
    scene = heaving_coastal_scene()
    result = run(scene, fmu, stop_time=0.6)
    s = result.signals
    assert np.max(np.abs(s["heave"])) > 0.99 * HEAVE_M   # the heave from the start reaches 1.3 m
    az, el, rng = independent_direction(scene, s)
    assert np.max(np.abs(result.signal("target_azimuth") - az)) < 1e-9
    assert np.max(np.abs(result.signal("target_elevation") - el)) < 1e-9
    assert np.max(np.abs(result.signal("target_range") - rng)) < 1e-6
    # what the heave alone moves: far more than the tolerance (the rhumb line's direction ignored it)
    flat_s = {**s, "heave": np.zeros_like(s["heave"])}
    assert np.max(np.abs(independent_direction(scene, flat_s)[1] - el)) > 1e-4
    # the controller's command follows the same direction (a noiseless IMU, an exact INS)
    assert np.max(np.abs(s["beta_ref"] - result.signal("beta_cmd"))) < 1e-12


def test_an_ins_position_error_moves_the_command_not_the_truth():
    exact = heaving_coastal_scene()
    wrong = heaving_coastal_scene(ins_position_error_m=[0.0, 0.0, 2.0])   # the INS thinks the gimbal 2 m higher
    t = np.arange(5) * 0.1
    rows = exact.base_motion().sample(t)
    commands = [pointing(scene.moving_target, t, rows[:, 0:3], rows[:, 3:6], rows[:, 6:9]) for scene in (exact, wrong)]
    truths = [scene.moving_target.kinematics(t) for scene in (exact, wrong)]
    assert all(np.array_equal(a, b) for a, b in zip(*truths))
    lowered = commands[0].beta - commands[1].beta   # seen from higher up, the lantern is lower
    ranges = truths[0][3]
    assert np.allclose(lowered, 2.0 * np.cos(commands[0].beta) / ranges, rtol=0.02)


@pytest.mark.parametrize("value", [[1.0, 2.0], "2 m", [0.0, 0.0, 1e9]])
def test_an_ins_position_error_that_is_no_vector_is_refused_by_its_key(value):
    table = {**load_scene(SCENES / "track_coastal_point.toml").raw["target"], "ins_position_error_m": value}
    with pytest.raises(SceneError, match=r"target\.ins_position_error_m"):
        parse(table)


def overhead_pass():
    """track_flyby_keyhole passing exactly overhead (closest_approach_m = 0) a gimbal on a fixed base."""
    scene = load_scene(SCENES / "track_flyby_keyhole.toml")
    return scene.with_changes(target_spec={**scene.target_spec, "closest_approach_m": 0.0},
                              base_motion_spec={"type": "fixed"}, fidelity={**scene.fidelity, "base.fixed": True})


def test_on_the_azimuth_axis_the_command_holds_the_azimuth():
    up = np.array([[0.3, 0.0, -0.3], [0.4, 0.0, 0.4], [0.8, 1.0, 0.8]])
    up /= np.linalg.norm(up, axis=0)
    rate = np.array([[0.0, 0.5, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        command = PointingCommand(up, rate, np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)))
    assert command.alpha[1] == command.alpha[0] and command.beta[1] == math.pi / 2
    for name in ("alpha_dot", "alpha_ddot", "beta_dot", "beta_ddot"):
        assert getattr(command, name)[1] == 0.0
        assert np.all(np.isfinite(getattr(command, name)))
    assert np.all(np.isfinite(command.los_rate))


def test_an_exact_overhead_pass_runs_through_holding_the_azimuth(fmu):
    scene = overhead_pass()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        result = run(scene, fmu, stop_time=16.0)
    assert result.stopped is None
    s = result.signals
    for name in ("alpha_ref", "beta_ref", "u_R1", "u_R2"):
        assert np.all(np.isfinite(s[name])), name
    assert np.all(np.isfinite(result.signal("alpha_cmd_dot")))
    # the aircraft passes: the azimuth turns half a turn, at no more than its drive allows (~5 rad/s)
    assert abs(s["alpha"][-1] - s["alpha"][0]) > 3.0
    assert np.max(np.abs(s["alpha_dot"])) < 5.5
