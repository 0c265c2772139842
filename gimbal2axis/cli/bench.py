"""What the scene runner's simulation loop costs, and how much of it is the master's own:

    gimbal2axis bench [scenes/ship_stabilization.toml] [--stop-time 20]

1. runs the scene through the master (gimbal2axis.master.run: sensors, controller, delay, records),
   once with the compiled loop (the default for the built-in controllers) and once with the Python
   loop (what a user controller runs in), and takes the CPU time of each loop; a scene with a Python
   controller runs in the Python loop only, and its master's own cost includes the controller's;
2. replays exactly the voltages that run commanded (a Replay controller, same delay) through the
   compiled loop: the FMU alone, with nothing of the master but the loop itself; and through the
   Python loop: the FMU plus the cost of calling it from Python;
3. the master's own cost per step is the difference to the replay. Each replay must reproduce the
   run's outputs bit for bit, which checks that they measured the same work.

All repeated (--repeat, best of) in one process, on CPU time (machines are shared and noisy).
Writes the figures as JSON (--out, default benchmarks/results/scene_runner.json) and prints those
docs/benchmarks.md quotes.
"""
from __future__ import annotations

import datetime
import json
import math
import pathlib
import sys
import time

from ..errors import SceneError, one_line
from ..locations import fmu_path
from .defaults import scene_file

SUMMARY = "CPU time of the scene runner's loop: the FMU alone, the master's own cost per step"
PROG = "gimbal2axis bench"
DEFAULT_SCENE = pathlib.Path("scenes", "ship_stabilization.toml")   # relative to the current directory
LOOPS = ("compiled", "python")
EXIT_STATUSES = {0: "done", 1: "a replay did not reproduce its run's outputs: the figures would not compare the "
                                "same work, none are written",
                 2: "refused: an argument, the scene, the FMU, or an --out that cannot be written",
                 130: "interrupted (SIGINT, Ctrl-C)"}


def loop_cpu(scene, fmu, compiled: bool, controller=None):
    """CPU seconds of the run's loop, of the whole run (with the base motion evaluated up front and
    the set points), and the result."""
    from ..master import run

    before = time.process_time()
    result = run(scene, fmu, compiled=compiled, controller=controller)
    return result.loop_cpu_time, time.process_time() - before, result


def same_outputs(a, b, fmu) -> bool:
    import numpy as np

    from ..master import real_outputs

    return all(np.array_equal(a.signals[name], b.signals[name]) for name in real_outputs(fmu))


def loops_of(scene, fmu) -> tuple:
    """The loops the scene's controller runs in: both for a built-in controller, the Python loop only
    for a Python one (the compiled loop runs the built-in controllers only)."""
    from ..master import run

    first = run(scene.with_changes(stop_time=scene.step_size), fmu)   # the loop the runner chooses
    return LOOPS if first.loop == "compiled" else ("python",)


def measure(scene, fmu, repeat: int, loops: tuple = LOOPS) -> dict:
    """Best-of-`repeat` CPU seconds: 'run_<loop>', 'whole_<loop>' and 'replay_<loop>' per loop, and
    'spread_<key>_<loop>' the largest minus the smallest of the repeats (the noise of the machine);
    None when a replay did not reproduce its run. The compiled loop's replay is always measured: the
    FMU alone, the reference of every loop."""
    import numpy as np

    from ..scene.drives import command_columns
    from ..scene.controllers import Replay

    samples: dict = {}
    for _ in range(repeat):
        for loop in loops:
            cpu, whole, result = loop_cpu(scene, fmu, loop == "compiled")
            commands = np.column_stack([result.signals[command_columns(result.signals, j).commanded] for j in (1, 2)])
            for replay_loop in (loop,) if "compiled" in loops else ("compiled", loop):
                replay, _, replayed = loop_cpu(scene, fmu, replay_loop == "compiled", Replay(commands))
                if not same_outputs(result, replayed, fmu):
                    return None
                samples.setdefault(f"replay_{replay_loop}", []).append(replay)
            for key, value in (("run", cpu), ("whole", whole)):
                samples.setdefault(f"{key}_{loop}", []).append(value)
    best = {key: min(values) for key, values in samples.items()}
    best.update({f"spread_{key}": max(values) - min(values) for key, values in samples.items()})
    return best


def cost_text(cost_us: float, noise_us: float) -> str:
    """A per-step cost that is the difference of two measured times: said as a number only when it
    stands out of the noise (the spread between repeats of the two). A negative difference, the run
    faster than its replay, is noise by definition: the run does all the replay does and more."""
    if cost_us <= noise_us:
        return f"below the noise ({cost_us:+.2f} us per step measured, the repeats spread over {noise_us:.2f})"
    return f"{cost_us:.2f} us per step (+- {noise_us:.2f})"


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?", default=None,
                        help=f"the scene to measure (default: {DEFAULT_SCENE} in the current directory, the "
                             "repository's when run from its root)")
    parser.add_argument("--scene", dest="scene_option", default=None, metavar="SCENE",
                        help="the same, as an option")
    parser.add_argument("--fmu", default=None,
                        help="the FMU (default $GIMBAL2AXIS_FMU, else the build the package was configured with)")
    parser.add_argument("--stop-time", type=float, default=20.0, metavar="T",
                        help="simulated seconds per run (default 20)")
    parser.add_argument("--repeat", type=int, default=3, metavar="N",
                        help="runs of each kind; the fastest counts (default 3)")
    parser.add_argument("--out", default="benchmarks/results/scene_runner.json",
                        help="the JSON of the figures (default benchmarks/results/scene_runner.json in the current "
                             "directory)")


def execute(args) -> int:
    if not (math.isfinite(args.stop_time) and args.stop_time > 0):
        args.command_parser.error(f"--stop-time {args.stop_time:g}: need a positive number of seconds")
    if args.repeat < 1:
        args.command_parser.error(f"--repeat {args.repeat}: need at least 1")
    if args.scene is not None and args.scene_option is not None and args.scene != args.scene_option:
        args.command_parser.error(f"two scenes, {args.scene} and --scene {args.scene_option}: give one")
    # here, not at the top: `gimbal2axis --help` does without numpy and fmpy
    from ..fmu import FMU
    from ..scene import load_scene

    try:
        scene = load_scene(scene_file(args.scene or args.scene_option, DEFAULT_SCENE, "the scene: gimbal2axis bench "
                                                                                     "SCENE.toml"))
        scene = scene.with_changes(stop_time=args.stop_time)
        with FMU(fmu_path(args.fmu)) as fmu:
            loops = loops_of(scene, fmu)
            best = measure(scene, fmu, args.repeat, loops)
    except SceneError as exc:
        print(one_line(f"{PROG}: error: {exc}"), file=sys.stderr)
        return 2
    if best is None:
        print(f"{PROG}: a replay did not reproduce its run's outputs", file=sys.stderr)
        return 1
    steps = int(round(args.stop_time / scene.step_size))
    per_step = 1e6 / steps
    figures = {
        "scene": scene.name, "controller": scene.controller_spec.get("type", "none"), "stop_time_s": args.stop_time,
        "steps": steps, "date": datetime.date.today().isoformat(),
        "fmu_alone_cpu_s": best["replay_compiled"], "fmu_alone_real_time_factor": args.stop_time / best["replay_compiled"],
        "fmu_us_per_step": best["replay_compiled"] * per_step,
        "note": "loop CPU time includes the instance's set-up and initialization and the recording; the base "
                "motion and the set points of the whole run, evaluated before the loop, are in whole_run_cpu_s only",
    }
    for loop in loops:
        # the differences' noise: the repeats' spread of each of the two times subtracted
        own_noise = (best[f"spread_run_{loop}"] + best["spread_replay_compiled"]) * per_step
        alone_noise = (best[f"spread_replay_{loop}"] + best["spread_replay_compiled"]) * per_step
        figures[loop] = {
            "loop_cpu_s": best[f"run_{loop}"], "real_time_factor_cpu": args.stop_time / best[f"run_{loop}"],
            "whole_run_cpu_s": best[f"whole_{loop}"],
            "replay_cpu_s": best[f"replay_{loop}"],
            "master_own_us_per_step": (best[f"run_{loop}"] - best["replay_compiled"]) * per_step,
            "master_own_noise_us_per_step": own_noise,
            "loop_alone_us_per_step": (best[f"replay_{loop}"] - best["replay_compiled"]) * per_step,
            "loop_alone_noise_us_per_step": alone_noise,
        }
    out = pathlib.Path(args.out)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(figures, indent=2) + "\n")
    except OSError as exc:
        print(f"{PROG}: error: --out {out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    print(f"{scene.name}, {args.stop_time:g} s at h = {scene.step_size:g} s ({steps} steps), "
          f"controller {figures['controller']}, CPU time, best of {args.repeat}:")
    print(f"  FMU alone (compiled replay)  {best['replay_compiled']:.3f} s = "
          f"{figures['fmu_alone_real_time_factor']:.0f}x real time, {figures['fmu_us_per_step']:.2f} us per step")
    for loop in loops:
        f = figures[loop]
        alone = "the reference" if loop == "compiled" else cost_text(f["loop_alone_us_per_step"],
                                                                     f["loop_alone_noise_us_per_step"])
        own = "master's own (with the Python controller)" if len(loops) == 1 else "master's own"
        print(f"  {loop + ' loop':<28} {f['loop_cpu_s']:.3f} s = {f['real_time_factor_cpu']:.0f}x real time; {own} "
              f"{cost_text(f['master_own_us_per_step'], f['master_own_noise_us_per_step'])} (the loop alone, without "
              f"the controller: {alone}); "
              f"whole run {f['whole_run_cpu_s']:.3f} s")
    print(f"wrote {out}")
    return 0
