"""What runs on a worker for a tuning: one evaluation (a candidate's gains on one member of the
robustness set) on the worker's FMU instance, as a sweep's case runs (gimbal2axis.sweep.worker: the
FMU extracted once per worker, its instance reused through fmi2Reset), with the metrics a tuning's
objective and constraints need besides a sweep's:

  i_frac_peak            max |i_R| / motor.i_L over both motors (the current-limit constraint)
  u_sat_s                time the controller asked for |u| >= motor.U_L (the larger of the two motors), s
  psd_band_<lo>_<hi>Hz_<axis>_rms_mrad   the LOS error's RMS in [lo, hi) Hz from the run's own PSD
                         (Welch, the scene's psd_resolution_hz; axis both = root-sum-square of xel and el)
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..sweep.worker import _worker_name, metrics

SATURATION_TOLERANCE = 1e-9   # relative: an asked voltage this close to U_L counts as saturated


def extra_metrics(result, fmu, from_s: float | None, bands: dict) -> dict:
    """The tuning's metrics of one run (see the module's doc)."""
    from ..master import spectra
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
        u_limit = float(parameter_value(scene, fmu, f"motor{j}.U_L"))
        fractions.append(float(np.max(np.abs(s[f"i_R{j}"]))) / i_limit)
        asked = s.get(f"u_R{j}_asked", s[f"u_R{j}"])
        saturated.append(float(np.count_nonzero(np.abs(asked) >= u_limit * (1 - SATURATION_TOLERANCE))) * dt)
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
    """One evaluation on this worker's FMU instance: its row (metrics, status 'ok'), or status 'failed'
    with the error and the FMU's log (a diverging candidate is a result too). Never raises for a case."""
    from ..errors import SceneError
    from ..fmu.worker_cache import loaded_fmu
    from ..master.master import run

    row = {"case_id": case_id, "status": "failed", "message": "", "fmu_log": "", "wall_time_s": math.nan,
           "worker": _worker_name()}
    wall0, cpu0 = time.perf_counter(), time.thread_time()
    loaded = None
    try:
        loaded = loaded_fmu(fmu_bytes, digest)
        try:
            result = run(scene, loaded.fmu, slave=loaded.instance(), log=loaded.log)
        except SceneError:
            raise
        except Exception:   # the reused instance would not reset: once more on a fresh one
            loaded.discard_instance()
            result = run(scene, loaded.fmu, slave=loaded.instance(), log=loaded.log)
        row.update(metrics(result, from_s))
        row.update(extra_metrics(result, loaded.fmu, from_s, bands))
        row["status"] = "ok"
    except SceneError as exc:
        row["message"] = str(exc)
    except Exception as exc:   # anything else: report it, and do not trust the instance any more
        row["message"] = f"{type(exc).__name__}: {exc}"
        if loaded is not None:
            loaded.discard_instance()
    if loaded is not None and loaded.log:
        row["fmu_log"] = "\n".join(map(str, loaded.log))[-4000:]
    row["wall_time_s"] = time.perf_counter() - wall0
    row["cpu_time_s"] = time.thread_time() - cpu0
    if loaded is not None:
        loaded.cases += 1
        row["instance_use"] = loaded.cases
    return row


def run_tune_cases(cases: list, fmu_bytes: bytes, digest: str, from_s: float | None = None,
                   bands: dict | None = None) -> list:
    """The (scene, case_id) pairs of one Dask task, one after the other; their rows in order."""
    return [run_tune_case(scene, case_id, fmu_bytes, digest, from_s, bands or {}) for scene, case_id in cases]
