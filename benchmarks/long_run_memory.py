#!/usr/bin/env python3
"""Peak memory and wall time of `gimbal2axis run` against the run's length (issue 33): the ship scene
(scenes/ship_stabilization.toml) at 1 ms for 60 s, 20 min and 1 h by default, each run as a child
process whose peak resident set size is read from the kernel's accounting of its children
(resource.getrusage(RUSAGE_CHILDREN).ru_maxrss: the largest child so far, so one child per
measurement, started from a fresh parent), and the size of what it wrote (CSV, Parquet, plots).

Not run in CI: an hour of simulated time takes about a minute per length on 2 cores.

Writes benchmarks/results/long_run_memory.json and prints one line per length.

Usage: .venv/bin/python benchmarks/long_run_memory.py [--lengths 60 1200 3600] [--fmu FMU] [--out FILE]
"""
import argparse
import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[1]

# Started per length: a fresh interpreter, so RUSAGE_CHILDREN's maximum is this run's alone.
MEASURE = r"""
import json, resource, subprocess, sys, time
start = time.perf_counter()
done = subprocess.run(sys.argv[1:], capture_output=True, text=True)
wall = time.perf_counter() - start
print(json.dumps({"returncode": done.returncode, "wall_s": wall, "stdout": done.stdout, "stderr": done.stderr,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024}))
"""


def scene_with_stop_time(scene: pathlib.Path, stop_time: float, folder: pathlib.Path) -> pathlib.Path:
    """A copy of `scene` with its stop_time (the command's --stop-time would do the same; a file
    states the run in the results)."""
    lines = []
    for line in scene.read_text().splitlines():
        lines.append(f"stop_time = {stop_time!r}" if line.startswith("stop_time = ") else line)
    path = folder / scene.name
    path.write_text("\n".join(lines) + "\n")
    return path


def measure(scene: pathlib.Path, fmu: str, length: float, folder: pathlib.Path) -> dict:
    out = folder / f"out_{length:g}"
    command = [sys.executable, "-m", "gimbal2axis", "run", str(scene_with_stop_time(scene, length, folder)),
               "--fmu", fmu, "--out", str(out)]   # not --quiet: its summary line is recorded
    # run from the temporary folder: `python -m` puts the current directory first on the path, and the
    # repository's root would shadow a PYTHONPATH that points at another version of the package
    child = subprocess.run([sys.executable, "-c", MEASURE, *command], capture_output=True, text=True, check=True,
                           cwd=folder)
    record = json.loads(child.stdout)
    if record["returncode"] != 0:
        raise SystemExit(f"gimbal2axis run of {length:g} s failed ({record['returncode']}): {record['stderr'].strip()}")
    sizes = {path.name: path.stat().st_size for path in sorted(out.iterdir())}
    return {"simulated_s": length, "wall_s": round(record["wall_s"], 2), "peak_rss_mb": round(record["peak_rss_mb"], 1),
            "csv_mb": round(sum(v for k, v in sizes.items() if k.endswith(".csv")) / 1e6, 1),
            "parquet_mb": round(sum(v for k, v in sizes.items() if k.endswith(".parquet")) / 1e6, 1),
            "files": sizes, "summary": record["stdout"].splitlines()[0]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lengths", type=float, nargs="+", default=[60.0, 1200.0, 3600.0], help="simulated seconds")
    parser.add_argument("--scene", default=str(REPO / "scenes" / "ship_stabilization.toml"))
    parser.add_argument("--fmu", default=os.environ.get("GIMBAL2AXIS_FMU", str(REPO / "build" / "Gimbal2Axis.fmu")))
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "long_run_memory.json"))
    args = parser.parse_args()
    results = []
    with tempfile.TemporaryDirectory(prefix="gimbal_long_run_") as folder:
        for length in args.lengths:
            row = measure(pathlib.Path(args.scene), args.fmu, length, pathlib.Path(folder))
            results.append(row)
            print(f"{length:8g} s simulated: {row['wall_s']:7.2f} s wall, peak RSS {row['peak_rss_mb']:6.1f} MB, "
                  f"CSV {row['csv_mb']:.1f} MB, Parquet {row['parquet_mb']:.1f} MB", flush=True)
    report = {"date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "machine": platform.machine(),
              "cpus": os.cpu_count(), "python": platform.python_version(), "scene": args.scene, "results": results}
    pathlib.Path(args.out).write_text(json.dumps(report, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
