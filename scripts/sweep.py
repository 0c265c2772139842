#!/usr/bin/env python3
"""Run a parameter sweep / Monte Carlo of a scene on Dask: every case of SWEEP.toml (grid and/or
seeded random sampling) applied to SCENE.toml, in parallel on a local cluster (processes, one
thread each) or on an existing Dask scheduler; each worker extracts the FMU once and reuses its
instance (fmi2Reset). Writes <out>/<sweep>__<scene>.parquet and .csv (one row per case:
parameters, seeds, metrics, status, FMU log of failures) and .png (each metric against each swept
parameter). A rerun skips the cases already in the table.

Usage: sweep.py SCENE.toml SWEEP.toml [--scheduler ADDRESS] [--workers N] [--out DIR] [--quiet]
                [--fmu build/Gimbal2Axis.fmu] [--serial] [--threads] [--redo failed|all]
"""
import argparse
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from scene_lib import SceneError  # noqa: E402
from sweep_lib import SweepError, run_sweep  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", help="scene file (scenes/*.toml)")
    parser.add_argument("sweep", help="sweep description (sweeps/*.toml)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="an existing Dask scheduler (e.g. tcp://10.0.0.5:8786); default: a local cluster")
    parser.add_argument("--workers", type=int, default=2, help="workers of the local cluster (default 2)")
    parser.add_argument("--out", default=str(REPO / "results" / "sweeps"), help="output directory")
    parser.add_argument("--fmu", default=str(REPO / "build" / "Gimbal2Axis.fmu"))
    parser.add_argument("--quiet", action="store_true", help="no progress counter")
    parser.add_argument("--serial", action="store_true", help="no Dask: run the cases one after the other here")
    parser.add_argument("--threads", action="store_true",
                        help="local cluster of threads in this process instead of worker processes")
    parser.add_argument("--redo", choices=["failed", "all"], default=None,
                        help="rerun the failed cases (or all) even though they are in the table")
    args = parser.parse_args()
    if args.workers < 1:
        parser.error("--workers must be >= 1")
    try:
        outcome = run_sweep(args.scene, args.sweep, args.fmu, args.out, scheduler=args.scheduler,
                            workers=args.workers, serial=args.serial, progress=not args.quiet, redo=args.redo,
                            processes=not args.threads)
    except (SceneError, SweepError) as exc:
        print(f"sweep.py: error: {exc}", file=sys.stderr)
        return 2
    total = outcome.ran + outcome.skipped
    print(f"{total} cases ({outcome.ran} run, {outcome.skipped} already done): {total - outcome.failed} ok, "
          f"{outcome.failed} failed; {outcome.wall_time:.1f} s")
    if outcome.failed:
        failed = [r for r in outcome.rows if r.get("status") != "ok"][:3]
        for r in failed:
            print(f"  failed case {r['case']} ({r['case_id']}): {r['message'].splitlines()[0][:200]}")
    print(f"wrote {outcome.parquet}, {outcome.csv} and {outcome.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
