"""Spectra of a run's signals: Welch power spectral density, cumulative RMS over frequency, RMS in
a band, and the H1 transfer estimate with its coherence and the coherence below which its random error
exceeds H1_RANDOM_ERROR. Pure functions of numpy arrays.

Conventions (docs/jitter.md):

- One-sided PSD [unit^2/Hz] by Welch's method: Hann window, 50 % overlap, segments of
  `segment_length(sample_rate, resolution_hz)` samples, so the bins are `resolution` apart (the
  resolution actually used is sample_rate / segment, returned with the spectrum).
- The mean over the whole window is removed once, not per segment: a per-segment detrend would
  throw away the power at periods longer than a segment (a sea's 10-s swell under 2-s segments);
  kept, it lands in the lowest bins. So the PSD and its cumulative RMS account for the signal's
  variance, and the mean (a static pointing offset) is reported separately. Exactly (Parseval, per
  segment), sum(PSD) * df is the mean square of the samples weighted by welch_sample_weights: the
  segments' squared Hann windows summed, which taper over the first and last half segment and, at
  50 % overlap, swing between 1/2 and 1 of their peak once per step inside. For a stationary signal
  that is its variance up to the estimate's statistics (within 1 % on noise: tests/package/master/test_cumulative_rms.py);
  a window whose power is not evenly spread (a transient at its start, a sea of few long periods)
  gets a top of the cumulative RMS some per cent off the window's standard deviation (docs/jitter.md).
- Integrals are sums over bins times the bin width df (a bin holds the power around its centre);
  a bin belongs to the band [f_lo, f_hi) when its centre frequency does, and a band reaching the
  Nyquist frequency also holds the Nyquist bin, so bands that tile [0, Nyquist] tile the spectrum.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

WINDOW = "hann"
OVERLAP = 0.5


def hann_window(n: int) -> np.ndarray:
    """scipy.signal.get_window(WINDOW, n), the periodic Hann window welch uses, computed as scipy
    computes it (bit for bit: tests/layout/test_package_layout.py) without importing scipy.signal, which
    takes 0.5 s: `gimbal2axis run` needs the window and nothing else of it."""
    if n == 1:
        return np.ones(1)
    return (0.5 + 0.5 * np.cos(np.linspace(-np.pi, np.pi, n + 1)))[:n]


@dataclass(frozen=True)
class Spectrum:
    frequency: np.ndarray       # Hz, 0 to Nyquist, `resolution` apart
    psd: np.ndarray             # one-sided power spectral density, unit^2/Hz
    resolution: float           # Hz, the bin width df
    segments: int               # segments averaged
    mean: float                 # the mean removed before the estimate (the static part)

    def cumulative_rms(self) -> np.ndarray:
        return cumulative_rms(self.psd, self.resolution)

    def band_rms(self, f_lo: float, f_hi: float) -> float:
        return band_rms(self.frequency, self.psd, self.resolution, f_lo, f_hi)


def segment_length(sample_rate: float, resolution_hz: float) -> int:
    """Samples per Welch segment for bins `resolution_hz` apart (rounded to whole samples)."""
    if not (sample_rate > 0 and resolution_hz > 0):
        raise ValueError(f"need a positive sample rate and resolution, got {sample_rate!r}, {resolution_hz!r}")
    return max(2, int(round(sample_rate / resolution_hz)))


def segment_count(samples: int, segment: int) -> int:
    """Segments Welch averages over `samples` with 50 % overlap."""
    step = segment - int(segment * OVERLAP)
    return 0 if samples < segment else 1 + (samples - segment) // step


def psd(x, sample_rate: float, resolution_hz: float) -> Spectrum:
    """One-sided Welch PSD of `x` (module docstring). A signal shorter than one segment is taken as
    a single segment of its own length: a coarser resolution, which the Spectrum reports."""
    from scipy import signal

    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise ValueError(f"need a 1-D signal of at least 2 samples, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("the signal has non-finite samples")
    segment = min(segment_length(sample_rate, resolution_hz), x.size)
    mean = float(np.mean(x))
    frequency, density = signal.welch(x - mean, fs=sample_rate, window=WINDOW, nperseg=segment,
                                      noverlap=int(segment * OVERLAP), detrend=False, return_onesided=True,
                                      scaling="density")
    return Spectrum(frequency, density, sample_rate / segment, segment_count(x.size, segment), mean)


def cumulative_rms(density: np.ndarray, resolution: float) -> np.ndarray:
    """sqrt of the running integral of the PSD from 0 Hz up to each bin (inclusive): at the top, the RMS
    about the mean of the samples weighted by welch_sample_weights (for a stationary signal, its
    standard deviation; module docstring)."""
    return np.sqrt(np.cumsum(np.asarray(density, dtype=float)) * resolution)


def welch_sample_weights(samples: int, segment: int) -> np.ndarray:
    """The weight of each sample in psd's integral: the squared windows of the segments Welch averages
    (WINDOW, OVERLAP), summed. sum(PSD) * df = sum(weights (x - mean)^2) / sum(weights); samples after
    the last whole segment weigh 0."""
    segment = min(segment, samples)
    window = hann_window(segment) ** 2
    step = segment - int(segment * OVERLAP)
    weights = np.zeros(samples)
    for start in range(0, segment_count(samples, segment) * step, step):
        weights[start:start + segment] += window
    return weights


def band_mask(frequency: np.ndarray, f_lo: float, f_hi: float) -> np.ndarray:
    """The bins of [f_lo, f_hi) (by centre frequency); with the Nyquist bin when f_hi reaches it."""
    frequency = np.asarray(frequency, dtype=float)
    mask = (frequency >= f_lo) & (frequency < f_hi)
    if f_hi >= frequency[-1]:
        mask |= frequency >= max(f_lo, frequency[-1])
    return mask


def band_rms(frequency: np.ndarray, density: np.ndarray, resolution: float, f_lo: float, f_hi: float) -> float:
    """RMS of the part of the signal in [f_lo, f_hi): sqrt(sum of the band's PSD bins * df)."""
    if not f_lo < f_hi:
        raise ValueError(f"a band needs f_lo < f_hi, got [{f_lo:g}, {f_hi:g})")
    return float(math.sqrt(np.sum(np.asarray(density)[band_mask(frequency, f_lo, f_hi)]) * resolution))


# The random error an H1 estimate is read to: 1 sigma of 10 % in gain (0.8 dB) and, the same expression,
# 0.1 rad (5.7 deg) in phase. A choice of accuracy, not a property of the data: the isolation is read
# in dB over decades, where 0.8 dB is below what the eye separates on the plot, while an estimate with
# a larger error is one the plot would show as a gain it does not know. Bins whose estimate is worse are
# masked (coherence_bound).
H1_RANDOM_ERROR = 0.1


def independent_segments(segments: int, segment: int) -> float:
    """The number of independent averages that `segments` Welch segments of `segment` samples (WINDOW,
    OVERLAP) are worth: overlapping segments are correlated, and the variance of the averaged estimate is
    (1 / K) (1 + 2 (K - 1) / K rho^2), rho the window's overlap correlation sum(w[i] w[i + step]) /
    sum(w^2) (Welch 1967; Hann at 50 %: rho = 0.167, so K segments are worth about 0.95 K)."""
    if segments < 1:
        return 0.0
    window = hann_window(segment)
    step = segment - int(segment * OVERLAP)
    rho = float(np.dot(window[:segment - step], window[step:]) / np.dot(window, window)) if step < segment else 0.0
    return segments / (1 + 2 * (segments - 1) / segments * rho * rho)


def h1_random_error(coherence, averages: float) -> np.ndarray:
    """The normalized random error (1 sigma) of the H1 gain, and in radians of its phase, at the given
    magnitude-squared coherence from `averages` independent averages (Bendat & Piersol, Random Data,
    eq. 9.52 and 9.73): sqrt(1 - coherence) / (sqrt(coherence) sqrt(2 averages)); inf at coherence 0,
    nan where the coherence is."""
    coherence = np.asarray(coherence, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(1 - coherence) / np.sqrt(coherence * 2 * max(averages, 0.0))


def coherence_bound(averages: float, relative_error: float = H1_RANDOM_ERROR) -> float:
    """The magnitude-squared coherence below which h1_random_error exceeds `relative_error`:
    1 / (1 + 2 averages relative_error^2) (e.g. 46 Hann segments at 50 %: 0.54; 10: 0.84; 2: 0.96)."""
    return 1.0 / (1.0 + 2.0 * averages * relative_error ** 2)


@dataclass(frozen=True)
class TransferEstimate:
    frequency: np.ndarray       # Hz
    response: np.ndarray        # H1 = S_xy / S_xx, complex
    coherence: np.ndarray       # magnitude-squared coherence, 0..1
    resolution: float           # Hz
    segments: int
    segment: int = 0            # samples per segment (0: unknown, then the segments count as independent)

    @property
    def averages(self) -> float:
        """The independent averages the segments are worth (independent_segments)."""
        return independent_segments(self.segments, self.segment) if self.segment else float(self.segments)

    @property
    def random_error(self) -> np.ndarray:
        """h1_random_error per bin: the 1-sigma relative error of |H1| (and in rad of its phase)."""
        return h1_random_error(self.coherence, self.averages)

    @property
    def coherence_bound(self) -> float:
        """The coherence below which a bin's H1 has more than H1_RANDOM_ERROR of random error."""
        return coherence_bound(self.averages)

    @property
    def coherent(self) -> np.ndarray:
        """The bins whose H1 is known to H1_RANDOM_ERROR (False where the coherence is nan). None from a
        single segment: its coherence is 1 by construction (|S_xy|^2 = S_xx S_yy for one periodogram)."""
        if self.segments < 2:
            return np.zeros(self.coherence.shape, dtype=bool)
        return np.nan_to_num(self.coherence, nan=-1.0) >= self.coherence_bound


def transfer_estimate(x, y, sample_rate: float, resolution_hz: float) -> TransferEstimate:
    """The H1 estimate of the transfer from input `x` to output `y`, H1 = S_xy / S_xx (unbiased by
    noise on the output), and the magnitude-squared coherence |S_xy|^2 / (S_xx S_yy), both by Welch
    with the PSD's window, overlap and mean removal. Where the input has no power (S_xx = 0) H1 is nan.
    Coherence from K segments is biased up by about 1/K where there is no relation; the estimate's
    `coherent` bins are those whose H1 has at most H1_RANDOM_ERROR of random error (coherence_bound)."""
    from scipy import signal

    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.shape != y.shape or x.ndim != 1 or x.size < 2:
        raise ValueError(f"need two 1-D signals of the same length (>= 2), got {x.shape} and {y.shape}")
    segment = min(segment_length(sample_rate, resolution_hz), x.size)
    options = dict(fs=sample_rate, window=WINDOW, nperseg=segment, noverlap=int(segment * OVERLAP), detrend=False)
    x, y = x - x.mean(), y - y.mean()
    frequency, s_xx = signal.welch(x, **options)
    _, s_yy = signal.welch(y, **options)
    _, s_xy = signal.csd(x, y, **options)
    with np.errstate(divide="ignore", invalid="ignore"):
        response = np.where(s_xx > 0, s_xy / s_xx, np.nan)
        coherence = np.where((s_xx > 0) & (s_yy > 0), np.abs(s_xy) ** 2 / (s_xx * s_yy), np.nan)
    return TransferEstimate(frequency, response, np.clip(coherence, 0.0, 1.0), sample_rate / segment,
                            segment_count(x.size, segment), segment)


class WelchAccumulator:
    """psd and transfer_estimate of signals too long to hold, fed a chunk at a time (a run streamed
    to disk, master/streaming.py): the same segments, window, overlap, scaling and mean removal as
    scipy's welch and csd do over the whole signal, so the same estimate up to the order of the
    sums (the segments' periodograms are summed in order instead of averaged by numpy's pairwise
    mean: the last bits may differ).

    `means`: {signal: its mean over the samples that will be fed} (found by a first pass);
    `samples`: how many will be fed; `pairs`: the (x, y) whose cross spectrum is wanted."""

    def __init__(self, sample_rate: float, resolution_hz: float, samples: int, means: dict, pairs=()):
        if samples < 2:
            raise ValueError(f"need at least 2 samples, got {samples}")
        self.sample_rate, self.samples, self.means = sample_rate, samples, dict(means)
        self.segment = min(segment_length(sample_rate, resolution_hz), samples)
        self.step = self.segment - int(self.segment * OVERLAP)
        self.window = hann_window(self.segment)
        self.scale = 1.0 / (sample_rate * np.sum(self.window * self.window))
        self.pairs = list(pairs)
        self.pending = {name: np.empty(0) for name in self.means}
        self.power = {name: 0.0 for name in self.means}
        self.cross = {pair: 0.0 for pair in self.pairs}
        self.segments = 0

    def feed(self, chunk: dict) -> None:
        """The next samples of every signal (equal lengths)."""
        for name in self.pending:
            self.pending[name] = np.concatenate([self.pending[name], np.asarray(chunk[name], dtype=float)])
        while len(next(iter(self.pending.values()))) >= self.segment:
            spectra = {name: np.fft.rfft(self.window * (x[:self.segment] - self.means[name]))
                       for name, x in self.pending.items()}
            for name, values in spectra.items():
                self.power[name] = self.power[name] + (np.conjugate(values) * values).real
            for x, y in self.pairs:
                self.cross[(x, y)] = self.cross[(x, y)] + np.conjugate(spectra[x]) * spectra[y]
            self.segments += 1
            self.pending = {name: x[self.step:] for name, x in self.pending.items()}

    def _one_sided(self, summed):
        density = summed * (self.scale / self.segments)
        if self.segment % 2 == 0:
            density[1:-1] *= 2
        else:
            density[1:] *= 2
        return density

    @property
    def frequency(self) -> np.ndarray:
        return np.fft.rfftfreq(self.segment, 1.0 / self.sample_rate)

    def spectrum(self, name: str) -> Spectrum:
        return Spectrum(self.frequency, self._one_sided(np.array(self.power[name], dtype=float)),
                        self.sample_rate / self.segment, self.segments, float(self.means[name]))

    def transfer(self, x: str, y: str) -> TransferEstimate:
        s_xx = self._one_sided(np.array(self.power[x], dtype=float))
        s_yy = self._one_sided(np.array(self.power[y], dtype=float))
        s_xy = self._one_sided(np.array(self.cross[(x, y)], dtype=complex))
        with np.errstate(divide="ignore", invalid="ignore"):
            response = np.where(s_xx > 0, s_xy / s_xx, np.nan)
            coherence = np.where((s_xx > 0) & (s_yy > 0), np.abs(s_xy) ** 2 / (s_xx * s_yy), np.nan)
        return TransferEstimate(self.frequency, response, np.clip(coherence, 0.0, 1.0), self.sample_rate / self.segment,
                                self.segments, self.segment)
