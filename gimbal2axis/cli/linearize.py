"""Linearizes the gimbal's continuous model at an operating point and writes A, B, C, D
(gimbal2axis.analysis.linearization; docs/linearization.md).

The operating point is the FMU's start values, changed by a scene's parameters, fidelity and initial
state (--scene) and by --set NAME=VALUE (parameters, fidelity switches, start values of states such as
beta=0.3, inputs such as u_R1=2 or base.gamma=0.1). With --at-time T the scene is run with its
controller up to T and the model is linearized where the simulation is then: its state and modes, the
voltages applied from T on and the carrier's motion at T (--set may change these inputs).

Writes <out> (.npz or .mat: A, B, C, D, the names of states, inputs and outputs, the modes and the
point) and prints the states, the modes and the poles. With --bode INPUT:OUTPUT (repeatable) it also
writes <out stem>_bode.png and .csv of those transfer functions, prints each one's DC gain and -3 dB
frequency (pair_line), and warns (one line each on stderr)
where one of them is identically zero because of a mode the model holds in at the point (a body stuck
by dry friction, a gear in its backlash gap, a limited current, a clamped voltage), naming the setting
that frees it: the linear model holds within those modes (docs/linearization.md).

  # the rigid azimuth axis with a quasi-static motor, without dry friction, on a fixed base: from
  # u_R1 to alpha_dot a first-order lag: it prints DC gain 0.2063 (rad/s per V), -3 dB at 4.175 Hz,
  # the pole -26.23 1/s
  gimbal2axis linearize --set gear1.model=0 --set motor1.model=0 --set dry_friction=false \\
      --set base.fixed=true --out results/azimuth.npz --bode u_R1:alpha_dot
  gimbal2axis linearize --scene scenes/ship_stabilization.toml --at-time 5 --out results/ship_5s.mat
"""
from __future__ import annotations

import csv
import math
import pathlib
import sys
import warnings

from ..analysis.names import did_you_mean
from ..errors import SceneError, excerpt, shown
from ..locations import fmu_path
from .failures import run_reporting_failures

SUMMARY = "linearize the model at an operating point: A, B, C, D, poles, Bode plots"
PROG = "gimbal2axis linearize"
EXIT_STATUSES = {0: "written (warnings or not)", 2: "refused: an argument, a name, the scene, the output",
                 130: "interrupted (SIGINT, Ctrl-C)"}   # listed at the end of --help


def parse_assignments(assignments: list[str]) -> dict:
    values = {}
    for item in assignments:
        name, sep, text = item.partition("=")
        if not sep:
            raise SceneError(f"--set {shown(item)}: expected NAME=VALUE")
        low = text.strip().lower()
        try:
            values[name.strip()] = True if low == "true" else False if low == "false" else float(text)
        except ValueError:
            raise SceneError(f"--set {shown(item)}: {shown(text)} is not a number, true or false") from None
    return angles_in_radians(values)


def angles_in_radians(values: dict) -> dict:
    """The scene format's rule for angles (docs/scenes.md, Units) on the command line too: NAME_deg is
    degrees, a bare angle radians, and a start alpha or beta beyond half a turn is refused as the
    degrees it most likely is."""
    from ..scene.scene import ANGLE_STATES, initial_in_radians

    def is_angle(name: str) -> bool:
        return name in ANGLE_STATES or (name.endswith("_deg") and name[:-len("_deg")] in ANGLE_STATES)

    angles = {name: value for name, value in values.items() if is_angle(name)}
    try:
        converted = initial_in_radians(angles)
    except SceneError as exc:
        raise SceneError(f"--set: {str(exc).replace('initial.', '')}") from None
    return {**{name: value for name, value in values.items() if not is_angle(name)}, **converted}


def scene_point(scene_path: str, fmu_file, at_time: float | None, overrides: dict, build_dir: str | None = None):
    """The linear model of the scene's operating point: its start values, or where its run is at `at_time`."""
    from ..analysis import linearization   # here, not at the top: --help does without numpy
    from ..scene import load_scene
    from ..fmu import FMU
    from ..master import Plan, run
    from ..scene import start_values
    from ..limits import steps_of

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # a scene's advice (e.g. 'no controller') does not apply here
        scene = load_scene(scene_path)
    with FMU(fmu_file) as fmu:
        if at_time is None:
            plan = Plan(scene, fmu, scene.step_size, None)
            values = start_values(scene, fmu, plan.base[0])
            values.update(overrides)
            if not plan.motion.fixed:
                names = ["base.delta", "base.psi", "base.gamma", "base.delta_dot", "base.psi_dot", "base.gamma_dot",
                         "base.delta_ddot", "base.psi_ddot", "base.gamma_ddot", "base.v_a[1]", "base.v_a[2]",
                         "base.v_a[3]", "base.a_a[1]", "base.a_a[2]", "base.a_a[3]"]
                for name, value in zip(names, plan.base[0].tolist()):
                    values.setdefault(name, value)
            return linearization.linearize(values, build_dir)
        bad = [name for name in overrides if fmu.variable(name).causality != "input"]
        if bad:
            raise SceneError(f"--at-time: only inputs can be changed at a running simulation's point, not {bad} "
                             f"(change parameters in the scene)")
        steps = steps_of("--at-time", at_time, scene.step_size)
        if abs(steps - round(steps)) > 1e-9 * max(steps, 1.0):
            raise SceneError(f"--at-time {at_time:g}: not a whole number of the scene's steps ({scene.step_size:g} s)")
        scene = scene.with_changes(stop_time=at_time)
        log: list = []
        slave = fmu.instantiate("linearize", log)
        try:
            signals = run(scene, fmu, slave=slave, log=log).signals
            return linearization.linearize_instance(fmu, slave, {**inputs_at_end(scene, signals), **overrides},
                                                    build_dir)
        finally:
            slave.freeInstance()


def inputs_at_end(scene, signals: dict) -> dict:
    """The inputs of the step that would start at the run's end: the voltages applied from there (the
    controller's commands of `delay_steps` before; a current-driven motor's current command) and the
    carrier's motion there. The instance itself still holds those of the step that ended."""
    from ..scene.drives import command_columns
    from ..scene.base_motion import INPUTS as BASE_INPUTS

    applied = [command_columns(signals, motor).applied for motor in (1, 2)]
    inputs = {name: float(signals[name][-1]) for name in applied}
    if not (scene.fidelity.get("base.fixed", False) or scene.base_motion().fixed):
        inputs.update({name: float(signals[name][-1]) for name in BASE_INPUTS})
    return inputs


def parse_pair(pair: str) -> tuple[str, str]:
    source, sep, target = pair.partition(":")
    if not sep or not source or not target:
        raise SceneError(f"--bode {shown(pair)}: expected INPUT:OUTPUT, e.g. u_R1:alpha_dot")
    return source, target


def write_bode(model, pairs: list[tuple[str, str]], stem: pathlib.Path, f_min: float, f_max: float) -> list[pathlib.Path]:
    import matplotlib
    import numpy as np   # here, not at the top: --help does without numpy

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frequencies = np.logspace(math.log10(f_min), math.log10(f_max), 400)
    fig, (ax_g, ax_p) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    rows = []
    for source, target in pairs:
        G = model.frequency_response(frequencies, source, target)
        gain_db = 20 * np.log10(np.maximum(np.abs(G), 1e-300))
        phase = np.degrees(np.unwrap(np.angle(G)))
        ax_g.semilogx(frequencies, gain_db, label=f"{source} -> {target}")
        ax_p.semilogx(frequencies, phase)
        rows += [dict(input=source, output=target, frequency_hz=f, gain=abs(g), gain_db=db, phase_deg=p)
                 for f, g, db, p in zip(frequencies, G, gain_db, phase)]
    ax_g.set_ylabel("gain [dB]")
    ax_p.set_ylabel("phase [deg] (unwrapped)")
    ax_p.set_xlabel("frequency [Hz]")
    for ax in (ax_g, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    ax_g.legend(fontsize=8)
    ax_g.set_title(f"linear model at t = {model.time:g} s", fontsize=10)
    fig.tight_layout()
    png, csv_path = stem.with_name(stem.name + "_bode.png"), stem.with_name(stem.name + "_bode.csv")
    fig.savefig(png, dpi=110)
    plt.close(fig)
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, ["input", "output", "frequency_hz", "gain", "gain_db", "phase_deg"])
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in row.items()})
    return [png, csv_path]


# Where the DC gain is read: well below any pole of the gimbal's models (the slowest, gravity's on a
# payload off its axis, is near 0.5 Hz), and a decade lower to tell a free integrator (gain x 10) from
# a finite gain.
DC_FREQUENCY_HZ = 1e-4


def pair_line(model, source: str, target: str, f_max: float) -> str | None:
    """One line for a --bode pair: its DC gain (with its sign) and the frequency where the gain has
    dropped by 3 dB from it (for a first-order lag, its pole), or that the path integrates; None for a
    path that is identically zero (zero_path_warning says why)."""
    import numpy as np

    if model.zero_path_warning(source, target):
        return None
    low, lower = model.frequency_response([DC_FREQUENCY_HZ, DC_FREQUENCY_HZ / 10], source, target)
    if abs(low) == 0.0:
        return None
    if abs(lower) > 5 * abs(low):
        return f"{source} -> {target}: integrates at low frequency (the gain rises as 1/f below the poles): no DC gain"
    dc = float(np.real(low)) if abs(np.imag(low)) < 1e-3 * abs(low) else abs(low)
    text = f"{source} -> {target}: DC gain {dc:.4g} ({20 * math.log10(abs(low)):.2f} dB)"
    frequencies = np.logspace(math.log10(DC_FREQUENCY_HZ), math.log10(max(f_max, 1.0)), 2000)
    below = np.nonzero(np.abs(model.frequency_response(frequencies, source, target)) < abs(low) / math.sqrt(2))[0]
    if len(below) == 0:
        return text + f", no -3 dB point up to {f_max:g} Hz"
    a, b = math.log10(frequencies[below[0] - 1]), math.log10(frequencies[below[0]])
    for _ in range(50):   # bisection in log f: to far below the 4 digits printed
        middle = (a + b) / 2
        if abs(model.frequency_response([10 ** middle], source, target)[0]) < abs(low) / math.sqrt(2):
            b = middle
        else:
            a = middle
    return text + f", -3 dB at {10 ** b:.4g} Hz"


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default=None, help="take parameters, fidelity and initial state from this scene")
    parser.add_argument("--at-time", type=float, default=None,
                        help="run the scene (with its controller) to this time and linearize there")
    parser.add_argument("--fmu", default=None, help="the FMU a scene runs on (default $GIMBAL2AXIS_FMU, else the build "
                                                    "the package was configured with)")
    parser.add_argument("--build-dir", default=None, help="where libgimbal_probe.so is (default "
                                                          "$GIMBAL2AXIS_PROBE_LIBRARY, else the build the package was "
                                                          "configured with)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="a parameter, fidelity switch, start value or input (repeatable; numbers, true/false)")
    parser.add_argument("--out", default="results/linear_model.npz",
                        help=".npz or .mat (default results/linear_model.npz in the current directory)")
    parser.add_argument("--bode", action="append", default=[], metavar="INPUT:OUTPUT",
                        help="also plot this transfer function (repeatable), e.g. u_R1:alpha_dot")
    parser.add_argument("--fmin", type=float, default=0.01, help="Bode plot from (Hz)")
    parser.add_argument("--fmax", type=float, default=1000.0, help="Bode plot to (Hz)")


def check_names(overrides: dict, known) -> None:
    """Refuses a --set name the gimbal model does not have, naming the option and the close matches."""
    for name in overrides:
        if name not in known:
            raise SceneError(f"--set: '{excerpt(name)}' is not a variable of the gimbal model"
                             f"{did_you_mean(name, known)}")


def execute(args) -> int:
    return run_reporting_failures(PROG, lambda: linearize_and_write(args))


def linearize_and_write(args) -> int:
    from ..analysis import linearization   # here, not at the top: --help does without numpy

    overrides = parse_assignments(args.set)
    if args.at_time is not None and args.scene is None:
        raise SceneError("--at-time needs --scene: the run that reaches the operating point")
    if args.at_time is not None and not (args.at_time > 0 and math.isfinite(args.at_time)):
        raise SceneError(f"--at-time {args.at_time:g}: need a positive time (s)")
    if args.bode and not (0 < args.fmin <= args.fmax and math.isfinite(args.fmax)):
        raise SceneError(f"--fmin {args.fmin:g} --fmax {args.fmax:g}: need 0 < fmin <= fmax (Hz)")
    bode_pairs = [parse_pair(pair) for pair in args.bode]
    out = pathlib.Path(args.out)
    if out.suffix not in (".npz", ".mat"):
        raise SceneError(f"--out {out}: write .npz or .mat")
    try:
        check_names(overrides, linearization.variable_names(args.build_dir))
        if args.scene is not None:
            model = scene_point(args.scene, fmu_path(args.fmu), args.at_time, overrides, args.build_dir)
        else:
            model = linearization.linearize(overrides, args.build_dir)
    except SceneError as exc:   # the linearization's own messages start with "linearize: ": the PROG says it
        text = str(exc)
        raise SceneError(text.removeprefix("linearize: ")) from None
    for source, target in bode_pairs:
        if source not in model.inputs:
            raise SceneError(f"--bode '{source}:{target}': '{source}' is not an input of the model"
                             f"{did_you_mean(source, model.inputs) or ' (' + ', '.join(model.inputs) + ')'}")
        if target not in model.outputs:
            raise SceneError(f"--bode '{source}:{target}': '{target}' is not an output of the model"
                             f"{did_you_mean(target, model.outputs) or ' (' + ', '.join(model.outputs) + ')'}")
    out.parent.mkdir(parents=True, exist_ok=True)
    model.save(out)
    written = [out]
    if bode_pairs:
        written += write_bode(model, bode_pairs, out.with_suffix(""), args.fmin, args.fmax)
    print(model.summary())
    for source, target in bode_pairs:
        line = pair_line(model, source, target, args.fmax)
        if line:
            print(line)
    print("wrote " + ", ".join(str(p) for p in written))
    for source, target in bode_pairs:   # after the summary: the last lines a user reads
        warning = model.zero_path_warning(source, target)
        if warning:
            print(f"{PROG}: warning: {warning}", file=sys.stderr)
    return 0
