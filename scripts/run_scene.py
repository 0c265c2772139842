#!/usr/bin/env python3
"""Run a scene file (scenes/*.toml) on the Gimbal2Axis FMU: an fmpy master with the controller and
its one-sample zero-order-hold delay; writes <out>/<name>.csv and <out>/<name>.png and prints a
summary line (line-of-sight error, wall time, real-time factor).

Usage: run_scene.py [scene.toml] [--fmu build/Gimbal2Axis.fmu] [--out results] [--quiet]
                    [--stop-time T] [--check]
"""
import argparse
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from scene_lib import SceneError, run_scene_file  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "free_swing.toml"))
    parser.add_argument("--fmu", default=str(REPO / "build" / "Gimbal2Axis.fmu"))
    parser.add_argument("--out", default=str(REPO / "results"))
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("--stop-time", type=float, default=None, help="end the run earlier than the scene says")
    parser.add_argument("--check", action="store_true",
                        help="exit with status 1 when the scene's [requirements] are not met")
    args = parser.parse_args()
    try:
        result, csv_path, png_path = run_scene_file(args.scene, args.fmu, args.out, progress=not args.quiet,
                                                    stop_time=args.stop_time)
    except SceneError as exc:
        print(f"run_scene.py: error: {exc}", file=sys.stderr)
        return 2
    print(result.summary())
    print(f"wrote {csv_path} and {png_path}")
    return 1 if args.check and result.requirement_failures() else 0


if __name__ == "__main__":
    sys.exit(main())
