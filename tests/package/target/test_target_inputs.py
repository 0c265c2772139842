"""A moving target's inputs are checked as the recorded ship motions are (issue 44, items 12 and 15):
a track read by the same reader (a column named twice refused, a UTF-8 byte-order mark skipped), every
number of [target] and [target.carrier] within a physical range named by its key, and a geometry
without a line of sight (a target at the gimbal, a carrier sailing onto a pole) refused when the scene
loads, naming the keys, instead of a NaN deep in the run and numpy's warnings. The sea state's and the
sinusoids' numbers likewise. Pure Python: load_scene and the target's own functions, no FMU."""
import math
import warnings

import numpy as np
import pytest

from gimbal2axis import SceneError, load_scene

pytestmark = pytest.mark.python_bound

POINT = """name = "point"
stop_time = 1.0
step_size = 1e-3
[fidelity]
"base.fixed" = true
[base_motion]
type = "fixed"
[controller]
type = "none"
[target]
type = "earth_point"
latitude_deg = 59.835
longitude_deg = 10.615
altitude_m = 30.0
[target.carrier]
latitude_deg = 59.8
longitude_deg = 10.56
altitude_m = 15.0
course_deg = 20.0
speed_m_s = 8.0
"""

TRACKED = POINT.replace("""type = "earth_point"
latitude_deg = 59.835
longitude_deg = 10.615
altitude_m = 30.0""", """type = "track"
file = "boat.csv\"""")

FLYBY = POINT.replace("""type = "earth_point"
latitude_deg = 59.835
longitude_deg = 10.615
altitude_m = 30.0""", """type = "flyby"
altitude_m = 315.0
speed_m_s = 100.0
heading_deg = 90.0
closest_approach_m = 500.0
closest_approach_s = 0.5""")

SEA_STATE = """name = "sea"
stop_time = 0.01
step_size = 1e-3
[base_motion]
type = "sea_state"
roll = { significant_amplitude_deg = 5.0, peak_period_s = 8.0, gamma = 3.3 }
heave = { significant_amplitude_m = 1.0, peak_period_s = 8.0 }
[controller]
type = "none"
"""

SINUSOIDS = """name = "sines"
stop_time = 0.01
step_size = 1e-3
[base_motion]
type = "sinusoids"
roll = { amplitude_deg = 2.0, period_s = 8.0, phase_deg = 10.0, offset_deg = 1.0 }
heave = { amplitude_m = 0.5, frequency_hz = 0.1 }
velocity_m_s = [0.0, 5.0, 0.0]
[controller]
type = "none"
"""

BOAT_HEADER = "time,latitude_deg,longitude_deg,altitude_m"


def boat_rows(count=8):
    return [f"{t:.1f},{59.82 + 1e-5 * t!r},{10.6 + 2e-5 * t!r},4.0" for t in range(-1, count - 1)]


def load(tmp_path, text, track: str | None = None):
    if track is not None:
        (tmp_path / "boat.csv").write_text(track)
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # a numpy warning is a failure here
        return load_scene(path)


def refusal(tmp_path, text, track: str | None = None) -> str:
    with pytest.raises(SceneError) as caught:
        load(tmp_path, text, track)
    return str(caught.value)


def test_a_track_with_a_column_named_twice_is_refused_naming_it(tmp_path):
    # the second latitude_deg column was ignored: the track that ran was not the one the file held
    rows = [f"{row},{59.9 + i}" for i, row in enumerate(boat_rows())]
    message = refusal(tmp_path, TRACKED, "\n".join([BOAT_HEADER + ",latitude_deg"] + rows) + "\n")
    assert "boat.csv" in message and "'latitude_deg' appears twice" in message, message


def test_a_track_with_a_byte_order_mark_reads_as_without(tmp_path):
    from gimbal2axis.target.motion import Track

    text = "\n".join([BOAT_HEADER] + boat_rows()) + "\n"
    plain, marked = tmp_path / "plain.csv", tmp_path / "marked.csv"
    plain.write_text(text, encoding="utf-8")
    marked.write_text(text, encoding="utf-8-sig")
    assert marked.read_bytes().startswith(b"\xef\xbb\xbf")
    times = np.linspace(0.0, 5.0, 11)
    expected, got = Track("target.file", plain).geodetic(times), Track("target.file", marked).geodetic(times)
    for a, b in zip(expected, got):
        assert np.array_equal(a, b)
    assert load(tmp_path, TRACKED, "\ufeff" + text).moving_target is not None


@pytest.mark.parametrize("column, value", [("latitude_deg", "90.5"), ("longitude_deg", "1e308"),
                                           ("altitude_m", "-1e300")])
def test_a_track_coordinate_out_of_its_range_is_refused_naming_the_column(tmp_path, column, value):
    rows = boat_rows()
    cells = rows[3].split(",")
    cells[BOAT_HEADER.split(",").index(column)] = value
    rows[3] = ",".join(cells)
    message = refusal(tmp_path, TRACKED, "\n".join([BOAT_HEADER] + rows) + "\n")
    assert "boat.csv" in message and "data row 4" in message and column in message and "outside" in message, \
        message


@pytest.mark.parametrize("scene, old, new, key", [
    (POINT, "longitude_deg = 10.615", "longitude_deg = 1e308", "target.longitude_deg"),
    (POINT, "longitude_deg = 10.615", "longitude_deg = -180.5", "target.longitude_deg"),
    (POINT, "altitude_m = 30.0", "altitude_m = 1e300", "target.altitude_m"),
    (POINT, "longitude_deg = 10.56", "longitude_deg = 1e308", "target.carrier.longitude_deg"),
    (POINT, "altitude_m = 15.0", "altitude_m = -1e300", "target.carrier.altitude_m"),
    (POINT, "course_deg = 20.0", "course_deg = 1e300", "target.carrier.course_deg"),
    (POINT, "speed_m_s = 8.0", "speed_m_s = 1e300", "target.carrier.speed_m_s"),
    (POINT, "[target.carrier]", "beam_width_mrad = 1e300\n[target.carrier]", "target.beam_width_mrad"),
    (FLYBY, "speed_m_s = 100.0", "speed_m_s = 1e300", "target.speed_m_s"),
    (FLYBY, "heading_deg = 90.0", "heading_deg = 1e300", "target.heading_deg"),
    (FLYBY, "closest_approach_m = 500.0", "closest_approach_m = 1e300", "target.closest_approach_m"),
    (FLYBY, "closest_approach_s = 0.5", "closest_approach_s = -1e300", "target.closest_approach_s"),
], ids=lambda value: value if isinstance(value, str) and value.startswith("target") else "")
def test_a_target_number_out_of_its_physical_range_is_refused_naming_the_key(tmp_path, scene, old, new, key):
    assert old in scene
    message = refusal(tmp_path, scene.replace(old, new, 1))
    assert f"{key} = " in message and "is outside [" in message, message


def test_the_local_form_is_range_checked_too(tmp_path):
    local = POINT.replace("latitude_deg = 59.835\nlongitude_deg = 10.615\naltitude_m = 30.0",
                          "north_m = 1e300\neast_m = 0.0\ndown_m = 0.0")
    assert "target.north_m = 1e+300 is outside" in refusal(tmp_path, local)


@pytest.mark.parametrize("edit", [
    lambda s: s.replace("latitude_deg = 59.835", "latitude_deg = 59.8").replace("longitude_deg = 10.615",
                                                                                 "longitude_deg = 10.56")
               .replace("altitude_m = 30.0", "altitude_m = 15.0").replace("speed_m_s = 8.0", "speed_m_s = 0.0"),
    lambda s: s.replace("latitude_deg = 59.835\nlongitude_deg = 10.615\naltitude_m = 30.0",
                        "north_m = 0.0\neast_m = 0.0\ndown_m = 0.0"),
], ids=["geodetic", "local"])
def test_a_target_at_the_gimbal_is_refused_when_the_scene_loads(tmp_path, edit):
    message = refusal(tmp_path, edit(POINT))
    assert "from the gimbal at t = 0 s" in message and "latitude_deg" in message and "north_m" in message, message


def test_a_carrier_at_a_pole_that_sails_is_refused_naming_the_keys(tmp_path):
    message = refusal(tmp_path, POINT.replace("latitude_deg = 59.8\n", "latitude_deg = 90.0\n"))
    assert "target.carrier.latitude_deg = 90" in message and "target.carrier.speed_m_s" in message, message


def test_a_carrier_that_sails_onto_a_pole_during_the_run_is_refused(tmp_path):
    # 8 m/s on course 20 deg covers the last 1.1 m to the pole within the 1 s run
    message = refusal(tmp_path, POINT.replace("latitude_deg = 59.8\n", "latitude_deg = 89.99999999\n"))
    assert "target.carrier" in message and "reaches a pole" in message, message


def test_the_kinematics_refuse_a_target_at_the_gimbal_without_numpy_warnings():
    from gimbal2axis.target.motion import Carrier, EarthPoint

    carrier = Carrier(59.8, 10.56, 15.0, 0.0, 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SceneError, match="at the gimbal"):
            EarthPoint(carrier, 59.8, 10.56, 15.0).kinematics(np.array([0.0, 1.0]))


def test_an_exact_overhead_pass_leaks_no_numpy_warning():
    # the keyhole's policy (the NaN rate on the azimuth axis) is the callers'; numpy's division
    # warnings about it are noise on the user's terminal
    from gimbal2axis.target import pointing
    from gimbal2axis.target.motion import Carrier, Flyby

    overhead = Flyby(Carrier(0.0, 0.0, 0.0, 0.0, 0.0), 300.0, 100.0, math.radians(90.0), 0.0, 15.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        command = pointing(overhead, np.array([14.999, 15.0, 15.001]), np.zeros((3, 3)), np.zeros((3, 3)))
    assert np.isfinite(command.alpha_dot[[0, 2]]).all()


@pytest.mark.parametrize("scene, old, new, key", [
    (SEA_STATE, "peak_period_s = 8.0, gamma", "peak_period_s = 1e-300, gamma", "base_motion.roll.peak_period_s"),
    (SEA_STATE, "peak_period_s = 8.0, gamma", "peak_period_s = 1e300, gamma", "base_motion.roll.peak_period_s"),
    (SEA_STATE, "gamma = 3.3", "gamma = 1e300", "base_motion.roll.gamma"),
    (SEA_STATE, "significant_amplitude_deg = 5.0", "significant_amplitude_deg = 1e300",
     "base_motion.roll.significant_amplitude_deg"),
    (SEA_STATE, "significant_amplitude_m = 1.0", "significant_amplitude_m = 1e300",
     "base_motion.heave.significant_amplitude_m"),
    (SINUSOIDS, "period_s = 8.0", "period_s = 1e-300", "base_motion.roll.period_s"),
    (SINUSOIDS, "frequency_hz = 0.1", "frequency_hz = 1e300", "base_motion.heave.frequency_hz"),
    (SINUSOIDS, "amplitude_deg = 2.0", "amplitude_deg = 1e300", "base_motion.roll.amplitude_deg"),
    (SINUSOIDS, "amplitude_m = 0.5", "amplitude_m = -1e300", "base_motion.heave.amplitude_m"),
    (SINUSOIDS, "phase_deg = 10.0", "phase_deg = 1e300", "base_motion.roll.phase_deg"),
    (SINUSOIDS, "offset_deg = 1.0", "offset_deg = 1e300", "base_motion.roll.offset_deg"),
    (SINUSOIDS, "velocity_m_s = [0.0, 5.0, 0.0]", "velocity_m_s = [0.0, 1e300, 0.0]", "base_motion.velocity_m_s[1]"),
], ids=lambda value: value if isinstance(value, str) and value.startswith("base_motion") else "")
def test_a_base_motion_number_out_of_its_range_is_refused_naming_the_key(tmp_path, scene, old, new, key):
    assert old in scene
    path = tmp_path / "scene.toml"
    path.write_text(scene.replace(old, new, 1))
    with pytest.raises(SceneError) as caught:
        load_scene(path).base_motion()
    assert f"{key} = " in str(caught.value) and "is outside [" in str(caught.value), str(caught.value)


def test_the_shipped_motions_and_targets_are_within_the_ranges():
    import pathlib

    for path in sorted((pathlib.Path(__file__).resolve().parents[3] / "scenes").glob("*.toml")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            scene = load_scene(path)
            scene.base_motion()
            scene.moving_target
