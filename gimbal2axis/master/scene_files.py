"""A scene file run from start to end: the run, its CSV of every recorded signal, its plots, and
<name>_run.json, which says whether the record is whole or partial (a run that failed, was
interrupted or terminated keeps what it recorded up to its last whole communication point)."""
from __future__ import annotations

import contextlib
import json
import os
import pathlib

from ..errors import SceneError, StopSignal
from ..fmu import FMU
from ..scene.scene import load_scene, parameter_value
from .master import StopRequest, run
from .record_files import check_no_collision


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
    it ends). At the end the lock file is removed while still held, so no empty file stays: a run that
    locked a file since removed (it opened the path before the removal) takes the lock again on the
    file now at the path, so two runs never hold two different files. Windows cannot remove an open
    file: there the empty file stays."""
    path = out / f".{name}.run.lock"
    while True:
        handle = open(path, "a+b")
        try:
            if os.name == "nt":
                import msvcrt
                msvcrt.locking(handle.fileno(), msvcrt.LK_NBLCK, 1)
                break
            import fcntl
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            raise SceneError(f"another gimbal2axis run is writing {name}'s files into {out}: wait for it to end or "
                             f"give this one another --out (two runs into the same files would mix them)") from None
        if _same_file(handle, path):
            break
        handle.close()   # the run before removed it after this one opened it: lock the path's file
    try:
        yield
    finally:
        if os.name != "nt":
            with contextlib.suppress(OSError):
                path.unlink()
        handle.close()


def _same_file(handle, path: pathlib.Path) -> bool:
    try:
        return os.path.samestat(os.fstat(handle.fileno()), os.stat(path))
    except FileNotFoundError:
        return False


def run_scene_file(scene_path, fmu_path, out_dir, progress: bool = False, stop_time: float | None = None,
                   keep_partial: bool = False, stop=None, stream: bool = False):
    """Runs one scene file and writes <out>/<scene file's name>.csv and .png; with a target also
    <name>_psd.csv and <name>_spectrum.png (the line-of-sight error's spectrum), on a moving base
    <name>_isolation.csv (the isolation estimated from the run); with a moving target
    <name>_tracking.png (plotting.tracking_figure); and <name>_run.json (run_status).
    Returns (result, csv, png). `keep_partial`, `stop`: as master.run; a partial result is written
    the same way, over the time it covers. A derived file the run cannot make (a spectrum of fewer
    than 2 samples) is removed, not left from an earlier run; one it could not write (a full disk)
    is named in _run.json, and the record stays.

    `stream`: the run is written as it goes (streaming.run_streamed and record_files.RunRecord: also
    <name>.parquet, memory bounded whatever the length; an earlier run's files stay until this one
    has recorded its first chunk; a run that stops early, even by a signal during its plots, keeps
    its record and says so in _run.json); else it is held in memory (master.run) and written at the
    end. A second run of the same scene into the same folder while this one writes is refused
    (only_writer)."""
    scene = load_scene(scene_path)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    check_no_collision(out, scene.name)   # again when the run claims its files (RunRecord.take_over)
    with only_writer(out, scene.name):
        return _run_and_write(scene, fmu_path, out, progress, stop_time, keep_partial, stop, stream)


def _run_and_write(scene, fmu_path, out: pathlib.Path, progress, stop_time, keep_partial, stop, stream):
    from .streaming import record_for, run_streamed

    csv_path, png_path = out / f"{scene.name}.csv", out / f"{scene.name}.png"
    stop = stop or StopRequest()
    record = record_for(scene, out, stop_time, stop) if stream else None
    written = []
    try:
        with FMU(fmu_path) as fmu:
            if stream:
                result = run_streamed(scene, fmu, out, progress=progress, stop_time=stop_time, stop=stop, record=record)
            else:
                result = run(scene, fmu, progress=progress, stop_time=stop_time, keep_partial=keep_partial, stop=stop)
            limits = plot_limits(scene, fmu)
        if stream:
            written = [csv_path, record.parquet_path]
        else:
            result.write_csv(csv_path)
            (out / f"{scene.name}.parquet").unlink(missing_ok=True)   # an earlier streamed run's: not this run
            written = [csv_path]
        stop.phase = "computing the spectra and drawing the plots"
        not_written = write_derived_files(scene, result, out, limits, written, record)
    except StopSignal as signal:   # a signal while the record was being written, or the plots drawn
        stop.stepping = False
        if record is not None and record.taken_over:
            record_kept_after_signal(record, stop, written, signal)
        raise
    status = run_status(result, written)
    if not_written:
        status["not_written"] = not_written
    if record is not None:
        record.write_status(status)
    else:
        status_path = out / f"{scene.name}_run.json"
        status_path.write_text(json.dumps(run_status(result, written) | status, indent=1) + "\n")
    result.not_written, result.files_written = not_written, written + [out / f"{scene.name}_run.json"]
    return result, csv_path, png_path


def plot_limits(scene, fmu) -> dict:
    """The limits the plots draw: each motor's current limit and each gear's backlash half-gap."""
    limits = {}
    for j in (1, 2):
        i_l, eta = parameter_value(scene, fmu, f"motor{j}.i_L"), parameter_value(scene, fmu, f"gear{j}.eta")
        if i_l is not None:
            limits[f"i_R{j}"] = float(i_l)
        if eta:
            limits[f"theta_b{j}"] = float(eta)
    return limits


def write_derived_files(scene, result, out: pathlib.Path, limits: dict, written: list, record) -> dict:
    """The plots and spectra of a run, each appended to `written` when made, removed when the run has
    nothing for it; {file name: why} of those that could not be written (a full disk): the record stays
    the result, and the reason goes to _run.json."""
    from .plotting import plot, plot_spectrum, plot_tracking

    parquet = record.parquet_path if record is not None else None
    not_written = {}
    for path, write in ((out / f"{scene.name}.png", lambda p: plot(result, p, limits) or True),
                        (out / f"{scene.name}_psd.csv", result.write_psd_csv),
                        (out / f"{scene.name}_isolation.csv", result.write_isolation_csv),
                        (out / f"{scene.name}_spectrum.png", lambda p: plot_spectrum(result, p)),
                        (out / f"{scene.name}_tracking.png", lambda p: plot_tracking(result, p, parquet))):
        try:
            made = write(path)
        except OSError as exc:
            path.unlink(missing_ok=True)
            not_written[path.name] = exc.strerror or str(exc)
            continue
        if made:
            written.append(path)
        else:
            path.unlink(missing_ok=True)
    return not_written


def record_kept_after_signal(record, stop, written: list, signal: BaseException) -> None:
    """_run.json of a run a signal ended while its record or its plots were being written: the record
    as far as it goes (the chunks' folder when the merge did not finish), the files made so far."""
    if record.csv_file is not None and not record.csv_file.closed:
        record.close_without_merge()
    state = dict(record.last_state)
    during_record = state.get("status") == "running"
    state.update({"status": stop.kind or "interrupted",
                  "reason": f"{stop.reason or 'a signal'} while {stop.phase}; the record is kept as far as it goes",
                  "files": [path.name for path in written] or [record.csv_path.name, record.parquet_path.name]})
    if during_record:
        state.update({"partial": True, "recorded_until_s": record.recorded_until})
    record.write_status(state)
