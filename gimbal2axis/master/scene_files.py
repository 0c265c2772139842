"""A scene file run from start to end: the run, its CSV of every recorded signal and its plots."""
from __future__ import annotations

import pathlib

from ..fmu import FMU
from ..scene.scene import load_scene, parameter_value
from .master import run


def run_scene_file(scene_path, fmu_path, out_dir, progress: bool = False, stop_time: float | None = None):
    """Runs one scene file and writes <out>/<scene file's name>.csv and .png; with a target also
    <name>_psd.csv and <name>_spectrum.png (the line-of-sight error's spectrum), on a moving base
    <name>_isolation.csv (the isolation estimated from the run); returns (result, csv, png)."""
    from .plotting import plot, plot_spectrum

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
    result.write_psd_csv(out / f"{scene.name}_psd.csv")
    result.write_isolation_csv(out / f"{scene.name}_isolation.csv")
    plot_spectrum(result, out / f"{scene.name}_spectrum.png")
    return result, csv_path, png_path
