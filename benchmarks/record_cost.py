#!/usr/bin/env python3
"""What the crash-safe run record costs (issue 44's record_files.py): the ship scene
(scenes/ship_stabilization.toml, 1 ms) run twice, each in a fresh child process:

- in memory: gimbal2axis.master.run, the record held as arrays and written nowhere;
- to disk: gimbal2axis.master.streaming.run_streamed, as `gimbal2axis run` records (Parquet chunk
  files, the CSV by whole rows, _run.json after each chunk, the chunks merged into one Parquet file
  at the end), with the record's own methods timed inside that run.

Reported per run: CPU time (user + sys of the child, getrusage) and peak resident set size; for the
run to disk also the CPU time inside the record, by part: the chunks' Parquet files, the CSV's rows
(picked and formatted), the _run.json updates, and the end (the CSV's last row, the chunks merged
into one file). The runs to disk do more than record (the chunks' metrics, the plots'
decimation, the spectra read back from the file); the timed parts are the record alone.

Usage: .venv/bin/python benchmarks/record_cost.py [--seconds 600] [--fmu FMU] [--out FILE]
Writes benchmarks/results/record_cost.json.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile

from gimbal2axis.locations import fmu_path

REPO = pathlib.Path(__file__).resolve().parents[1]
SCENE = REPO / "scenes" / "ship_stabilization.toml"

# Run in a fresh interpreter per mode, so its peak RSS and CPU time are that run's alone. argv: mode,
# scene, fmu, seconds, output folder. Prints one JSON line.
CHILD = r"""
import json, pathlib, resource, sys, time
from gimbal2axis import FMU, load_scene
from gimbal2axis.master import run
from gimbal2axis.master.record_files import RunRecord
from gimbal2axis.master.streaming import record_for, run_streamed

mode, scene_path, fmu_path, seconds, out = sys.argv[1:6]
seconds, out = float(seconds), pathlib.Path(out)
spent = {"parquet_chunk_files": 0.0, "csv_rows": 0.0, "run_json": 0.0, "merge_and_end": 0.0}
inside = []   # the record's methods being timed, outermost first

def timed(method, part):
    def wrapper(self, *args, **kwargs):
        inside.append(part)
        start = time.process_time()
        try:
            return method(self, *args, **kwargs)
        finally:
            inside.pop()
            elapsed = time.process_time() - start
            spent[part] += elapsed
            if inside and inside[-1] == "csv_rows":   # append's own share is the CSV's: take the nested part out
                spent["csv_rows"] -= elapsed
    return wrapper

class TimedRecord(RunRecord):
    append = timed(RunRecord.append, "csv_rows")   # a chunk: its Parquet file, its CSV rows, _run.json
    write_chunk = timed(RunRecord.write_chunk, "parquet_chunk_files")
    write_status = timed(RunRecord.write_status, "run_json")
    close = timed(RunRecord.close, "merge_and_end")   # the CSV's last row, the merge into one file

import pyarrow.parquet, scipy.signal   # imported before the clock starts, for both runs alike
scene = load_scene(scene_path)
with FMU(fmu_path) as fmu:
    start = resource.getrusage(resource.RUSAGE_SELF)
    if mode == "memory":
        result = run(scene, fmu, stop_time=seconds)
    else:
        plain = record_for(scene, out, seconds, None)
        record = TimedRecord(plain.out, plain.name, plain.every, plain.base_status, None)
        result = run_streamed(scene, fmu, out, stop_time=seconds, record=record)
    end = resource.getrusage(resource.RUSAGE_SELF)
user, system = end.ru_utime - start.ru_utime, end.ru_stime - start.ru_stime
print(json.dumps({"cpu_s": user + system, "user_s": user, "sys_s": system,
                  "peak_rss_mb": end.ru_maxrss / 1024,
                  "record_parts_cpu_s": spent if mode == "disk" else None}))
"""


def measure(mode: str, fmu: str, seconds: float, folder: pathlib.Path) -> dict:
    (folder / mode).mkdir()
    # from the temporary folder: `python -c` puts the current directory first on the path
    child = subprocess.run([sys.executable, "-c", CHILD, mode, str(SCENE), fmu, repr(seconds), str(folder / mode)],
                           capture_output=True, text=True, cwd=folder)
    if child.returncode != 0:
        raise SystemExit(f"the run {mode} failed ({child.returncode}): {child.stderr.strip()[-2000:]}")
    row = json.loads(child.stdout.strip().splitlines()[-1])
    if mode == "disk":
        row["files_mb"] = round(sum(p.stat().st_size for p in (folder / mode).rglob("*") if p.is_file()) / 1e6, 1)
    return row


def rounded(value):
    if isinstance(value, dict):
        return {key: rounded(v) for key, v in value.items()}
    return round(value, 3) if isinstance(value, float) else value


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=600.0, help="simulated seconds (default 600)")
    parser.add_argument("--fmu", help="the FMU (default: $GIMBAL2AXIS_FMU, else the configured build's)")
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "record_cost.json"))
    args = parser.parse_args(argv)
    fmu = str(fmu_path(args.fmu))
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="gimbal_record_cost_") as folder:
        runs = {mode: rounded(measure(mode, fmu, args.seconds, pathlib.Path(folder))) for mode in ("memory", "disk")}
    record_cpu = sum(runs["disk"]["record_parts_cpu_s"].values())
    report = {"benchmark": "record_cost", "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
              "machine": platform.machine(), "cpus": os.cpu_count(), "python": platform.python_version(),
              "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)], "scene": "scenes/ship_stabilization.toml", "simulated_s": args.seconds, "runs": runs,
              "record_cpu_s": round(record_cpu, 3),
              "record_share_of_disk_run": round(record_cpu / runs["disk"]["cpu_s"], 4),
              "disk_over_memory_cpu": round(runs["disk"]["cpu_s"] / runs["memory"]["cpu_s"], 4)}
    pathlib.Path(args.out).write_text(json.dumps(report, indent=1) + "\n")
    for mode, row in runs.items():
        print(f"{mode:6s}: CPU {row['cpu_s']:.2f} s, peak RSS {row['peak_rss_mb']:.0f} MB")
    print(f"the record: {record_cpu:.2f} s CPU, {100 * report['record_share_of_disk_run']:.1f} % of the run to disk "
          f"({', '.join(f'{k} {v:.2f} s' for k, v in runs['disk']['record_parts_cpu_s'].items())}); wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
