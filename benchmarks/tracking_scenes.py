"""The tracking scenes' real-time factors, and the keyhole flyby's speed against its error in either drive.

Each scenes/track_*.toml is run whole by the scene runner's compiled loop (gimbal2axis.run, held in
memory: no files, no plots), its CPU time being RunResult.loop_cpu_time (initialization and the loop;
time.process_time, the median of `--repeat` runs) and its real-time factor the simulated time over it.
Beside them, the current-drive flyby (track_flyby_keyhole_current) in two more variants:
- its quasi-static reduction (motor<j>.model = quasi_static: the amplifier an ideal current source
  limited by the bus, no current state, no 2 kHz pole; docs/physics.md section 4.6);
- RODAS4 alone (solver.method 6) and the real-time method (7: RODAS4 in 8 or 16 fixed substeps per
  step), against the automatic method's choice (Dormand-Prince, switching to RODAS4 while stiff);
- at solver.rtol 1e-10, atol 1e-12: the reference every variant is measured against (the largest
  differences of alpha, beta [rad], los_error [mrad] and i_R1 [A] over the run).
The FMU's work comes from its counters (solver.steps, solver.rhs_evaluations, events.total), read from
the instance after the run.

    .venv/bin/python benchmarks/tracking_scenes.py [--repeat 3] [--stop-time S]
Prints a table and writes benchmarks/results/tracking_scenes.json.
"""
from __future__ import annotations

import argparse
import datetime
import json
import pathlib
import platform
import statistics

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]
COUNTERS = ["solver.steps", "solver.rhs_evaluations", "events.total"]
CURRENT_FLYBY = "track_flyby_keyhole_current"
VARIANTS = {
    "quasi-static reduction": {"motor1.model": 0, "motor2.model": 0},
    "RODAS4 only": {"solver.method": 6},
    "real-time method, 8 substeps": {"solver.method": 7, "solver.substeps": 8},
    "real-time method, 16 substeps": {"solver.method": 7, "solver.substeps": 16},
    "rtol 1e-10 (reference)": {"solver.rtol": 1e-10, "solver.atol": 1e-12},
}


def run_once(scene, fmu, stop_time):
    from gimbal2axis import run

    log: list = []
    slave = fmu.instantiate(scene.name, log)
    try:
        result = run(scene, fmu, stop_time=stop_time, slave=slave, log=log, compiled=True)
        counters = dict(zip(COUNTERS, (int(v) for v in fmu.get_values(slave, COUNTERS))))
    finally:
        slave.freeInstance()
    return result, counters


def measure(scene, fmu, stop_time, repeat):
    cpu, result, counters = [], None, None
    for _ in range(repeat):
        result, counters = run_once(scene, fmu, stop_time)
        cpu.append(result.loop_cpu_time)
    seconds = result.stop_time
    tracking = result.tracking_metrics().as_dict()
    return result, {"simulated_s": seconds, "cpu_s": statistics.median(cpu), "cpu_spread_s": max(cpu) - min(cpu),
                    "real_time_factor": seconds / statistics.median(cpu), **counters,
                    "los_rms_mrad": result.los_metrics()["rms"] * 1e3,
                    "time_lost_near_keyhole_s": tracking["time_lost_near_keyhole_s"],
                    "on_target_fraction": tracking["on_target_fraction"]}


def differences(result, reference) -> dict:
    a, b = result.signals, reference.signals
    return {"alpha_rad": float(np.max(np.abs(a["alpha"] - b["alpha"]))),
            "beta_rad": float(np.max(np.abs(a["beta"] - b["beta"]))),
            "los_error_mrad": float(np.max(np.abs(result.signal("los_error") - reference.signal("los_error")))) * 1e3,
            "i_R1_A": float(np.max(np.abs(a["i_R1"] - b["i_R1"])))}


def main() -> int:
    from gimbal2axis import FMU, load_scene, locations

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--stop-time", type=float, default=None, help="shorter runs than the scenes' own (s)")
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "tracking_scenes.json"))
    args = parser.parse_args()
    rows, results = {}, {}
    with FMU(locations.fmu_path()) as fmu:
        for path in sorted((REPO / "scenes").glob("track_*.toml")):
            scene = load_scene(path)
            results[scene.name], rows[scene.name] = measure(scene, fmu, args.stop_time, args.repeat)
            print(f"{scene.name}: {rows[scene.name]['real_time_factor']:.1f}x real time", flush=True)
        base = load_scene(REPO / "scenes" / f"{CURRENT_FLYBY}.toml")
        for label, values in VARIANTS.items():
            scene = base.with_changes(fidelity={**base.fidelity, **{k: v for k, v in values.items() if "model" in k}},
                                      parameters={**base.parameters, **{k: v for k, v in values.items()
                                                                        if "model" not in k}})
            name = f"{CURRENT_FLYBY}, {label}"
            results[name], rows[name] = measure(scene, fmu, args.stop_time, 1 if "reference" in label else args.repeat)
            print(f"{name}: {rows[name]['real_time_factor']:.1f}x real time", flush=True)
    reference = results[f"{CURRENT_FLYBY}, rtol 1e-10 (reference)"]
    compared = [CURRENT_FLYBY] + [f"{CURRENT_FLYBY}, {label}" for label in VARIANTS if "reference" not in label]
    for name in compared:
        rows[name]["against_reference"] = differences(results[name], reference)
    voltage_cpu = rows["track_flyby_keyhole"]["cpu_s"]
    print(f"\n{'scene':58s} {'CPU [s]':>8s} {'x real time':>11s} {'vs voltage':>10s} {'steps':>9s} {'rhs':>10s} "
          f"{'events':>7s} {'LOS RMS':>8s} {'lost at keyhole':>15s}")
    for name, row in rows.items():
        ratio = row["cpu_s"] / voltage_cpu if name.startswith("track_flyby_keyhole") else float("nan")
        print(f"{name:58s} {row['cpu_s']:8.3f} {row['real_time_factor']:11.1f} {ratio:10.2f} {row['solver.steps']:9d} "
              f"{row['solver.rhs_evaluations']:10d} {row['events.total']:7d} {row['los_rms_mrad']:8.4g} "
              f"{row['time_lost_near_keyhole_s']:15.3g}")
    for name in compared:
        d = rows[name]["against_reference"]
        print(f"{name} against the reference: alpha {d['alpha_rad']:.2g} rad, beta {d['beta_rad']:.2g} rad, "
              f"los_error {d['los_error_mrad']:.2g} mrad, i_R1 {d['i_R1_A']:.2g} A")
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"date": datetime.date.today().isoformat(),
                               "machine": platform.processor() or platform.machine(), "repeat": args.repeat,
                               "rows": rows}, indent=1) + "\n")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
