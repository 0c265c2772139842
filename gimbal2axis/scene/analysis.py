"""A scene's [analysis] table: how the line-of-sight error's spectrum is estimated and which
frequency bands its RMS is reported in (docs/jitter.md).

  [analysis]
  psd_resolution_hz = 0.5          # Welch bin width of the LOS error's PSD (default DEFAULT_RESOLUTION_HZ)
  isolation_resolution_hz = 0.05   # bin width of the isolation estimate from a moving base
  [analysis.bands]                 # optional: user-named bands [f_lo, f_hi) in Hz
  low = [0.0, 1.0]
  mid = [1.0, 10.0]
  high = [10.0, 500.0]

Bands may not reach above the Nyquist frequency 1 / (2 step_size): the run has no power there.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..errors import SceneError, check_keys, excerpt, number, positive, shown
from ..limits import MAX_ANALYSIS_BANDS, MAX_STEPS, over_limit

# 2-s segments: fine enough to separate the sea's band (below 1 Hz) from the loop's and the gears'
# (several Hz up), coarse enough that a 10-s window averages 9 segments and a 60-s one 59.
DEFAULT_RESOLUTION_HZ = 0.5
# 20-s segments: a sea's energy lies between about 0.05 and 0.5 Hz, so the isolation estimate needs
# bins that fine; a 600-s run then averages 59 segments, a 60-s one only 5 (coherence biased up by ~1/5).
DEFAULT_ISOLATION_RESOLUTION_HZ = 0.05
KEYS = {"psd_resolution_hz", "isolation_resolution_hz", "bands"}


@dataclass(frozen=True)
class AnalysisSettings:
    psd_resolution_hz: float = DEFAULT_RESOLUTION_HZ
    isolation_resolution_hz: float = DEFAULT_ISOLATION_RESOLUTION_HZ
    bands: dict = field(default_factory=dict)   # name -> (f_lo, f_hi), Hz, in the file's order
    resolution_given: bool = False              # psd_resolution_hz was stated in the file


def parse(table: dict, step_size: float) -> AnalysisSettings:
    """The settings of an [analysis] table (empty: the defaults, no bands); SceneError for anything
    that cannot be meant."""
    if not isinstance(table, dict):
        raise SceneError(f"'analysis' must be a table ([analysis]), got {shown(table)}")
    check_keys("analysis", table, KEYS)
    nyquist = 0.5 / step_size
    resolution = positive("analysis.psd_resolution_hz", table.get("psd_resolution_hz", DEFAULT_RESOLUTION_HZ))
    isolation = positive("analysis.isolation_resolution_hz",
                         table.get("isolation_resolution_hz", DEFAULT_ISOLATION_RESOLUTION_HZ))
    for key, value in (("psd_resolution_hz", resolution), ("isolation_resolution_hz", isolation)):
        # a Welch segment of 1 / resolution seconds: its samples are counted, allocated and transformed
        if not 1.0 / value / step_size <= MAX_STEPS:
            raise SceneError(f"analysis.{key} = {value:g} Hz asks for Welch segments of {1.0 / value:g} s, over the "
                             f"limit of {MAX_STEPS:,} steps of {step_size:g} s")
        if value >= nyquist:
            raise SceneError(f"analysis.{key} = {value:g} Hz is not below the Nyquist frequency {nyquist:g} Hz "
                             f"(1 / (2 step_size)): the spectrum would have no bins")
    bands_table = table.get("bands", {})
    if not isinstance(bands_table, dict):
        raise SceneError("analysis.bands must be a table ([analysis.bands]) of name = [f_lo, f_hi] in Hz")
    over_limit("analysis.bands: the number of bands", len(bands_table), MAX_ANALYSIS_BANDS)
    bands = {name: _band(name, value, nyquist) for name, value in bands_table.items()}
    return AnalysisSettings(resolution, isolation, bands, "psd_resolution_hz" in table)


def _band(name: str, value, nyquist: float) -> tuple[float, float]:
    where = f"analysis.bands.{excerpt(name)}"
    if not name.replace("_", "").isalnum():
        raise SceneError(f"{where}: a band's name may hold letters, digits and '_' only (it names a sweep column)")
    if not (isinstance(value, list) and len(value) == 2):
        raise SceneError(f"{where} must be [f_lo, f_hi] in Hz, got {shown(value)}")
    f_lo, f_hi = number(f"{where}[0]", value[0]), number(f"{where}[1]", value[1])
    if f_lo < 0:
        raise SceneError(f"{where} = [{f_lo:g}, {f_hi:g}]: f_lo must be >= 0 Hz")
    if not f_lo < f_hi:
        raise SceneError(f"{where} = [{f_lo:g}, {f_hi:g}]: f_lo must be below f_hi")
    if f_hi > nyquist * (1 + 1e-12):
        raise SceneError(f"{where} = [{f_lo:g}, {f_hi:g}]: f_hi is above the Nyquist frequency {nyquist:g} Hz "
                         f"(1 / (2 step_size)); the run has no power there")
    return f_lo, f_hi


def check_window(settings: AnalysisSettings, stop_time: float, from_s: float) -> None:
    """A stated resolution needs a window [from_s, stop_time] of at least one segment (1 / resolution).
    Checked on the file as written; a run shortened later (--stop-time, a sweep) takes its window as
    one coarser segment instead, and says so."""
    window = stop_time - max(from_s, 0.0)
    needed = 1.0 / settings.psd_resolution_hz
    if settings.resolution_given and window < needed * (1 - 1e-9):
        raise SceneError(f"analysis.psd_resolution_hz = {settings.psd_resolution_hz:g} Hz needs a window of "
                         f"{needed:g} s (one Welch segment), but [{max(from_s, 0.0):g}, {stop_time:g}] s is "
                         f"{window:g} s: ask for at least {1.0 / window:.3g} Hz or run longer")
