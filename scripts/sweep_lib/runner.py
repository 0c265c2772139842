"""A sweep end to end: expand the cases, skip those already in the table, run the others on Dask
(or serially), merge, write the table (Parquet + CSV) and the summary plot."""
from __future__ import annotations

import logging
import math
import os
import pathlib
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass

from scene_lib.errors import SceneError
from scene_lib.fmu import FMU
from scene_lib.scene import check_against_fmu, load_scene

from . import table
from .spec import SweepError, apply_case, case_key, load_sweep, resolve_names, scene_hash
from .worker import fmu_digest, run_case

SCRIPTS = pathlib.Path(__file__).resolve().parents[1]


@dataclass
class Outcome:
    parquet: pathlib.Path
    csv: pathlib.Path
    png: pathlib.Path
    rows: list            # the whole table after the merge
    ran: int              # cases run now
    skipped: int          # cases found in the table already
    failed: int           # failed cases among those of this sweep
    wall_time: float


@dataclass
class Case:
    index: int
    case_id: str
    values: dict
    scene: object = None       # the scene with the values put in, or None when invalid
    error: str = ""


class Progress:
    """A counter on stderr: done/total, ok/failed, rate and time left; redrawn in place on a
    terminal, else a line every 10 % (or 30 s)."""

    def __init__(self, total: int, enabled: bool = True, stream=sys.stderr):
        self.total, self.enabled, self.stream = total, enabled, stream
        self.done = self.failed = 0
        self.start = time.perf_counter()
        self.tty = hasattr(stream, "isatty") and stream.isatty()
        self.last_draw = 0.0
        self.last_decile = -1

    def update(self, status: str) -> None:
        self.done += 1
        self.failed += status != "ok"
        if not self.enabled:
            return
        now = time.perf_counter() - self.start
        decile = int(10 * self.done / max(self.total, 1))
        final = self.done == self.total
        if self.tty and (now - self.last_draw < 0.2 and not final):
            return
        if not self.tty and not final and decile == self.last_decile and now - self.last_draw < 30:
            return
        self.last_draw, self.last_decile = now, decile
        rate = self.done / now if now > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        text = (f"[{self.done:>{len(str(self.total))}}/{self.total}] {100 * self.done / max(self.total, 1):5.1f} %  "
                f"ok {self.done - self.failed}  failed {self.failed}  {rate:6.2f} cases/s  ~{left:5.0f} s left")
        self.stream.write(("\r" + text + ("\n" if final else "")) if self.tty else text + "\n")
        self.stream.flush()


def _effective_seed(scene) -> int | None:
    spec = scene.base_motion_spec or {}
    return spec.get("seed", 1) if spec.get("type") == "sea_state" else None


def prepare(scene_path, sweep_path, fmu: FMU):
    """(scene, sweep, cases): every case keyed and applied to the scene; a case whose values the
    scene or the FMU refuse before running carries its error (it is reported as failed)."""
    scene = load_scene(scene_path)
    check_against_fmu(scene, fmu)
    sweep = load_sweep(sweep_path)
    resolved = resolve_names(sweep, fmu)
    digest = scene_hash(scene)
    cases = []
    for index, values in enumerate(sweep.expand()):
        case = Case(index, case_key(digest, sweep, values), values)
        try:
            case.scene = apply_case(scene, resolved, values, sweep.stop_time)
            check_against_fmu(case.scene, fmu)
        except SceneError as exc:
            case.scene, case.error = None, f"invalid case: {exc}"
        cases.append(case)
    return scene, sweep, cases


def _base_row(case: Case, scene, sweep, scene_digest: str, fmu_sha: str) -> dict:
    row = {"case_id": case.case_id, "case": case.index, "sweep": sweep.name, "scene": scene.name,
           "scene_hash": scene_digest, "stop_time": (case.scene or scene).stop_time if case.scene else
           (sweep.stop_time or scene.stop_time)}
    row.update(case.values)
    row["seed"] = _effective_seed(case.scene or scene)
    row["sampling_seed"] = sweep.seed
    row["fmu_sha256"] = fmu_sha[:12]
    return row


def _zip_packages() -> pathlib.Path:
    """scene_lib and sweep_lib in a zip, for client.upload_file to workers of an existing scheduler."""
    path = pathlib.Path(tempfile.mkdtemp(prefix="gimbal_sweep_upload_")) / "gimbal_sweep_libs.zip"
    with zipfile.ZipFile(path, "w") as z:
        for package in ("scene_lib", "sweep_lib"):
            for file in sorted((SCRIPTS / package).glob("*.py")):
                z.write(file, f"{package}/{file.name}")
    return path


def make_client(scheduler: str | None = None, workers: int = 2, processes: bool = True):
    """(client, cluster): a Client of the scheduler at `scheduler`, else of a new LocalCluster with
    `workers` workers of one thread each (processes by default)."""
    from distributed import Client, LocalCluster

    if scheduler:
        client = Client(scheduler)
        try:   # workers elsewhere may not have this checkout on their path
            client.upload_file(str(_zip_packages()))
        except Exception as exc:  # pragma: no cover - depends on the remote cluster
            print(f"sweep: warning: could not upload scene_lib/sweep_lib to the workers ({exc}); they must "
                  f"import them (PYTHONPATH={SCRIPTS})", file=sys.stderr)
        return client, None
    path = os.environ.get("PYTHONPATH", "")
    if str(SCRIPTS) not in path.split(os.pathsep):   # spawned worker processes import sweep_lib
        os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(SCRIPTS), path) if p)
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes, dashboard_address=None,
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


def run_sweep(scene_path, sweep_path, fmu_path, out_dir, scheduler: str | None = None, workers: int = 2,
              serial: bool = False, progress: bool = True, redo: str | None = None, processes: bool = True,
              client=None, checkpoint_s: float = 20.0, plot: bool = True) -> Outcome:
    """Runs the sweep; `serial` runs in this process without Dask (one reused instance); `client`:
    use this Dask client (else one is made from `scheduler`/`workers`/`processes` and closed after).
    `redo`: None, 'failed' (rerun failed cases) or 'all'."""
    wall0 = time.perf_counter()
    out = pathlib.Path(out_dir)
    with FMU(fmu_path) as fmu:
        scene, sweep, cases = prepare(scene_path, sweep_path, fmu)
    fmu_bytes = pathlib.Path(fmu_path).read_bytes()
    digest = fmu_digest(fmu_bytes)
    scene_digest = scene_hash(scene)
    stem = f"{sweep.name}__{scene.name}"
    parquet, csv, png = out / f"{stem}.parquet", out / f"{stem}.csv", out / f"{stem}.png"
    existing = table.read_rows(parquet)
    done = {r["case_id"]: r for r in existing}
    todo, skipped, seen = [], 0, set()
    for case in cases:
        if case.case_id in seen:   # the same values twice (e.g. a repeated grid value): one case
            continue
        seen.add(case.case_id)
        old = done.get(case.case_id)
        if old is not None and not (redo == "all" or (redo == "failed" and old.get("status") != "ok")):
            skipped += 1
        else:
            todo.append(case)
    parameters = sweep.parameters
    new_rows: list[dict] = []

    def save():
        table.write(table.merge(existing, new_rows), parameters, parquet, csv)

    bar = Progress(len(todo), enabled=progress and bool(todo))
    if progress:
        print(f"sweep {sweep.name} on scene {scene.name}: {len(cases)} cases, {skipped} already done, "
              f"{len(todo)} to run" + ("" if not todo else " serially" if serial else
                                        f" on {scheduler or f'a local cluster of {workers} workers'}"),
              file=sys.stderr)
    last_save = time.perf_counter()
    from_s = sweep.metrics_from_s

    def finish(case: Case, result: dict):
        nonlocal last_save
        row = _base_row(case, scene, sweep, scene_digest, digest)
        row.update(result)
        new_rows.append(row)
        bar.update(row["status"])
        if time.perf_counter() - last_save > checkpoint_s:
            save()
            last_save = time.perf_counter()

    runnable = []
    for case in todo:
        if case.scene is None:
            finish(case, {"case_id": case.case_id, "status": "failed", "message": case.error, "fmu_log": "",
                          "wall_time_s": 0.0, "worker": "client"})
        else:
            runnable.append(case)
    own_client = cluster = None
    try:
        if serial:
            for case in runnable:
                finish(case, run_case(case.scene, case.case_id, fmu_bytes, digest, from_s))
        elif runnable:
            from distributed import as_completed

            if client is None:
                own_client, cluster = make_client(scheduler, workers, processes)
                client = own_client
            fmu_future = client.scatter(fmu_bytes, broadcast=True, hash=False)
            bar.start = time.perf_counter()   # the rate counts from here, not from the cluster's start
            futures, cases_of = [], {}
            for case in runnable:
                future = client.submit(run_case, case.scene, case.case_id, fmu_future, digest, from_s,
                                       key=f"gimbal-case-{digest[:8]}-{case.case_id}", pure=False, retries=1)
                futures.append(future)
                cases_of[future.key] = case
            for future in as_completed(futures):
                case = cases_of[future.key]
                try:
                    result = future.result()
                except Exception as exc:   # the task itself died (e.g. its worker crashed twice)
                    result = {"case_id": case.case_id, "status": "failed", "message": f"{type(exc).__name__}: {exc}",
                              "fmu_log": "", "wall_time_s": math.nan, "worker": "?"}
                future.release()
                finish(case, result)
    except KeyboardInterrupt:
        save()
        print(f"\nsweep: interrupted; {len(new_rows)} new cases kept in {parquet} (a rerun continues)",
              file=sys.stderr)
        raise
    finally:
        if own_client is not None:
            own_client.close()
        if cluster is not None:
            cluster.close()
    rows = table.merge(existing, new_rows)
    table.write(rows, parameters, parquet, csv)
    ids = {c.case_id for c in cases}
    mine = [r for r in rows if r["case_id"] in ids]
    failed = sum(r.get("status") != "ok" for r in mine)
    if plot:
        table.plot_summary(mine, parameters, png, f"sweep {sweep.name} on {scene.name}: {len(mine)} cases, "
                                                 f"{len(mine) - failed} ok, {failed} failed")
    return Outcome(parquet, csv, png, rows, len(todo), skipped, failed, time.perf_counter() - wall0)

