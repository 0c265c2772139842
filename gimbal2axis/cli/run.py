"""Run a scene file (scenes/*.toml) on the Gimbal2Axis FMU.

An fmpy master steps the FMU with the scene's controller in the loop (the voltage computed from the
sensors at one communication point is applied over the step after the next) and writes, as the run
goes, <out>/<scene>.parquet (every recorded signal at every step, SI units, each field's unit in the
schema) and <out>/<scene>.csv (the same at the scene's output interval, each column headed `name
[unit]`: `time [s]`, `alpha [rad]`), then <out>/<scene>.png (plots) and <out>/<scene>_run.json
(complete or partial), where <scene> is the scene file's name without .toml; then, unless --quiet, it
prints a summary line (line-of-sight error, wall time, real-time factor, events, requirements).
"""
import math
import os
import pathlib
import sys
import tempfile
import warnings

from ..errors import SceneError, SceneWarning, StopSignal, one_line
from ..locations import fmu_path
from .defaults import scene_file
from .failures import (EXIT_DONE, EXIT_ERROR, EXIT_FAILED_CHECK, EXIT_FAILED_PARTIAL, EXIT_FOR_STOP, EXIT_INTERRUPTED,
                       EXIT_TERMINATED, run_reporting_failures, signals_end_the_run)

SUMMARY = "run a scene file: CSV, plots and a summary line"
PROG = "gimbal2axis run"
DEFAULT_SCENE = pathlib.Path("scenes", "free_swing.toml")   # relative to the current directory
EXIT_STATUSES = {EXIT_DONE: "done", EXIT_FAILED_CHECK: "done, and --check found the scene's requirements not met",
                 EXIT_ERROR: "refused: the scene, an option or the output directory (a run too long for the disk "
                             "included); nothing run",
                 EXIT_FAILED_PARTIAL: "the run failed part-way: the results up to the last good step are written, "
                                      "marked partial",
                 EXIT_INTERRUPTED: "interrupted (SIGINT, Ctrl-C): likewise", EXIT_TERMINATED: "terminated (SIGTERM): likewise"}


def show_warning(message, category, filename, lineno, file=None, line=None):
    """Scene warnings as one line each; anything else as Python prints it."""
    if issubclass(category, SceneWarning):
        print(f"{PROG}: warning: {message}", file=sys.stderr)
    else:
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def check_stop_time(stop_time: float, scene) -> None:
    """A --stop-time shortens or lengthens the run, by whole steps."""
    if not math.isfinite(stop_time) or stop_time <= 0:
        raise SceneError(f"--stop-time must be a positive number of seconds, got {stop_time:g}")
    steps = stop_time / scene.step_size
    if round(steps) < 1:   # 0 steps would be a run of nothing that reports success
        raise SceneError(f"--stop-time {stop_time:g} s is shorter than one step of the scene (step_size "
                         f"{scene.step_size:g} s): give at least {scene.step_size:g} s")
    if abs(steps - round(steps)) > 1e-9 * max(steps, 1.0):
        raise SceneError(f"--stop-time {stop_time:g} is not a whole number of steps of the scene's step_size "
                         f"({scene.step_size:g} s)")


def check_output_directory(out: pathlib.Path, stem: str) -> None:
    """Fails before the run, not after it, when the results cannot be written."""
    if out.exists() and not out.is_dir():
        raise SceneError(f"--out {out}: exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SceneError(f"--out {out}: cannot create the directory: {exc.strerror or exc}") from None
    try:
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        raise SceneError(f"--out {out}: cannot write there: {exc.strerror or exc}") from None
    from ..master.record_files import is_record_folder

    for suffix in (".csv", ".parquet", ".png", "_run.json"):
        target = out / f"{stem}{suffix}"
        # A folder of chunks: a run writing it (the run lock refuses this one by name) or a killed run's.
        if suffix == ".parquet" and is_record_folder(target):
            continue
        if target.is_dir() or (target.exists() and not os.access(target, os.W_OK)):
            raise SceneError(f"cannot write {target}: {'it is a directory' if target.is_dir() else 'not writable'}")


def add_arguments(parser) -> None:
    parser.epilog = ("Warnings (a scene that runs, but probably not as meant) and errors go to stderr, one line\n"
                     "each. A run that stops early writes what it computed up to its last good step, marked\n"
                     "partial in <scene>_run.json and the summary.")
    parser.add_argument("scene", nargs="?", default=None,
                        help=f"the scene file (default: {DEFAULT_SCENE} in the current directory, the "
                             "repository's free swing when run from its root)")
    parser.add_argument("--fmu", default=None,
                        help="the FMU to run (default: $GIMBAL2AXIS_FMU, else the build the package was configured "
                             "with)")
    parser.add_argument("--out", default="results",
                        help="directory for the CSV and PNG, created if missing (default: results/ in the current "
                             "directory); files of the same scene are overwritten")
    parser.add_argument("--quiet", action="store_true",
                        help="print nothing but errors and warnings (no progress bar, summary or list of files)")
    parser.add_argument("--stop-time", type=float, default=None, metavar="T",
                        help="end the run at T seconds instead of the scene's stop_time, before or after it (a whole "
                             "number of steps)")
    parser.add_argument("--check", action="store_true",
                        help="exit with status 1 when the scene's [requirements] are not met")
    parser.add_argument("--traceback", action="store_true",
                        help="when a user controller raises, print its Python traceback on stderr after the one-line "
                             "error (which names the class, file and line)")


def execute(args) -> int:
    warnings.showwarning = show_warning
    return run_reporting_failures(PROG, lambda: _run(args))


def _run(args) -> int:
    # here, not at the top: `gimbal2axis --help` and the other subcommands do without numpy and fmpy
    from ..master.stopping import StopRequest

    stop = StopRequest()
    with signals_end_the_run(stop):   # from the start: no phase of the run may ignore Ctrl-C
        try:
            return _run_scene(args, stop)
        except StopSignal:
            stop.stepping = False
            return _stopped_outside_steps(args, stop)


def _run_scene(args, stop) -> int:
    from ..master import run_scene_file
    from ..master.stopping import STOP_KINDS
    from ..scene import load_scene

    scene_path = scene_file(args.scene, DEFAULT_SCENE, "the scene file: gimbal2axis run SCENE.toml")
    scene = load_scene(scene_path)
    if args.stop_time is not None:
        check_stop_time(args.stop_time, scene)
    fmu = fmu_path(args.fmu)
    out = pathlib.Path(args.out)
    check_output_directory(out, scene.name)
    args.scene_name = scene.name
    try:
        result, csv_path, png_path = run_scene_file(scene_path, fmu, out, progress=not args.quiet,
                                                    stop_time=args.stop_time, keep_partial=True, stop=stop,
                                                    stream=True)
    except SceneError as exc:
        if stop.kind is None and args.traceback and getattr(exc, "details", None):   # a user controller's
            print(f"{PROG}: error: {exc}\n{exc.details}", end="", file=sys.stderr)
            return EXIT_ERROR
        if stop.kind is None:
            raise
        # stopped before the first communication point (nothing recorded, nothing written)
        print(one_line(f"{PROG}: {STOP_KINDS[stop.kind]} before the run started: {exc}"), file=sys.stderr)
        return EXIT_FOR_STOP[stop.kind]
    if not args.quiet:
        print(result.summary())
        print(f"wrote {', '.join(str(path) for path in result.files_written)}")
    return _exit_status(args, stop, result, csv_path, csv_path.with_name(scene.name + "_run.json"))


def _exit_status(args, stop, result, csv_path: pathlib.Path, status_path: pathlib.Path) -> int:
    """What a run that recorded something says on stderr, and its exit status: stopped early, files not
    written, requirements not met (with --check), or done."""
    if result.stopped is not None:
        stopped = result.stopped
        kept = (f"the results for [0, {stopped.time:g}] s are in {csv_path} and .parquet, marked partial in "
                f"{status_path}")
        if stopped.kind == "failed":   # the reason says where and why
            print(one_line(f"{PROG}: error: {stopped.reason}; {kept}"), file=sys.stderr)
            if args.traceback and stopped.details:   # a user controller's exception
                print(stopped.details, end="", file=sys.stderr)
        else:
            print(one_line(f"{PROG}: {stop.reason} at t = {stopped.time:g} s; {kept}"), file=sys.stderr)
        return EXIT_FOR_STOP[stopped.kind]
    if result.not_written:
        missing = "; ".join(f"{name}: {why}" for name, why in result.not_written.items())
        print(f"{PROG}: error: the run is complete and its record written, but not {missing} (said in "
              f"{status_path})", file=sys.stderr)
        return EXIT_FAILED_PARTIAL
    failures = result.requirement_failures() if args.check else []
    if failures:   # also when --quiet: the reason for exit status 1
        print(one_line(f"{PROG}: requirements not met: {'; '.join(failures)}"), file=sys.stderr)
        return EXIT_FAILED_CHECK
    return EXIT_DONE


def _stopped_outside_steps(args, stop) -> int:
    """A signal raised where the run could not end at a step (loading, a repeated signal, the record's
    merge, the plots): the record as far as it was written is kept, and _run.json says how far."""
    from ..master.stopping import STOP_KINDS

    status_path = getattr(stop, "record_status_path", None)   # set once this run's record took the name over
    where = f"; the record is kept as far as it goes, as {status_path} says" if status_path else \
        "; nothing was written (an earlier run's files are as they were)"
    print(f"{PROG}: {stop.reason or STOP_KINDS.get(stop.kind, 'interrupted')}{where}", file=sys.stderr)
    return EXIT_FOR_STOP.get(stop.kind, EXIT_INTERRUPTED)
