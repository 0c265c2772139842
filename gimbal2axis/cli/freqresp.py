"""Frequency responses of the Gimbal2Axis FMU by sine dwell (gimbal2axis.analysis.frequency_response; how
to read the results: docs/frequency_response.md).

  open-loop: the plant from a motor voltage u_R<axis> to the line-of-sight and gimbal rates, on a fixed
             base, motor voltage = offset + amplitude sin(w t) (no controller, the other motor at 0 V)
  isolation: the carrier's roll/pitch/yaw rate as a sine through the scene's closed loop: LOS inertial
             rate / carrier rate (the stabilization ratio)
  loop-gain: the scene's closed loop on a carrier at rest, a sine of --amplitude V injected into motor
             --axis's computed voltage: the loop gain L = -U/A broken there (U the controller's output,
             A = U + D what goes on to the motor), the sensitivity A/D and the LOS rate per D
All for the scene's model ("full model") and with backlash and dry friction switched off
(gear*.model = 1, dry_friction = false).

The linear prediction without backlash and dry friction is drawn over the simulated curves as thin
lines, and its values at the simulated frequencies are rows of curve "linear model" in the CSV
(--no-linear: not): open loop, the plant's G(jw) from the core's A, B, C, D
(gimbal2axis.analysis.linearization); isolation and loop-gain, the sampled-data closed loop of the scene's
PID controller (gimbal2axis.analysis.isolation_prediction; for another controller, or a loop that does not
settle, the command says so and measures without it). loop-gain also prints the predicted crossover,
phase and gain margins, and the lower gain margin of a conditionally stable loop (an open-loop unstable
plant: the top-heavy payload's elevation), where the gain may not drop by more.

Every simulated point is checked: harmonics and drift of its output over the window, and against the
linear prediction (the "no backlash, no dry friction" points) and its operating point (open loop: the
window's gimbal angles); the points that are not a frequency response to 1 % and 1 deg get their
reasons in the CSV's column marks, a grey marker in the plot and a count in one printed line, and
open-loop points measured away from the prediction's operating point (an unbalanced payload falling)
a warning (docs/frequency_response.md, "Points that are not a frequency response").

Writes <out>/<name>.csv (every point of every curve) and <out>/<name>.png (Bode plots).
Frequencies run in parallel on Dask (a local cluster of --workers, or --scheduler), or --serial.
Each frequency is snapped so that --measure-periods periods are a whole number of the scene's steps h;
a frequency left with fewer than 4 steps per period (above 1/(4 h): 250 Hz at 1 ms) is refused before
anything runs: closer to the Nyquist frequency 1/(2 h) the samples alias and the measurement leaves the
linear prediction (docs/frequency_response.md).

  gimbal2axis freqresp isolation --axis roll --fmin 0.1 --fmax 100 --points 13
  gimbal2axis freqresp open-loop --axis 1 --amplitude 1 --serial
  gimbal2axis freqresp loop-gain --axis 1 --amplitude 0.2
"""
from __future__ import annotations

import contextlib
import math
import pathlib
import sys
import time
import warnings

from ..errors import SceneError, excerpt, shown
from ..locations import fmu_path
from .defaults import scene_file
from .failures import run_reporting_failures

SUMMARY = "frequency responses by sine dwell: open loop, isolation, loop gain, with the linear prediction"
PROG = "gimbal2axis freqresp"
EXIT_STATUSES = {0: "written", 2: "refused: an argument, a --set name, the scene, the output directory",
                 130: "interrupted (SIGINT, Ctrl-C)"}   # listed at the end of --help
DEFAULT_SCENE = pathlib.Path("scenes", "ship_stabilization.toml")   # relative to the current directory


def with_overrides(scene, assignments: list[str], fmu_file):
    """The scene with NAME=VALUE assignments: a name of [fidelity] (gear1.model, dry_friction, ...) goes
    there, any other name to [parameters]. A name the FMU does not have, or that is no parameter, is
    refused here, as the command-line option it is (with the close matches), not later as the scene's."""
    from fmpy import read_model_description

    from ..analysis.names import did_you_mean
    from ..fmu import FIDELITY

    variables = {v.name: v for v in read_model_description(str(fmu_file)).modelVariables}
    parameters_of_fmu = [name for name, v in variables.items() if v.causality in SETTABLE_CAUSALITIES]
    fidelity, parameters = dict(scene.fidelity), dict(scene.parameters)
    for item in assignments:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep:
            raise SceneError(f"--set {shown(item)}: expected NAME=VALUE")
        if name not in variables:
            raise SceneError(f"--set: '{excerpt(name)}' is not a variable of {fmu_file}{did_you_mean(name, variables)}")
        if variables[name].causality not in SETTABLE_CAUSALITIES:
            raise SceneError(f"--set: '{name}' is {variables[name].causality!r}, not a parameter or fidelity "
                             f"switch (freqresp drives the inputs itself){did_you_mean(name, parameters_of_fmu)}")
        low = text.strip().lower()
        try:
            value = True if low == "true" else False if low == "false" else float(text)
        except ValueError:
            raise SceneError(f"--set {shown(item)}: {shown(text)} is not a number, true or false") from None
        if isinstance(value, float) and value.is_integer() and name in FIDELITY:
            value = int(value)
        (fidelity if name in FIDELITY else parameters)[name] = value
    return scene.with_changes(fidelity=fidelity, parameters=parameters)


SETTABLE_CAUSALITIES = ("parameter", "structuralParameter")   # what a scene's [parameters] and [fidelity] take


def check_arguments(args) -> None:
    """What argparse cannot say: ranges (the frequencies against the scene's step: check_frequencies)."""
    if not (args.fmin > 0 and args.fmax >= args.fmin and math.isfinite(args.fmax)):
        raise SceneError(f"--fmin {args.fmin:g} --fmax {args.fmax:g}: need 0 < fmin <= fmax (Hz)")
    if args.points < 1:
        raise SceneError(f"--points {args.points}: need at least 1")
    if args.measure_periods < 1:
        raise SceneError(f"--measure-periods {args.measure_periods}: need at least 1")
    if not (args.settle_periods >= 0 and args.settle_s >= 0 and math.isfinite(args.settle_periods + args.settle_s)):
        raise SceneError(f"--settle-periods {args.settle_periods:g} --settle-s {args.settle_s:g}: need finite "
                         f"values >= 0")
    for amplitude in args.amplitude or []:
        if not (amplitude > 0 and math.isfinite(amplitude)):
            raise SceneError(f"--amplitude {amplitude:g}: need a positive amplitude")


def check_frequencies(frequencies, scene, dwell) -> None:
    """Refuses, before anything runs, a frequency the scene's step cannot resolve, named as the option
    that asked for it: the highest of the log-spaced frequencies is --fmax, and it has the fewest steps
    per period (the snapped step count falls with the frequency), so it is the one to check."""
    from ..analysis import frequency_response as fr   # here, not at the top: --help does without numpy

    fr.check_resolvable([max(frequencies)], scene.step_size, dwell, what="--fmax")


def motor_drive(scene, fmu_file, axis: str) -> str:
    """"voltage" or "current": the drive of motor `axis` in the scene (scene/drives.py); "voltage" for an
    axis that is not a motor's (refused later, with its own message)."""
    from ..fmu import FMU
    from ..scene.drives import scene_drives

    if axis not in ("1", "2"):
        return "voltage"
    with FMU(fmu_file) as fmu:
        return scene_drives(scene, fmu)[int(axis) - 1].kind


def add_arguments(parser) -> None:
    parser.add_argument("mode", choices=["open-loop", "isolation", "loop-gain"])
    parser.add_argument("--scene", default=None,
                        help=f"scene whose parameters, fidelity, step size and controller are used (default: "
                             f"{DEFAULT_SCENE} in the current directory, the repository's when run from its root)")
    parser.add_argument("--fmu", default=None,
                        help="the FMU (default $GIMBAL2AXIS_FMU, else the build the package was configured with)")
    parser.add_argument("--axis", default=None,
                        help="open-loop, loop-gain: motor 1 or 2 (default 1); isolation: roll, pitch or yaw "
                             "(default roll)")
    parser.add_argument("--amplitude", type=float, nargs="+", default=None, metavar="A",
                        help="open-loop: voltage amplitude in V (default 1; a current command in A for a motor in current drive, --set motor<j>.drive=1); isolation: carrier rate amplitude "
                             "in deg/s (default 1); loop-gain: injected voltage amplitude in V (default 0.2). Several: a curve per amplitude (the nonlinear model's "
                             "describing function changes with it; the linear one does not)")
    parser.add_argument("--offset", type=float, default=0.0, help="open-loop: constant voltage added, V")
    parser.add_argument("--fmin", type=float, default=0.1)
    parser.add_argument("--fmax", type=float, default=100.0)
    parser.add_argument("--points", type=int, default=13, help="log-spaced frequencies (default 13)")
    parser.add_argument("--settle-periods", type=float, default=5.0)
    parser.add_argument("--settle-s", type=float, default=1.0, help="settle at least this long, s (default 1)")
    parser.add_argument("--measure-periods", type=int, default=4)
    parser.add_argument("--linear-only", action="store_true",
                        help="only the curve without backlash and dry friction")
    parser.add_argument("--full-only", action="store_true", help="only the scene's model (its own fidelity)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="override an FMU parameter or fidelity switch of the scene, e.g. --set body2.d_bd[3]=0 "
                             "(repeatable; numbers, true/false)")
    parser.add_argument("--no-linear", action="store_true",
                        help="do not add the linear prediction (it needs libgimbal_probe.so, found through "
                             "$GIMBAL2AXIS_PROBE_LIBRARY or the configured build; isolation: a PID scene)")
    parser.add_argument("--serial", action="store_true", help="run the frequencies one after the other here")
    parser.add_argument("--workers", type=int, default=4, help="local Dask workers (default 4)")
    parser.add_argument("--scheduler", default=None, help="address of a running Dask scheduler")
    parser.add_argument("--out", default="results", help="directory of the CSV and PNG (default results/ in the "
                                                         "current directory)")
    parser.add_argument("--sea-estimate", default=None, metavar="CSV",
                        help="isolation: draw the isolation estimated from a sea-state run (<scene>_isolation.csv "
                             "of gimbal2axis run) over the dwell, put on the dwell's scale by the projection of "
                             "the --axis carrier axis on each payload axis at the scene's target (docs/jitter.md)")
    parser.add_argument("--name", default=None, help="file name stem (default frequency_response_<mode>_<axis>)")


def execute(args) -> int:
    return run_reporting_failures(PROG, lambda: measure_and_write(args))


def measure_and_write(args) -> int:
    # here, not at the top: --help does without numpy and fmpy
    from ..analysis import dwell_plan
    from ..analysis import frequency_response as fr
    from ..analysis.measured_margins import measured_margins
    from ..analysis.point_checks import check_points, checks_summary, operating_point_hint

    check_arguments(args)
    fmu = fmu_path(args.fmu)
    scene = with_overrides(_load_scene(args.scene), args.set, fmu)
    frequencies = fr.log_frequencies(args.fmin, args.fmax, args.points)
    dwell = fr.Dwell(args.settle_periods, args.settle_s, args.measure_periods)
    check_frequencies(frequencies, scene, dwell)
    drive = motor_drive(scene, fmu, args.axis or "1") if args.mode != "isolation" else "voltage"
    dwell_plan.check_fixed_target(scene, args.mode)
    plan = dwell_plan.plan_dwell(args.mode, scene, args.axis, args.amplitude, args.offset, drive)
    sea = _sea_estimate(args, plan) if args.sea_estimate else None
    variants = dwell_plan.variants(args.linear_only, args.full_only)
    lines, predict_rows = (None, None) if args.no_linear else _prediction(args, plan, fmu)
    with _dask_client(args) as client:
        wall = time.perf_counter()   # the measurement's time, without the cluster's start
        rows = dwell_plan.measure_curves(plan, fmu, frequencies, dwell, variants, client)
    if predict_rows is not None:
        rows += predict_rows(rows)
    check_points(rows, plan.scene, fmu, plan.excitation, predict_rows is not None)
    csv_path, png_path = _write(args, plan, rows, lines, sea)
    if plan.excitation.kind == "injection":
        for line in measured_margins(rows):
            print(line)
    print(checks_summary(rows, predict_rows is not None))
    hint = operating_point_hint(rows)
    if hint:
        print(f"{PROG}: warning: {hint}", file=sys.stderr)
    simulated = len({r["frequency_hz"] for r in rows if r["curve"] != fr.LINEAR_CURVE})
    runs = len(plan.excitations) * len(variants)
    print(f"{simulated} frequencies x {runs} simulated curve{'s' if runs != 1 else ''} ({len(rows)} CSV rows: "
          f"one per frequency, curve and output, the linear prediction's included) in "
          f"{time.perf_counter() - wall:.1f} s: {csv_path}, {png_path}")
    return 0


def _load_scene(argument):
    from ..scene import load_scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # a scene's advice (e.g. 'no controller') does not apply here
        return load_scene(scene_file(argument, DEFAULT_SCENE, "--scene SCENE.toml"))


def _sea_estimate(args, plan):
    """The sea-state run's isolation estimate on the dwell's scale (--sea-estimate)."""
    from ..analysis import frequency_response as fr
    from ..analysis.carrier_projection import dwell_scale

    if plan.excitation.kind != "base":
        raise SceneError("--sea-estimate goes with freqresp isolation (a carrier rate as the input)")
    try:
        return fr.read_sea_estimate(args.sea_estimate, args.fmin, args.fmax, dwell_scale(plan.scene, plan.axis))
    except ValueError as exc:   # a file that is not an isolation CSV: refused like a bad argument
        raise SceneError(str(exc)) from None


def _prediction(args, plan, fmu) -> tuple:
    """(the linear prediction's lines, its rows at the simulated points), its summary printed; (None,
    None) and a warning when there is none (e.g. not a PID scene, or a loop that does not settle)."""
    from ..analysis.linear_prediction import linear_prediction

    try:
        lines, predict_rows, summary = linear_prediction(plan.scene, fmu, plan.excitation, plan.outputs,
                                                         args.fmin, args.fmax)
    except SceneError as exc:   # measured anyway
        print(f"{PROG}: warning: no linear prediction: {exc}", file=sys.stderr)
        return None, None
    if summary:
        print(summary)
    return lines, predict_rows


@contextlib.contextmanager
def _dask_client(args):
    """A Dask client on --scheduler or a local cluster of --workers, closed at the end; None with --serial."""
    if args.serial:
        yield None
        return
    from ..sweep import close_client, make_client
    from ..sweep.spec import SweepError

    try:
        client, cluster = make_client(args.scheduler, workers=args.workers)
    except SweepError as exc:   # --scheduler, --workers refused: one line, as the scene's refusals
        raise SceneError(str(exc)) from None
    try:
        yield client
    finally:
        close_client(client, cluster)


def _write(args, plan, rows: list, lines, sea) -> tuple:
    """Writes <out>/<name>.csv and .png; their paths."""
    from ..analysis import dwell_plan
    from ..analysis import frequency_response as fr

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = args.name or f"frequency_response_{args.mode.replace('-', '_')}_{plan.axis}"
    csv_path, png_path = out / f"{name}.csv", out / f"{name}.png"
    fr.write_csv(rows, csv_path)
    plotted_rows, plotted_lines = dwell_plan.plotted(plan, rows, lines)
    fr.plot_bode(plotted_rows, png_path, dwell_plan.plot_title(plan, plan.scene.name), plotted_lines, sea)
    return csv_path, png_path
