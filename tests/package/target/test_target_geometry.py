"""Moving targets' geometry (gimbal2axis/target) against independent computations: a point on the
Earth seen from a carrier at a known position (angles by hand, and pymap3d's own test values), a
flyby's azimuth rate at closest approach against the closed form v / (d cos el), the carrier's rhumb
line against pymap3d's loxodrome test values; the inverse kinematics' rates and accelerations
against differences of its angles, and forward kinematics of its angles against the target. No FMU."""
import math

import numpy as np
import pytest

from gimbal2axis.scene import geometry
from gimbal2axis.target import pointing
from gimbal2axis.target.kinematics import PointingCommand, carrier_rate_and_acceleration, unit_and_derivatives
from gimbal2axis.target.motion import Carrier, EarthPoint, Flyby

pytestmark = pytest.mark.python_bound

WGS84_A = 6378137.0


def level(n=1):
    return np.zeros((n, 3))


def test_a_point_on_the_equator_seen_from_the_equator_by_hand():
    # Carrier at (0, 0, 0), target at (0, dl, 0): in ECEF (a cos dl, a sin dl, 0) and (a, 0, 0), so in
    # the carrier's east-north-up frame (a sin dl, 0, -a (1 - cos dl)): due east, elevation -dl/2 (the
    # chord's angle below the horizon), range 2 a sin(dl/2). With course 30 deg (y_G), the bearing 90
    # is 60 deg to starboard: alpha = -60 deg on a level base.
    dl = 0.1
    target = EarthPoint(Carrier(0.0, 0.0, 0.0, math.radians(30.0), 0.0), 0.0, dl, 0.0)
    u, _, _, distance, _ = target.kinematics([0.0])
    command = pointing(target, [0.0], level(), level())
    assert command.alpha[0] == pytest.approx(math.radians(-60.0), abs=1e-12)
    assert command.beta[0] == pytest.approx(-math.radians(dl) / 2.0, abs=1e-12)
    assert distance[0] == pytest.approx(2 * WGS84_A * math.sin(math.radians(dl) / 2.0), rel=1e-12)
    # fixed carrier, fixed point: nothing moves
    assert np.max(np.abs(pointing(target, [0.0, 5.0], level(2), level(2)).alpha_dot)) < 1e-12


def test_a_point_on_the_earth_at_pymap3ds_own_test_values():
    # pymap3d's tests/test_ned.py: from lla0 = (42, -82, 200) the point aer0 = (33 deg, 70 deg, 1000 m)
    import pymap3d

    lla0, aer0 = (42, -82, 200), (33, 70, 1000)
    point = pymap3d.aer2geodetic(*aer0, *lla0)
    target = EarthPoint(Carrier(*lla0, 0.0, 0.0), *point)
    u, _, _, distance, _ = target.kinematics([0.0])
    assert math.degrees(math.atan2(-u[0, 0], u[1, 0])) == pytest.approx(-33.0, abs=1e-9)   # bearing 33: az_G = -33
    assert math.degrees(math.atan2(u[2, 0], math.hypot(u[0, 0], u[1, 0]))) == pytest.approx(70.0, abs=1e-9)
    assert distance[0] == pytest.approx(1000.0, abs=1e-6)


@pytest.mark.parametrize("lat0, lon0, rng, az, lat1, lon1", [
    (40, -80, 10000, 30, 40.0000779959676, -79.9999414477481),   # pymap3d's tests/test_rhumb.py
    (35, 140, 50000, 90, 35, 140.548934481815),
    (35, 140, 50000, 270, 35, 139.451065518185),
    (0, 0, 110574.4, 180, -1, 0),
])
def test_the_carrier_sails_pymap3ds_rhumb_line(lat0, lon0, rng, az, lat1, lon1):
    # pymap3d's own test values (MATLAB's reckon('rh', ...)) with its own tolerances
    carrier = Carrier(lat0, lon0, 0.0, math.radians(az), 10.0)
    lat, lon, _ = carrier.geodetic(np.array([rng / 10.0]))
    assert lat[0] == pytest.approx(lat1, rel=0.005, abs=1e-6)
    assert lon[0] == pytest.approx(lon1, rel=0.001)


@pytest.mark.parametrize("course_deg, sign", [(90.0, 1.0), (270.0, -1.0)])
def test_sailing_along_a_parallel_turns_the_longitude_by_s_over_n_cos_latitude(course_deg, sign):
    # by hand: along a parallel the rhumb line is the parallel, of radius N cos(lat) (N the prime
    # vertical radius of curvature of WGS 84); 50 km at 35 deg N
    f = 1 / 298.257223563
    e2 = f * (2 - f)
    latitude = math.radians(35.0)
    n = WGS84_A / math.sqrt(1 - e2 * math.sin(latitude) ** 2)
    carrier = Carrier(35.0, 140.0, 0.0, math.radians(course_deg), 5.0)
    lat, lon, _ = carrier.geodetic(np.array([10000.0]))
    assert lat[0] == pytest.approx(35.0, abs=1e-9)
    assert lon[0] == pytest.approx(140.0 + sign * math.degrees(50000.0 / (n * math.cos(latitude))), abs=1e-10)


def test_a_fixed_point_seen_from_a_sailing_carrier_turns_as_by_hand():
    # 10 km due north of the start, the carrier sailing east at 10 m/s: after t s the point is at
    # bearing atan2(-10 t, 10000) east of... i.e. the azimuth in G (course 090: y_G east, x_G south)
    # is atan2(10000, -10 t) - 90 deg seen counter-clockwise; on a sphere the offsets are exact to
    # the flat approximation within 1e-3 rad at 10 km. Rates: d/dt atan(v t / D) = v D / (D^2 + v^2 t^2).
    import pymap3d

    start = (45.0, 7.0, 0.0)
    point = pymap3d.ned2geodetic(10000.0, 0.0, 0.0, *start)
    target = EarthPoint(Carrier(*start, math.radians(90.0), 10.0), *point)
    times = np.array([0.0, 30.0])
    command = pointing(target, times, level(2), level(2))
    flat = np.radians(90.0) + np.arctan2(10.0 * times, 10000.0)   # port of the bow, growing
    assert np.allclose(command.alpha, flat, atol=2e-3)
    assert np.allclose(command.alpha_dot, 10.0 * 10000.0 / (10000.0 ** 2 + (10.0 * times) ** 2), rtol=2e-3)


@pytest.mark.parametrize("height, d", [(300.0, 10.0), (300.0, 40.0), (50.0, 400.0)])
def test_a_flybys_azimuth_rate_at_closest_approach_is_v_over_d_cos_el(height, d):
    v = 120.0
    carrier = Carrier(0.0, 0.0, 0.0, math.radians(250.0), 0.0)
    flyby = Flyby(carrier, height, v, math.radians(290.0), d, 15.0)
    command = pointing(flyby, [15.0], level(), level())
    slant = math.hypot(d, height)
    elevation = math.atan2(height, d)
    assert command.beta[0] == pytest.approx(elevation, abs=1e-12)
    # the track on the gimbal's right seen along the heading: the azimuth turns counter-clockwise (> 0)
    assert command.alpha_dot[0] == pytest.approx(v / (slant * math.cos(elevation)), rel=1e-12)
    assert command.beta_dot[0] == pytest.approx(0.0, abs=1e-12)
    # and against differences of the angles over +-1 us (independent of the closed form)
    around = pointing(flyby, [15.0 - 1e-6, 15.0 + 1e-6], level(2), level(2))
    assert (around.alpha[1] - around.alpha[0]) / 2e-6 == pytest.approx(v / d, rel=1e-6)


def sea_motion(times):
    """An attitude with exact rates and accelerations (three sinusoids), (n, 3) each."""
    amplitude, omega, phase = np.array([0.05, 0.2, 0.1]), np.array([0.9, 0.5, 0.7]), np.array([0.3, 1.1, -0.4])
    arg = np.outer(times, omega) + phase
    return amplitude * np.sin(arg), amplitude * omega * np.cos(arg), -amplitude * omega ** 2 * np.sin(arg)


@pytest.mark.parametrize("kind", ["flyby", "earth_point"])
def test_inverse_kinematics_on_a_moving_carrier_rates_accelerations_and_forward_kinematics(kind):
    carrier = Carrier(59.8, 10.56, 15.0, math.radians(20.0), 8.0)
    target = Flyby(carrier, 290.0, 120.0, math.radians(290.0), 60.0, 5.0) if kind == "flyby" else \
        EarthPoint(carrier, 59.835, 10.615, 30.0)
    h = 1e-4
    times = np.arange(0.0, 10.0, 0.5)
    stacked = np.concatenate([times - h, times, times + h])
    attitude, rates, accelerations = sea_motion(stacked)
    command = pointing(target, stacked, attitude, rates, accelerations)
    n = len(times)
    before, now, after = (slice(i * n, (i + 1) * n) for i in range(3))
    for angle in ("alpha", "beta"):
        values = getattr(command, angle)
        rate = getattr(command, f"{angle}_dot")
        difference = np.unwrap(values[after] - values[before]) / (2 * h)
        assert np.allclose(rate[now], difference, rtol=1e-6, atol=1e-9), angle
        assert np.allclose(getattr(command, f"{angle}_ddot")[now], (rate[after] - rate[before]) / (2 * h),
                           rtol=1e-5, atol=1e-8), angle
    # forward kinematics of the commanded angles points the line of sight along the target
    u = target.direction(stacked)
    los = geometry.los_direction(command.alpha, command.beta, *attitude.T)
    assert np.max(geometry.angle_between(los, u)) < 1e-12


def test_unit_vector_derivatives_and_carrier_acceleration_against_differences():
    t, h = np.array([0.7, 2.0]), 1e-5
    def p(t):
        return np.array([100 + 30 * t + np.sin(t), 200 - 5 * t ** 2, 50 + np.cos(2 * t)])
    u, u1, u2, r, r1 = unit_and_derivatives(p(t), (p(t + h) - p(t - h)) / (2 * h),
                                            (p(t + h) - 2 * p(t) + p(t - h)) / h ** 2)
    up, _, _, rp, _ = unit_and_derivatives(p(t + h), p(t), p(t))
    um, _, _, rm, _ = unit_and_derivatives(p(t - h), p(t), p(t))
    assert np.allclose(u1, (up - um) / (2 * h), rtol=1e-6, atol=1e-12)
    assert np.allclose(u2, (up - 2 * u + um) / h ** 2, rtol=1e-3, atol=1e-9)
    assert np.allclose(r1, (rp - rm) / (2 * h), rtol=1e-7)
    attitude, rates, accelerations = sea_motion(np.concatenate([t - h, t, t + h]))
    w, w_dot = carrier_rate_and_acceleration(attitude.T, rates.T, accelerations.T)
    assert np.allclose(w[:, 2:4], geometry.carrier_rate(attitude[2:4, 1], attitude[2:4, 2], *rates[2:4].T))
    assert np.allclose(w_dot[:, 2:4], (w[:, 4:] - w[:, :2]) / (2 * h), rtol=1e-6, atol=1e-10)


def test_the_keyhole_azimuth_rate_grows_as_the_target_nears_the_azimuth_axis():
    rates = []
    for d in (100.0, 10.0, 1.0):
        flyby = Flyby(Carrier(0.0, 0.0, 0.0, 0.0, 0.0), 300.0, 100.0, 0.0, d, 0.0)
        rates.append(pointing(flyby, [0.0], level(), level()).alpha_dot[0])
    assert rates == pytest.approx([1.0, 10.0, 100.0], rel=1e-12)
    assert isinstance(PointingCommand, type)


def test_a_recorded_carrier_track_gives_the_directions_of_the_sailing_it_records(tmp_path):
    # the carrier's positions every second along its rhumb line, as a recorded navigation track: the
    # spline through them puts the target where the sailing carrier sees it
    from gimbal2axis.target.motion import Track

    sailing = Carrier(59.8, 10.56, 15.0, math.radians(20.0), 8.0)
    times = np.arange(-2.0, 13.0)
    lat, lon, alt = sailing.geodetic(times)
    path = tmp_path / "own_ship.csv"
    path.write_text("time,latitude_deg,longitude_deg,altitude_m\n" + "".join(
        f"{t:.1f},{float(a)!r},{float(b)!r},{float(c)!r}\n" for t, a, b, c in zip(times, lat, lon, alt)))
    recorded = Carrier(59.8, 10.56, 15.0, math.radians(20.0), 0.0, Track("carrier", path))
    at = np.linspace(0.0, 10.0, 7)
    u_sailing = EarthPoint(sailing, 59.835, 10.615, 30.0).kinematics(at)
    u_recorded = EarthPoint(recorded, 59.835, 10.615, 30.0).kinematics(at)
    assert np.max(geometry.angle_between(u_sailing[0], u_recorded[0])) < 1e-9
    assert np.allclose(u_sailing[1], u_recorded[1], atol=1e-9)


def test_the_tracking_metrics_count_by_hand():
    from gimbal2axis.target.metrics import TrackingMetrics

    metrics = TrackingMetrics(beam_width_mrad=2.0, keyhole_deg=10.0, step_size=0.5, window_start=0.5)
    near, far = math.radians(85.0), math.radians(30.0)
    metrics.add({"time": np.array([0.0, 0.5, 1.0, 1.5, 2.0]),
                 "los_error": np.array([9e-3, 0.5e-3, 2e-3, 0.9e-3, 1.5e-3]),   # on: 0.5, 0.9 mrad (<= 1)
                 "beta_cmd": np.array([far, far, near, near, far]),
                 "alpha_cmd_dot": np.array([9.0, 0.1, 3.0, -4.0, 0.2]), "alpha_cmd_ddot": np.array([0, 0, 5.0, -6.0, 0]),
                 "alpha_dot": np.array([0.0, 0.1, 1.0, -1.5, 0.2]), "i_R1": np.array([0, 0.1, 2.0, -3.5, 0.1]),
                 "u_R1_asked": np.array([50.0, 1.0, -30.0, 20.0, 1.0])})
    m = metrics.as_dict()
    assert m["on_target_fraction"] == 0.5 and m["time_lost_s"] == 1.0 and m["time_on_target_s"] == 1.0
    assert m["time_near_keyhole_s"] == 1.0 and m["time_lost_near_keyhole_s"] == 0.5
    assert (m["keyhole_asked_rate_max"], m["keyhole_asked_acceleration_max"], m["keyhole_achieved_rate_max"],
            m["keyhole_current_max"], m["asked_azimuth_rate_max"], m["keyhole_asked_voltage_max"]) == \
        (4.0, 6.0, 1.5, 3.5, 4.0, 30.0)
