"""The sea state's components in C (c_kernel/src/numpy_random.c, sea_state.c) against the numpy
code that made them before (kept here as the reference): numpy's default_rng([seed, index]) draws bit
for bit, the frequencies and phases bit for bit, the amplitudes bit for bit against the same
arithmetic done with libm's exp and pow (Python's math module), and within a few units in the last
place of numpy's own exp and pow, which may be SIMD code rounding the last bit differently."""
import math

import numpy as np
import pytest

from gimbal2axis import native
from gimbal2axis.scene.base_motion import seed_words, sea_state_components


def reference_components(significant_amplitude, peak_period, gamma, components, rng, band=(0.5, 3.0),
                         exp=np.exp, power=np.power):
    """base_motion.sea_state_components as it was in numpy (exp and power replaceable)."""
    wp = 2.0 * math.pi / peak_period
    edges = np.linspace(band[0] * wp, band[1] * wp, components + 1)
    dw = np.diff(edges)
    omega = edges[:-1] + rng.uniform(0.0, 1.0, components) * dw
    phase = rng.uniform(0.0, 2.0 * math.pi, components)
    sigma = np.where(omega <= wp, 0.07, 0.09)
    shape = power(omega, -5.0) * exp(-1.25 * power(wp / omega, 4.0))
    shape = shape * power(gamma, exp(-((omega - wp) ** 2) / (2.0 * sigma**2 * wp**2)))
    s = shape * dw
    amplitude = np.sqrt(2.0 * s / s.sum()) * (significant_amplitude / 2.0)
    return amplitude, omega, phase


def libm_exp(x):
    return np.array([math.exp(v) for v in np.atleast_1d(x)])


def libm_power(base, exponent):
    base, exponent = np.broadcast_arrays(np.asarray(base, dtype=float), np.asarray(exponent, dtype=float))
    return np.array([math.pow(b, e) for b, e in zip(base.ravel(), exponent.ravel())])


SPECTRA = [(math.radians(5.0), 9.0, 3.3), (math.radians(2.0), 7.0, 3.3), (math.radians(1.0), 12.0, 1.0),
           (1.0, 8.0, 3.3), (0.35, 5.5, 7.0), (2.5, 14.0, 1.5)]


def bits(x):
    return np.ascontiguousarray(x, dtype=np.float64).view(np.uint64)


def kernel_uniform(entropy, count, low, high):
    out = np.empty(count)
    native.kernel().gimbal_random_uniform(entropy.ctypes.data, len(entropy), count, low, high, out.ctypes.data)
    return out


@pytest.mark.parametrize("seed", [0, 1, 7, 12345, 2**31 - 1, 2**32 - 1, 2**32, 2**64 + 3, 2**100 + 2**70 + 11])
@pytest.mark.parametrize("index", [0, 3, 5, 2**40])
def test_draws_equal_numpys_default_rng(seed, index):
    entropy = seed_words(seed, index)   # up to 6 words: the pool of 4 and the words mixed in after it
    for low, high, count in ((0.0, 1.0, 300), (0.0, 2.0 * math.pi, 17), (-2.5, 1e3, 5)):
        expected = np.random.default_rng([seed, index]).uniform(low, high, count)
        assert np.array_equal(bits(kernel_uniform(entropy, count, low, high)), bits(expected))


def test_seed_words_refuse_a_negative_seed():
    with pytest.raises(ValueError, match="-1"):
        seed_words(-1, 0)


@pytest.mark.parametrize("count", list(range(0, 140)) + [255, 256, 257, 1000, 4099, 10007])
def test_pairwise_sum_equals_numpys_sum(count):
    x = np.random.default_rng(count).standard_normal(count) * np.logspace(-8, 8, count)
    assert bits(native.kernel().gimbal_pairwise_sum(x.ctypes.data, count)) == bits(x.sum())


@pytest.mark.parametrize("seed", [1, 7, 99, 2**33 + 1])
@pytest.mark.parametrize("index, spectrum", list(enumerate(SPECTRA)))
@pytest.mark.parametrize("components", [1, 7, 100, 120, 333])
def test_components_equal_the_numpy_reference(seed, index, spectrum, components):
    amplitude, omega, phase = sea_state_components(*spectrum, components, seed, index)
    numpy_amplitude, numpy_omega, numpy_phase = reference_components(
        *spectrum, components, np.random.default_rng([seed, index]))
    # What the generator draws, and the frequencies built from the draws: exact.
    assert np.array_equal(bits(omega), bits(numpy_omega))
    assert np.array_equal(bits(phase), bits(numpy_phase))
    # The same arithmetic with libm's exp and pow: exact.
    libm_amplitude, _, _ = reference_components(*spectrum, components, np.random.default_rng([seed, index]),
                                                exp=libm_exp, power=libm_power)
    assert np.array_equal(bits(amplitude), bits(libm_amplitude))
    # numpy's exp and pow: a few units in the last place, through the normalization.
    assert np.max(np.abs(amplitude - numpy_amplitude) / numpy_amplitude) < 1e-14
    sigma = spectrum[0] / 2.0
    assert math.isclose(float(np.sum(amplitude**2 / 2.0)), sigma**2, rel_tol=1e-13)


def test_other_bands_follow_the_reference():
    band = (0.3, 4.5)
    amplitude, omega, phase = sea_state_components(1.0, 8.0, 3.3, 64, 4, 2, band=band)
    libm_amplitude, numpy_omega, numpy_phase = reference_components(
        1.0, 8.0, 3.3, 64, np.random.default_rng([4, 2]), band=band, exp=libm_exp, power=libm_power)
    assert np.array_equal(bits(omega), bits(numpy_omega))
    assert np.array_equal(bits(amplitude), bits(libm_amplitude))


@pytest.mark.parametrize("arguments, message", [
    ((-1.0, 8.0, 3.3, 10), "significant amplitude"), ((math.nan, 8.0, 3.3, 10), "significant amplitude"),
    ((1.0, 0.0, 3.3, 10), "peak period"), ((1.0, math.inf, 3.3, 10), "peak period"),
    ((1.0, 8.0, 0.9, 10), "gamma"), ((1.0, 8.0, math.nan, 10), "gamma"), ((1.0, 8.0, 3.3, 0), "components")])
def test_bad_arguments_are_refused(arguments, message):
    with pytest.raises(ValueError, match=message):
        sea_state_components(*arguments, seed=1, index=0)


@pytest.mark.parametrize("band", [(0.0, 3.0), (3.0, 3.0), (2.0, 1.0), (0.5, math.inf), (math.nan, 3.0)])
def test_bad_bands_are_refused(band):
    with pytest.raises(ValueError, match="band"):
        sea_state_components(1.0, 8.0, 3.3, 10, seed=1, index=0, band=band)
