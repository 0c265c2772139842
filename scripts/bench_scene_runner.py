#!/usr/bin/env python3
"""What the scene runner's simulation loop costs, and how much of it is the master's own:

    .venv/bin/python scripts/bench_scene_runner.py [--scene scenes/ship_stabilization.toml] [--stop-time 20]

1. runs the scene through the master (scene_lib.master.run: sensors, controller, delay, records) and
   takes the CPU time of its loop;
2. replays exactly the same inputs (the applied voltages and base inputs of that run) through the FMU
   alone, with the same raw calls (one set of all inputs, one doStep, one get of all outputs per
   step), and takes its CPU time;
3. the master's own cost per step is the difference. The replay must reproduce the run's outputs bit
   for bit, which checks that the two measured the same work.

Both are repeated (--repeat, best of) in one process, on CPU time (machines are shared and noisy).
Writes benchmarks/results/scene_runner.json and prints the figures docs/benchmarks.md quotes.
"""
from __future__ import annotations

import argparse
import ctypes
import datetime
import json
import pathlib
import sys
import time

import numpy as np

from scene_lib import FMU, load_scene, run
from scene_lib.base_motion import INPUTS as BASE_INPUTS
from scene_lib.master import REAL_OUTPUTS, RawCalls
from scene_lib.scene import start_values

REPO = pathlib.Path(__file__).resolve().parents[1]


def master_loop_cpu(scene, fmu, stop_time: float) -> tuple[float, float, object]:
    """CPU seconds of the master's loop, of the whole run (with the base motion's evaluation up
    front), and the result."""
    before = time.process_time()
    result = run(scene.with_changes(stop_time=stop_time), fmu)
    return result.loop_cpu_time, time.process_time() - before, result


def replay_cpu(scene, fmu, result) -> tuple[float, np.ndarray]:
    """The FMU alone over the run's applied inputs: CPU seconds and the outputs it gives."""
    signals = result.signals
    h = scene.step_size
    n = len(signals["time"]) - 1
    motion = scene.base_motion()
    names = ["u_R1", "u_R2"] + ([] if motion.fixed else BASE_INPUTS)
    inputs = np.ascontiguousarray(np.column_stack([signals[name] for name in names]))
    real_names = [name for name in REAL_OUTPUTS if fmu.has(name)]
    outputs = np.zeros((n + 1, len(real_names)))
    input_vrs = np.array([fmu.vr(name) for name in names], dtype=np.uint32)
    output_vrs = np.array([fmu.vr(name) for name in real_names], dtype=np.uint32)
    slave = fmu.instantiate("replay")
    try:
        slave.setupExperiment(startTime=0.0, stopTime=n * h)
        # The start values exactly as the master computes them (numpy's vectorised sin may differ in
        # the last bit between array lengths).
        base = motion.sample(np.arange(n + 1) * h)
        fmu.set_values(slave, start_values(scene, fmu, base[0], motion.sample(np.array([1e-6]))[0]))
        slave.enterInitializationMode()
        slave.setReal(list(map(int, input_vrs)), [0.0, 0.0] + ([] if motion.fixed else base[0].tolist()))
        slave.exitInitializationMode()
        calls = RawCalls(slave)
        component = slave.component
        in_row, in_stride = inputs.ctypes.data, inputs.strides[0]
        out_row, out_stride = outputs.ctypes.data, outputs.strides[0]
        before = time.process_time()
        for k in range(n + 1):
            calls.get_real(component, output_vrs.ctypes.data, len(output_vrs), out_row + k * out_stride)
            if k == n:
                break
            calls.set_real(component, input_vrs.ctypes.data, len(input_vrs), in_row + k * in_stride)
            if calls.do_step(component, k * h, h, 1) > 1:
                raise RuntimeError(f"the replay failed at step {k}")
        cpu = time.process_time() - before
    finally:
        slave.freeInstance()
    recorded = np.column_stack([signals[name] for name in real_names])
    return cpu, np.array_equal(outputs, recorded)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default=str(REPO / "scenes" / "ship_stabilization.toml"))
    parser.add_argument("--fmu", default=str(REPO / "build" / "Gimbal2Axis.fmu"))
    parser.add_argument("--stop-time", type=float, default=20.0, help="simulated seconds per run (default 20)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each kind; the fastest counts (default 3)")
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "scene_runner.json"))
    args = parser.parse_args()

    scene = load_scene(args.scene)
    with FMU(args.fmu) as fmu:
        loops, replays = [], []
        for _ in range(args.repeat):
            cpu, whole, result = master_loop_cpu(scene, fmu, args.stop_time)
            loops.append((cpu, result.wall_time, whole))
            replay, identical = replay_cpu(scene, fmu, result)
            replays.append(replay)
            if not identical:
                print("bench_scene_runner: the replay did not reproduce the run's outputs", file=sys.stderr)
                return 1
    steps = int(round(args.stop_time / scene.step_size))
    loop_cpu = min(cpu for cpu, _, _ in loops)
    whole_cpu = min(whole for _, _, whole in loops)
    fmu_cpu = min(replays)
    figures = {
        "scene": scene.name, "controller": scene.controller_spec.get("type", "none"), "stop_time_s": args.stop_time,
        "steps": steps, "date": datetime.date.today().isoformat(),
        "master_loop_cpu_s": loop_cpu, "master_loop_wall_s": min(wall for _, wall, _ in loops),
        "whole_run_cpu_s": whole_cpu,
        "real_time_factor_cpu": args.stop_time / loop_cpu,
        "fmu_alone_cpu_s": fmu_cpu, "fmu_alone_real_time_factor": args.stop_time / fmu_cpu,
        "fmu_us_per_step": fmu_cpu / steps * 1e6,
        "master_own_us_per_step": (loop_cpu - fmu_cpu) / steps * 1e6,
        "note": "loop CPU time includes the instance's set-up and initialization and the recording; the "
                "base motion of the whole run, evaluated before the loop, is in whole_run_cpu_s only",
    }
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(figures, indent=2) + "\n")
    print(f"{scene.name}, {args.stop_time:g} s at h = {scene.step_size:g} s ({steps} steps), "
          f"controller {figures['controller']}:")
    print(f"  master loop      {loop_cpu:.3f} s CPU = {figures['real_time_factor_cpu']:.0f}x real time")
    print(f"  FMU alone        {fmu_cpu:.3f} s CPU = {figures['fmu_alone_real_time_factor']:.0f}x real time "
          f"({figures['fmu_us_per_step']:.2f} us per step, same inputs, outputs bit-identical)")
    print(f"  master's own     {figures['master_own_us_per_step']:.2f} us per step")
    print(f"  whole run        {whole_cpu:.3f} s CPU (with the base motion evaluated up front, and the metrics)")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
