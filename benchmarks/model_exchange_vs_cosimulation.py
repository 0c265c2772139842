"""Model Exchange under fmpy's CVode next to the Co-Simulation FMU: CPU time and error, one run.

Two fixed-base scenes with constant inputs (so that every host sees the same problem exactly): the
free swing of scenes/free_swing.toml (2 s, no event) and a hard drive (motors at 6 V and -4 V: the
current limiter, the backlash and dry friction switch; 1 s). Each is run as
- Model Exchange with fmpy.simulate_fmu (CVode BDF, fmpy's Python loop, output every 1 ms) at rtol
  1e-6 and 1e-8;
- Co-Simulation with the FMU's own integrator at solver.rtol 1e-6 and 1e-8, 1 ms steps;
against a reference: Co-Simulation at solver.rtol 1e-12. Errors are the largest differences of alpha
and beta at the 1 ms points; CPU time is time.process_time of the whole fmpy call (Python included).
Also runs build/benchmarks/gimbal_bench_me (the cost of one evaluation through the interface).

    .venv/bin/python benchmarks/model_exchange_vs_cosimulation.py [--build build] [--out benchmarks/results]
"""
from __future__ import annotations

import argparse
import datetime
import json
import pathlib
import subprocess
import sys
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]

SCENES = {
    "free swing (2 s)": (2.0, {"base.fixed": True, "solver.atol": 1e-10, "motor2.k_torque": 0.0,
                                          "motor2.k_emf": 0.0, "beta": 0.5235987755982988,
                                          "beta_m": 31.41592653589793}),
    "hard drive, 6 V / -4 V (1 s, events)": (1.0, {"base.fixed": True, "beta": 0.3, "beta_m": 18.0,
                                                    "u_R1": 6.0, "u_R2": -4.0}),
}
OUTPUTS = ["alpha", "beta", "events.total"]


def run(fmu: str, fmi_type: str, stop: float, start: dict, rtol: float) -> tuple[dict, float]:
    import fmpy

    values = dict(start)
    if fmi_type == "CoSimulation":
        values["solver.rtol"] = rtol
    cpu = time.process_time()
    result = fmpy.simulate_fmu(fmu, fmi_type=fmi_type, stop_time=stop, output_interval=1e-3, start_values=values,
                               relative_tolerance=rtol if fmi_type == "ModelExchange" else None, output=OUTPUTS)
    cpu = time.process_time() - cpu
    # Model Exchange also records the events between output points, and a point before and after an
    # event at an output point: keep the last value at each 1 ms point.
    times = result["time"]
    on_grid = np.abs(times * 1000 - np.round(times * 1000)) < 1e-6
    last = np.append(times[1:] != times[:-1], True)
    keep = on_grid & last
    return {name: result[name][keep] for name in OUTPUTS}, cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(REPO / "build"))
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results"))
    args = parser.parse_args()
    build = pathlib.Path(args.build)
    fmu = str(build / "Gimbal2Axis.fmu")
    rows = []
    for scene, (stop, start) in SCENES.items():
        reference, _ = run(fmu, "CoSimulation", stop, start, 1e-12)
        for fmi_type in ("ModelExchange", "CoSimulation"):
            for rtol in (1e-6, 1e-8):
                result, cpu = run(fmu, fmi_type, stop, start, rtol)
                n = min(len(result["alpha"]), len(reference["alpha"]))
                error = max(float(np.max(np.abs(result[a][:n] - reference[a][:n]))) for a in ("alpha", "beta"))
                rows.append({"scene": scene, "interface": fmi_type, "rtol": rtol, "cpu_s": cpu,
                             "real_time_factor": stop / cpu, "max_angle_error_rad": error,
                             "events": int(result["events.total"][-1]),
                             "reference_events": int(reference["events.total"][-1])})
                print(f"{scene:38s} {fmi_type:14s} rtol {rtol:.0e}: CPU {cpu:7.3f} s ({stop / cpu:7.1f}x real time), "
                      f"angle error {error:.1e} rad, {rows[-1]['events']} events (reference {rows[-1]['reference_events']})")
    bench = build / "benchmarks" / "gimbal_bench_me"
    evaluation = None
    if bench.is_file():
        done = subprocess.run([str(bench), "--fmu", str(build / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"),
                               "--model-description", str(build / "fmu_staging" / "modelDescription.xml"), "--json"],
                              capture_output=True, text=True, check=True)
        evaluation = json.loads(done.stdout)
        print("one evaluation through the interface:", evaluation)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "model_exchange.json").write_text(json.dumps({"date": datetime.date.today().isoformat(), "runs": rows,
                                                         "evaluation": evaluation}, indent=1) + "\n")
    print(f"written {out / 'model_exchange.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
