"""The loop gain of the ship-stabilization scene's PID loop measured by voltage injection (sine dwell,
Excitation("injection", ...)) against its linear prediction (gimbal2axis.analysis.isolation_prediction.loop_gain),
without backlash and dry friction and at a small injected amplitude (0.05 V); the margins helper on
loops with known margins; the command's CSV and PNG."""
import cmath
import csv
import dataclasses
import math

import numpy as np
import pytest

from gimbal2axis.analysis import isolation_prediction
from gimbal2axis.errors import SceneError
from gimbal2axis.analysis.frequency_response import (LINEAR_CURVE, LINEAR_FIDELITY, LOOP_GAIN, SENSITIVITY, Dwell, Excitation,
                                          InjectingController, prediction_errors, sweep)

FREQUENCIES_HZ = (0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 60.0, 100.0)
INJECTION_V = 0.05       # small: the gimbal moves by micro-radians, the loop stays linear
DWELL = Dwell(settle_periods=1, settle_s=1.0, measure_periods=1)


@pytest.fixture(scope="module")
def loop(ship_linear_loop):
    return ship_linear_loop


@pytest.fixture(scope="module", params=["1", "2"])
def dwell_rows(request, ship_scene, fmu_path):
    """(motor axis, simulated rows) of an injection sweep over FREQUENCIES_HZ."""
    axis = request.param
    return axis, sweep(ship_scene, fmu_path, FREQUENCIES_HZ, Excitation("injection", axis, INJECTION_V), DWELL,
                       fidelity=LINEAR_FIDELITY)


def errors_against(loop, axis: str, rows: list[dict]) -> list[tuple]:
    """(row, gain ratio - 1, phase difference in deg) of each simulated row against `loop`'s prediction."""
    return prediction_errors(rows, lambda output, f: isolation_prediction.loop_gain_gains(loop, axis, [f])[output][0])


def test_measured_loop_gain_matches_the_prediction_from_0p1_to_100_hz(loop, dwell_rows):
    """Motors 1 and 2, 0.1-100 Hz: the loop gain L = -U/A, the sensitivity A/D and the LOS rate per D
    within 1 % in gain and 1 deg in phase (the bar; no relaxation was needed).

    Measured: every row within 8e-6 in gain and 0.001 deg in phase (motor 1 within 2.1e-7), over
    |L| from +77 dB (0.1 Hz, where A is D / 7000) down to -18 dB (100 Hz). It is this close because the
    prediction is the exact sampled-data loop and A, U, D are all samples at t_k (no hold correction
    enters); the FMU's solver error on micro-radian motions is what is left."""
    axis, rows = dwell_rows
    assert [r["output"] for r in rows[:3]] == [LOOP_GAIN, SENSITIVITY, "los.omega[3]" if axis == "1" else "los.omega[1]"]
    assert {r["input"] for r in rows if r["output"] == LOOP_GAIN} == {f"u_R{axis}_cmd"}
    assert {r["input"] for r in rows if r["output"] != LOOP_GAIN} == {f"injection_R{axis}"}
    for row, gain_error, phase_error in errors_against(loop, axis, rows):
        where = f"motor {axis}: {row['output']} at {row['frequency_hz']:.4g} Hz"
        assert row["coherence"] > 0.999, where
        assert row["current_limited_fraction"] == 0.0, where
        assert abs(gain_error) < 0.01, where
        assert abs(phase_error) < 1.0, where


@pytest.mark.parametrize("mistake", ["one step more delay", "gyro sign"])
def test_a_wrong_loop_misses_the_measured_loop_gain(loop, dwell_rows, mistake):
    """The comparison can fail: one more step of delay, or the gyro term's sign flipped, misses the
    measurement by far more than the tolerance somewhere. (Leaving the other axis's loop open, L = -G_jj,
    would not: at this operating point the other loop changes L by at most 6e-6 over 0.1-100 Hz.)"""
    axis, rows = dwell_rows
    if mistake == "gyro sign":
        wrong = dataclasses.replace(loop, axes=tuple(dataclasses.replace(a, k_gyro=-a.k_gyro) for a in loop.axes))
    else:
        wrong = dataclasses.replace(loop, delay=loop.delay + 1)
    worst = max(max(abs(g), abs(p) / 100) for _, g, p in errors_against(wrong, axis, rows))
    assert worst > 0.05


@pytest.mark.parametrize("axis", ["1", "2"])
def test_breaking_the_loop_is_consistent_with_the_closed_loop(loop, axis):
    """1 / (1 + L_j) from the broken loop equals the sensitivity A_j / D of the whole closed loop,
    [(I - K P)^-1]_jj, computed independently; and L_j's closed form against a direct elimination of
    the other axis (the 2 x 2 closed loop with axis j driven by A_j)."""
    j = int(axis) - 1
    for f in np.logspace(-1, math.log10(499.0), 40):
        z = cmath.exp(2j * math.pi * f * loop.h)
        L = isolation_prediction.loop_gain(loop, axis, z)
        S = isolation_prediction.injection_sensitivity(loop, axis, z)
        assert abs(1 / (1 + L) - S) <= 1e-9 * abs(S)
        G = isolation_prediction.return_matrix(loop, z)
        # A_j = 1 given, A_i = U_i: [1 - G_ii] A_i = G_ij; then U_j = G_j. @ A
        i = 1 - j
        A = np.zeros(2, complex)
        A[j], A[i] = 1.0, G[i, j] / (1 - G[i, i])
        assert abs(-(G @ A)[j] - L) <= 1e-12 * abs(L)
        assert np.allclose(A[i], (G @ A)[i])   # the other axis's loop is closed


def test_predicted_margins_of_the_ship_loop(loop):
    """Both axes stable with the classical margins of a well-damped loop (numbers in docs/frequency_response.md)."""
    for axis in ("1", "2"):
        margins = isolation_prediction.predicted_margins(loop, axis)
        assert 5 < margins.crossover_hz < 15
        assert 30 < margins.phase_margin_deg < 70
        assert 6 < margins.gain_margin_db < 20
        assert margins.crossover_hz < margins.phase_crossover_hz < 0.5 / loop.h


def test_margins_of_textbook_loops():
    """L = K / (s (s + 1) (s + 2)): -180 deg at w = sqrt(2), |L| = K / 6 there; the gain crossover from
    K = w sqrt(1 + w^2) sqrt(4 + w^2). L = K exp(-s T) / s: crossover w = K, phase margin 90 deg - K T;
    -180 deg first at w T = pi / 2, gain margin pi / (2 K T) (of its many phase crossings the smallest
    margin in dB). L = K / (s (s + 1)): no -180 deg crossing, the gain margin NaN."""
    from scipy.optimize import brentq

    f = np.logspace(-3, 2, 40000)
    s = 2j * math.pi * f
    K = 2.0
    m = isolation_prediction.stability_margins(f, K / (s * (s + 1) * (s + 2)))
    wc = brentq(lambda w: w * math.hypot(1, w) * math.hypot(2, w) - K, 1e-3, 10)
    assert m.phase_crossover_hz == pytest.approx(math.sqrt(2) / (2 * math.pi), rel=1e-5)
    assert m.gain_margin_db == pytest.approx(20 * math.log10(6 / K), abs=1e-4)
    assert m.crossover_hz == pytest.approx(wc / (2 * math.pi), rel=1e-5)
    assert m.phase_margin_deg == pytest.approx(180 - 90 - math.degrees(math.atan(wc) + math.atan(wc / 2)), abs=1e-3)

    K, T = 3.0, 0.1
    m = isolation_prediction.stability_margins(f, K * np.exp(-s * T) / s)
    assert m.crossover_hz == pytest.approx(K / (2 * math.pi), rel=1e-5)
    assert m.phase_margin_deg == pytest.approx(90 - math.degrees(K * T), abs=1e-3)
    assert m.phase_crossover_hz == pytest.approx(math.pi / 2 / T / (2 * math.pi), rel=1e-5)
    assert m.gain_margin_db == pytest.approx(20 * math.log10(math.pi / (2 * K * T)), abs=1e-4)

    m = isolation_prediction.stability_margins(f, 1.0 / (s * (s + 1)))
    assert math.isnan(m.phase_crossover_hz) and math.isnan(m.gain_margin_db)
    assert m.phase_margin_deg == pytest.approx(90 - math.degrees(math.atan(brentq(lambda w: w * math.hypot(1, w) - 1, 0.1, 10))), abs=1e-3)
    m = isolation_prediction.stability_margins(f, 0.5 / (s + 1))   # never reaches 1
    assert math.isnan(m.crossover_hz) and math.isnan(m.phase_margin_deg)
    with pytest.raises(SceneError, match="increasing"):
        isolation_prediction.stability_margins(f[::-1], K / s[::-1])


def test_the_injecting_controller_is_the_scenes_controller_plus_the_sine(ship_scene, gimbal_fmu):
    """Same references and outputs as the wrapped controller on the same inputs, plus D on one axis only;
    a bad axis named."""
    inner, twin = ship_scene.controller((24.0, 24.0)), ship_scene.controller((24.0, 24.0))
    wrapped = InjectingController(twin, "2", 0.3, 5.0)
    times = np.arange(3) * 1e-3
    for c in (inner, wrapped):
        c.prepare(times, 1e-3, np.zeros((3, 3)), np.zeros((3, 3)))
        c.start(1e-3, "test")
    for k, t in enumerate(times):
        args = (t, 1e-3, 0.01 * k, 0.02, (0.001, 0.0, -0.002), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        u, v = inner(*args, step=k), wrapped(*args, step=k)
        assert v[0] == u[0] and v[1] == pytest.approx(u[1] + 0.3 * math.sin(2 * math.pi * 5.0 * t), abs=1e-15)
        assert wrapped.reference == inner.reference
    from gimbal2axis.master.master import choose_loop

    assert choose_loop(wrapped, None) == "python"   # the compiled loop stays as it is
    with pytest.raises(SceneError, match="'3'"):
        InjectingController(inner, "3", 0.3, 5.0)
    with pytest.raises(ValueError, match="axis '1' or '2'"):
        Excitation("injection", "roll", 0.1)


def test_command_writes_rows_and_plot(fmu_path, tmp_path):
    import pathlib

    from gimbal2axis.cli.main import main

    ship = pathlib.Path(__file__).resolve().parents[3] / "scenes" / "ship_stabilization.toml"
    assert main(["freqresp", "loop-gain", "--scene", str(ship), "--axis", "2", "--amplitude", "0.05", "--points", "2",
                 "--fmin", "3", "--fmax", "30", "--linear-only", "--serial", "--settle-s", "1", "--measure-periods", "1",
                 "--fmu", str(fmu_path), "--out", str(tmp_path), "--name", "lg"]) == 0
    with open(tmp_path / "lg.csv") as f:
        rows = list(csv.DictReader(f))
    curves = {(r["curve"], r["output"]) for r in rows}
    for curve in ("no backlash, no dry friction", LINEAR_CURVE):
        assert {(curve, LOOP_GAIN), (curve, SENSITIVITY), (curve, "los.omega[1]")} <= curves
    assert len(rows) == 12
    measured = {round(float(r["frequency_hz"]), 6): float(r["gain"]) for r in rows
                if r["output"] == LOOP_GAIN and r["curve"] != LINEAR_CURVE}
    predicted = {round(float(r["frequency_hz"]), 6): float(r["gain"]) for r in rows
                 if r["output"] == LOOP_GAIN and r["curve"] == LINEAR_CURVE}
    assert measured.keys() == predicted.keys()
    assert all(measured[f] == pytest.approx(predicted[f], rel=1e-4) for f in measured)
    assert (tmp_path / "lg.png").stat().st_size > 10000
