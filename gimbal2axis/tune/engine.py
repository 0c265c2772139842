"""A tuning end to end: an Optuna study asks for candidates in batches; each candidate runs on every
member of the robustness set as cases of the sweep engine (Dask: a local cluster or a scheduler's
workers, one FMU instance per worker reused; or serially); each evaluation is stored as it finishes
in a table of the sweep machinery (gimbal2axis.sweep.store: Parquet + CSV, merged under a lock);
the candidate is judged (objective.py) and told to the study.

Resuming and reproducibility: the study is seeded (the sampler's seed is the tuning's), its candidates
are told in the order they were asked, and every evaluation is keyed by its values (the candidate's
and the scenario's), the scene's content, the stop time, the metrics window and the band metrics. A
tuning run again replays the study from its first trial; an evaluation whose key is in the table is
taken from it instead of being run. The study sees the same values in the same order, so an
interrupted tuning continues where it stopped and ends where an uninterrupted one with the same seed
ends, evaluation for evaluation.
"""
from __future__ import annotations

import hashlib
import math
import pathlib
import sys
import time
import warnings
from dataclasses import dataclass, field

from ..errors import SceneError
from ..fmu import FMU
from ..fmu.worker_cache import fmu_digest
from ..scene.scene import check_against_fmu, load_scene
from ..sweep import store
from ..sweep.names import check_cases_accepted, resolve_names
from ..sweep.runner import Case, CaseSignals, make_client, close_client, cases_per_task, _worker_count
from ..sweep.spec import Sweep, apply_case, canonical, check_metrics_window, scene_hash
from . import objective as judge
from .spec import TuneError, Tuning, load_tuning
from .worker import run_tune_cases


@dataclass(frozen=True)
class TuneOptions:
    scheduler: str | None = None
    workers: int = 2
    processes: bool = True
    serial: bool = False
    progress: bool = True
    checkpoint_s: float = 20.0
    trials: int | None = None        # overrides the file's [optimizer] trials
    client: object = None            # an existing distributed.Client to run on


@dataclass
class Problem:
    """A tuning ready to run: the scene, the tuning, the FMU (open, for the margins), the scenarios,
    and the tables."""
    scene: object
    tuning: Tuning
    fmu: FMU
    fmu_bytes: bytes
    fmu_sha: str
    scene_digest: str
    resolved: dict
    scenarios: list
    holdout: list
    evaluations: store.TableFiles
    trials_files: store.TableFiles
    columns: list                     # the evaluation table's parameter columns
    loops: object = None              # margins.LoopModels, when the constraints or the report need it

    def apply(self, values: dict):
        """The scene with these values (and the tuning's stop_time) put in."""
        return apply_case(self.scene, self.resolved, values, self.tuning.stop_time)

    def key(self, values: dict) -> str:
        payload = {"scene": self.scene_digest, "stop_time": self.tuning.stop_time,
                   "metrics_from_s": self.tuning.metrics_from_s, "bands": sorted(self.tuning.bands),
                   "case": values}
        return hashlib.sha256(canonical(payload).encode()).hexdigest()[:16]


def _pseudo_sweep(tuning: Tuning, names: list[str], values: dict) -> Sweep:
    """The tuning's names as a sweep's, for the sweep's name checks and their did-you-mean messages."""
    return Sweep(path=tuning.path, name=tuning.name, description="", cases_limit=None, seed=tuning.seed, samples=None,
                 stop_time=tuning.stop_time, metrics_from_s=tuning.metrics_from_s,
                 grid={name: [values.get(name, 0.0)] for name in names})


def midpoint(parameter) -> float:
    if parameter.start is not None:
        return parameter.start
    if parameter.log:
        return math.sqrt(parameter.low * parameter.high)
    return 0.5 * (parameter.low + parameter.high)


def plan(scene_path, tuning_path, fmu_path, out_dir, tuning: Tuning | None = None) -> Problem:
    """Loads and checks the scene and the tuning file against each other and the FMU (TuneError or
    SceneError in one line, before anything runs), and claims the tables in `out_dir`."""
    tuning = tuning or load_tuning(tuning_path)
    scene = load_scene(scene_path)
    scene = scene.with_changes(path=scene.path.resolve())
    fmu = FMU(fmu_path)
    try:
        check_against_fmu(scene, fmu)
        scenarios = tuning.robustness.scenarios()
        holdout = tuning.holdout.scenarios() if tuning.holdout else []
        names = list(dict.fromkeys(tuning.parameter_names + tuning.robustness.names +
                                   (tuning.holdout.names if tuning.holdout else [])))
        resolved = _check_scenarios(tuning, scene, fmu, names, scenarios + holdout)
        _check_objective_against_scene(tuning, scene)
        fmu_bytes = pathlib.Path(fmu_path).read_bytes()
        stem = f"{tuning.name}__{scene.name}"
        evaluations = store.TableFiles.of(out_dir, stem)
        trials_files = store.TableFiles.of(out_dir, f"{stem}_trials")
        problem = Problem(scene, tuning, fmu, fmu_bytes, fmu_digest(fmu_bytes), scene_hash(scene), resolved,
                          scenarios, holdout, evaluations, trials_files, names)
        if tuning.constraints.needs_margins:
            _add_loop_models(problem)
        store.claim(evaluations, names)
        store.claim(trials_files, tuning.parameter_names)
        return problem
    except BaseException:
        fmu.close()
        raise


def _check_scenarios(tuning: Tuning, scene, fmu, names: list, scenarios: list) -> dict:
    """The names resolved as a sweep's (resolve_names); every scenario (robustness and holdout) with the
    midpoint candidate checked as a case, its metrics window against its stop time."""
    probe_values = {p.name: midpoint(p) for p in tuning.parameters}
    for scenario in scenarios:
        probe_values.update({k: v for k, v in scenario.items() if k not in probe_values})
    sweep = _pseudo_sweep(tuning, names, probe_values)
    resolved, candidates = resolve_names(sweep, scene, fmu)
    for scenario in scenarios:
        values = {p.name: midpoint(p) for p in tuning.parameters}
        values.update(scenario)
        case = Case(0, "", dict(probe_values, **values))
        try:
            scenario_scene = apply_case(scene, resolved, values, tuning.stop_time)
            check_against_fmu(scenario_scene, fmu)
        except (SceneError, TypeError, ValueError, KeyError) as exc:
            case.error = f"invalid case: {exc}"
            check_cases_accepted(scene, sweep, fmu, resolved, [case], candidates)
        else:
            try:
                check_metrics_window(tuning.metrics_from_s, scenario_scene.stop_time, "the stop time of its runs",
                                     TuneError)
            except TuneError as exc:
                raise TuneError(f"{tuning.path}: {exc}") from None
    return resolved


def _check_objective_against_scene(tuning: Tuning, scene) -> None:
    """What the objective and the constraints measure must be in the scene: a target, a moving one for
    tracking and on-target shares, requirements."""
    if not scene.target_spec:
        raise TuneError(f"{tuning.path}: scene {scene.name} has no [target]: there is no line-of-sight error to "
                        f"minimize")
    if scene.moving_target is None:
        fixed = "its target is a fixed direction, whose error is metric = \"los_rms\""
        if any(term.metric == "tracking_rms" for term in tuning.objective.terms):
            raise TuneError(f"{tuning.path}: [objective] metric = \"tracking_rms\" needs a moving target "
                            f"([target] type = \"earth_point\", \"flyby\" or \"track\") in scene {scene.name}: {fixed}")
        if tuning.constraints.on_target_min_fraction is not None:
            raise TuneError(f"{tuning.path}: [constraints] on_target_min_fraction needs a moving target in scene "
                            f"{scene.name}: {fixed}")
    if tuning.constraints.requirements and not scene.requirements:
        raise TuneError(f"{tuning.path}: [constraints] requirements = true, but scene {scene.name} has no "
                        f"[requirements]")


def _add_loop_models(problem: Problem) -> None:
    """The linear loops of the margin constraints: a PID scene's only."""
    from ..analysis.isolation_prediction import pid_gains
    from .margins import LoopModels
    try:
        pid_gains(problem.scene, problem.fmu)
    except SceneError as exc:
        raise TuneError(f"{problem.tuning.path}: [constraints] gain/phase margins: {exc}") from None
    problem.loops = LoopModels(problem.scene, problem.fmu, problem.apply)


class Evaluator:
    """Runs evaluations (scene, key) on Dask or serially, taking those already in the table from it,
    and stores each row as it finishes (saved at least every `checkpoint_s` and after each batch)."""

    def __init__(self, problem: Problem, options: TuneOptions):
        self.problem, self.options = problem, options
        stored = store.read(problem.evaluations).rows
        self.done = {row["case_id"]: row for row in stored}
        self.new_rows: list = []
        self.ran = 0
        self.reused = 0
        self.client = options.client
        self.own_client = self.cluster = None
        self.fmu_future = None
        self.last_save = time.perf_counter()
        self.progress = None

    def start_progress(self, total: int) -> None:
        from ..sweep.progress import Progress
        self.progress = Progress(total, enabled=self.options.progress)

    def _client(self):
        if self.client is None:
            self.own_client, self.cluster = make_client(self.options.scheduler, self.options.workers,
                                                        self.options.processes)
            self.client = self.own_client
        if self.fmu_future is None:
            self.fmu_future = self.client.scatter(self.problem.fmu_bytes, broadcast=True, hash=False)
        return self.client

    def rows(self, requests: list, role: str, extra: list | None = None) -> list:
        """The rows of `requests` ([(values, label dict)]) in their order: from the table, else run now."""
        problem = self.problem
        keyed = [(problem.key(values), values, labels) for values, labels in requests]
        todo = {}
        for key, values, labels in keyed:
            if key in self.done:
                self.reused += 1
                if self.progress:
                    self.progress.update(self.done[key].get("status", "ok"))
            elif key not in todo:
                todo[key] = (values, labels)
        if todo:
            self._run(todo, role)
        return [self.done[key] for key, _, _ in keyed]

    def _record(self, key: str, values: dict, labels: dict, result: dict, role: str) -> None:
        problem = self.problem
        row = {"case_id": key, "case": None, "sweep": problem.tuning.name, "scene": problem.scene.name,
               "scene_hash": problem.scene_digest,
               "stop_time": problem.tuning.stop_time or problem.scene.stop_time}
        row.update(values)
        row.update(labels)
        row["role"] = role
        row["sampling_seed"] = problem.tuning.seed
        row["fmu_sha256"] = problem.fmu_sha[:12]
        row.update(result)
        self.done[key] = row
        self.new_rows.append(row)
        self.ran += 1
        if self.progress:
            self.progress.update(row["status"])
        if time.perf_counter() - self.last_save > self.options.checkpoint_s:
            self.save()

    def save(self) -> None:
        if self.new_rows:
            store.save(self.problem.evaluations, self.new_rows, self.problem.columns)
            self.new_rows = []
        self.last_save = time.perf_counter()

    def _run(self, todo: dict, role: str) -> None:
        problem = self.problem
        tuning = problem.tuning
        cases = []
        for key, (values, labels) in todo.items():
            try:
                cases.append((key, values, labels, problem.apply(values)))
            except (SceneError, TypeError, ValueError, KeyError) as exc:   # refused before running: a failed case
                self._record(key, values, labels, {"case_id": key, "status": "failed", "message": f"invalid case: {exc}",
                                                   "fmu_log": "", "wall_time_s": 0.0, "worker": "client"}, role)
        if not cases:
            return
        if self.options.serial:
            with CaseSignals() as signals:   # only Ctrl-C and SIGTERM stop the tuning, not the controller's code
                for key, values, labels, scene in cases:
                    row, = run_tune_cases([(scene, key)], problem.fmu_bytes, problem.fmu_sha, tuning.metrics_from_s,
                                          tuning.bands)
                    signals.check()
                    self._record(key, values, labels, row, role)
            return
        self._run_dask(cases, role)

    def _run_dask(self, cases: list, role: str) -> None:
        from distributed import as_completed

        from ..sweep import worker_package

        problem, tuning = self.problem, self.problem.tuning
        client = self._client()
        per_task = cases_per_task(len(cases), _worker_count(client), most=8)
        futures, chunk_of = [], {}
        for first in range(0, len(cases), per_task):
            chunk = cases[first:first + per_task]
            call = worker_package.pickled_call(run_tune_cases, [(scene, key) for key, _, _, scene in chunk],
                                               digest=problem.fmu_sha, from_s=tuning.metrics_from_s, bands=tuning.bands)
            future = client.submit(worker_package.call_pickled, call, fmu_bytes=self.fmu_future,
                                   key=f"gimbal-tune-{problem.fmu_sha[:8]}-{chunk[0][0]}-{len(chunk)}", pure=False,
                                   retries=1)
            futures.append(future)
            chunk_of[future.key] = chunk
        try:
            for future in as_completed(futures):
                chunk = chunk_of[future.key]
                try:
                    results = future.result()
                except Exception as exc:   # the task died (its worker crashed twice): its cases failed
                    results = [{"case_id": key, "status": "failed", "message": f"{type(exc).__name__}: {exc}",
                                "fmu_log": "", "wall_time_s": math.nan, "worker": "?"} for key, _, _, _ in chunk]
                for (key, values, labels, _), result in zip(chunk, results):
                    self._record(key, values, labels, result, role)
                future.release()
        except BaseException:
            try:
                client.cancel(futures)
            except Exception:
                pass
            raise

    def close(self, interrupted: bool = False) -> None:
        if self.progress:
            self.progress.close()
        if self.own_client is not None:
            if interrupted:
                import logging
                disabled = logging.root.manager.disable
                logging.disable(logging.CRITICAL)
                try:
                    close_client(self.own_client, self.cluster)
                finally:
                    logging.disable(disabled)
            else:
                close_client(self.own_client, self.cluster)
            self.own_client = self.cluster = None


def make_sampler(tuning: Tuning, batch: int):
    import optuna

    if tuning.sampler == "tpe":
        return optuna.samplers.TPESampler(seed=tuning.seed, n_startup_trials=max(batch, 10), multivariate=True)
    if tuning.sampler == "random":
        return optuna.samplers.RandomSampler(seed=tuning.seed)
    x0 = {p.name: p.start for p in tuning.parameters} if all(p.start is not None for p in tuning.parameters) else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # the population is the batch (one generation per batch), at least 4: below, CMA-ES's recombination
        # weights degenerate (one parent: cmaes divides by zero); a generation then spans batches
        return optuna.samplers.CmaEsSampler(seed=tuning.seed, popsize=max(batch, 4), x0=x0, n_startup_trials=0,
                                            warn_independent_sampling=False)


@dataclass
class TuneResult:
    problem: Problem
    trials: list                  # judged candidates (objective.Judgement as rows), in trial order
    best: dict | None             # the best feasible trial's row, else None
    least_violating: dict | None  # without a feasible one: the trial of least violation
    evaluations_run: int
    evaluations_reused: int
    wall_time: float
    holdout: dict = field(default_factory=dict)


def suggest(trial, tuning: Tuning) -> dict:
    return {p.name: trial.suggest_float(p.name, p.low, p.high, log=p.log) for p in tuning.parameters}


def requests_for(candidate: dict, scenarios: list, trial_number: int | None) -> list:
    labels = {} if trial_number is None else {"trial": trial_number}
    return [(dict(candidate, **scenario), dict(labels, scenario=index)) for index, scenario in enumerate(scenarios)]


def run_tuning(problem: Problem, options: TuneOptions = TuneOptions(), evaluator: Evaluator | None = None) -> TuneResult:
    """Runs (or resumes) the study; every evaluation stored as it finishes; the trials table written after
    each batch. KeyboardInterrupt (Ctrl-C, SIGTERM as runner.Stopped) keeps what finished."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    wall0 = time.perf_counter()
    tuning = problem.tuning
    total = options.trials or tuning.trials
    batch = min(tuning.batch, total)
    own = evaluator is None
    evaluator = evaluator or Evaluator(problem, options)
    evaluator.start_progress(total * len(problem.scenarios))
    interrupted = False
    trial_rows: list = []
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", category=optuna.exceptions.ExperimentalWarning)
            study, from_start = _study(tuning, batch)
            number = batch_number = 0
            while number < total:
                size = 1 if number == 0 and from_start else min(batch, total - number)
                trial_rows += _run_batch(problem, evaluator, study, size, batch_number)
                number += size
                batch_number += 1
                store.save(problem.trials_files, trial_rows, tuning.parameter_names)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        try:
            evaluator.save()
            if trial_rows:
                store.save(problem.trials_files, trial_rows, tuning.parameter_names)
        finally:
            if own:
                evaluator.close(interrupted)
    best, least = judge.pick_best(trial_rows)
    return TuneResult(problem, trial_rows, best, least, evaluator.ran, evaluator.reused,
                      time.perf_counter() - wall0)


def _study(tuning: Tuning, batch: int):
    """(the Optuna study, whether its first trial is the start point): with a start for every parameter
    (e.g. the scene's own gains) that start is trial 0, run alone: the study knows its search space after
    it, so CMA-ES's first generation is drawn around x0, not at random."""
    import optuna

    study = optuna.create_study(direction="minimize", sampler=make_sampler(tuning, batch))
    start = {p.name: p.start for p in tuning.parameters if p.start is not None}
    from_start = len(start) == len(tuning.parameters)
    if from_start:
        study.enqueue_trial(start)
    return study, from_start


def _run_batch(problem: Problem, evaluator: Evaluator, study, size: int, batch_number: int) -> list:
    """Asks the study for `size` candidates, runs each on the robustness set, tells it their values; their
    trial rows."""
    tuning, runs = problem.tuning, len(problem.scenarios)
    asked = [study.ask() for _ in range(size)]
    candidates = [suggest(trial, tuning) for trial in asked]
    requests = [r for trial, c in zip(asked, candidates) for r in requests_for(c, problem.scenarios, trial.number)]
    rows = evaluator.rows(requests, "tuning")
    evaluator.save()
    trial_rows = []
    for index, (trial, candidate) in enumerate(zip(asked, candidates)):
        margins = problem.loops.margins(candidate) if problem.loops is not None else {}
        verdict = judge.judge(tuning, rows[index * runs:(index + 1) * runs], margins)
        study.tell(trial, verdict.value)
        trial_rows.append(judge.trial_row(problem, trial.number, batch_number, candidate, verdict, margins))
    return trial_rows


def evaluate(problem: Problem, evaluator: Evaluator, candidate: dict, scenarios: list, role: str) -> dict:
    """A candidate on a list of scenarios (e.g. the holdout set), judged as a trial is: the verdict's row
    with the per-scenario objective values (`per_scenario`)."""
    rows = evaluator.rows(requests_for(candidate, scenarios, None), role)
    evaluator.save()
    margins = problem.loops.margins(candidate) if problem.loops is not None else {}
    verdict = judge.judge(problem.tuning, rows, margins)
    row = judge.trial_row(problem, -1, -1, candidate, verdict, margins)
    row["per_scenario"] = verdict.per_run
    return row


def scene_gains(problem: Problem) -> dict:
    """The scene's own values of the tuned parameters (None where the scene does not set one)."""
    from ..scene.scene import parameter_value
    from ..sweep.spec import parse_name

    values = {}
    for p in problem.tuning.parameters:
        section, path = parse_name(p.name)
        if section == "fmu" or section in ("parameters", "fidelity"):
            values[p.name] = parameter_value(problem.scene, problem.fmu, path[0])
        elif section in ("controller", "base_motion", "sensors", "target"):
            node = getattr(problem.scene, {"controller": "controller_spec", "base_motion": "base_motion_spec",
                                           "sensors": "sensors_spec", "target": "target_spec"}[section]) or {}
            for key in path:
                node = node[key] if isinstance(node, (dict, list)) and (isinstance(node, dict) and key in node or
                                                                        isinstance(node, list) and key < len(node)) \
                    else None
                if node is None:
                    break
            values[p.name] = node
        else:
            values[p.name] = None
    return values


def describe_candidate(candidate: dict) -> str:
    return ", ".join(f"{name} = {value:.4g}" for name, value in candidate.items())


def warn(message: str) -> None:
    print(f"tune: warning: {message}", file=sys.stderr)
