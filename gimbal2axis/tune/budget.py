"""A pointing error budget per axis from a run's own line-of-sight error over its metrics window:

  bias     the mean (the static pointing offset; the PSD is taken with it removed)
  drift    the linear trend of the error over the window: its slope [mrad/s] and its RMS about the mean
  jitter   the RMS of the error (mean removed) in each band, from the Welch PSD of the run
           (gimbal2axis.master.spectra.psd, the scene's psd_resolution_hz): sea [0, f_sea), loop
           [f_sea, f_high), high [f_high, Nyquist]; the bands tile [0, Nyquist], so their root-sum-square
           is the standard deviation (up to Welch's end weighting)
  total    sqrt(bias^2 + jitter sea^2 + loop^2 + high^2), against the RMS of the error itself

Axes: cross-elevation (los_error_xel) and elevation (los_error_el), in mrad. The default band edges:
1 Hz (a sea's energy lies below it) and 30 Hz (a few times the loops' crossovers of 5 to 10 Hz).
"""
from __future__ import annotations

import math

import numpy as np

SEA_HZ, HIGH_HZ = 1.0, 30.0
AXES = {"xel": "los_error_xel", "el": "los_error_el"}


def budget(result, from_s: float | None, sea_hz: float = SEA_HZ, high_hz: float = HIGH_HZ) -> dict:
    """{axis: {bias, drift_slope_per_s, drift_rms, sea, loop, high, total, rms}} in mrad (slope in mrad/s)."""
    from ..master import spectra

    window = result.metrics_window(from_s)
    t = result.signals["time"][window]
    fs = 1.0 / result.scene.step_size
    nyquist = 0.5 * fs
    out = {}
    for axis, name in AXES.items():
        e = np.asarray(result.derived[name][window], float)
        mean = float(np.mean(e))
        slope, intercept = np.polyfit(t - t[0], e, 1) if len(e) > 2 else (0.0, mean)
        trend = slope * (t - t[0]) + intercept
        spectrum = spectra.psd(e, fs, result.scene.analysis.psd_resolution_hz)
        bands = {"sea": spectrum.band_rms(0.0, sea_hz), "loop": spectrum.band_rms(sea_hz, high_hz),
                 "high": spectrum.band_rms(high_hz, nyquist)}
        total = math.sqrt(mean ** 2 + sum(v ** 2 for v in bands.values()))
        out[axis] = {"bias": mean * 1e3, "drift_slope_per_s": float(slope) * 1e3,
                     "drift_rms": float(np.sqrt(np.mean((trend - mean) ** 2))) * 1e3,
                     **{k: v * 1e3 for k, v in bands.items()}, "total": total * 1e3,
                     "rms": float(np.sqrt(np.mean(e ** 2))) * 1e3}
    return out


def spectra_of(result, from_s: float | None) -> dict:
    """{axis: (frequency [Hz], PSD [mrad^2/Hz])} over the metrics window."""
    from ..master import spectra

    window = result.metrics_window(from_s)
    fs = 1.0 / result.scene.step_size
    out = {}
    for axis, name in AXES.items():
        spectrum = spectra.psd(np.asarray(result.derived[name][window], float), fs, result.scene.analysis.psd_resolution_hz)
        out[axis] = (spectrum.frequency, spectrum.psd * 1e6)
    return out
