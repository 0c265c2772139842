"""A scene file run from start to end: the run, its CSV of every recorded signal, its plots, and
<name>_run.json, which says whether the record is whole or partial (a run that failed, was
interrupted or terminated keeps what it recorded up to its last whole communication point)."""
from __future__ import annotations

import contextlib
import json
import os
import pathlib

from ..errors import SceneError
from ..fmu import FMU
from ..scene.scene import load_scene, parameter_value
from .master import run


def run_status(result, files: list[pathlib.Path]) -> dict:
    """The content of <name>_run.json: 'status' complete, failed, interrupted or terminated;
    'partial' whether the record ends before the stop time asked for; where it ends and why."""
    stopped = result.stopped
    return {"scene": result.scene.name, "status": "complete" if stopped is None else stopped.kind,
            "partial": stopped is not None, "stop_time_s": result.requested_stop_time,
            "recorded_until_s": result.stop_time, "step_size_s": result.scene.step_size,
            "reason": None if stopped is None else stopped.reason, "summary": result.summary(),
            "files": [path.name for path in files]}


@contextlib.contextmanager
def only_writer(out: pathlib.Path, name: str):
    """Holds `<out>/.<name>.run.lock` for the whole run, or refuses: two runs of one scene into one
    folder would write the same files at once and mix them (a CSV of one run, a plot of the other, a
    Parquet file of both). The lock is the operating system's (released when the process ends, however
    it ends); its empty file stays, as the sweep store's does."""
    handle = open(out / f".{name}.run.lock", "a+b")
    try:
        try:
            if os.name == "nt":
                import msvcrt
                msvcrt.locking(handle.fileno(), msvcrt.LK_NBLCK, 1)
            else:
                import fcntl
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise SceneError(f"another gimbal2axis run is writing {name}'s files into {out}: wait for it to end or "
                             f"give this one another --out (two runs into the same files would mix them)") from None
        yield
    finally:
        handle.close()


def run_scene_file(scene_path, fmu_path, out_dir, progress: bool = False, stop_time: float | None = None,
                   keep_partial: bool = False, stop=None, stream: bool = False):
    """Runs one scene file and writes <out>/<scene file's name>.csv and .png; with a target also
    <name>_psd.csv and <name>_spectrum.png (the line-of-sight error's spectrum), on a moving base
    <name>_isolation.csv (the isolation estimated from the run); with a moving target
    <name>_tracking.png (plotting.tracking_figure); and <name>_run.json (run_status).
    Returns (result, csv, png). `keep_partial`, `stop`: as master.run; a partial result is written
    the same way, over the time it covers. A derived file the run cannot make (a spectrum of fewer
    than 2 samples) is removed, not left from an earlier run.

    `stream`: the run is written as it goes (streaming.run_streamed: also <name>.parquet, memory
    bounded whatever the length; a run that stops early always keeps its partial record); else it
    is held in memory (master.run) and written at the end. A second run of the same scene into the
    same folder while this one writes is refused (only_writer)."""
    scene = load_scene(scene_path)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with only_writer(out, scene.name):
        return _run_and_write(scene, fmu_path, out, progress, stop_time, keep_partial, stop, stream)


def _run_and_write(scene, fmu_path, out: pathlib.Path, progress, stop_time, keep_partial, stop, stream):
    from .plotting import plot, plot_spectrum, plot_tracking
    from .streaming import run_streamed

    csv_path, png_path = out / f"{scene.name}.csv", out / f"{scene.name}.png"
    with FMU(fmu_path) as fmu:
        if stream:
            result = run_streamed(scene, fmu, out, progress=progress, stop_time=stop_time, stop=stop)
        else:
            result = run(scene, fmu, progress=progress, stop_time=stop_time, keep_partial=keep_partial, stop=stop)
        limits = {}
        for j in (1, 2):
            i_l, eta = parameter_value(scene, fmu, f"motor{j}.i_L"), parameter_value(scene, fmu, f"gear{j}.eta")
            if i_l is not None:
                limits[f"i_R{j}"] = float(i_l)
            if eta:
                limits[f"theta_b{j}"] = float(eta)
    written = [csv_path, out / f"{scene.name}.parquet"] if stream else [csv_path]
    if not stream:
        result.write_csv(csv_path)
        (out / f"{scene.name}.parquet").unlink(missing_ok=True)   # an earlier streamed run's: not this run
    plot(result, png_path, limits)
    written.append(png_path)
    for path, write in ((out / f"{scene.name}_psd.csv", result.write_psd_csv),
                        (out / f"{scene.name}_isolation.csv", result.write_isolation_csv),
                        (out / f"{scene.name}_spectrum.png", lambda p: plot_spectrum(result, p)),
        (out / f"{scene.name}_tracking.png",
         lambda p: plot_tracking(result, p, out / f"{scene.name}.parquet" if stream else None))):
        if write(path):
            written.append(path)
        else:
            path.unlink(missing_ok=True)
    status_path = out / f"{scene.name}_run.json"
    status_path.write_text(json.dumps(run_status(result, written), indent=1) + "\n")
    return result, csv_path, png_path
