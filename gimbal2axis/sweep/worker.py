"""What runs on a worker: one case of a sweep on a worker-local FMU instance.

Each worker (a Dask worker, or the calling thread for a serial sweep) extracts the FMU once and
instantiates it once (gimbal2axis.fmu.worker_cache); every further case reuses that instance through
fmi2Reset (gimbal2axis.master.run with `slave=`). The FMU's logger messages of a case are collected and
returned with a failure.

A task's cases whose controller is a user class with `batch = True` run together in lockstep
(gimbal2axis.master.lockstep: one instance per case, one step() call for all), on a pool of instances
the worker keeps and reuses through fmi2Reset like its single one.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

from ..fmu.worker_cache import dask_worker, loaded_fmu

def metrics(result, from_s: float | None) -> dict:
    """Summary metrics of a run: RMS, peak and final line-of-sight error [mrad] over [from_s, end]
    (nan without a [target]), peak |current| per motor and overall [A], events, requirements met, and
    the band RMS of the scene's [analysis.bands] (band_columns)."""
    s = result.signals
    if from_s is None:
        start = result.window_start()
        from_s = start if start < result.stop_time else 0.0
    if result.has_target:
        los = result.los_metrics(from_s=from_s)
        rms, peak, final = los["rms"] * 1e3, los["max"] * 1e3, los["final"] * 1e3
    else:
        rms = peak = final = math.nan
    i1, i2 = float(np.max(np.abs(s["i_R1"]))), float(np.max(np.abs(s["i_R2"])))
    failures = result.requirement_failures()
    judged = bool(result.scene.requirements) and result.has_target and result.window_start() < result.stop_time
    row = {"los_rms_mrad": rms, "los_peak_mrad": peak, "los_final_mrad": final, "los_from_s": float(from_s),
           "i_peak_R1_A": i1, "i_peak_R2_A": i2, "i_peak_A": max(i1, i2),
           "events": int(s["events.total"][-1]) if "events.total" in s else -1,
           "requirements_met": (not failures) if judged else None}
    row.update(band_columns(result, from_s))
    row.update(tracking_columns(result, from_s))
    return row


# The tracking figures a sweep's row carries for a moving target (target.metrics.TrackingMetrics, over the
# window of the LOS metrics): what a user compares cases by besides the pointing error's RMS and peak.
TRACKING_COLUMNS = ("on_target_fraction", "time_lost_s", "time_near_keyhole_s", "time_lost_near_keyhole_s",
                    "asked_azimuth_rate_max")


def tracking_columns(result, from_s: float) -> dict:
    """on_target_fraction, time_lost_s, ... (TRACKING_COLUMNS) of a run with a moving target, over
    [from_s, end]; none for a fixed direction."""
    if result.scene.moving_target is None:
        return {}
    from ..target.metrics import NEEDED, TrackingMetrics

    spec = result.scene.target_spec
    tracking = TrackingMetrics(spec["beam_width_mrad"], spec["keyhole_deg"], result.scene.step_size, from_s)
    tracking.add({name: np.asarray(result.signal(name)) for name in NEEDED
                  if name in result.signals or name in result.derived})
    figures = tracking.as_dict()
    return {name: figures[name] for name in TRACKING_COLUMNS}


def band_columns(result, from_s: float) -> dict:
    """los_band_<name>_rms_mrad per [analysis.bands] of the scene (none without bands): the band RMS of
    the line-of-sight error over [from_s, end] (the window of the other LOS metrics), both axes combined."""
    return {f"los_band_{name}_rms_mrad": value * 1e3 for name, value in result.band_rms(from_s).items()}


def failure_message(exc: BaseException) -> str:
    """A failed case's message for an exception that is not a SceneError: its class and text, and
    for a BaseException that is not an Exception (sys.exit, KeyboardInterrupt, GeneratorExit, one of
    the user's own, raised by a user's code outside the controller's wrappers) where it was raised."""
    from ..errors import excerpt
    from ..scene.controllers import raised_where

    text = excerpt(str(exc))
    where = "" if isinstance(exc, Exception) else raised_where(exc, None)
    return f"{type(exc).__name__}{': ' + text if text else ''}{where}"


def run_case(scene, case_id: str, fmu_bytes: bytes, digest: str, from_s: float | None = None,
             extra_metrics=None) -> dict:
    """Runs one case (the scene with its values already put in) on this worker's FMU instance and
    returns its row: metrics and status 'ok', or status 'failed' with the error and the FMU's log.
    Never raises for a failing case: failures are results too, also a BaseException of the case's
    code (sys.exit, KeyboardInterrupt); only a StopSignal (Ctrl-C or SIGTERM of this process, see
    runner.CaseSignals) goes through. `extra_metrics(result, fmu)`, when given, adds its columns to
    the row of a run that went through (the tuner's objectives)."""
    from ..errors import SceneError, StopSignal
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
        except Exception:   # the reused instance would not reset: retry once on a fresh one
            loaded.discard_instance()
            result = run(scene, loaded.fmu, slave=loaded.instance(), log=loaded.log)
        row.update(metrics(result, from_s))
        if extra_metrics is not None:
            row.update(extra_metrics(result, loaded.fmu))
        row["status"] = "ok"
        row["wall_time_s"] = time.perf_counter() - wall0   # the whole case: set-up, run, metrics
        if loaded.log:   # warnings of a run that went through
            row["fmu_log"] = "\n".join(map(str, loaded.log))
    except SceneError as exc:
        row["message"] = str(exc)
        row["wall_time_s"] = time.perf_counter() - wall0
        if loaded is not None:
            row["fmu_log"] = "\n".join(map(str, loaded.log))
    except StopSignal:
        raise
    except BaseException as exc:   # anything else: report it, and do not trust the instance any more
        row["message"] = failure_message(exc)
        row["wall_time_s"] = time.perf_counter() - wall0
        if loaded is not None:
            row["fmu_log"] = "\n".join(map(str, loaded.log))
            loaded.discard_instance()
    row["cpu_time_s"] = time.thread_time() - cpu0   # less than wall_time_s when the CPU is shared
    if loaded is not None:
        loaded.cases += 1
        row["instance_use"] = loaded.cases   # the n-th case of this worker's FMU (extracted once)
    return row


def _worker_name() -> str:
    worker = dask_worker()
    return worker.address if worker is not None else f"serial-{os.getpid()}"


def run_batch(cases: list, fmu_bytes: bytes, digest: str, from_s: float | None = None) -> list:
    """The (scene, case_id) pairs of one lockstep batch (gimbal2axis.master.lockstep.batch_key equal) run
    together on this worker's pool of instances; the rows as run_case gives them, with the batch's
    wall and CPU time shared out evenly and `batch_size`. Never raises for a failing case."""
    from ..errors import SceneError, StopSignal
    from ..master.lockstep import run_lockstep

    wall0, cpu0 = time.perf_counter(), time.thread_time()
    scenes = [scene for scene, _ in cases]
    loaded, outcomes = None, None
    try:
        loaded = loaded_fmu(fmu_bytes, digest)
        try:
            outcomes = run_lockstep(scenes, loaded.fmu, loaded.instances(len(scenes)))
        except SceneError:
            raise
        except Exception:   # an instance would not reset: once more on fresh ones
            loaded.discard_pool()
            outcomes = run_lockstep(scenes, loaded.fmu, loaded.instances(len(scenes)))
    except StopSignal:
        raise
    except BaseException as exc:   # the batch as a whole could not run: every case fails with the reason
        message = str(exc) if isinstance(exc, SceneError) else failure_message(exc)
        outcomes = [SceneError(message)] * len(cases)
        if loaded is not None and not isinstance(exc, SceneError):
            loaded.discard_pool()
    wall, cpu = (time.perf_counter() - wall0) / len(cases), (time.thread_time() - cpu0) / len(cases)
    rows = []
    for position, ((scene, case_id), outcome) in enumerate(zip(cases, outcomes)):
        row = {"case_id": case_id, "status": "failed", "message": "", "fmu_log": "", "wall_time_s": wall,
               "worker": _worker_name()}
        log = loaded.pool[position][1] if loaded is not None and position < len(loaded.pool) else []
        if isinstance(outcome, Exception):
            row["message"] = str(outcome)
        else:
            row.update(metrics(outcome, from_s))
            row["status"] = "ok"
        if log:
            row["fmu_log"] = "\n".join(map(str, log))
        row["cpu_time_s"] = cpu
        row["batch_size"] = len(cases)
        if loaded is not None:
            loaded.cases += 1
            row["instance_use"] = loaded.cases
        rows.append(row)
    return rows


def run_cases(cases: list, fmu_bytes: bytes, digest: str, from_s: float | None = None) -> list:
    """The (scene, case_id) pairs of a Dask task: those whose controller is a user class with
    `batch = True` together in lockstep (run_batch, grouped by gimbal2axis.master.lockstep.batch_key), the
    others one after the other on this worker's instance (run_case). The rows in the given order."""
    from ..master.lockstep import batch_key

    rows: list = [None] * len(cases)
    batches: dict = {}
    for position, (scene, case_id) in enumerate(cases):
        key = batch_key(scene)
        if key is None:
            rows[position] = run_case(scene, case_id, fmu_bytes, digest, from_s)
        else:
            batches.setdefault(key, []).append(position)
    for positions in batches.values():
        for position, row in zip(positions, run_batch([cases[p] for p in positions], fmu_bytes, digest, from_s)):
            rows[position] = row
    return rows
