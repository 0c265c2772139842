"""The lower gain margin of a conditionally stable loop (issue 45.3): a loop around an open-loop unstable
plant passes -180 deg twice, once where |L| > 1 (how much the gain may drop) and once where |L| < 1 (how
much it may rise). The margins helper against root-finding on the exact phase and against the closed
loop's poles; the tuning's constraint on it. Pure Python (no FMU)."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from gimbal2axis.analysis import isolation_prediction
from gimbal2axis.tune import objective, spec

pytestmark = pytest.mark.python_bound

# L(s) = K (s + z) / (s (s - p) (s / b + 1)^2): an integrator, an unstable pole at +p, a lead zero, two lags
P, Z, B, K = 1.0, 2.0, 20.0, 5.0


def loop_gain(w):
    s = 1j * np.asarray(w)
    return K * (s + Z) / (s * (s - P) * (s / B + 1) ** 2)


def phase_deg(w: float) -> float:
    """The exact phase of L (continuous in w): -270 deg at w -> 0, back to -270 deg at w -> infinity."""
    return -270.0 + math.degrees(math.atan(w / P) + math.atan(w / Z) - 2 * math.atan(w / B))


def closed_loop_unstable(k: float) -> bool:
    """A root of s (s - p) (s / b + 1)^2 + k K (s + z) in the right half plane."""
    lags = np.polymul([1 / B, 1.0], [1 / B, 1.0])
    characteristic = np.polyadd(np.polymul(np.polymul([1.0, 0.0], [1.0, -P]), lags), k * K * np.array([1.0, Z]))
    return bool(np.max(np.roots(characteristic).real) > 0)


def test_both_gain_margins_of_a_conditionally_stable_loop():
    """-180 deg at w1 ~ 1.69 rad/s with |L| > 1 (lower margin ~ -11.8 dB) and at w2 ~ 16.7 rad/s with
    |L| < 1 (upper ~ +15.0 dB): both found, each with its frequency, to 1e-5; and they are the edges of the
    stable range of a gain factor on L (the closed loop's poles just inside and just outside each edge).
    The helper used to report only the crossing nearest 0 dB, here the lower one, as 'the gain margin'."""
    w_lower = brentq(lambda w: phase_deg(w) + 180.0, 0.1, 5.0)
    w_upper = brentq(lambda w: phase_deg(w) + 180.0, 5.0, 100.0)
    lower_db = -20 * math.log10(abs(loop_gain(w_lower)))
    upper_db = -20 * math.log10(abs(loop_gain(w_upper)))
    assert lower_db < -6 and upper_db > 6   # the loop is what the test means: two crossings, either side of 1

    f = np.logspace(-3, 3, 40000)
    m = isolation_prediction.stability_margins(f, loop_gain(2 * math.pi * f))
    assert m.lower_gain_margin_db == pytest.approx(lower_db, abs=1e-4)
    assert m.lower_phase_crossover_hz == pytest.approx(w_lower / (2 * math.pi), rel=1e-5)
    assert m.gain_margin_db == pytest.approx(upper_db, abs=1e-4)
    assert m.phase_crossover_hz == pytest.approx(w_upper / (2 * math.pi), rel=1e-5)
    assert "lower gain margin -11.8 dB" in m.describe()

    assert not closed_loop_unstable(1.0)
    for margin_db in (m.lower_gain_margin_db, m.gain_margin_db):
        edge = 10 ** (margin_db / 20)
        inside, outside = (edge * 1.01, edge * 0.99) if margin_db < 0 else (edge * 0.99, edge * 1.01)
        assert not closed_loop_unstable(inside) and closed_loop_unstable(outside), margin_db


def test_a_loop_without_a_crossing_above_1_has_no_lower_margin():
    """L = 2 / (s (s + 1) (s + 2)): one -180 deg crossing, with |L| < 1; the lower margin NaN and not said."""
    f = np.logspace(-3, 2, 20000)
    s = 2j * math.pi * f
    m = isolation_prediction.stability_margins(f, 2.0 / (s * (s + 1) * (s + 2)))
    assert math.isnan(m.lower_gain_margin_db) and math.isnan(m.lower_phase_crossover_hz)
    assert m.gain_margin_db == pytest.approx(20 * math.log10(3.0), abs=1e-4)
    assert "lower" not in m.describe()


class _Tuning:
    def __init__(self, constraints):
        self.constraints = constraints
        self.objective = spec.Objective((spec.Term("los_rms"),))


def _judged(lower_limit_db: float, margins: dict) -> dict:
    constraints = spec._constraints({"lower_gain_margin_min_db": lower_limit_db})
    assert constraints.needs_margins
    rows = [{"status": "ok", "los_rms_mrad": 0.1, "i_frac_peak": 0.1, "u_sat_s": 0.0}]
    return objective.judge(_Tuning(constraints), rows, margins).violations


def test_the_tuning_constrains_the_lower_gain_margin():
    """`lower_gain_margin_min_db = 20`: a loop whose gain may drop by 37 dB meets it, one that may drop by 17
    dB violates it by (20 - 17) / 20; an axis without a lower margin (-inf) does not count; an unstable
    linear loop violates it by 1; a negative limit or a non-number refused with the key named."""
    stable = {"linear_stable": True, "lower_gm_az_db": -math.inf}
    assert _judged(20.0, {**stable, "lower_gm_el_db": -37.0})["lower_gain_margin"] < 0
    assert _judged(20.0, {**stable, "lower_gm_el_db": -17.0})["lower_gain_margin"] == pytest.approx(3 / 20)
    assert _judged(20.0, {**stable, "lower_gm_el_db": -math.inf})["lower_gain_margin"] < 0
    assert _judged(20.0, {"linear_stable": False, "lower_gm_az_db": math.nan,
                          "lower_gm_el_db": math.nan})["lower_gain_margin"] == 1.0
    with pytest.raises(spec.TuneError, match=r"\[constraints\] lower_gain_margin_min_db"):
        spec._constraints({"lower_gain_margin_min_db": "big"})
    with pytest.raises(spec.TuneError, match=r"\[constraints\] lower_gain_margin_min_db"):
        spec._constraints({"lower_gain_margin_min_db": -6.0})
