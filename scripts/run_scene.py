#!/usr/bin/env python3
"""Run a scene file (scenes/*.toml) on the Gimbal2Axis FMU with fmpy: CSV and PNG results.

Usage: run_scene.py [scene.toml] [--fmu build/Gimbal2Axis.fmu] [--out results]
"""
import argparse
import pathlib
import sys
import time
import tomllib

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]


def load_scene(path: pathlib.Path) -> dict:
    with open(path, "rb") as f:
        scene = tomllib.load(f)
    for key in ("name", "stop_time", "step_size"):
        if key not in scene:
            raise SystemExit(f"{path}: missing required key '{key}'")
    return scene


def run(scene: dict, fmu: pathlib.Path, progress: bool = True) -> np.ndarray:
    import fmpy

    start_values = dict(scene.get("parameters", {}))
    start_values.update(scene.get("initial", {}))
    stop_time = float(scene["stop_time"])
    plot = scene.get("plot", {})
    outputs = sorted({name for names in plot.values() for name in names} |
                     {"alpha", "beta", "alpha_dot", "beta_dot", "i_R1", "i_R2", "theta_b1", "theta_b2",
                      "T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "los.omega[3]"})
    last_report = [0.0]

    def step_finished(t, recorder):
        if progress and (t - last_report[0] >= stop_time / 20 or t >= stop_time):
            last_report[0] = t
            done = min(t / stop_time, 1.0)
            bar = "#" * int(30 * done)
            print(f"\r[{bar:<30}] {100 * done:5.1f} %  t = {t:.3f} s", end="", file=sys.stderr, flush=True)
        return True

    result = fmpy.simulate_fmu(str(fmu), stop_time=stop_time, step_size=float(scene["step_size"]),
                               output_interval=float(scene.get("output_interval", scene["step_size"])),
                               start_values=start_values, output=outputs, step_finished=step_finished)
    if progress:
        print(file=sys.stderr)
    return result


def write_csv(result: np.ndarray, path: pathlib.Path) -> None:
    names = result.dtype.names
    data = np.column_stack([result[n] for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")


def plot(result: np.ndarray, scene: dict, path: pathlib.Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = scene.get("plot") or {"angles": ["alpha", "beta"]}
    units = {"angles": "deg", "rates": "deg/s", "currents": "A", "torques": "N.m", "backlash": "deg"}
    to_degrees = {"angles", "rates", "backlash"}
    fig, axes = plt.subplots(len(groups), 1, sharex=True, figsize=(9, 2.4 * len(groups)), squeeze=False)
    for ax, (group, names) in zip(axes[:, 0], groups.items()):
        for name in names:
            values = result[name] * (180 / np.pi if group in to_degrees else 1.0)
            ax.plot(result["time"], values, label=name)
        ax.set_ylabel(f"{group} [{units.get(group, '')}]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize="small")
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"{scene['name']}: {scene.get('description', '')}", fontsize="medium")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "free_swing.toml"))
    parser.add_argument("--fmu", default=str(REPO / "build" / "Gimbal2Axis.fmu"))
    parser.add_argument("--out", default=str(REPO / "results"))
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    args = parser.parse_args()

    scene = load_scene(pathlib.Path(args.scene))
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    wall_start = time.perf_counter()
    result = run(scene, pathlib.Path(args.fmu), progress=not args.quiet)
    wall = time.perf_counter() - wall_start
    csv_path, png_path = out / f"{scene['name']}.csv", out / f"{scene['name']}.png"
    write_csv(result, csv_path)
    plot(result, scene, png_path)
    stop = float(scene["stop_time"])
    print(f"{scene['name']}: simulated {stop:g} s in {wall:.3f} s wall ({stop / wall:.1f}x real time, "
          f"fmpy in the loop); final alpha = {np.degrees(result['alpha'][-1]):.4f} deg, "
          f"beta = {np.degrees(result['beta'][-1]):.4f} deg")
    print(f"wrote {csv_path} and {png_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
