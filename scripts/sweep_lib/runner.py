"""A sweep end to end: expand the cases, skip those already in the table, run the others on Dask
(or serially), merge, write the table (Parquet + CSV) and the summary plot."""
from __future__ import annotations

import logging
import math
import pathlib
import signal
import sys
import tempfile
import threading
import time
import zipfile
from dataclasses import dataclass

from scene_lib.errors import SceneError
from scene_lib.fmu import FMU
from scene_lib.scene import check_against_fmu, load_scene

from . import table
from .names import check_cases_accepted, resolve_names
from .spec import SweepError, apply_case, case_key, load_sweep, scene_hash
from .worker import fmu_digest, run_case, run_cases

SCHEDULER_TIMEOUT_S = 5.0   # a scheduler that does not answer by then is not coming


class Stopped(KeyboardInterrupt):
    """SIGTERM, ending the sweep as Ctrl-C does (the cases finished so far are kept); its message
    names the signal, and sweep.py's exit status tells the two apart."""


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
    failed_before: int = 0   # of `failed`, those kept from an earlier run (not rerun now)


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
    resolved, candidates = resolve_names(sweep, scene, fmu)
    digest = scene_hash(scene)
    cases = []
    for index, values in enumerate(sweep.expand()):
        case = Case(index, case_key(digest, sweep, values), values)
        try:
            case.scene = apply_case(scene, resolved, values, sweep.stop_time)
            check_against_fmu(case.scene, fmu)
        except SceneError as exc:
            case.scene, case.error = None, f"invalid case: {exc}"
        except (TypeError, ValueError, KeyError) as exc:   # a value of a type the scene's checks do not expect
            case.scene, case.error = None, f"invalid case: {type(exc).__name__}: {exc}"
        cases.append(case)
    check_cases_accepted(scene, sweep, fmu, resolved, cases, candidates)
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
    import scene_lib
    import sweep_lib

    path = pathlib.Path(tempfile.mkdtemp(prefix="gimbal_sweep_upload_")) / "gimbal_sweep_libs.zip"
    with zipfile.ZipFile(path, "w") as z:
        for package in (scene_lib, sweep_lib):   # from wherever this process imported them
            directory = pathlib.Path(package.__file__).resolve().parent
            for file in sorted(directory.glob("*.py")):
                z.write(file, f"{package.__name__}/{file.name}")
    return path


def make_client(scheduler: str | None = None, workers: int = 2, processes: bool = True):
    """(client, cluster): a Client of the scheduler at `scheduler`, else of a new LocalCluster with
    `workers` workers of one thread each (processes by default)."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S}s")
        except ValueError as exc:
            raise SweepError(f"--scheduler {scheduler}: {exc}") from None
        except (OSError, TimeoutError):
            raise SweepError(f"no Dask scheduler answered at {scheduler} within {SCHEDULER_TIMEOUT_S:g} s; start one "
                             f"(dask scheduler; dask worker ADDRESS --nthreads 1), or leave out --scheduler for a "
                             f"local cluster") from None
        try:   # workers elsewhere may not have this checkout on their path
            client.upload_file(str(_zip_packages()))
        except Exception as exc:  # pragma: no cover - depends on the remote cluster
            print(f"sweep: warning: could not upload scene_lib/sweep_lib to the workers ({exc}); they must "
                  "have them installed (pip install the repository there)", file=sys.stderr)
        return client, None
    # The local workers are processes of this Python: they import the installed scene_lib and sweep_lib.
    cluster = None
    try:
        with _StopRequests():   # a half-started cluster cannot be closed in order
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                                   dashboard_address=None, silence_logs=logging.ERROR)
        return Client(cluster), cluster
    except BaseException:
        if cluster is not None:
            cluster.close()
        raise


class _StopRequests:
    """While active (in the main thread), Ctrl-C and SIGTERM are only recorded; check() raises them
    (KeyboardInterrupt, Stopped) where the sweep can stop in order, never inside Dask's own code,
    where an exception leaves a half-started cluster or a scheduler writing to a closed client. On
    leaving, a request not raised yet is delivered again."""

    def __init__(self):
        self.pending: list = []
        self.previous: dict = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self.previous = {sig: signal.signal(sig, lambda signum, frame: self.pending.append(signum))
                             for sig in (signal.SIGINT, signal.SIGTERM)}
        return self

    def check(self) -> None:
        if self.pending:
            signum = self.pending.pop(0)
            self.pending.clear()
            raise Stopped("terminated (SIGTERM)") if signum == signal.SIGTERM else KeyboardInterrupt()

    def __exit__(self, *exc):
        for sig, handler in self.previous.items():
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)
        for sig in dict.fromkeys(self.pending):
            signal.raise_signal(sig)


def cases_per_task(cases: int, workers: int, most: int = 16) -> int:
    """Cases a Dask task runs one after the other: up to `most`, while every worker still gets at
    least 8 tasks (the last ones balance the load)."""
    return max(1, min(most, cases // (8 * max(workers, 1))))


def _worker_count(client) -> int:
    try:
        return max(1, len(client.scheduler_info().get("workers", {})))
    except Exception:
        return 1


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
    warning = sweep.limit_warning()
    if warning:
        print(f"sweep: warning: {warning}", file=sys.stderr)
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
    futures: list = []
    scattered: list = []
    interrupted = False
    try:
        if serial:
            for case in runnable:
                finish(case, run_case(case.scene, case.case_id, fmu_bytes, digest, from_s))
        elif runnable:
            from distributed import as_completed

            with _StopRequests() as stop:
                if client is None:
                    own_client, cluster = make_client(scheduler, workers, processes)
                    client = own_client
                stop.check()
                fmu_future = client.scatter(fmu_bytes, broadcast=True, hash=False)
                scattered.append(fmu_future)
                bar.start = time.perf_counter()   # the rate counts from here, not from the cluster's start
                cases_of = {}
                # Several cases per task: a short case costs the scheduler about as much as it costs to
                # run, so tasks carry a few (at least 8 tasks per worker remain, to balance the load).
                per_task = cases_per_task(len(runnable), _worker_count(client))
                for first in range(0, len(runnable), per_task):
                    chunk = runnable[first:first + per_task]
                    future = client.submit(run_cases, [(c.scene, c.case_id) for c in chunk], fmu_future, digest,
                                           from_s, key=f"gimbal-cases-{digest[:8]}-{chunk[0].case_id}-{len(chunk)}",
                                           pure=False, retries=1)
                    futures.append(future)
                    cases_of[future.key] = chunk
                completed = as_completed(futures)
                while not completed.is_empty():
                    stop.check()
                    batch = completed.next_batch(block=False)
                    if not batch:
                        time.sleep(0.05)
                    for future in batch:
                        chunk = cases_of[future.key]
                        try:
                            results = future.result()
                        except Exception as exc:   # the task itself died (e.g. its worker crashed twice)
                            results = [{"case_id": case.case_id, "status": "failed",
                                        "message": f"{type(exc).__name__}: {exc}", "fmu_log": "",
                                        "wall_time_s": math.nan, "worker": "?"} for case in chunk]
                        future.release()
                        for case, result in zip(chunk, results):
                            finish(case, result)
        rows = table.merge(existing, new_rows)
        table.write(rows, parameters, parquet, csv)
    except KeyboardInterrupt as exc:
        interrupted = True
        reason = str(exc) or "interrupted"
        if new_rows:
            save()
            print(f"\nsweep: {reason}; the {len(new_rows)} cases finished in this run are kept in {parquet} (with "
                  f"those of earlier runs); the same command again runs the rest", file=sys.stderr)
        else:
            print(f"\nsweep: {reason} before any case of this run finished; the same command again runs them",
                  file=sys.stderr)
        exc.reported = True   # for sweep.py: this message was the last word
        raise
    finally:
        if interrupted and futures:
            try:   # queued cases would keep a shared scheduler's workers busy
                client.cancel(futures + scattered)
            except Exception:
                pass
        if cluster is not None and interrupted:
            # Our own cluster, dropped with cases still running: its scheduler's complaints about
            # the work and the scattered FMU it loses are no news to the user who stopped it.
            disabled = logging.root.manager.disable
            logging.disable(logging.CRITICAL)
            try:
                cluster.close()
            finally:
                logging.disable(disabled)
        if own_client is not None:
            own_client.close()
        if cluster is not None and not interrupted:
            cluster.close()
    ids = {c.case_id for c in cases}
    mine = [r for r in rows if r["case_id"] in ids]
    failed = sum(r.get("status") != "ok" for r in mine)
    ran_now = {c.case_id for c in todo}
    failed_before = sum(r.get("status") != "ok" and r["case_id"] not in ran_now for r in mine)
    if plot:
        table.plot_summary(mine, parameters, png, f"sweep {sweep.name} on {scene.name}: {len(mine)} cases, "
                                                 f"{len(mine) - failed} ok, {failed} failed", grid=list(sweep.grid))
    return Outcome(parquet, csv, png, rows, len(todo), skipped, failed, time.perf_counter() - wall0, failed_before)

