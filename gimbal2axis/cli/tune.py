"""Tune a controller: an optimizer (Optuna's CMA-ES by default) over the sweep engine.

TUNE.toml names the parameters to tune (the paths a sweep takes: controller.azimuth.kp, gear1.k_s,
...) with bounds and scale, the objective (line-of-sight RMS over a window, a band RMS from the run's
PSD, or a weighted sum), the constraints (peak current against the limit, voltage saturation time,
gain and phase margins of the linearized loop, the scene's requirements) and the robustness set (sea
states x seeds x parameter draws) on which every candidate runs, the same for all of them. The
candidates run in batches on Dask (a local cluster or a scheduler's workers, one FMU instance per
worker), or serially.

Writes <out>/<tuning>__<scene>.parquet and .csv (every evaluation: candidate x scenario, as it
finishes), <out>/<tuning>__<scene>_trials.parquet and .csv (one row per candidate: objective,
constraints, margins), and unless --no-report <out>/<tuning>__<scene>_report.html with its figures
(convergence, the best candidates, time and PSD plots of the best against the scene's own gains, S and
T with the margins, the pointing error budget, the held-out check). The same command again continues
an interrupted tuning: evaluations in the table are not run again, and the seeded study ends where an
uninterrupted one would.
"""
import signal
import sys

from ..errors import SceneError, one_line
from ..locations import fmu_path

SUMMARY = "tune controller gains (or any parameters) with an optimizer over the sweep engine"
PROG = "gimbal2axis tune"
EXIT_STATUSES = {
    0: "done: the best candidate meets every constraint",
    1: "ran, but no candidate met the constraints (the least violating one is reported)",
    2: "refused: the scene, the tuning file (a misspelt key or parameter name, bad bounds, ...) or an option; "
       "nothing ran",
    130: "interrupted by Ctrl-C (SIGINT): the evaluations finished so far are kept; the same command continues",
    143: "terminated (SIGTERM): likewise",
}

EPILOG = """\
tuning file: [parameters] (name = { bounds = [low, high], scale = "linear" | "log" }),
  [objective], [constraints], [robustness], [holdout], [optimizer]; the format in full:
  docs/tuning.md in the repository, and gimbal2axis/tune/spec.py.

example:
  gimbal2axis tune scenes/ship_stabilization.toml tunings/ship_pid.toml --workers 2
"""


def _stopped(signum, frame):
    """Ctrl-C and SIGTERM as StopSignals (runner.stop_signal): the wrappers of a user controller's
    code let them pass, where they fail the case for a KeyboardInterrupt the code raised itself."""
    from ..sweep.runner import stop_signal

    raise stop_signal(signum)


def add_arguments(parser) -> None:
    parser.epilog = EPILOG
    parser.add_argument("scene", metavar="SCENE.toml", help="scene file (scenes/*.toml)")
    parser.add_argument("tuning", metavar="TUNE.toml", help="tuning file (tunings/*.toml)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="run on the workers of this Dask scheduler instead of a local cluster")
    parser.add_argument("--workers", type=int, default=2, metavar="N",
                        help="worker processes of the local cluster (default 2)")
    parser.add_argument("--out", default="results/tuning", metavar="DIR",
                        help="directory of the tables and the report (default results/tuning)")
    parser.add_argument("--fmu", default=None,
                        help="the FMU to run (default $GIMBAL2AXIS_FMU, else the build the package was configured with)")
    parser.add_argument("--quiet", action="store_true",
                        help="print nothing but errors and warnings (no progress, no summary)")
    parser.add_argument("--serial", action="store_true", help="no Dask: run the evaluations in this process")
    parser.add_argument("--threads", action="store_true",
                        help="local cluster of threads in this process instead of worker processes")
    parser.add_argument("--trials", type=int, default=None, metavar="N",
                        help="candidates in all (default: the file's [optimizer] trials)")
    parser.add_argument("--save-every", type=float, default=20.0, metavar="SECONDS",
                        help="while evaluations finish, save them at least this often (default 20; and after "
                             "every batch)")
    parser.add_argument("--no-report", action="store_true",
                        help="no report page (nor its runs of the best and the scene's gains, nor the held-out check)")


def against_the_start(tuning, trials: list, best: dict) -> str | None:
    """The best against trial 0 where trial 0 is the tuning file's start (every parameter has a start):
    how much the search gained, or that it has not left the start yet (too few --trials)."""
    if not trials or any(p.start is None for p in tuning.parameters):
        return None
    start = next((t for t in trials if t.get("trial") == 0), None)
    if start is None or not start.get("objective_mrad"):
        return None
    gain = 1.0 - best["objective_mrad"] / start["objective_mrad"]
    verdict = (f"{gain:.1%} lower" if gain >= 0.01 else
               "not 1 % lower: the search has not left the start yet; give it more --trials")
    return f"start (trial 0, the tuning file's start values): objective {start['objective_mrad']:.5g} mrad; the best {verdict}"


def check_options(args) -> None:
    """What argparse cannot say: the ranges of the numeric options (refused as usage errors, status 2)."""
    from ..limits import MAX_TUNE_TRIALS

    refusals = [(args.workers < 1, "--workers must be >= 1"),
                (args.trials is not None and args.trials < 1, "--trials must be >= 1"),
                (args.trials is not None and args.trials > MAX_TUNE_TRIALS,
                 f"--trials {args.trials} is over the limit of {MAX_TUNE_TRIALS:,} candidates"),
                (not args.save_every >= 0, "--save-every must be >= 0 seconds")]
    for refused, message in refusals:
        if refused:
            args.command_parser.error(message)


def execute(args) -> int:
    check_options(args)
    from ..sweep import SweepError
    from ..sweep.runner import Stopped
    from ..tune.engine import TuneOptions, plan

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _stopped)
    options = TuneOptions(scheduler=args.scheduler, workers=args.workers, processes=not args.threads,
                          serial=args.serial, progress=not args.quiet, checkpoint_s=args.save_every,
                          trials=args.trials)
    problem = None
    try:
        problem = plan(args.scene, args.tuning, fmu_path(args.fmu), args.out)
        if not args.quiet:
            print(_plan_line(problem, options), file=sys.stderr)
        result, report_path = _tune_and_report(problem, options, args.no_report)
    except (SceneError, SweepError) as exc:
        print(one_line(f"{PROG}: error: {' '.join(str(exc).split())}"), file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        print(f"\ntune: {str(exc) or 'interrupted'}; the evaluations finished so far are kept in "
              f"{problem.evaluations.parquet if problem else args.out}; the same command again continues",
              file=sys.stderr)
        return 128 + (signal.SIGTERM if isinstance(exc, Stopped) else signal.SIGINT)
    finally:
        if problem is not None:
            problem.fmu.close()
    if not args.quiet:
        _print_outcome(problem, result, report_path)
    if result.best is None:
        print(f"{PROG}: no candidate met the constraints; see {problem.trials_files.csv} (violation_* columns)",
              file=sys.stderr)
        return 1
    return 0


def _plan_line(problem, options) -> str:
    t = problem.tuning
    return (f"tune {t.name} on scene {problem.scene.name}: {len(t.parameters)} parameters, "
            f"{options.trials or t.trials} candidates in batches of {min(t.batch, options.trials or t.trials)}, "
            f"each on {len(problem.scenarios)} runs ({t.sampler}, seed {t.seed}); "
            f"{'serially' if options.serial else options.scheduler or f'{options.workers} local workers'}")


def _tune_and_report(problem, options, no_report: bool):
    """(the tuning's result, the report page's path or None); the evaluator closed however it ends."""
    from ..tune.engine import Evaluator, run_tuning

    evaluator = Evaluator(problem, options)
    interrupted = False
    try:
        result = run_tuning(problem, options, evaluator)
        report_path = None
        if not no_report:
            from ..tune.report import write_report
            evaluator.progress = None
            report_path = write_report(result, evaluator)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        evaluator.close(interrupted)
    return result, report_path


def _print_outcome(problem, result, report_path) -> None:
    print(f"{len(result.trials)} candidates, {result.evaluations_run} evaluations run, "
          f"{result.evaluations_reused} taken from the table; {result.wall_time:.1f} s")
    best = result.best or result.least_violating
    if best is not None:
        print(_best_line(problem, result, best))
    start_line = against_the_start(problem.tuning, result.trials, best) if result.best is not None else None
    if start_line:
        print(start_line)
    if result.holdout:
        h = result.holdout
        print(f"held out ({h['runs']} runs): best {h['best_mrad']:.5g} mrad, scene's own {h['own_mrad']:.5g} mrad")
    print(f"wrote {problem.evaluations.parquet}, {problem.trials_files.parquet} (and .csv)"
          + (f", {report_path}" if report_path else ""))


def _best_line(problem, result, best: dict) -> str:
    from ..tune.engine import describe_candidate

    names = problem.tuning.parameter_names
    margins = (f"; margins az {best['gm_az_db']:.3g} dB / {best['pm_az_deg']:.3g} deg, el {best['gm_el_db']:.3g}"
               f" dB / {best['pm_el_deg']:.3g} deg" if "gm_az_db" in best else "")
    return (f"{'best' if result.best else 'least violating (no candidate met the constraints)'}: trial "
            f"{best['trial']}: {describe_candidate({n: best[n] for n in names})}; objective "
            f"{best['objective_mrad']:.5g} mrad; peak current {best['worst_i_frac_peak']:.3g} of the limit" + margins)
