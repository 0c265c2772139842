"""Run a parameter sweep or Monte Carlo study of a scene on Dask.

Every case of SWEEP.toml (a grid and/or seeded random draws) is applied to SCENE.toml and run, in
parallel on a local cluster (worker processes of one thread each) or on the workers of an existing
Dask scheduler. Each worker extracts the FMU once and reuses its instance (fmi2Reset) case after case.

Writes <out>/<sweep>__<scene>.parquet and .csv (one row per case: parameters, seeds, metrics,
status, and the error and FMU log of a failed case) and .png (a summary plot). A rerun skips the
cases already in the table, so an interrupted sweep (Ctrl-C, SIGTERM) continues where it stopped.
Several sweeps may write one table at the same time: each merges its rows in under a lock.
"""
import signal
import sys

from ..errors import SceneError, one_line
from ..locations import fmu_path

SUMMARY = "run a parameter sweep or Monte Carlo study of a scene on Dask"
PROG = "gimbal2axis sweep"
EXIT_STATUSES = {
    0: "every case of the sweep ran to the end (status ok)",
    1: "some cases failed: their rows in the table have status = failed, the error in the column 'message' and "
       "the FMU's log in 'fmu_log'",
    2: "nothing ran: the scene, the sweep file or the options were refused (a misspelt parameter name, a scheduler "
       "that does not answer, an --out that cannot be written, a table of the same name from a sweep over other "
       "parameters, ...)",
    130: "interrupted by Ctrl-C (SIGINT): the cases finished so far are kept",
    143: "terminated (SIGTERM): likewise",
}

EPILOG = """\
sweep file:
  [grid] (every combination) and/or [random] (seeded draws) tables of parameters, named by
  their path into the scene (controller.azimuth.kp, base_motion.seed) or as FMU parameters
  (gear1.k_s); a 'cases' limit; optional stop_time and metrics_from_s. The format in full:
  docs/sweeps.md in the repository, and gimbal2axis/sweep/spec.py.

example:
  gimbal2axis sweep scenes/ship_stabilization.toml sweeps/gains_1000.toml --workers 2
"""


def _stopped(signum, frame):
    """Ctrl-C and SIGTERM as StopSignals (runner.stop_signal): the wrappers of a user controller's
    code let them pass, where they fail the case for a KeyboardInterrupt the code raised itself."""
    from ..sweep.runner import stop_signal

    raise stop_signal(signum)


def add_arguments(parser) -> None:
    parser.epilog = EPILOG
    parser.add_argument("scene", metavar="SCENE.toml", help="scene file (scenes/*.toml)")
    parser.add_argument("sweep", metavar="SWEEP.toml", help="sweep file (sweeps/*.toml): what to vary and how")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="run on the workers of this Dask scheduler (e.g. tcp://10.0.0.5:8786) instead of a "
                             "local cluster")
    parser.add_argument("--workers", type=int, default=2, metavar="N",
                        help="worker processes of the local cluster (default 2)")
    parser.add_argument("--out", default="results/sweeps", metavar="DIR",
                        help="directory of the table and plot (default results/sweeps in the current directory)")
    parser.add_argument("--fmu", default=None,
                        help="the FMU to run (default $GIMBAL2AXIS_FMU, else the build the package was configured "
                             "with)")
    parser.add_argument("--quiet", action="store_true",
                        help="print nothing but errors and warnings (no progress counter, no summary)")
    parser.add_argument("--serial", action="store_true", help="no Dask: run the cases one after the other in this "
                                                              "process")
    parser.add_argument("--threads", action="store_true",
                        help="local cluster of threads in this process instead of worker processes")
    parser.add_argument("--save-every", type=float, default=20.0, metavar="SECONDS",
                        help="while cases finish, merge them into the table at least this often (default 20)")
    parser.add_argument("--redo", choices=["failed", "all"], default=None,
                        help="run the failed cases (or all cases) again, although the table has them")


def requirements_note(scene_path, rows: list) -> str | None:
    """Why the column requirements_met is empty in every case of the scene that ran, or None where a
    case was judged: a case is judged only by a scene with [requirements] and a [target] whose window
    (requirements.from_s) starts before the case's stop time (sweep.worker.metrics)."""
    import warnings

    from ..scene import load_scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the scene's advice was given when the sweep loaded it
        scene = load_scene(scene_path)
    ok = [r for r in rows if r.get("scene") == scene.name and r.get("status") == "ok"]
    if not ok or any(r.get("requirements_met") is not None for r in ok):
        return None
    if not scene.requirements:
        why = "the scene has no [requirements]"
    elif scene.target_spec is None:
        why = "the scene has no [target]: no line-of-sight error to judge"
    else:
        from_s = float(scene.requirements.get("from_s", 0.0))
        stop = max(float(r["stop_time"]) for r in ok)
        why = (f"the scene's requirements window starts at {from_s:g} s (requirements.from_s), at or after the "
               f"cases' stop time {stop:g} s" if stop <= from_s else "no case was judged")
    return f"requirements_met is empty in every case: {why}"


def execute(args) -> int:
    if args.workers < 1:
        args.command_parser.error("--workers must be >= 1")
    if not args.save_every >= 0:   # also refuses nan
        args.command_parser.error("--save-every must be >= 0 seconds")
    # here, not at the top: Dask, pyarrow and matplotlib are for this subcommand only
    from ..sweep import SweepError, SweepOptions, run_sweep
    from ..sweep.runner import Stopped

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _stopped)
    try:
        options = SweepOptions(scheduler=args.scheduler, workers=args.workers, processes=not args.threads,
                               serial=args.serial, redo=args.redo, progress=not args.quiet,
                               checkpoint_s=args.save_every)
        outcome = run_sweep(args.scene, args.sweep, fmu_path(args.fmu), args.out, options)
    except (SceneError, SweepError) as exc:
        print(one_line(f"{PROG}: error: {exc}"), file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        if not getattr(exc, "reported", False):
            print(f"\nsweep: {str(exc) or 'interrupted'}", file=sys.stderr)
        return 128 + (signal.SIGTERM if isinstance(exc, Stopped) else signal.SIGINT)
    total = outcome.ran + outcome.skipped
    if not args.quiet:
        print(f"{total} cases ({outcome.ran} run, {outcome.skipped} already done): {total - outcome.failed} ok, "
              f"{outcome.failed} failed; {outcome.wall_time:.1f} s")
        note = requirements_note(args.scene, outcome.rows)
        if note:
            print(note)
        print(f"wrote {outcome.parquet}, {outcome.csv} and {outcome.png}")
    if not outcome.failed:
        return 0
    for r in [r for r in outcome.rows if r.get("status") != "ok"][:3]:   # errors: shown under --quiet too
        print(f"  failed case {r['case']} ({r['case_id']}): {r['message'].splitlines()[0][:200]}")
    before = (f" ({outcome.failed_before} of them from an earlier run; --redo failed runs them again)"
              if outcome.failed_before else "")
    print(f"{PROG}: {outcome.failed} of {total} cases failed{before}: their rows in {outcome.csv} (and "
          f".parquet) have status = failed, the error in the column 'message' and the FMU's log in 'fmu_log'",
          file=sys.stderr)
    return 1
