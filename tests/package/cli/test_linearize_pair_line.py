"""`gimbal2axis linearize --bode` prints each pair's DC gain and -3 dB frequency (cli.linearize.pair_line):
the figures the README quotes of the azimuth axis (tests/docs/test_docs_commands.py runs that command). Here
on transfer functions whose answers are known: a first-order lag, an integrator, a zero path."""
import math

import numpy as np

from gimbal2axis.cli.linearize import pair_line


class Path:
    """A model with one transfer function G(s) from 'u' to 'y'."""

    def __init__(self, G, zero=False):
        self.G, self.zero = G, zero

    def frequency_response(self, frequencies_hz, source, target):
        return np.array([self.G(2j * math.pi * f) for f in np.atleast_1d(frequencies_hz)])

    def zero_path_warning(self, source, target):
        return "held" if self.zero else None


def test_a_first_order_lag_has_its_gain_and_its_pole_as_the_3_db_frequency():
    pole_hz, gain = 4.175, -0.2063
    lag = Path(lambda s: gain / (1 + s / (2 * math.pi * pole_hz)))
    assert pair_line(lag, "u", "y", 1000.0) == "u -> y: DC gain -0.2063 (-13.71 dB), -3 dB at 4.175 Hz"


def test_an_integrator_has_no_dc_gain_and_a_zero_path_no_line():
    assert "integrates at low frequency" in pair_line(Path(lambda s: 3.0 / s), "u", "y", 1000.0)
    assert pair_line(Path(lambda s: 0.0 * s, zero=True), "u", "y", 1000.0) is None


def test_a_gain_that_never_drops_says_so():
    assert pair_line(Path(lambda s: 2.0 + 0 * s), "u", "y", 100.0) == \
        "u -> y: DC gain 2 (6.02 dB), no -3 dB point up to 100 Hz"
