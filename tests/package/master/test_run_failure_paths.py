"""Nothing lost on any failure path of `gimbal2axis run` (issue 44, items 1-6, 9, 13): a refused run
leaves an earlier run's record and its _run.json as they were; a full disk ends the record on a whole
chunk and a whole CSV row, exit 3; repeated signals keep the record (130, 143); a controller that
calls sys.exit or raises a BaseException fails the run (3) and keeps the record; a killed run leaves
every chunk it finished readable and a _run.json that says "running"; a scene name cannot make its
record another scene's derived file; a signal in any phase stops the run and keeps the record; the
summary's wall time is the run's whole."""
import hashlib
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pyarrow.parquet as pq
import pytest

from gimbal2axis.cli.main import main

from support.scenes import cheap_scene

pytestmark = pytest.mark.python_bound

RUN = [sys.executable, "-m", "gimbal2axis", "run"]

# A cheap gimbal on a fixed base (support.scenes), open loop or a user controller: these tests need the
# run's length and its files, not its physics.
OPEN_LOOP = """[controller]
type = "none"
voltage_V = [0.2, -0.1]
"""
USER = """[controller]
type = "python"
file = "user.py"
class = "{cls}"
"""
CONTROLLERS = '''
import os, sys, time


class Steady:
    def reset(self, context):
        pass

    def step(self, t, m):
        return (0.1, -0.1)


class ResetRaises(Steady):
    def reset(self, context):
        raise RuntimeError("no reset today")


class ExitsLater(Steady):
    def step(self, t, m):
        if t >= 0.05:
            sys.exit(0)
        return (0.1, -0.1)


class InterruptsItselfLater(Steady):
    def step(self, t, m):
        if t >= 0.05:
            raise KeyboardInterrupt
        return (0.1, -0.1)


class Doom(BaseException):
    pass


class RaisesBaseExceptionLater(Steady):
    def step(self, t, m):
        if t >= 0.05:
            raise Doom("the end of the world")
        return (0.1, -0.1)


class HangsLater(Steady):
    def step(self, t, m):
        if t >= 20.0:
            while True:   # deaf to a request to stop: only a raised signal gets out
                time.sleep(0.01)
        return (0.1, -0.1)


class WaitsForGoLater(Steady):
    """Holds the run at t = 20 s (after its first chunk) until the file named by $GIMBAL_TEST_GO exists."""
    def step(self, t, m):
        if t >= 20.0:
            while not os.path.exists(os.environ["GIMBAL_TEST_GO"]):
                time.sleep(0.01)
        return (0.1, -0.1)
'''


def scene(folder: pathlib.Path, name: str = "cheap", stop_time: float = 0.2, controller: str | None = None,
          extra: str = "") -> pathlib.Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "user.py").write_text(CONTROLLERS)
    path = folder / f"{name}.toml"
    path.write_text(cheap_scene(stop_time) + (USER.format(cls=controller) if controller else OPEN_LOOP)
                    + extra)
    return path


def digests(out: pathlib.Path) -> dict:
    """Every file in `out` (a folder of chunks as its files) by name, with its content's digest."""
    found = {}
    for path in sorted(out.rglob("*")):
        if path.is_file() and not path.name.endswith(".lock"):
            found[str(path.relative_to(out))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


def run_in_process(capsys, *args) -> tuple[int, str]:
    status = main(["run", *map(str, args), "--quiet"])
    return status, capsys.readouterr().err


def status_of(out: pathlib.Path, name: str = "cheap") -> dict:
    return json.loads((out / f"{name}_run.json").read_text())


def record_times(out: pathlib.Path, name: str = "cheap") -> np.ndarray:
    """The record's time column, read as a user reads it: one path, a file or a folder of chunks."""
    return pq.read_table(out / f"{name}.parquet", columns=["time"]).column("time").to_numpy()


def csv_rows(out: pathlib.Path, name: str = "cheap") -> list[list[str]]:
    data = (out / f"{name}.csv").read_bytes()
    assert data.endswith(b"\n"), "the CSV ends in the middle of a row"
    rows = [line.split(",") for line in data.decode().splitlines()]
    assert len({len(row) for row in rows}) == 1, "a CSV row has fewer fields than the header"
    return rows


def assert_consistent(out: pathlib.Path, status: dict, name: str = "cheap") -> float:
    """_run.json, the Parquet record and the CSV end at the same point, every step there once."""
    t = record_times(out, name)
    assert np.array_equal(t, np.arange(len(t)) * 0.001)
    end = status["recorded_until_s"]
    assert t[-1] == pytest.approx(end, abs=1e-12)
    assert float(csv_rows(out, name)[-1][0]) == pytest.approx(end, abs=1e-9)
    return end


# --- item 1: a refused run leaves the earlier record as it was --------------------------------------

@pytest.mark.parametrize("refusal, extra, controller", [
    ("a parameter the FMU refuses", '[parameters]\n"motor1.R" = -1.0\n', None),
    ("a controller whose reset raises", "", "ResetRaises"),
])
def test_a_refused_run_leaves_the_earlier_record_as_it_was(tmp_path, capsys, refusal, extra, controller):
    out = tmp_path / "out"
    status, err = run_in_process(capsys, scene(tmp_path / "a"), "--out", out)
    assert status == 0, err
    before = digests(out)
    assert status_of(out)["status"] == "complete" and {"cheap.csv", "cheap.png", "cheap_run.json"} <= set(before)
    status, err = run_in_process(capsys, scene(tmp_path / "b", extra=extra, controller=controller), "--out", out)
    assert status == 2, (refusal, err)
    assert digests(out) == before, f"{refusal}: the refused run changed the earlier record"
    assert status_of(out)["status"] == "complete"


# --- item 2: a full disk ---------------------------------------------------------------------------

@pytest.fixture
def small_disk(tmp_path):
    """A 48 MB file system of its own (tmpfs), where a test can fill the disk; skipped where mounting
    is not allowed (the project's CI runs as root and may)."""
    mount = tmp_path / "disk"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=48m", "tmpfs", str(mount)], capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    yield mount
    subprocess.run(["umount", "-l", str(mount)], check=False)


def wait_for(predicate, process, what: str, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert process.poll() is None, (what, process.communicate())
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def first_chunk_written(out: pathlib.Path, name: str = "cheap") -> bool:
    """Whether the run's _run.json says a chunk is written whole (part, CSV rows and status)."""
    try:
        return status_of(out, name).get("recorded_until_s") is not None
    except (OSError, ValueError):
        return False


def chunks(out: pathlib.Path, name: str = "cheap") -> list[pathlib.Path]:
    folder = out / f"{name}.parquet"
    return sorted(folder.glob("part-*.parquet")) if folder.is_dir() else []


def test_a_full_disk_ends_the_record_on_a_whole_chunk_and_row(tmp_path, small_disk):
    out = small_disk / "out"
    go = tmp_path / "go"
    path = scene(tmp_path / "s", stop_time=30.0, controller="WaitsForGoLater")
    process = subprocess.Popen([*RUN, str(path), "--out", str(out), "--quiet"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env={**os.environ, "GIMBAL_TEST_GO": str(go)})
    try:
        wait_for(lambda: first_chunk_written(out), process, "the first chunk")
        free = os.statvfs(small_disk).f_bavail * os.statvfs(small_disk).f_frsize
        with open(small_disk / "filler", "wb") as filler:   # the disk fills up under the run
            filler.write(b"\0" * free)
            filler.flush()
        go.touch()
        stdout, stderr = process.communicate(timeout=300)
    finally:
        process.kill()
    assert process.returncode == 3, stderr
    assert "Traceback" not in stderr and len(stderr.strip().splitlines()) == 1, stderr
    assert "writing the record failed" in stderr and "No space left on device" in stderr, stderr
    status = status_of(out)
    assert status["status"] == "failed" and status["partial"] is True, status
    end = assert_consistent(out, status)
    assert 16.0 < end < 30.0   # the first chunk (16,384 points) is there, the run is not


# --- item 3 and 9: signals, repeated or in any phase ----------------------------------------------

@pytest.mark.parametrize("signum, kind, code", [(signal.SIGINT, "interrupted", 130),
                                                (signal.SIGTERM, "terminated", 143)])
def test_a_repeated_signal_keeps_the_record(tmp_path, signum, kind, code):
    """The second signal raises inside a controller deaf to the first: the record stays."""
    out = tmp_path / "out"
    path = scene(tmp_path / "s", stop_time=600.0, controller="HangsLater")
    process = subprocess.Popen([*RUN, str(path), "--out", str(out), "--quiet"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: len(chunks(out)) >= 1, process, "the first chunk")
        time.sleep(0.5)   # into the hanging step
        process.send_signal(signum)
        time.sleep(0.3)
        assert process.poll() is None, "the first signal should only ask the run to end at its next step"
        process.send_signal(signum)
        stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == code, stderr
    assert "Traceback" not in stderr and "raised" not in stderr, stderr
    status = status_of(out)
    assert status["status"] == kind and status["partial"] is True, status
    end = assert_consistent(out, status)
    assert end >= 16.0


def test_a_signal_while_the_plots_are_drawn_ends_the_run_and_keeps_the_record(tmp_path, capsys, monkeypatch):
    from gimbal2axis.master import plotting

    def plot_until_interrupted(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(30)   # the signal must end this at once
        raise AssertionError("the signal did not stop the plots")

    monkeypatch.setattr(plotting, "plot", plot_until_interrupted)
    out = tmp_path / "out"
    started = time.monotonic()
    status, err = run_in_process(capsys, scene(tmp_path / "s", stop_time=0.3), "--out", out)
    assert status == 130 and time.monotonic() - started < 20, err
    assert len(err.strip().splitlines()) == 1 and "record is kept" in err, err
    run_status = status_of(out)
    assert run_status["status"] == "interrupted" and run_status["partial"] is False, run_status
    assert "cheap.png" not in run_status["files"] and not (out / "cheap.png").exists()
    assert assert_consistent(out, run_status) == pytest.approx(0.3)


def test_a_signal_while_the_chunks_are_merged_keeps_the_folder_as_the_record(tmp_path, capsys, monkeypatch):
    from gimbal2axis.master import record_files

    real = record_files.record_tables

    def tables_until_interrupted(path, columns=None):
        for number, table in enumerate(real(path, columns)):
            if number == 1:
                os.kill(os.getpid(), signal.SIGTERM)
            yield table

    monkeypatch.setattr(record_files, "record_tables", tables_until_interrupted)
    out = tmp_path / "out"
    status, err = run_in_process(capsys, scene(tmp_path / "s", stop_time=40.0), "--out", out)
    assert status == 143, err
    run_status = status_of(out)
    assert run_status["status"] == "terminated" and run_status["parquet_layout"] == "folder", run_status
    assert len(chunks(out)) == 3 and not list(out.glob(".cheap.parquet.*"))
    assert assert_consistent(out, run_status) == pytest.approx(40.0)


# --- item 4: a controller cannot end the run silently or take the record with it ------------------

@pytest.mark.parametrize("controller, raised", [("ExitsLater", "SystemExit"),
                                                ("InterruptsItselfLater", "KeyboardInterrupt"),
                                                ("RaisesBaseExceptionLater", "Doom")])
def test_a_controller_that_exits_or_raises_a_base_exception_fails_the_run_and_keeps_the_record(
        tmp_path, capsys, controller, raised):
    out = tmp_path / "out"
    status, err = run_in_process(capsys, scene(tmp_path / "s", controller=controller), "--out", out)
    assert status == 3, err
    assert f"step() raised {raised}" in err and "user.py" in err and controller in err, err
    run_status = status_of(out)
    assert run_status["status"] == "failed" and run_status["partial"] is True
    assert assert_consistent(out, run_status) == pytest.approx(0.049, abs=1e-9)


# --- item 5: a killed run leaves readable chunks and says it was running --------------------------

def test_a_killed_run_leaves_its_chunks_readable_and_says_it_was_running(tmp_path, capsys):
    out = tmp_path / "out"
    status, err = run_in_process(capsys, scene(tmp_path / "a"), "--out", out)   # an earlier, complete run
    assert status == 0, err
    path = scene(tmp_path / "s", stop_time=600.0, controller="Steady")
    process = subprocess.Popen([*RUN, str(path), "--out", str(out), "--quiet"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: len(chunks(out)) >= 2, process, "two chunks")
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=60)
    finally:
        process.kill()
    run_status = status_of(out)
    assert run_status["status"] == "running" and run_status["pid"] == process.pid, run_status
    assert not (out / "cheap.png").exists(), "the earlier run's plot beside the new run's record"
    t = record_times(out)
    assert np.array_equal(t, np.arange(len(t)) * 0.001) and t[-1] >= run_status["recorded_until_s"] >= 16.383
    csv_rows(out)
    # The killed run's folder of chunks is no obstacle: the next run of the scene replaces it.
    status, err = run_in_process(capsys, scene(tmp_path / "s"), "--out", out)
    assert status == 0, err
    assert (out / "cheap.parquet").is_file() and status_of(out)["status"] == "complete"


def test_a_second_run_of_a_scene_while_the_first_writes_is_refused_by_name(tmp_path, capsys):
    out = tmp_path / "out"
    path = scene(tmp_path / "s", stop_time=600.0, controller="Steady")
    process = subprocess.Popen([*RUN, str(path), "--out", str(out), "--quiet"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: len(chunks(out)) >= 1, process, "a chunk")
        status, err = run_in_process(capsys, scene(tmp_path / "s"), "--out", out)
        assert status == 2 and "another gimbal2axis run is writing cheap's files" in err, err
        assert process.poll() is None and len(chunks(out)) >= 1, "the first run was disturbed"
    finally:
        process.kill()
        process.wait(timeout=60)


def test_a_folder_of_the_records_name_that_is_not_a_record_is_refused_and_kept(tmp_path, capsys):
    out = tmp_path / "out"
    (out / "cheap.parquet").mkdir(parents=True)
    (out / "cheap.parquet" / "notes.txt").write_text("the user's\n")
    status, err = run_in_process(capsys, scene(tmp_path / "s"), "--out", out)
    assert status == 2 and "cheap.parquet: it is a directory" in err, err
    assert (out / "cheap.parquet" / "notes.txt").read_text() == "the user's\n"


# --- item 6: derived files never collide with a record --------------------------------------------

TARGET = """[target]
azimuth_deg = 10.0
elevation_deg = 5.0
"""


@pytest.mark.parametrize("suffix", ["_psd", "_spectrum"])
@pytest.mark.parametrize("first", ["derived", "record"])
def test_a_scene_never_writes_another_scenes_file(tmp_path, capsys, suffix, first):
    """Scene `cheap` writes cheap_psd.csv and cheap_spectrum.png, the record and plot of scenes
    `cheap_psd` and `cheap_spectrum`: whichever runs second into the folder is refused, and the first's
    files stay as they were."""
    out = tmp_path / "out"
    runs = {"derived": scene(tmp_path / "a", extra=TARGET), "record": scene(tmp_path / "b", name=f"cheap{suffix}")}
    second = "record" if first == "derived" else "derived"
    status, err = run_in_process(capsys, runs[first], "--out", out)
    assert status == 0, err
    before = digests(out)
    status, err = run_in_process(capsys, runs[second], "--out", out)
    assert status == 2 and "another --out" in err, err
    assert digests(out) == before


def test_a_scene_whose_name_ends_like_a_derived_file_runs_alone(tmp_path, capsys):
    out = tmp_path / "out"
    status, err = run_in_process(capsys, scene(tmp_path / "s", name="cheap_tracking"), "--out", out)
    assert status == 0, err


# --- item 13: the wall time is the run's whole ----------------------------------------------------

def test_the_summary_wall_time_includes_writing_the_record(tmp_path, capsys, monkeypatch):
    from gimbal2axis.master import record_files

    real = record_files.RunRecord.append

    def slow_append(self, *args, **kwargs):
        time.sleep(0.5)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(record_files.RunRecord, "append", slow_append)
    out = tmp_path / "out"
    assert main(["run", str(scene(tmp_path / "s", stop_time=40.0)), "--out", str(out)]) == 0
    summary = capsys.readouterr().out.splitlines()[0]
    wall = float(summary.split(" s simulated in ")[1].split(" s wall")[0])
    assert wall >= 1.5, summary   # three chunks written at 0.5 s each
