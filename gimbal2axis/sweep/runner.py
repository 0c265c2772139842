"""A sweep end to end, in phases: plan (expand the cases, check the output folder and claim the
table, skip the cases already in it), run the others on Dask or serially while recording each result
(the table saved as they come), finish (the merged table, Parquet + CSV, and the summary plot). The
table is shared safely with other sweeps writing it at the same time (store.py)."""
from __future__ import annotations

import logging
import math
import pathlib
import signal
import sys
import threading
import time
from dataclasses import dataclass

from ..errors import Interrupted, SceneError, StopSignal
from ..fmu import FMU
from ..fmu.worker_cache import fmu_digest
from ..scene.scene import check_against_fmu, load_scene

from . import store, table
from .names import check_cases_accepted, resolve_names
from .progress import Progress
from .spec import SweepError, apply_case, case_key, check_cases_window, load_sweep, scene_hash
from .worker import run_case, run_cases

MAX_LOCAL_WORKERS = 256     # processes of a local cluster: beyond, --workers is a typo, not a machine
SCHEDULER_TIMEOUT_S = 5.0   # a scheduler that does not answer by then is not coming


class Stopped(StopSignal, KeyboardInterrupt):
    """SIGTERM, ending the sweep as Ctrl-C does (the cases finished so far are kept); its message
    names the signal, and gimbal2axis sweep's exit status tells the two apart. A StopSignal: the
    wrappers of a user controller's code let it pass (errors.StopSignal)."""


def stop_signal(signum: int) -> StopSignal:
    """The exception that the signal `signum` (SIGINT or SIGTERM) ends a sweep or a tuning with."""
    return Stopped("terminated (SIGTERM)") if signum == signal.SIGTERM else Interrupted()


class CaseSignals:
    """While cases run in this process (a serial sweep or tuning; in the main thread): Ctrl-C and
    SIGTERM raise their StopSignal (stop_signal) at once, which a user controller's wrappers let pass,
    whereas any other BaseException its code raises (sys.exit, a KeyboardInterrupt of its own) is its
    case's failure. Each signal is also recorded: check() raises it again after a case whose code
    swallowed it, so that only the signals end the sweep, and always do."""

    def __init__(self):
        self.received: int | None = None
        self.previous: dict = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self.previous = {sig: signal.signal(sig, self._handle) for sig in (signal.SIGINT, signal.SIGTERM)}
        return self

    def _handle(self, signum, frame):
        self.received = signum
        raise stop_signal(signum)

    def check(self) -> None:
        if self.received is not None:
            raise stop_signal(self.received)

    def __exit__(self, *exc):
        for sig, handler in self.previous.items():
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)
        return False


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


def _effective_seed(scene) -> int | None:
    spec = scene.base_motion_spec or {}
    return spec.get("seed", 1) if spec.get("type") == "sea_state" else None


def prepare(scene_path, sweep_path, fmu: FMU):
    """(scene, sweep, cases): every case keyed and applied to the scene; a case whose values the
    scene or the FMU refuse before running carries its error (it is reported as failed)."""
    scene = load_scene(scene_path)
    # The files a scene names (a user controller's module, a recorded motion) are looked for beside
    # it, on the workers: from an absolute folder, as the workers' current directory is not ours.
    scene = scene.with_changes(path=scene.path.resolve())
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
    try:
        check_cases_window(sweep.metrics_from_s, [case.scene for case in cases])
    except SweepError as exc:
        raise SweepError(f"{sweep.path}: {exc}") from None
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


def make_client(scheduler: str | None = None, workers: int = 2, processes: bool = True):
    """(client, cluster): a Client of the scheduler at `scheduler`, its workers sent this gimbal2axis
    package and checked (worker_package.py; SweepError in one line if one cannot run it), else of a
    new LocalCluster with `workers` workers of one thread each (processes by default; they ignore
    Ctrl-C, see worker_interrupts.py)."""
    from distributed import Client, LocalCluster

    if scheduler:
        from .scheduler_check import check_scheduler

        check_scheduler(scheduler, SCHEDULER_TIMEOUT_S)
        try:
            client = Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S}s")
        except (ValueError, MemoryError) as exc:   # MemoryError: a service whose answer reads as a huge message
            raise SweepError(f"--scheduler {scheduler}: {type(exc).__name__}: {exc}") from None
        except (OSError, TimeoutError):
            raise SweepError(f"no Dask scheduler answered at {scheduler} within {SCHEDULER_TIMEOUT_S:g} s; start one "
                             f"(dask scheduler; dask worker ADDRESS --nthreads 1), or leave out --scheduler for a "
                             f"local cluster") from None
        try:
            send_package(client, scheduler)
        except BaseException:
            client.close()
            raise
        return client, None
    # The local workers are processes of this Python: they import the installed gimbal2axis.
    if not 1 <= workers <= MAX_LOCAL_WORKERS:
        raise SweepError(f"--workers {workers}: a local cluster has 1 to {MAX_LOCAL_WORKERS} workers")
    cluster = None
    try:
        with _StopRequests():   # a half-started cluster cannot be closed in order
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                                   dashboard_address=None, silence_logs=logging.ERROR,
                                   preload=[f"{__package__}.worker_interrupts"] if processes else [])
        return Client(cluster), cluster
    except BaseException:
        if cluster is not None:
            cluster.close()
        raise


def send_package(client, scheduler: str) -> None:
    """Sends this gimbal2axis package, compiled kernel included, to the workers of the scheduler
    (worker_package.ShippedPackage, also for workers that join later) and checks that each of them
    imports it and loads its kernel; SweepError in one line, before any case runs, if there is no
    worker or one cannot."""
    from . import worker_package

    worker_package.register_by_value()   # the workers cannot import it before it ran
    try:
        client.wait_for_workers(1, timeout=SCHEDULER_TIMEOUT_S)
    except TimeoutError:
        raise SweepError(f"no Dask worker is connected to the scheduler at {scheduler} (waited "
                         f"{SCHEDULER_TIMEOUT_S:g} s); start some: dask worker {scheduler} --nthreads 1") from None
    archive, digest = worker_package.package_archive()
    try:
        client.register_plugin(worker_package.ShippedPackage(archive, digest), name=worker_package.PLUGIN_NAME)
    except Exception as exc:
        raise SweepError(f"could not send the gimbal2axis package to the workers of {scheduler}: "
                         f"{_first_line(exc)}") from None
    reports = client.run(worker_package.check_worker, digest, worker_package.python_and_platform(),
                         on_error="return")
    refusal = worker_refusal(reports, scheduler)
    if refusal:
        raise SweepError(refusal)
    difference = version_difference(reports, worker_package.dependency_versions())
    if difference:
        print(f"sweep: warning: {difference}", file=sys.stderr)


def version_difference(reports: dict, here: dict) -> str | None:
    """A worker whose numpy, scipy or fmpy differs from this process's (its results may differ from a
    local run's in the last digits), in one line; None if all have the same versions."""
    for address, report in sorted(reports.items()):
        theirs = report.get("versions", {})
        differing = [f"{name} {theirs.get(name)} (here {version})" for name, version in here.items()
                     if theirs.get(name) != version]
        if differing:
            return (f"worker {address} has {', '.join(differing)}: its results may differ from this machine's in the "
                    f"last digits (requirements-run.txt pins the versions)")
    return None


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [""])[0] or type(exc).__name__


def worker_refusal(reports: dict, scheduler: str) -> str | None:
    """The one-line refusal of a sweep whose workers' reports (worker_package.check_worker, or the
    exception it raised, by worker address) are not all ok; None if they are."""
    bad = {}
    for address, report in sorted(reports.items()):
        if isinstance(report, BaseException):
            bad[address] = f"the check failed ({type(report).__name__}: {_first_line(report)})"
        elif not report.get("ok"):
            bad[address] = report.get("reason", "?")
    if not bad:
        return None
    address, reason = next(iter(bad.items()))
    others = f" (and {len(bad) - 1} more of the {len(reports)} workers)" if len(bad) > 1 else ""
    return (f"worker {address} of {scheduler}{others} cannot run the cases: {reason}; the workers need this "
            f"Python version and platform with the package's dependencies (pip install -r requirements-run.txt, "
            f"docs/sweeps.md)")


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
            raise stop_signal(signum)

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


@dataclass(frozen=True)
class SweepOptions:
    """How a sweep runs (none of these change its results)."""
    scheduler: str | None = None   # address of a Dask scheduler to run on; None: a new local cluster
    workers: int = 2               # workers of that local cluster, one thread each
    processes: bool = True         # its workers are processes (False: threads of this process)
    serial: bool = False           # no Dask: the cases one after the other in this process (one reused instance)
    client: object = None          # a Dask client to use (left open); None: one is made and closed after. A
                                   # client of a scheduler whose workers lack gimbal2axis: send_package first
    redo: str | None = None        # None, 'failed' (rerun the failed cases) or 'all'
    progress: bool = True          # what runs where, and how far it got, on stderr
    checkpoint_s: float = 20.0     # while cases finish, the table is written at least this often
    plot: bool = True              # write the summary plot (.png)


@dataclass
class Plan:
    """What a sweep is to do: its cases, which of them run now, and where the table goes."""
    scene: object
    sweep: object
    cases: list            # every case of the sweep
    todo: list             # those to run now: not in the table yet, or to run again (redo)
    skipped: int           # cases the table has already
    existing: list         # the table's rows before this run
    fmu_bytes: bytes
    fmu_sha: str
    scene_digest: str
    files: store.TableFiles

    @property
    def parquet(self) -> pathlib.Path:
        return self.files.parquet

    @property
    def csv(self) -> pathlib.Path:
        return self.files.csv

    @property
    def png(self) -> pathlib.Path:
        return self.files.png


def plan_sweep(scene_path, sweep_path, fmu_path, out_dir, redo: str | None = None) -> Plan:
    """Expands and checks the cases, checks the output folder and claims the table (SceneError,
    SweepError before anything runs), and reads the table of earlier runs to leave out the cases
    done already."""
    with FMU(fmu_path) as fmu:
        scene, sweep, cases = prepare(scene_path, sweep_path, fmu)
    fmu_bytes = pathlib.Path(fmu_path).read_bytes()
    files = store.TableFiles.of(out_dir, f"{sweep.name}__{scene.name}")
    existing = store.claim(files, sweep.parameters)
    todo, skipped = cases_to_run(cases, existing, redo)
    return Plan(scene, sweep, cases, todo, skipped, existing, fmu_bytes, fmu_digest(fmu_bytes), scene_hash(scene),
                files)


def cases_to_run(cases: list, existing: list, redo: str | None) -> tuple[list, int]:
    """(todo, skipped): the cases without a row in `existing`, and those `redo` asks for again
    ('failed' or 'all'); the same values twice (e.g. a repeated grid value) are one case."""
    done = {r["case_id"]: r for r in existing}
    todo, skipped, seen = [], 0, set()
    for case in cases:
        if case.case_id in seen:
            continue
        seen.add(case.case_id)
        old = done.get(case.case_id)
        if old is not None and not (redo == "all" or (redo == "failed" and old.get("status") != "ok")):
            skipped += 1
        else:
            todo.append(case)
    return todo, skipped


def announce(plan: Plan, options: SweepOptions) -> None:
    """On stderr: the sweep's warning (a `cases` limit that drops grid points), and with progress,
    how many cases run where."""
    for warning in (plan.sweep.limit_warning(), plan.sweep.drive_warning()):
        if warning:
            print(f"sweep: warning: {warning}", file=sys.stderr)
    if options.progress:
        todo = plan.todo
        where = ("" if not todo else " serially" if options.serial else
                 f" on {options.scheduler or f'a local cluster of {options.workers} workers'}")
        print(f"sweep {plan.sweep.name} on scene {plan.scene.name}: {len(plan.cases)} cases, {plan.skipped} already "
              f"done, {len(todo)} to run{where}", file=sys.stderr)


class Recorder:
    """The rows of the cases finished in this run, one per result as it comes, with the progress
    display; they are merged into the table (as it is on disk then: other sweeps may write it too)
    every `checkpoint_s` seconds, at the end, and when the sweep is interrupted: leaving the `with`
    block by Ctrl-C or SIGTERM saves the rows and says so (the exception is marked `reported` for
    gimbal2axis sweep)."""

    def __init__(self, plan: Plan, checkpoint_s: float = 20.0, progress: bool = True):
        self.plan, self.checkpoint_s = plan, checkpoint_s
        self.rows: list[dict] = []
        self.last_save = time.perf_counter()
        self.progress = Progress(len(plan.todo), enabled=progress and bool(plan.todo))

    def record(self, case: Case, result: dict) -> None:
        plan = self.plan
        row = _base_row(case, plan.scene, plan.sweep, plan.scene_digest, plan.fmu_sha)
        row.update(result)
        self.rows.append(row)
        self.progress.update(row["status"])
        if time.perf_counter() - self.last_save > self.checkpoint_s:
            self.save()
            self.last_save = time.perf_counter()

    def save(self) -> list[dict]:
        """Merges this run's rows into the table (Parquet and CSV); returns the table's rows."""
        return store.save(self.plan.files, self.rows, self.plan.sweep.parameters)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.progress.close()
        if isinstance(exc, KeyboardInterrupt):
            reason = str(exc) or "interrupted"
            if self.rows:
                self.save()
                print(f"\nsweep: {reason}; the {len(self.rows)} cases finished in this run are kept in "
                      f"{self.plan.parquet} (with those of earlier runs); the same command again runs the rest",
                      file=sys.stderr)
            else:
                print(f"\nsweep: {reason} before any case of this run finished; the same command again runs them",
                      file=sys.stderr)
            exc.reported = True   # for gimbal2axis sweep: this message was the last word
        return False


def run_planned(plan: Plan, options: SweepOptions, recorder: Recorder, dask: DaskRun) -> None:
    """Runs the cases of `plan.todo`, serially or on Dask, each result to `recorder` as it comes;
    a case refused before running is recorded as failed with the reason. Serially, only Ctrl-C and
    SIGTERM (CaseSignals) end the sweep early: whatever a case's code raises is that case's row."""
    runnable = []
    for case in plan.todo:
        if case.scene is None:
            recorder.record(case, {"case_id": case.case_id, "status": "failed", "message": case.error, "fmu_log": "",
                                   "wall_time_s": 0.0, "worker": "client"})
        else:
            runnable.append(case)
    if options.serial:
        with CaseSignals() as signals:
            for chunk in _serial_chunks(runnable):
                if len(chunk) == 1:
                    results = [run_case(chunk[0].scene, chunk[0].case_id, plan.fmu_bytes, plan.fmu_sha,
                                        plan.sweep.metrics_from_s)]
                else:   # cases of a batch user controller: together, as a Dask task runs them
                    results = run_cases([(c.scene, c.case_id) for c in chunk], plan.fmu_bytes, plan.fmu_sha,
                                        plan.sweep.metrics_from_s)
                signals.check()   # a signal the case's code swallowed: its row is not a result
                for case, result in zip(chunk, results):
                    recorder.record(case, result)
    elif runnable:
        dask.run(plan, runnable, recorder)


def _serial_chunks(cases: list, most: int = 16):
    """The cases of a serial sweep in the order given: one by one, except consecutive cases of a
    batch user controller (gimbal2axis.master.lockstep.batch_key equal), up to `most` together."""
    from ..master.lockstep import batch_key

    chunk, chunk_key = [], None
    for case in cases:
        key = batch_key(case.scene)
        if chunk and (key is None or key != chunk_key or len(chunk) == most):
            yield chunk
            chunk = []
        chunk.append(case)
        chunk_key = key
        if key is None:
            yield chunk
            chunk = []
    if chunk:
        yield chunk


class DaskRun:
    """Cases on Dask: on `options.client`, else on a client it makes (of `options.scheduler` or of
    a new local cluster); the FMU is scattered to the workers once, the cases go in tasks of a few
    each. Leaving the `with` block cancels what an interruption left queued, and closes the
    client and cluster it made."""

    def __init__(self, options: SweepOptions):
        self.options = options
        self.client = options.client
        self.own_client = self.cluster = None
        self.futures: list = []     # the tasks
        self.scattered: list = []   # the FMU on the workers

    def run(self, plan: Plan, cases: list, recorder: Recorder) -> None:
        from distributed import as_completed

        with _StopRequests() as stop:
            if self.client is None:
                options = self.options
                self.own_client, self.cluster = make_client(options.scheduler, options.workers, options.processes)
                self.client = self.own_client
            stop.check()
            fmu_future = self.client.scatter(plan.fmu_bytes, broadcast=True, hash=False)
            self.scattered.append(fmu_future)
            recorder.progress.restart_clock()   # the rate counts from here, not from the cluster's start
            cases_of = self._submit(plan, cases, fmu_future)
            completed = as_completed(self.futures)
            while not completed.is_empty():
                stop.check()
                batch = completed.next_batch(block=False)
                if not batch:
                    time.sleep(0.05)
                for future in batch:
                    chunk = cases_of[future.key]
                    for case, result in zip(chunk, _task_results(future, chunk)):
                        recorder.record(case, result)

    def _submit(self, plan: Plan, cases: list, fmu_future) -> dict:
        """Submits the tasks; returns the cases of each task by its key. Several cases per task: a
        short case costs the scheduler about as much as it costs to run, so tasks carry a few (at
        least 8 tasks per worker remain, to balance the load). A task's call goes as bytes that only
        the worker unpickles (worker_package.call_pickled): a scheduler elsewhere need not have
        gimbal2axis to take it."""
        from . import worker_package

        cases_of = {}
        per_task = cases_per_task(len(cases), _worker_count(self.client))
        for first in range(0, len(cases), per_task):
            chunk = cases[first:first + per_task]
            call = worker_package.pickled_call(run_cases, [(c.scene, c.case_id) for c in chunk], digest=plan.fmu_sha,
                                               from_s=plan.sweep.metrics_from_s)
            future = self.client.submit(worker_package.call_pickled, call, fmu_bytes=fmu_future,
                                        key=f"gimbal-cases-{plan.fmu_sha[:8]}-{chunk[0].case_id}-{len(chunk)}",
                                        pure=False, retries=1)
            self.futures.append(future)
            cases_of[future.key] = chunk
        return cases_of

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        interrupted = isinstance(exc, KeyboardInterrupt)
        if interrupted and self.futures:
            try:   # queued cases would keep a shared scheduler's workers busy
                self.client.cancel(self.futures + self.scattered)
            except Exception:
                pass
        if self.cluster is not None and getattr(self.cluster, "processes", True):
            _quiet_workers_for_shutdown(self.client)
        if self.cluster is not None and interrupted:
            # Our own cluster, dropped with cases still running: its scheduler's complaints about
            # the work and the scattered FMU it loses are no news to the user who stopped it.
            disabled = logging.root.manager.disable
            logging.disable(logging.CRITICAL)
            try:
                self.cluster.close()
            finally:
                logging.disable(disabled)
        if self.own_client is not None:
            self.own_client.close()
        if self.cluster is not None and not interrupted:
            self.cluster.close()
        return False


def close_client(client, cluster) -> None:
    """Closes a client and the local cluster make_client made with it (None: nothing to close);
    the cluster's workers are silenced first, see _quiet_workers_for_shutdown."""
    if client is not None and cluster is not None and getattr(cluster, "processes", True):
        _quiet_workers_for_shutdown(client)
    if client is not None:
        client.close()
    if cluster is not None:
        cluster.close()


def _silence_logging() -> None:
    logging.disable(logging.CRITICAL)


def _quiet_workers_for_shutdown(client) -> None:
    """Silences the logging of our own cluster's workers before it closes: a worker whose
    heartbeat is in flight when the scheduler goes logs the failed connection with a traceback,
    which is the cluster closing, not news to the user (the cases' own errors are in the table)."""
    def silence():
        try:
            client.run(_silence_logging, on_error="ignore")
        except Exception:
            pass

    # a worker that does not answer must not hold up the shutdown that follows
    asking = threading.Thread(target=silence, daemon=True)
    asking.start()
    asking.join(timeout=5.0)


def _task_results(future, chunk: list) -> list[dict]:
    """The results of a task's cases; all failed if the task itself died (e.g. its worker crashed
    twice)."""
    try:
        results = future.result()
    except Exception as exc:
        results = [{"case_id": case.case_id, "status": "failed", "message": f"{type(exc).__name__}: {exc}",
                    "fmu_log": "", "wall_time_s": math.nan, "worker": "?"} for case in chunk]
    future.release()
    return results


def finish(plan: Plan, rows: list, plot: bool, wall0: float) -> Outcome:
    """The outcome of the sweep's own cases in the table (which may hold others of an earlier,
    longer version of the sweep), and the summary plot."""
    ids = {c.case_id for c in plan.cases}
    mine = [r for r in rows if r["case_id"] in ids]
    failed = sum(r.get("status") != "ok" for r in mine)
    ran_now = {c.case_id for c in plan.todo}
    failed_before = sum(r.get("status") != "ok" and r["case_id"] not in ran_now for r in mine)
    if plot:
        sweep = plan.sweep
        title = f"sweep {sweep.name} on {plan.scene.name}: {len(mine)} cases, {len(mine) - failed} ok, {failed} failed"
        store.publish(plan.png, lambda path: table.plot_summary(mine, sweep.parameters, path, title,
                                                                grid=list(sweep.grid)))
    return Outcome(plan.parquet, plan.csv, plan.png, rows, len(plan.todo), plan.skipped, failed,
                   time.perf_counter() - wall0, failed_before)


def run_sweep(scene_path, sweep_path, fmu_path, out_dir, options: SweepOptions = SweepOptions()) -> Outcome:
    """Runs the sweep SWEEP.toml of the scene on the FMU, the table and plot in `out_dir`: plan
    (the cases, those done already), run (serially or on Dask) while recording each result, finish
    (the table, the plot, the outcome). Ctrl-C, SIGTERM (Stopped): the finished cases are kept."""
    wall0 = time.perf_counter()
    plan = plan_sweep(scene_path, sweep_path, fmu_path, out_dir, options.redo)
    announce(plan, options)
    # Leaving the block, the recorder saves and reports first, then Dask's cancelling and closing.
    with DaskRun(options) as dask, Recorder(plan, options.checkpoint_s, options.progress) as recorder:
        run_planned(plan, options, recorder, dask)
        rows = recorder.save()
    return finish(plan, rows, options.plot, wall0)
