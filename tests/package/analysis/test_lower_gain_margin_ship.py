"""The ship scene's elevation loop is conditionally stable (issue 45.3): the top-heavy payload makes the
plant open-loop unstable, so the loop broken at motor 2 passes -180 deg where |L| > 1, and the gain may
not drop by more than the lower gain margin. Reported by the margins helper (against the closed loop's
poles in the time domain), by `freqresp loop-gain`'s printed summary and by the tuning's margins."""
import dataclasses
import math

import numpy as np
import pytest

from gimbal2axis.analysis import isolation_prediction
from gimbal2axis.analysis.frequency_response import Excitation


@pytest.fixture(scope="module")
def elevation(ship_linear_loop):
    """The dense prediction's margins of the loop broken at motor 2."""
    return isolation_prediction.predicted_margins(ship_linear_loop, "2")


def _elevation_scaled(loop, k: float):
    """The loop with the elevation controller's feedback gains times k: L broken at motor 2 times k."""
    el = loop.axes[1]
    return dataclasses.replace(loop, axes=(loop.axes[0], dataclasses.replace(
        el, kp=k * el.kp, ki=k * el.ki, kd=k * el.kd, k_gyro=k * el.k_gyro)))


def _spectral_radius(loop) -> float:
    return float(np.max(np.abs(isolation_prediction.closed_loop_poles(loop))))


def test_the_elevation_loop_has_a_lower_gain_margin_at_the_stability_edge(ship_linear_loop, elevation):
    """The plant has a pole outside the unit circle (the payload falling, ~ +0.34 1/s); the elevation loop's
    lower gain margin is negative, a few Hz, and is where the closed loop (its poles from the time-domain
    transition matrix, not from L) goes unstable: stable with the gains 2 % above that drop, unstable 2 %
    below. The azimuth (balanced) has none. The upper margin is the one docs/frequency_response.md gives."""
    loop = ship_linear_loop
    growth_per_s = math.log(np.max(np.abs(np.linalg.eigvals(loop.plant.Phi)))) / loop.h
    assert 0.1 < growth_per_s < 1.0

    assert elevation.lower_gain_margin_db < -6
    assert 0.5 < elevation.lower_phase_crossover_hz < elevation.crossover_hz
    assert 6 < elevation.gain_margin_db < 20 and elevation.phase_crossover_hz > elevation.crossover_hz
    edge = 10 ** (elevation.lower_gain_margin_db / 20)
    assert _spectral_radius(_elevation_scaled(loop, edge * 1.02)) < 1 < _spectral_radius(_elevation_scaled(loop, edge * 0.98))

    azimuth = isolation_prediction.predicted_margins(loop, "1")
    assert math.isnan(azimuth.lower_gain_margin_db)


def test_freqresp_loop_gain_prints_the_lower_margin(ship_scene, fmu_path, elevation):
    """`freqresp loop-gain --axis 2`'s printed prediction names the lower gain margin and its frequency."""
    from gimbal2axis.analysis.linear_prediction import linear_prediction

    _, _, summary = linear_prediction(ship_scene, fmu_path, Excitation("injection", "2", 0.2),
                                      ["loop_gain"], 0.1, 100.0)
    assert (f"-180 deg at {elevation.lower_phase_crossover_hz:.4g} Hz, lower gain margin "
            f"{elevation.lower_gain_margin_db:.3g} dB") in summary


def test_the_tunings_margins_carry_the_lower_margin(ship_linear_loop, elevation):
    """tune.margins.frequency_response (800 points) finds the dense prediction's lower margin to 0.05 dB,
    and gain margins each side of 0 dB (python-control alone gives one, the nearest 0 dB); the azimuth's
    lower margin is -inf (no crossing: its gain may drop to nothing)."""
    from gimbal2axis.tune.margins import frequency_response

    sampled = frequency_response(ship_linear_loop, "2")
    assert sampled["lower_gm_db"] == pytest.approx(elevation.lower_gain_margin_db, abs=0.05)
    assert sampled["lower_gm_hz"] == pytest.approx(elevation.lower_phase_crossover_hz, rel=1e-3)
    assert sampled["gm_db"] == pytest.approx(elevation.gain_margin_db, abs=0.05)
    assert frequency_response(ship_linear_loop, "1")["lower_gm_db"] == -math.inf
