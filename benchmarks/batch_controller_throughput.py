#!/usr/bin/env python3
"""A sweep of a user controller: its cases in lockstep (the batch form, GyroStabilizerBatch of
examples/gyro_stabilizer.py, gimbal2axis/master/lockstep.py) against one case at a time (the scalar form,
GyroStabilizer, in master.run's Python loop), for batches of N = 1, 4, 16 cases, on one core.

Cases: examples/user_controller.toml (sea state, full drive train) with per case its own gains and
sea-state seed, --stop-time s each. Per N, in one process, best of --repeat, on CPU time:
  - one at a time: master.run of each case with the scalar class on one reused instance (as a
    sweep worker runs a task of a non-batch class);
  - lockstep: run_lockstep of the N cases on a pool of N reused instances (as a worker runs a task
    of a batch class);
  - the FMU alone: each case's commanded voltages replayed through the compiled loop (Replay).
Reported: simulated seconds per CPU second, and the master's own cost per case-step (the run's
CPU time minus the FMU alone, per case and step; includes the user's step(), shared out over the
cases in lockstep). Also, with --sweep-cases > 0, a whole serial sweep (gimbal2axis sweep --serial)
of that many cases with each class. Writes benchmarks/results/batch_controller.json.

Usage: .venv/bin/python benchmarks/batch_controller_throughput.py [--stop-time 2] [--repeat 3] [--sweep-cases 32]
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import pathlib
import platform
import tempfile
import time

import numpy as np

from gimbal2axis import FMU, load_scene, run
from gimbal2axis.scene.controllers import Replay
from gimbal2axis.master.lockstep import run_lockstep

REPO = pathlib.Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "user_controller.toml"


def cases(count: int, stop_time: float, class_name: str):
    scene = load_scene(EXAMPLE)
    rng = np.random.default_rng(5)
    out = []
    for i in range(count):
        spec = dict(scene.controller_spec, **{"class": class_name})
        spec["options"] = dict(spec["options"], kp=float(rng.uniform(200.0, 800.0)),
                               k_gyro=float(rng.uniform(4.0, 12.0)))
        motion = dict(scene.base_motion_spec, seed=int(rng.integers(0, 99999)))
        out.append(scene.with_changes(controller_spec=spec, base_motion_spec=motion, stop_time=stop_time))
    return out


def measure(fmu, n: int, stop_time: float, repeat: int) -> dict:
    scalar, batch = cases(n, stop_time, "GyroStabilizer"), cases(n, stop_time, "GyroStabilizerBatch")
    log: list = []
    slave = fmu.instantiate("one", log)
    pool = [(fmu.instantiate(f"pool-{i}", l), l) for i, l in enumerate([[] for _ in range(n)])]
    best = {"one_at_a_time": np.inf, "lockstep": np.inf, "fmu_alone": np.inf}
    for _ in range(repeat):
        t0 = time.process_time()
        singles = [run(scene, fmu, slave=slave, log=log) for scene in scalar]
        best["one_at_a_time"] = min(best["one_at_a_time"], time.process_time() - t0)
        t0 = time.process_time()
        together = run_lockstep(batch, fmu, pool)
        best["lockstep"] = min(best["lockstep"], time.process_time() - t0)
        assert all(r.loop == "lockstep" for r in together), together
        alone = 0.0
        for result in together:
            commands = np.column_stack((result.signals["u_R1_cmd"], result.signals["u_R2_cmd"]))
            replayed = run(result.scene, fmu, slave=slave, log=log, controller=Replay(commands), compiled=True)
            assert np.array_equal(replayed.signals["beta"], result.signals["beta"])   # the same work
            alone += replayed.loop_cpu_time
        best["fmu_alone"] = min(best["fmu_alone"], alone)
    for p, _ in pool:
        p.freeInstance()
    slave.freeInstance()
    rms_diff = max(abs(a.los_metrics()["rms"] - b.los_metrics()["rms"]) / b.los_metrics()["rms"]
                   for a, b in zip(together, singles))
    steps = n * (int(round(stop_time / 1e-3)) + 1)
    simulated = n * stop_time
    return {"cases": n, "stop_time_s": stop_time, "cpu_s": best,
            "simulated_s_per_cpu_s": {k: simulated / v for k, v in best.items()},
            "master_us_per_case_step": {k: (best[k] - best["fmu_alone"]) / steps * 1e6
                                        for k in ("one_at_a_time", "lockstep")},
            "fmu_us_per_case_step": best["fmu_alone"] / steps * 1e6,
            "speedup_lockstep": best["one_at_a_time"] / best["lockstep"],
            "max_relative_los_rms_difference_batch_vs_scalar": rms_diff}


def sweep(fmu_path, count: int, stop_time: float) -> dict:
    from gimbal2axis.sweep import SweepOptions, run_sweep

    text = (f'name = "bench"\nseed = 2\nsamples = {max(1, count // 4)}\nstop_time = {stop_time}\n'
            '[grid]\n"controller.options.kp" = [200.0, 400.0]\n"controller.options.k_gyro" = [4.0, 8.0]\n'
            '[random]\n"base_motion.seed" = { integers = [0, 99999] }\n')
    figures = {}
    with tempfile.TemporaryDirectory(prefix="gimbal_batch_bench_") as tmp:
        tmp = pathlib.Path(tmp)
        (tmp / "sweep.toml").write_text(text)
        for class_name in ("GyroStabilizer", "GyroStabilizerBatch"):
            # the scene in another folder: its controller file by its absolute path
            scene = EXAMPLE.read_text().replace('file = "gyro_stabilizer.py"',
                                                f'file = "{REPO / "examples" / "gyro_stabilizer.py"}"')
            scene = scene.replace('class = "GyroStabilizer"', f'class = "{class_name}"')
            (tmp / "scene.toml").write_text(scene)
            t0, c0 = time.perf_counter(), time.process_time()
            outcome = run_sweep(tmp / "scene.toml", tmp / "sweep.toml", fmu_path, tmp / class_name,
                                SweepOptions(serial=True, progress=False, plot=False))
            figures[class_name] = {"cases": outcome.ran, "failed": outcome.failed,
                                   "wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}
    return figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stop-time", type=float, default=2.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--sweep-cases", type=int, default=32)
    parser.add_argument("--fmu", default=str(REPO / "build" / "Gimbal2Axis.fmu"))
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "batch_controller.json"))
    args = parser.parse_args()
    with FMU(args.fmu) as fmu:
        rows = [measure(fmu, n, args.stop_time, args.repeat) for n in args.sizes]
    for row in rows:
        print(f"N = {row['cases']:2d}: simulated s per CPU s  one at a time {row['simulated_s_per_cpu_s']['one_at_a_time']:.1f}"
              f"  lockstep {row['simulated_s_per_cpu_s']['lockstep']:.1f}  FMU alone {row['simulated_s_per_cpu_s']['fmu_alone']:.1f};"
              f"  master us per case-step  one at a time {row['master_us_per_case_step']['one_at_a_time']:.1f}"
              f"  lockstep {row['master_us_per_case_step']['lockstep']:.1f}  (FMU {row['fmu_us_per_case_step']:.1f});"
              f"  speed-up {row['speedup_lockstep']:.2f}")
    result = {"date": datetime.date.today().isoformat(), "machine": platform.processor() or platform.machine(),
              "cpus": os.cpu_count(), "load_average": os.getloadavg(), "scene": str(EXAMPLE.relative_to(REPO)),
              "sizes": rows}
    if args.sweep_cases > 0:
        result["serial_sweep"] = sweep(args.fmu, args.sweep_cases, args.stop_time / 4)
        for name, fig in result["serial_sweep"].items():
            print(f"serial sweep, {fig['cases']} cases of {args.stop_time / 4:g} s, {name}: {fig['wall_s']:.2f} s wall, "
                  f"{fig['cpu_s']:.2f} s CPU")
    pathlib.Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
