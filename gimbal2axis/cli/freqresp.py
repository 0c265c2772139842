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


def unit_of(mode: str, drive: str = "voltage") -> str:
    """The unit of --amplitude: a motor's current command's in current drive."""
    return "deg/s" if mode == "isolation" else ("V" if drive == "voltage" else "A")


def motor_drive(scene, fmu_file, axis: str) -> str:
    """"voltage" or "current": the drive of motor `axis` in the scene (scene/drives.py); "voltage" for an
    axis that is not a motor's (refused later, with its own message)."""
    from ..fmu import FMU
    from ..scene.drives import scene_drives

    if axis not in ("1", "2"):
        return "voltage"
    with FMU(fmu_file) as fmu:
        return scene_drives(scene, fmu)[int(axis) - 1].kind


def linear_prediction(scene, fmu_path, excitation, outputs, f_min, f_max):
    """The linear model's Bode lines, a function giving its rows at the simulated points and a line of
    text to print (or None): open loop, the plant's G(jw) (analysis.linearization); isolation and loop
    gain, the sampled-data closed loop of the scene's PID controller (analysis.isolation_prediction),
    the loop gain with its predicted margins. All without backlash and dry friction."""
    from ..analysis import frequency_response as fr   # here, not at the top: --help does without numpy
    from ..fmu import FMU

    with FMU(fmu_path) as fmu:
        if excitation.kind == "voltage":
            from ..analysis import linearization

            model = linearization.linearize(fr.linear_point(scene, fmu, excitation, fr.LINEAR_FIDELITY))
            lines = fr.linear_lines(model, excitation.input_signal, outputs, f_min, f_max)
            return lines, lambda rows: fr.linear_rows(model, rows), None
        from ..analysis import isolation_prediction as isolation

        loop = isolation.build_loop(scene, fmu, fr.LINEAR_FIDELITY)
    def at_simulated(function):
        return lambda rows: function(loop, excitation.axis, sorted({r["frequency_hz"] for r in rows}))
    if excitation.kind == "injection":
        margins = isolation.predicted_margins(loop, excitation.axis)
        summary = f"linear model, loop gain at {fr.command_signal(excitation.axis, excitation.drive)}: {margins.describe()}"
        return (isolation.loop_gain_lines(loop, excitation.axis, f_min, f_max), at_simulated(isolation.loop_gain_rows),
                summary)
    return (isolation.isolation_lines(loop, excitation.axis, f_min, f_max), at_simulated(isolation.isolation_rows),
            None)


CARRIER_AXES = {"roll": (0.0, 1.0, 0.0), "pitch": (1.0, 0.0, 0.0), "yaw": (0.0, 0.0, 1.0)}   # in frame 0, level


def dwell_scale(scene, axis: str) -> dict:
    """{payload axis: |component of the dwell's carrier axis along it|} with the gimbal on the scene's
    target on a level carrier: the dwell's ratio (LOS rate / carrier rate about one carrier axis) is the
    per-payload-axis ratio times this, while the axes do not couple."""
    import numpy as np

    from ..scene import geometry

    if scene.target is None:
        raise SceneError("--sea-estimate needs a scene with a [target] (the gimbal's pointing sets the scale)")
    alpha, beta = geometry.gimbal_angles_for(scene.target, 0.0, 0.0, 0.0)
    carrier_axis = np.array(CARRIER_AXES[axis])
    to_payload = (geometry.rz(alpha) @ geometry.rx(beta)).T   # frame 0 -> frame 2
    components = to_payload @ carrier_axis
    return {"elevation": abs(components[0]), "cross_elevation": abs(components[2])}


def measured_margins(rows: list[dict]) -> list[str]:
    """A line per simulated curve: the margins of its loop_gain points (interpolated between the dwell's
    frequencies, so only as fine as its grid; a point of low coherence may place a crossing anywhere)."""
    from ..analysis import frequency_response as fr   # here, not at the top: --help does without numpy
    from ..analysis.isolation_prediction import stability_margins

    lines = []
    for (curve, output), points in fr.curves(rows).items():
        if output != fr.LOOP_GAIN or curve == fr.LINEAR_CURVE or len(points) < 2:
            continue
        f = [r["frequency_hz"] for r in points]
        L = [r["gain"] * complex(math.cos(math.radians(r["phase_deg"])), math.sin(math.radians(r["phase_deg"])))
             for r in points]
        lines.append(f"{curve}, from its {len(points)} points: {stability_margins(f, L).describe()}")
    return lines


NO_BACKLASH = "no backlash, no dry friction"   # the curve of the linear prediction's fidelity (with ", <amplitude>")


def check_points(rows: list[dict], scene, fmu_file, excitation, with_prediction: bool) -> None:
    """Marks the points that are not a frequency response (fr.mark_rows): harmonics and drift of every
    simulated point; with the prediction, the "no backlash, no dry friction" points against it, and in
    open loop every point's operating point (the window's gimbal angles) against the prediction's."""
    from ..analysis import frequency_response as fr   # here, not at the top: --help does without numpy

    if not with_prediction:
        fr.mark_rows(rows)
        return
    predicted = {(r["output"], r["frequency_hz"]): complex(r["gain"]) if math.isnan(r["phase_deg"]) else
                 r["gain"] * complex(math.cos(math.radians(r["phase_deg"])), math.sin(math.radians(r["phase_deg"])))
                 for r in rows if r["curve"] == fr.LINEAR_CURVE}
    changes = operating_point_changes(rows, scene, fmu_file, excitation) if excitation.kind == "voltage" else {}
    fr.mark_rows(rows, lambda curve: curve.startswith(NO_BACKLASH),
                 lambda output, f: predicted.get((output, f)),
                 lambda row: changes.get((row["curve"], row["frequency_hz"], row["output"])))


def operating_point_changes(rows: list[dict], scene, fmu_file, excitation) -> dict:
    """{(curve, frequency, output): (G of the linear model at the window's mean alpha and beta over G at the
    prediction's point, 'beta 5 -> -123 deg')} of every open-loop point: the prediction is made at the
    scene's initial angles, and on a fixed base gravity moves an unbalanced payload away from them while the
    dwell settles. Linearized without backlash and dry friction as the prediction (1 ms each)."""
    from ..analysis import frequency_response as fr   # here, not at the top: --help does without numpy
    from ..analysis import linearization
    from ..fmu import FMU

    changes = {}
    with FMU(fmu_file) as fmu:
        start = fr.linear_point(scene, fmu, excitation, fr.LINEAR_FIDELITY)
        reference = linearization.linearize(start)
        for row in rows:
            if row["curve"] == fr.LINEAR_CURVE or row["output"] not in reference.outputs:
                continue
            # within half a turn (a start angle beyond it is refused as degrees): the same configuration, as an
            # axis that walked round during the dwell (a torque-driven one, in current drive) left it
            alpha, beta = (math.remainder(math.radians(row[key]), 2 * math.pi) for key in ("alpha_mean_deg",
                                                                                          "beta_mean_deg"))
            # the rotors follow their loads there (start_values), not the angles the scene may give them
            initial = {k: v for k, v in scene.initial.items() if k not in ("alpha_m", "beta_m")}
            moved_scene = scene.with_changes(initial={**initial, "alpha": alpha, "beta": beta})
            moved = linearization.linearize(fr.linear_point(moved_scene, fmu, excitation, fr.LINEAR_FIDELITY))
            f = [row["frequency_hz"]]
            G0 = complex(reference.frequency_response(f, excitation.input_signal, row["output"])[0])
            G = complex(moved.frequency_response(f, excitation.input_signal, row["output"])[0])
            if G0 != 0:
                changes[(row["curve"], row["frequency_hz"], row["output"])] = (
                    G / G0, f"beta {math.degrees(start['beta']):.3g} -> {row['beta_mean_deg']:.3g} deg")
    return changes


def operating_point_hint(rows: list[dict]) -> str | None:
    """Why open-loop points left the prediction's operating point, when some did (the payload falls)."""
    moved = [r for r in rows if "operating point" in r.get("marks", "")]
    if not moved:
        return None
    first = moved[0]
    measured = [r for r in rows if "marks" in r]
    return (f"{len(moved)} of {len(measured)} points were measured away from the linear prediction's operating "
            f"point (e.g. {first['curve']}, {first['output']} at {first['frequency_hz']:.3g} Hz: "
            f"{next(m for m in first['marks'].split('; ') if m.startswith('operating point'))}): on the fixed base "
            f"and without a controller, gravity turns a payload whose centre of mass is off the elevation axis "
            f"while the dwell settles; balance it (--set \"body2.d_bd[2]=0\" --set \"body2.d_bd[3]=0\") to "
            f"measure the plant where it is linearized (docs/frequency_response.md)")


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
    from ..analysis import frequency_response as fr
    from ..scene import load_scene

    check_arguments(args)
    fmu = fmu_path(args.fmu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # a scene's advice (e.g. 'no controller') does not apply here
        scene = load_scene(scene_file(args.scene, DEFAULT_SCENE, "--scene SCENE.toml"))
    scene = with_overrides(scene, args.set, fmu)
    frequencies = fr.log_frequencies(args.fmin, args.fmax, args.points)
    dwell = fr.Dwell(args.settle_periods, args.settle_s, args.measure_periods)
    check_frequencies(frequencies, scene, dwell)
    amplitudes = args.amplitude or [0.2 if args.mode == "loop-gain" else 1.0]
    drive = motor_drive(scene, fmu, args.axis or "1") if args.mode != "isolation" else "voltage"
    if args.mode != "open-loop" and scene.moving_target is not None:
        raise SceneError(f"{scene.name}: its [target] moves (type = \"{scene.target_spec.get('type', '?')}\"), and "
                         f"freqresp {args.mode} measures the closed loop about one operating point: give the scene a "
                         f"fixed [target] (type = \"direction\") or no target")
    if args.mode == "open-loop":
        axis = args.axis or "1"
        if axis not in fr.MOTOR_AXES:
            raise SceneError(f"--axis {shown(axis)}: open-loop drives motor 1 or 2")
        excitations = [fr.Excitation("voltage", axis, a, args.offset, drive) for a in amplitudes]
        scene = scene.with_changes(base_motion_spec={"type": "fixed"},
                                   fidelity={**scene.fidelity, "base.fixed": True},
                                   controller_spec={"type": "none"})
        outputs = excitations[0].default_outputs()
    elif args.mode == "loop-gain":
        axis = args.axis or "1"
        if axis not in fr.MOTOR_AXES:
            raise SceneError(f"--axis {shown(axis)}: loop-gain injects at motor 1 or 2")
        excitations = [fr.Excitation("injection", axis, a, drive=drive) for a in amplitudes]
        outputs = None
    else:
        axis = args.axis or "roll"
        if axis not in fr.BASE_AXES:
            raise SceneError(f"--axis {shown(axis)}: isolation moves the carrier in roll, pitch or yaw")
        excitations = [fr.Excitation("base", axis, math.radians(a)) for a in amplitudes]
        outputs = None
    excitation = excitations[0]
    sea = None
    if args.sea_estimate:
        if excitation.kind != "base":
            raise SceneError("--sea-estimate goes with freqresp isolation (a carrier rate as the input)")
        try:
            sea = fr.read_sea_estimate(args.sea_estimate, args.fmin, args.fmax, dwell_scale(scene, axis))
        except ValueError as exc:   # a file that is not an isolation CSV: refused like a bad argument
            raise SceneError(str(exc)) from None
    variants = []
    if not args.linear_only:
        variants.append(("full model", None))
    if not args.full_only:
        variants.append((NO_BACKLASH, fr.LINEAR_FIDELITY))
    lines, predict_rows = None, None
    if not args.no_linear:
        try:
            lines, predict_rows, summary = linear_prediction(scene, fmu, excitation, outputs, args.fmin,
                                                             args.fmax)
            if summary:
                print(summary)
        except SceneError as exc:   # e.g. not a PID scene, or a loop that does not settle: measure anyway
            print(f"{PROG}: warning: no linear prediction: {exc}", file=sys.stderr)
    client = cluster = None
    if not args.serial:
        from ..sweep import make_client
        from ..sweep.spec import SweepError
        try:
            client, cluster = make_client(args.scheduler, workers=args.workers)
        except SweepError as exc:   # --scheduler, --workers refused: one line, as the scene's refusals
            raise SceneError(str(exc)) from None
    rows = []
    wall = time.perf_counter()
    try:
        for each, amplitude in zip(excitations, amplitudes):
            for label, fidelity in variants:
                curve = label if len(amplitudes) == 1 else f"{label}, {amplitude:g} {unit_of(args.mode, excitation.drive)}"
                rows += fr.sweep(scene, fmu, frequencies, each, dwell, outputs, fidelity, client, curve)
    finally:
        if client is not None:
            from ..sweep import close_client
            close_client(client, cluster)
    if predict_rows is not None:
        rows += predict_rows(rows)
    check_points(rows, scene, fmu, excitation, predict_rows is not None)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = args.name or f"frequency_response_{args.mode.replace('-', '_')}_{axis}"
    csv_path, png_path = out / f"{name}.csv", out / f"{name}.png"
    fr.write_csv(rows, csv_path)
    amplitudes_text = ", ".join(f"{a:g}" for a in amplitudes)
    if excitation.kind == "injection":
        title = (f"{scene.name}: loop gain L = -U/A at {fr.command_signal(axis, excitation.drive)} (other axis closed) and sensitivity A/D, "
                 f"injection {amplitudes_text} V")
    else:
        title = (f"{scene.name}: {excitation.input_signal} -> rates, amplitude{'s' if len(amplitudes) > 1 else ''} "
                 f"{amplitudes_text} {unit_of(args.mode, excitation.drive)}" + (" (LOS rate / carrier rate)" if excitation.kind == "base" else ""))
    plotted_rows, plotted_lines = rows, lines
    if excitation.kind == "injection":   # the LOS rate per D (-90 dB) would squeeze L and S: it is in the CSV
        shown_outputs = (fr.LOOP_GAIN, fr.SENSITIVITY)
        plotted_rows = [r for r in rows if r["output"] in shown_outputs]
        plotted_lines = lines and [line for line in lines if line[0].rsplit(": ", 1)[-1] in shown_outputs]
    fr.plot_bode(plotted_rows, png_path, title, plotted_lines, sea)
    if excitation.kind == "injection":
        for line in measured_margins(rows):
            print(line)
    print(fr.marks_summary(rows) or f"every point is a frequency response to {100 * fr.LINEARITY_TOLERANCE:g} % and "
          f"{fr.PHASE_TOLERANCE_DEG:g} deg (no harmonics, no drift" + (", on the linear prediction)" if predict_rows
                                                                      else ")"))
    hint = operating_point_hint(rows)
    if hint:
        print(f"{PROG}: warning: {hint}", file=sys.stderr)
    simulated = len({r["frequency_hz"] for r in rows if r["curve"] != fr.LINEAR_CURVE})
    runs = len(excitations) * len(variants)
    print(f"{simulated} frequencies x {runs} simulated curve{'s' if runs != 1 else ''} ({len(rows)} CSV rows: "
          f"one per frequency, curve and output, the linear prediction's included) in "
          f"{time.perf_counter() - wall:.1f} s: {csv_path}, {png_path}")
    return 0
