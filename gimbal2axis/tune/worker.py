"""What runs on a worker for a tuning: one evaluation (a candidate's gains on one member of the
robustness set) on the worker's FMU instance, as a sweep's case runs (gimbal2axis.sweep.worker: the
FMU extracted once per worker, its instance reused through fmi2Reset), with the metrics a tuning's
objective and constraints need besides a sweep's:

  i_frac_peak            max |i_R| / motor.i_L over both motors (the current-limit constraint)
  u_sat_s                time the controller asked for |u| >= motor.U_L (the larger of the two motors), s;
                         for a motor in current drive, for a current command |i| >= motor.i_L
  psd_band_<lo>_<hi>Hz_<axis>_rms_mrad   the LOS error's RMS in [lo, hi) Hz from the run's own PSD
                         (Welch, the scene's psd_resolution_hz; axis both = root-sum-square of xel and el)
"""
from __future__ import annotations

import math

import numpy as np

from ..sweep.worker import run_case

SATURATION_TOLERANCE = 1e-9   # relative: an asked voltage this close to U_L counts as saturated


def extra_metrics(result, fmu, from_s: float | None, bands: dict) -> dict:
    """The tuning's metrics of one run (see the module's doc)."""
    from ..master import spectra
    from ..scene.drives import command_columns
    from ..scene.scene import parameter_value

    s, scene = result.signals, result.scene
    if from_s is None:
        start = result.window_start()
        from_s = start if start < result.stop_time else 0.0
    row = {}
    fractions, saturated = [], []
    dt = scene.step_size
    for j in (1, 2):
        i_limit = float(parameter_value(scene, fmu, f"motor{j}.i_L"))
        drive = command_columns(s, j)
        limit = float(parameter_value(scene, fmu, f"motor{j}.U_L")) if drive.kind == "voltage" else i_limit
        fractions.append(float(np.max(np.abs(s[f"i_R{j}"]))) / i_limit)
        asked = s.get(drive.asked, s[drive.applied])
        saturated.append(float(np.count_nonzero(np.abs(asked) >= limit * (1 - SATURATION_TOLERANCE))) * dt)
    row["i_frac_peak"] = max(fractions)
    row["u_sat_s"] = max(saturated)
    if bands:
        window = result.metrics_window(from_s)
        spectra_by_axis = {}
        if result.has_target and window.sum() >= 2:
            for axis, name in (("xel", "los_error_xel"), ("el", "los_error_el")):
                spectra_by_axis[axis] = spectra.psd(result.derived[name][window], 1.0 / dt,
                                                    scene.analysis.psd_resolution_hz)
        for column, (lo, hi, axis) in bands.items():
            if not spectra_by_axis:
                row[column] = math.nan
                continue
            parts = [spectra_by_axis[a].band_rms(lo, hi) for a in (("xel", "el") if axis == "both" else (axis,))]
            row[column] = math.sqrt(sum(p * p for p in parts)) * 1e3
    return row


def run_tune_case(scene, case_id: str, fmu_bytes: bytes, digest: str, from_s: float | None, bands: dict) -> dict:
    """One evaluation on this worker's FMU instance: the sweep's case (its row, its failure handling
    and instance reuse) with the tuner's objective columns added; the FMU's log cut to its last 4000
    characters (a tuning stores thousands of rows)."""
    row = run_case(scene, case_id, fmu_bytes, digest, from_s,
                   extra_metrics=lambda result, fmu: extra_metrics(result, fmu, from_s, bands))
    row["fmu_log"] = row["fmu_log"][-4000:]
    return row


def run_tune_cases(cases: list, fmu_bytes: bytes, digest: str, from_s: float | None = None,
                   bands: dict | None = None) -> list:
    """The (scene, case_id) pairs of one Dask task, one after the other; their rows in order."""
    return [run_tune_case(scene, case_id, fmu_bytes, digest, from_s, bands or {}) for scene, case_id in cases]
