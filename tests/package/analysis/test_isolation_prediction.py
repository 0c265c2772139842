"""The linear prediction of the closed loop's isolation ratio (gimbal2axis.analysis.isolation_prediction) against the
sine dwell of the nonlinear FMU in the ship-stabilization scene's own PID loop (ideal sensors, 1 ms step,
delay_steps = 1), without backlash and dry friction and at a small carrier rate (0.1 deg/s)."""
import copy
import dataclasses
import math

import numpy as np
import pytest

from gimbal2axis.errors import SceneError
from gimbal2axis.analysis.frequency_response import LINEAR_CURVE, LINEAR_FIDELITY, Dwell, Excitation, prediction_errors, sweep
from gimbal2axis.analysis import isolation_prediction

pytestmark = pytest.mark.python_bound

FREQUENCIES_HZ = (0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 60.0, 100.0)
RATE_AMPLITUDE = math.radians(0.1)     # rad/s: small enough to stay linear, large against the solver's tolerance
DWELL = Dwell(settle_periods=3, settle_s=1.0, measure_periods=1)
OUTPUTS = ("los.omega[1]", "los.omega[3]", "los")


@pytest.fixture(scope="module")
def loop(ship_linear_loop):
    return ship_linear_loop


@pytest.fixture(scope="module", params=["roll", "pitch"])
def dwell_rows(request, ship_scene, fmu_path):
    """(axis, simulated rows) of a sweep over FREQUENCIES_HZ."""
    axis = request.param
    return axis, sweep(ship_scene, fmu_path, FREQUENCIES_HZ, Excitation("base", axis, RATE_AMPLITUDE), DWELL,
                       fidelity=LINEAR_FIDELITY)


def relative_errors(loop, axis: str, rows: list[dict]) -> list[tuple]:
    """(row, gain ratio - 1, phase difference in deg (NaN for 'los')) of each simulated row against `loop`."""
    return prediction_errors(rows, lambda output, f: isolation_prediction.isolation_gains(loop, axis, [f])[output][0])


def test_prediction_matches_the_simulated_isolation_from_0p1_to_100_hz(loop, dwell_rows):
    """Roll and pitch of the carrier, 0.1-100 Hz: los.omega[1], los.omega[3] and the combined 'los' within
    1 % in gain and 1 deg in phase (the issue's bar; no relaxation was needed).

    Measured (roll): from 1 to 100 Hz within 3.3e-5 in gain and 0.006 deg, over the whole range of the
    gain (-57 dB at 1 Hz to +3.6 dB at 100 Hz); 3.8e-4 and 0.012 deg at 0.3 Hz; at 0.1 Hz los.omega[1]
    (-113 dB of the carrier rate) is off by 1.7e-3 and 0.12 deg: the FMU's integration error (the
    scene's solver.rtol = 1e-6) on that tiny residual; it drops to 2e-4 and 0.015 deg at rtol = 1e-9.
    los.omega[3] and 'los' within 1.6e-5 everywhere. Pitch: the same (1.7e-3 and 0.12 deg at 0.1 Hz,
    3.2e-4 at 0.3 Hz, else within 1.9e-5 and 0.003 deg). The prediction is the exact sampled-data loop,
    so there is no aliasing residual near Nyquist (100 Hz: 1.6e-6). Two things it had to get right to
    get there: the operating point is the loop's steady state holding the elevation's gravity torque
    (about 0.95 V), not 0 V (that left 1 % and 0.05 deg in los.omega[3] under roll); the outputs
    published at t_k use the carrier inputs extrapolated to the end of the previous step (the exact
    rate at t_k instead is off by 4 % at 30 Hz).

    Yaw is not checked component by component: its elevation component los.omega[1] is a cross coupling
    of -41 to -220 dB of the carrier rate, down to the level of the solver's error (8 deg off at a notch
    near 3 Hz); its los.omega[3] and 'los' agree within 8e-4 and 0.03 deg."""
    axis, rows = dwell_rows
    assert {row["output"] for row in rows} == set(OUTPUTS)
    for row, gain_error, phase_error in relative_errors(loop, axis, rows):
        where = f"{axis}: {row['output']} at {row['frequency_hz']:.4g} Hz"
        assert row["coherence"] > 0.99, where          # linear: the response is at the fundamental
        assert abs(gain_error) < 0.01, where
        if row["output"] != "los":
            assert abs(phase_error) < 1.0, where


@pytest.mark.parametrize("mistake", ["gyro sign", "one step more delay", "no feed-forward"])
def test_a_wrong_loop_misses_the_simulation(loop, dwell_rows, mistake):
    """The comparison can fail: the prediction with a flipped gyro term, an extra step of delay or the
    feed-forward left out misses the simulated isolation by far more than the tolerance somewhere."""
    axis, rows = dwell_rows
    if mistake == "gyro sign":
        axes = tuple(dataclasses.replace(a, k_gyro=-a.k_gyro) for a in loop.axes)
        wrong = dataclasses.replace(loop, axes=axes)
    elif mistake == "one step more delay":
        wrong = dataclasses.replace(loop, delay=loop.delay + 1)
    else:
        wrong = dataclasses.replace(loop, axes=tuple(dataclasses.replace(a, k_ff=0.0) for a in loop.axes))
    worst = max(max(abs(g), abs(p) / 100 if math.isfinite(p) else 0.0)
                for _, g, p in relative_errors(wrong, axis, rows))
    assert worst > 0.05


def test_rows_and_lines(ship_scene, gimbal_fmu, tmp_path):
    """Rows in the CSV format of frequency_response (the 'los' row without phase) and dense lines that
    plot_bode draws."""
    from gimbal2axis.analysis.frequency_response import plot_bode, write_csv

    loop = isolation_prediction.build_loop(ship_scene, gimbal_fmu, LINEAR_FIDELITY)
    rows = isolation_prediction.isolation_rows(loop, "roll", [1.0, 10.0])
    assert [(r["output"], r["frequency_hz"]) for r in rows] == [(o, f) for f in (1.0, 10.0) for o in OUTPUTS]
    assert all(r["curve"] == LINEAR_CURVE and r["input"] == "base.gamma_dot" and r["coherence"] == 1.0 for r in rows)
    for f in (1.0, 10.0):
        parts = {r["output"]: r for r in rows if r["frequency_hz"] == f}
        assert math.isnan(parts["los"]["phase_deg"])
        assert parts["los"]["gain"] == pytest.approx(math.hypot(parts["los.omega[1]"]["gain"],
                                                                parts["los.omega[3]"]["gain"]))
    lines = isolation_prediction.isolation_lines(loop, "roll", 0.1, 100.0, points=50)
    assert len(lines) == 3 and all(len(f) == 50 and len(G) == 50 for _, f, G, _ in lines)
    assert [has_phase for *_, has_phase in lines] == [True, True, False]
    assert np.all(lines[2][2].imag == 0) and np.all(lines[2][2].real > 0)
    write_csv(rows, tmp_path / "iso.csv")
    plot_bode(rows, tmp_path / "iso.png", "roll isolation", lines)
    assert (tmp_path / "iso.png").stat().st_size > 0


def test_other_controllers_are_refused(ship_scene, gimbal_fmu):
    none = ship_scene.with_changes(controller_spec={"type": "none"})
    with pytest.raises(SceneError, match="PID controller only"):
        isolation_prediction.build_loop(none, gimbal_fmu, LINEAR_FIDELITY)
    loop = isolation_prediction.build_loop(ship_scene, gimbal_fmu, LINEAR_FIDELITY)
    with pytest.raises(SceneError, match="roll, pitch or yaw"):
        isolation_prediction.isolation_rows(loop, "heave", [1.0])


def test_the_closed_loop_poles_are_where_the_frequency_domain_loop_is_singular(loop):
    """The time-domain closed loop (closed_loop_transition, whose poles decide stability) and the
    frequency-domain one (loop_response: I - voltage_transfer(z) feedback(z)) are the same system: at each
    of the slowest closed-loop poles z_p, the return difference I - P(z_p) K(z_p) is singular."""
    poles = isolation_prediction.closed_loop_poles(loop)
    assert np.max(np.abs(poles)) < 1.0
    plant_poles = np.linalg.eigvals(loop.plant.Phi)
    # the slowest poles that are not also plant or controller poles (there P K itself is infinite)
    candidates = [p for p in sorted(poles, key=lambda p: -abs(p))
                  if np.min(np.abs(plant_poles - p)) > 1e-6 and abs(p - 1) > 1e-6 and abs(p) > 0.5][:6]
    assert len(candidates) >= 4
    for p in candidates:
        feedback, _ = isolation_prediction.controller_matrices(loop, "roll", p, 1.0)
        return_difference = np.eye(4) - isolation_prediction.voltage_transfer(loop, p) @ feedback
        singular = np.linalg.svd(return_difference, compute_uv=False)
        assert singular[-1] < 1e-7 * singular[0], (p, singular)
    # and a point that is no pole is not singular
    feedback, _ = isolation_prediction.controller_matrices(loop, "roll", 0.3 + 0.2j, 1.0)
    singular = np.linalg.svd(np.eye(4) - isolation_prediction.voltage_transfer(loop, 0.3 + 0.2j) @ feedback,
                             compute_uv=False)
    assert singular[-1] > 1e-3 * singular[0]


def test_a_loop_that_does_not_settle_is_refused(ship_scene, gimbal_fmu):
    """k_gyro = 32 excites the azimuth gear's resonance: the simulated loop ends current-limited, and no
    isolation ratio is predicted for it."""
    spec = dict(ship_scene.controller_spec)
    spec["azimuth"] = dict(spec["azimuth"], k_gyro=32.0)
    with pytest.raises(SceneError, match="does not come to rest"):
        isolation_prediction.build_loop(ship_scene.with_changes(controller_spec=spec), gimbal_fmu, LINEAR_FIDELITY)


def test_the_operating_point_is_that_of_ideal_sensors_and_decoupling_modes_are_named(ship_scene, ship_linear_loop,
                                                                                       gimbal_fmu):
    """Sensor noise and quantization would keep the settling run from ever resting: the operating point is
    found with ideal sensors, as the prediction assumes, so a noisy scene gets the ideal one's prediction.
    With the scene's own fidelity the gimbal rests in the backlash gap with the rotors stuck: the voltage
    does not reach the load, the linear loop has a pole at 1, and the refusal says why."""
    noisy = ship_scene.with_changes(sensors_spec={"encoder_resolution_deg": 0.01, "imu_attitude_noise_deg": 0.05})
    loop = isolation_prediction.build_loop(noisy, gimbal_fmu, LINEAR_FIDELITY)
    for axis in ("roll", "pitch"):
        noisy_gains = isolation_prediction.isolation_gains(loop, axis, [1.0, 10.0])["los"]
        ideal_gains = isolation_prediction.isolation_gains(ship_linear_loop, axis, [1.0, 10.0])["los"]
        assert np.allclose(noisy_gains, ideal_gains, rtol=1e-12)
    with pytest.raises(SceneError, match=r"gear1.contact = 0.*rotor1.friction = stuck.*without backlash and dry"):
        isolation_prediction.build_loop(ship_scene, gimbal_fmu, None)


@pytest.mark.parametrize("change", ["no delay", "two steps of delay", "filtered derivative"])
def test_other_delays_and_a_derivative_term_are_predicted_too(ship_scene, gimbal_fmu, change):
    """The ship loop's own configuration has delay_steps = 1 and kd = 0; the prediction's z^-d and its
    filtered backward difference are checked on two points each (roll at 3 and 30 Hz), same bar."""
    spec = copy.deepcopy(ship_scene.controller_spec)
    if change == "no delay":
        spec["delay_steps"] = 0
    elif change == "two steps of delay":
        spec["delay_steps"] = 2
    else:
        for axis in ("azimuth", "elevation"):
            spec[axis].update(kd=1.0, d_filter_s=0.003)
    scene = ship_scene.with_changes(controller_spec=spec)
    loop = isolation_prediction.build_loop(scene, gimbal_fmu, LINEAR_FIDELITY)
    rows = sweep(scene, gimbal_fmu.path, (3.0, 30.0), Excitation("base", "roll", RATE_AMPLITUDE), DWELL,
                 fidelity=LINEAR_FIDELITY)
    for row, gain_error, phase_error in relative_errors(loop, "roll", rows):
        where = f"{change}: {row['output']} at {row['frequency_hz']:.3g} Hz"
        assert abs(gain_error) < 0.01, where
        assert math.isnan(phase_error) or abs(phase_error) < 1.0, where
