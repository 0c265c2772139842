"""A scene file run from start to end: the run, its CSV of every recorded signal and its plots."""
from __future__ import annotations

import pathlib

from ..fmu import FMU
from ..scene.scene import load_scene, parameter_value
from .master import run


def run_scene_file(scene_path, fmu_path, out_dir, progress: bool = False, stop_time: float | None = None):
    """Runs one scene file and writes <out>/<scene file's name>.csv and .png; returns (result, csv, png)."""
    from .plotting import plot

    scene = load_scene(scene_path)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with FMU(fmu_path) as fmu:
        result = run(scene, fmu, progress=progress, stop_time=stop_time)
        limits = {}
        for j in (1, 2):
            i_l, eta = parameter_value(scene, fmu, f"motor{j}.i_L"), parameter_value(scene, fmu, f"gear{j}.eta")
            if i_l is not None:
                limits[f"i_R{j}"] = float(i_l)
            if eta:
                limits[f"theta_b{j}"] = float(eta)
    csv_path, png_path = out / f"{scene.name}.csv", out / f"{scene.name}.png"
    result.write_csv(csv_path)
    plot(result, png_path, limits)
    return result, csv_path, png_path
