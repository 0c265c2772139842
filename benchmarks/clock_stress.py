"""Stress of the communication-point rule (fmu_src/common/communication_point.h), not run in CI:
1e7 communication steps of the gimbal FMU under each master clock (t0 + k h, running sum, Kahan sum,
integer nanoseconds), at h = 1e-3 and 1e-4 s, from start times 0 and 1.7e9 s (a Unix-epoch clock),
through the FMI 2.0 and the FMI 3.0 binaries, each run in its own process (build/benchmarks/clock_stress)
with its resident set size sampled every 2^20 steps. Prints a table and writes
benchmarks/results/clock_stress.json; docs/reliability.md quotes it.

    .venv/bin/python benchmarks/clock_stress.py [--build-dir build] [--steps 10000000] [--jobs 2]
"""
from __future__ import annotations

import argparse
import concurrent.futures
import itertools
import json
import pathlib
import subprocess
import sys
import time
import zipfile

from fmpy import read_model_description

REPO = pathlib.Path(__file__).resolve().parents[1]
CLOCKS = ["kh", "sum", "kahan", "ns"]
STEPS = [1e-3, 1e-4]
STARTS = [0.0, 1.7e9]


def binary_and_token(build: pathlib.Path, fmi: str) -> tuple[pathlib.Path, str, int]:
    fmu = build / ("Gimbal2Axis.fmu" if fmi == "fmi2" else "Gimbal2Axis-fmi3.fmu")
    md = read_model_description(str(fmu))
    token = md.guid if fmi == "fmi2" else md.instantiationToken
    fixed_base = next(v.valueReference for v in md.modelVariables if v.name == "base.fixed")
    target = build / "clock_stress_binaries" / fmi
    with zipfile.ZipFile(fmu) as archive:
        archive.extract("binaries/x86_64-linux/Gimbal2Axis.so" if fmi == "fmi3" else "binaries/linux64/Gimbal2Axis.so",
                        target)
    return next(target.rglob("Gimbal2Axis.so")), token, fixed_base


def run_one(driver: pathlib.Path, fmi: str, binary: pathlib.Path, token: str, fixed_base: int, clock: str,
            start: float, step: float, steps: int) -> dict:
    began = time.perf_counter()
    completed = subprocess.run([str(driver), fmi, str(binary), token, str(fixed_base), clock, repr(start), repr(step),
                                str(steps)], capture_output=True, text=True)
    if completed.returncode not in (0, 1):
        raise RuntimeError(f"clock_stress {fmi} {clock} {start} {step}: {completed.stderr.strip()}")
    result = json.loads(completed.stdout)
    result.update(fmi=fmi, clock=clock, start=start, step_size=step, requested_steps=steps,
                  wall_s=time.perf_counter() - began, time_follows_master=result["reported_time"] == result["master_end"])
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build-dir", default=str(REPO / "build"))
    parser.add_argument("--steps", type=int, default=10_000_000)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "clock_stress.json"))
    args = parser.parse_args()
    build = pathlib.Path(args.build_dir).resolve()
    driver = build / "benchmarks" / "clock_stress"
    if not driver.is_file():
        print(f"clock_stress.py: error: {driver} is missing (cmake --build {build} --target clock_stress)",
              file=sys.stderr)
        return 2
    binaries = {fmi: binary_and_token(build, fmi) for fmi in ("fmi2", "fmi3")}
    cases = list(itertools.product(binaries, CLOCKS, STEPS, STARTS))
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(lambda c: run_one(driver, c[0], *binaries[c[0]], c[1], c[3], c[2], args.steps), cases))
    print(f"{'FMI':5} {'clock':6} {'h [s]':>7} {'start [s]':>10} {'steps':>10} {'refused':>8} {'time = master':>14} "
          f"{'peak RSS [MiB]':>15} {'RSS first/last [MiB]':>21} {'wall [s]':>9}")
    for r in results:
        first, last = r["rss_kib"][0] / 1024, r["rss_kib"][-1] / 1024
        print(f"{r['fmi']:5} {r['clock']:6} {r['step_size']:7g} {r['start']:10g} {r['steps']:10d} "
              f"{'yes' if r['refused'] else 'no':>8} {'yes' if r['time_follows_master'] else 'NO':>14} "
              f"{r['peak_rss_kib'] / 1024:15.1f} {first:10.1f}/{last:<10.1f} {r['wall_s']:9.1f}")
        if r["refused"]:
            print(f"      refused at t = {r['point']!r}: {r['message']}")
    pathlib.Path(args.out).write_text(json.dumps({"steps": args.steps, "runs": results}, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 1 if any(r["refused"] or not r["time_follows_master"] for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
