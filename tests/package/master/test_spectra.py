"""The spectra of gimbal2axis.master.spectra against what is known in closed form: Parseval (the PSD
integrates to the variance, also for a sea-like signal whose periods are longer than a segment), a
sine's power in its bin and band, the cumulative RMS's top, bands adding in quadrature, and the H1
estimate of a known first-order low-pass."""
import math

import numpy as np
import pytest
from scipy import signal

from gimbal2axis.master import spectra

pytestmark = pytest.mark.python_bound

FS = 1000.0


def sea_like(seconds: float = 600.0, seed: int = 3) -> np.ndarray:
    """A sum of 120 sinusoids with random phases around a 9-s peak period, plus a mean: most of its
    power is at periods longer than a 2-s segment."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / FS)
    f = np.linspace(0.05, 0.4, 120)
    amplitude = np.exp(-((f - 1 / 9.0) / 0.04) ** 2)
    x = 0.7 + sum(a * np.sin(2 * math.pi * fi * t + p) for a, fi, p in zip(amplitude, f, rng.uniform(0, 2 * math.pi, f.size)))
    return x


def integral(spectrum) -> float:
    return float(np.sum(spectrum.psd) * spectrum.resolution)


def test_the_psd_integrates_to_the_variance_of_white_noise():
    x = np.random.default_rng(1).normal(0.3, 2.0, 400_000)
    spectrum = spectra.psd(x, FS, 0.5)
    assert spectrum.resolution == pytest.approx(0.5)
    assert integral(spectrum) == pytest.approx(np.var(x), rel=0.01)
    assert spectrum.mean == pytest.approx(np.mean(x))


def test_the_psd_integrates_to_the_variance_of_a_sea_like_signal_longer_than_its_segments():
    # a per-segment detrend would lose most of this power (its periods are 4x a segment)
    x = sea_like()
    spectrum = spectra.psd(x, FS, 0.5)
    assert integral(spectrum) == pytest.approx(np.var(x), rel=0.01)
    assert spectrum.mean == pytest.approx(np.mean(x))


@pytest.mark.parametrize("frequency", [12.5, 37.3])   # on a bin, and between bins
def test_a_sine_lands_in_its_bin_and_its_band_holds_its_power(frequency):
    amplitude = 0.004
    t = np.arange(0.0, 40.0, 1.0 / FS)
    spectrum = spectra.psd(amplitude * np.sin(2 * math.pi * frequency * t + 0.3), FS, 0.5)
    peak = spectrum.frequency[np.argmax(spectrum.psd)]
    assert abs(peak - frequency) <= spectrum.resolution / 2 + 1e-12
    band = spectrum.band_rms(frequency - 3.0, frequency + 3.0)
    assert band == pytest.approx(amplitude / math.sqrt(2), rel=0.01)
    assert spectrum.band_rms(0.0, frequency - 5.0) < 1e-3 * band


def test_the_cumulative_rms_rises_to_the_standard_deviation():
    x = sea_like(300.0) + np.random.default_rng(2).normal(0.0, 0.05, int(300 * FS))
    spectrum = spectra.psd(x, FS, 0.25)
    cumulative = spectrum.cumulative_rms()
    assert np.all(np.diff(cumulative) >= 0)
    assert cumulative[-1] == pytest.approx(np.std(x), rel=0.01)


def test_adjacent_bands_add_in_quadrature_to_the_whole_spectrum():
    x = sea_like(200.0) + np.random.default_rng(4).normal(0.0, 0.1, int(200 * FS))
    spectrum = spectra.psd(x, FS, 0.5)
    edges = [0.0, 1.0, 10.0, FS / 2]
    bands = [spectrum.band_rms(lo, hi) for lo, hi in zip(edges[:-1], edges[1:])]
    total = math.sqrt(integral(spectrum))
    assert math.sqrt(sum(b * b for b in bands)) == pytest.approx(total, rel=1e-12)
    assert spectrum.cumulative_rms()[-1] == pytest.approx(total, rel=1e-12)


def test_a_band_needs_its_lower_edge_below_its_upper_one():
    spectrum = spectra.psd(np.sin(np.arange(1000.0)), FS, 10.0)
    with pytest.raises(ValueError, match="f_lo < f_hi"):
        spectrum.band_rms(5.0, 5.0)


def test_a_signal_shorter_than_a_segment_is_one_coarser_segment():
    x = np.random.default_rng(5).normal(size=500)
    spectrum = spectra.psd(x, FS, 0.5)   # 2000 samples asked for
    assert spectrum.segments == 1 and spectrum.resolution == pytest.approx(2.0)


def test_the_h1_estimate_recovers_a_first_order_low_pass():
    corner = 20.0
    rng = np.random.default_rng(6)
    x = rng.normal(size=int(200 * FS))
    b, a = signal.bilinear([2 * math.pi * corner], [1.0, 2 * math.pi * corner], fs=FS)
    y = signal.lfilter(b, a, x) + rng.normal(0.0, 0.05, x.size)   # noise on the output: H1 stays unbiased
    estimate = spectra.transfer_estimate(x, y, FS, 1.0)
    _, exact = signal.freqz(b, a, worN=estimate.frequency, fs=FS)
    usable = (estimate.frequency >= 1.0) & (estimate.frequency <= 100.0)
    assert np.all(estimate.coherence[usable] > 0.9)
    assert np.abs(estimate.response[usable]) == pytest.approx(np.abs(exact[usable]), rel=0.03)
    at_corner = np.argmin(np.abs(estimate.frequency - corner))
    assert abs(estimate.response[at_corner]) == pytest.approx(1 / math.sqrt(2), rel=0.03)


def test_coherence_is_low_where_the_output_is_unrelated():
    rng = np.random.default_rng(7)
    x, y = rng.normal(size=int(100 * FS)), rng.normal(size=int(100 * FS))
    estimate = spectra.transfer_estimate(x, y, FS, 1.0)
    assert estimate.segments == 199
    assert np.mean(estimate.coherence) < 0.02
