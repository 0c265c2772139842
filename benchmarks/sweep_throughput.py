#!/usr/bin/env python3
"""Throughput of a 200-case sweep: a local Dask cluster of N worker processes (default 2) against
the same cases run serially in one process (both reuse one FMU instance per worker via fmi2Reset).

Cases: the ship stabilization scene (sea state, PI + gyro loop, full drive train), 0.5 s each,
a grid over the azimuth gains times random sea states. Reports cases/s and the speed-up, with and
without the cluster's start-up; writes benchmarks/results/sweep_throughput.json and prints it.

Usage: .venv/bin/python benchmarks/sweep_throughput.py [--cases 200] [--workers 2] [--stop-time 0.5] [--repeat 2]
"""
import argparse
import datetime
import json
import os
import pathlib
import platform
import shutil
import sys
import tempfile
import time

from gimbal2axis.sweep import SweepOptions, make_client, run_sweep
from gimbal2axis.sweep.table import read_rows

REPO = pathlib.Path(__file__).resolve().parents[1]

SWEEP = """
name = "throughput"
cases = {cases}
seed = 11
stop_time = {stop_time}
metrics_from_s = 0.05
[grid]
"controller.azimuth.kp" = {{ geomspace = [100.0, 1600.0, 5] }}
"controller.azimuth.k_gyro" = [2.0, 4.0, 8.0, 16.0]
[random]
"base_motion.seed" = {{ integers = [0, 99999] }}
"base_motion.roll.significant_amplitude_deg" = {{ uniform = [2.0, 8.0] }}
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--stop-time", type=float, default=0.5)
    parser.add_argument("--repeat", type=int, default=2, help="alternate serial and Dask runs; keep the best of each")
    parser.add_argument("--scene", default=str(REPO / "scenes" / "ship_stabilization.toml"))
    parser.add_argument("--fmu", default=str(REPO / "build" / "Gimbal2Axis.fmu"))
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "sweep_throughput.json"))
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="gimbal_sweep_bench_") as tmp:
        tmp = pathlib.Path(tmp)
        fmu = tmp / "Gimbal2Axis.fmu"   # one copy for both runs (the build may replace the original meanwhile)
        shutil.copyfile(args.fmu, fmu)
        sweep = tmp / "throughput.toml"
        sweep.write_text(SWEEP.format(cases=args.cases, stop_time=args.stop_time))

        serial, dask, serial_times, dask_times, t_startup = timed_sweeps(args, fmu, sweep, tmp)
        t_serial, t_dask = min(serial_times), min(dask_times)
        compared = compare_tables(serial, dask)

    n = args.cases
    result = {
        "benchmark": "sweep_throughput",
        "date": datetime.date.today().isoformat(),
        "cases": n,
        "scene": pathlib.Path(args.scene).stem,
        "simulated_s_per_case": args.stop_time,
        "workers": args.workers,
        "cpus": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "python": platform.python_version(),
        "fmu_sha256": compared["fmu_sha"],
        "repeat": args.repeat,
        "serial": {"wall_s": round(t_serial, 3), "sum_of_case_times_s": round(compared["serial_case_time"], 3), "all_wall_s": [round(t, 3) for t in serial_times], "cases_per_s": round(n / t_serial, 3),
                   "failed": serial.failed},
        "dask": {"wall_s": round(t_dask, 3), "all_wall_s": [round(t, 3) for t in dask_times], "cases_per_s": round(n / t_dask, 3),
                 "cluster_startup_s": round(t_startup, 3),
                 "cases_per_s_with_startup": round(n / (t_dask + t_startup), 3),
                 "sum_of_case_times_s": round(compared["case_time"], 3),
                 "sum_of_case_cpu_s": round(compared["case_cpu"], 3),
                 "cpu_share_of_workers": round(compared["case_cpu"] / compared["case_time"], 3), "failed": dask.failed},
        "speedup": round(t_serial / t_dask, 3),
        "speedup_with_startup": round(t_serial / (t_dask + t_startup), 3),
        "dask_equals_serial": compared["same"],
        "note": ("best of the repetitions; times include case expansion and table writing, not the plot; each worker extracts the FMU once (its first case pays for it); other processes on the machine show in load_average_1min"),
    }
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    print(f"wrote {out}")
    return 0 if compared["same"] and not serial.failed and not dask.failed else 1


def timed_sweeps(args, fmu: pathlib.Path, sweep: pathlib.Path, tmp: pathlib.Path):
    """The sweep run serially and on a local Dask cluster, alternated --repeat times: the last
    outcomes, the wall times of each, and the cluster's start-up time."""
    t0 = time.perf_counter()
    client, cluster = make_client(workers=args.workers, processes=True)
    client.wait_for_workers(args.workers)
    t_startup = time.perf_counter() - t0
    serial_times, dask_times = [], []
    try:
        for rep in range(args.repeat):   # alternated, so a burst of load elsewhere hits both alike
            t0 = time.perf_counter()
            serial = run_sweep(args.scene, sweep, fmu, tmp / f"serial{rep}",
                               SweepOptions(serial=True, progress=False, plot=False))
            serial_times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            dask = run_sweep(args.scene, sweep, fmu, tmp / f"dask{rep}",
                             SweepOptions(client=client, progress=False, plot=False))
            dask_times.append(time.perf_counter() - t0)
    finally:
        client.close()
        cluster.close()
    return serial, dask, serial_times, dask_times, t_startup


def compare_tables(serial, dask) -> dict:
    """Whether Dask's table equals the serial one in every compared column, and the cases' summed times."""
    rows_serial = {r["case_id"]: r for r in read_rows(serial.parquet)}
    rows_dask = read_rows(dask.parquet)
    compared = ["status", "los_rms_mrad", "los_peak_mrad", "los_final_mrad", "i_peak_A", "events"]
    same = len(rows_dask) == len(rows_serial) and all(
        r[k] == rows_serial[r["case_id"]][k] for r in rows_dask for k in compared)
    return {"same": same, "fmu_sha": rows_dask[0]["fmu_sha256"],
            "case_time": sum(r["wall_time_s"] for r in rows_dask), "case_cpu": sum(r["cpu_time_s"] for r in rows_dask),
            "serial_case_time": sum(r["wall_time_s"] for r in rows_serial.values())}


if __name__ == "__main__":
    sys.exit(main())
