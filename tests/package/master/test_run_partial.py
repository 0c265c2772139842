"""Nothing lost, everything said (issue 33): a `gimbal2axis run` that fails part-way, is interrupted
(SIGINT) or terminated (SIGTERM) keeps what it recorded up to its last whole communication point,
marked partial (<scene>_run.json, the Parquet file's metadata, the summary line), with a one-line
message of where and why and its own exit status (3, 130, 143); a run too long for the disk is
refused before it starts (exit 2, one line); --stop-time lengthens a run as well as shortens it;
runs go past the times the FMU's old communication-point rule refused (349.36 s at 1 ms, 38.0021 s
at 0.1 ms)."""
import csv
import json
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pyarrow.parquet as pq
import pytest

from gimbal2axis import FMU, load_scene, run
from gimbal2axis.cli.failures import EXIT_FAILED_PARTIAL, EXIT_INTERRUPTED, EXIT_TERMINATED
from gimbal2axis.master.units import split_label

from support import scenes

pytestmark = pytest.mark.python_bound

RUN = [sys.executable, "-m", "gimbal2axis", "run"]

# A cheap gimbal on a fixed base (support.scenes) with an open loop: what these tests need of the run is
# its length and its clock, not its physics.
OPEN_LOOP = """[controller]
type = "none"
voltage_V = [0.2, -0.1]
"""

# A user controller that raises part-way (the Python loop's failure).
RAISING = """
class FailsLater:
    def reset(self, context):
        pass

    def step(self, t, m):
        if t >= 0.0505:
            raise RuntimeError("the controller gave up")
        return (0.1, -0.1)
"""


def cheap_scene(tmp_path, stop_time=1.0, step_size=1e-3, output_interval=None, extra=""):
    path = tmp_path / "cheap.toml"
    path.write_text(scenes.cheap_scene(stop_time, step_size, output_interval or step_size, name="cheap") + OPEN_LOOP + extra)
    return path


def start(*args, cwd):
    return subprocess.Popen([*RUN, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=cwd)


def finish(*args, cwd, timeout=600):
    done = subprocess.run([*RUN, *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=timeout)
    assert "Traceback" not in done.stderr, done.stderr
    return done


def read_csv(path: pathlib.Path) -> dict:
    """The CSV as a plain reader takes it: a header row (`name [unit]`), then numbers; by plain name."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, values = rows[0], np.array(rows[1:], dtype=float)
    return {split_label(label)[0]: values[:, j] for j, label in enumerate(header)}


def assert_partial(out: pathlib.Path, name: str, kind: str, step_size: float, stop_time: float) -> float:
    """The files of a run that stopped early: run.json, Parquet and CSV agree on where it ended, every
    recorded point is there, and the end is before the stop time. Returns the end."""
    status = json.loads((out / f"{name}_run.json").read_text())
    assert status["partial"] is True and status["status"] == kind, status
    end = status["recorded_until_s"]
    assert 0 <= end < stop_time and status["stop_time_s"] == stop_time
    assert "PARTIAL" in status["summary"]
    parquet = pq.ParquetFile(out / f"{name}.parquet")
    file_status = json.loads(parquet.metadata.metadata[b"gimbal2axis.status"])
    assert file_status["partial"] is True and file_status["status"] == kind
    assert file_status["recorded_until_s"] == end
    t = parquet.read(columns=["time"]).column("time").to_numpy()
    assert np.array_equal(t, np.arange(len(t)) * step_size)   # every point, none twice, none missing
    assert t[-1] == end
    table = read_csv(out / f"{name}.csv")
    assert table["time"][0] == 0.0 and table["time"][-1] == pytest.approx(end, abs=1e-12)
    assert np.all(np.isfinite(table["alpha"]))
    return end


def one_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    return lines[0]


def wait_for_first_chunk(process, path: pathlib.Path, timeout=120.0) -> None:
    """Until the run has written its first chunk (so it is in its loop, with a record to keep)."""
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "the run wrote no chunk"
        time.sleep(0.02)


@pytest.mark.parametrize("signum, kind, status", [(signal.SIGINT, "interrupted", EXIT_INTERRUPTED),
                                                   (signal.SIGTERM, "terminated", EXIT_TERMINATED)])
def test_a_signalled_run_keeps_its_record_marked_partial(tmp_path, fmu_path, signum, kind, status):
    scene = cheap_scene(tmp_path, stop_time=3600.0, output_interval=0.01)
    out = tmp_path / "out"
    process = start(scene, "--fmu", fmu_path, "--out", out, "--quiet", cwd=tmp_path)
    wait_for_first_chunk(process, out / "cheap.parquet")
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == status, (process.returncode, stdout, stderr)
    assert "Traceback" not in stderr
    message = one_line(stderr)
    assert message.startswith(f"gimbal2axis run: {kind}"), message
    assert "t = " in message and "partial" in message and signal.Signals(signum).name in message
    end = assert_partial(out, "cheap", kind, 1e-3, 3600.0)
    assert end > 0
    assert stdout == ""   # --quiet: the line on stderr and <scene>_run.json say it
    assert f"{end:g} s" in json.loads((out / "cheap_run.json").read_text())["summary"]
    assert (out / "cheap.png").stat().st_size > 0


def test_a_terminated_run_of_a_user_controller_stops_at_its_next_step(tmp_path, fmu_path):
    # the Python loop: it looks at the request before every step
    (tmp_path / "steady.py").write_text("class Steady:\n    def reset(self, context):\n        pass\n\n"
                                        "    def step(self, t, m):\n        return (0.1, -0.1)\n")
    scene = cheap_scene(tmp_path, stop_time=3600.0, output_interval=0.01)
    scene.write_text(scene.read_text().replace('type = "none"\nvoltage_V = [0.2, -0.1]',
                                               'type = "python"\nmodule = "steady.py"\nclass = "Steady"'))
    out = tmp_path / "out"
    process = start(scene, "--fmu", fmu_path, "--out", out, "--quiet", cwd=tmp_path)
    wait_for_first_chunk(process, out / "cheap.parquet")
    process.send_signal(signal.SIGTERM)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == EXIT_TERMINATED, (stdout, stderr)
    assert one_line(stderr).startswith("gimbal2axis run: terminated by SIGTERM at t = ")
    assert assert_partial(out, "cheap", "terminated", 1e-3, 3600.0) > 0


def test_a_run_the_fmu_refuses_part_way_keeps_its_record_up_to_the_last_good_step(tmp_path, fmu_path):
    # one internal step per communication step cannot follow the ship: the FMU discards a step (compiled loop)
    ship = (pathlib.Path(__file__).resolve().parents[3] / "scenes" / "ship_stabilization.toml").read_text()
    ship = ship.replace('"solver.atol" = 1e-8', '"solver.atol" = 1e-8\n"solver.max_steps" = 1')
    (tmp_path / "ship.toml").write_text(ship)
    out = tmp_path / "out"
    done = finish(tmp_path / "ship.toml", "--fmu", fmu_path, "--out", out, "--quiet", "--stop-time", "0.5",
                  cwd=tmp_path)
    assert done.returncode == EXIT_FAILED_PARTIAL, (done.stdout, done.stderr)
    message = one_line(done.stderr)
    assert message.startswith("gimbal2axis run: error: ship: the FMU failed at t = ") and "fmi2DoStep" in message
    end = assert_partial(out, "ship", "failed", 1e-3, 0.5)
    # the refused step starts at the last recorded point: its outputs were read before the step
    assert f"t = {end:.6g} s" in message


def test_a_controller_that_raises_part_way_keeps_the_record_and_names_the_exception(tmp_path, fmu_path):
    (tmp_path / "fails_later.py").write_text(RAISING)
    scene = cheap_scene(tmp_path, stop_time=0.2)
    text = scene.read_text().replace('type = "none"\nvoltage_V = [0.2, -0.1]',
                                     'type = "python"\nmodule = "fails_later.py"\nclass = "FailsLater"')
    scene.write_text(text)
    out = tmp_path / "out"
    done = finish(scene, "--fmu", fmu_path, "--out", out, "--quiet", cwd=tmp_path)
    assert done.returncode == EXIT_FAILED_PARTIAL, (done.stdout, done.stderr)
    message = one_line(done.stderr)
    assert "RuntimeError: the controller gave up" in message and "t = 0.051 s" in message, message
    end = assert_partial(out, "cheap", "failed", 1e-3, 0.2)
    assert end == pytest.approx(0.050)   # the last point whose voltage the controller gave


def test_the_library_keeps_a_partial_run_only_when_asked(tmp_path, fmu_path):
    (tmp_path / "fails_later.py").write_text(RAISING)
    scene_path = cheap_scene(tmp_path, stop_time=0.2)
    scene_path.write_text(scene_path.read_text().replace('type = "none"\nvoltage_V = [0.2, -0.1]',
                                                         'type = "python"\nmodule = "fails_later.py"\n'
                                                         'class = "FailsLater"'))
    scene = load_scene(scene_path)
    with FMU(fmu_path) as fmu:
        from gimbal2axis import SceneError
        with pytest.raises(SceneError, match="RuntimeError"):
            run(scene, fmu)
        partial = run(scene, fmu, keep_partial=True)
    assert partial.stopped.kind == "failed" and partial.stopped.time == pytest.approx(0.050)
    assert len(partial.signals["time"]) == 51 and partial.stop_time == partial.stopped.time
    assert partial.summary().startswith("cheap: PARTIAL, failed at t = 0.05 s of 0.2 s")


# 9e8 steps (under the limit of 1e9, gimbal2axis.limits.MAX_STEPS) of some 60 signals: 430 GB of record
@pytest.mark.parametrize("edit, stop_time, fragment", [("stop_time = 9e5", 60.0, "on disk"),
                                                       ("step_size = 1e-7", 90.0, "on disk")])
def test_a_run_the_disk_cannot_hold_is_refused_before_it_starts(tmp_path, fmu_path, edit, stop_time, fragment):
    scene = cheap_scene(tmp_path, stop_time=stop_time)
    key = edit.split(" = ")[0]
    text = "\n".join(edit if line.startswith(f"{key} = ") else line for line in scene.read_text().splitlines())
    scene.write_text(text.replace("output_interval = 0.001", "output_interval = 0.01"))
    out = tmp_path / "out"
    started = time.monotonic()
    done = finish(scene, "--fmu", fmu_path, "--out", out, "--quiet", cwd=tmp_path)
    assert done.returncode == 2, (done.stdout, done.stderr)
    message = one_line(done.stderr)
    assert message.startswith("gimbal2axis run: error: cheap: the record of ") and fragment in message
    assert "free" in message and "B" in message   # the numbers: what it needs, what there is
    assert time.monotonic() - started < 60
    assert not (out / "cheap.csv").exists() and not (out / "cheap.parquet").exists()


def test_stop_time_lengthens_a_run(tmp_path, fmu_path):
    scene = cheap_scene(tmp_path, stop_time=0.01)
    out = tmp_path / "out"
    done = finish(scene, "--fmu", fmu_path, "--out", out, "--stop-time", "0.05", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("cheap: 0.05 s simulated")
    table = read_csv(out / "cheap.csv")   # 12 significant digits
    assert np.allclose(table["time"], np.arange(51) * 1e-3, rtol=0, atol=1e-15)
    t = pq.read_table(out / "cheap.parquet", columns=["time"]).column("time").to_numpy()
    assert np.array_equal(t, np.arange(51) * 1e-3)
    status = json.loads((out / "cheap_run.json").read_text())
    assert status["status"] == "complete" and status["partial"] is False and status["recorded_until_s"] == 0.05


@pytest.mark.parametrize("step_size, stop_time, old_refusal", [(1e-3, 349.5, 349.36), (1e-4, 38.01, 38.0021)])
def test_a_run_goes_past_where_the_old_communication_point_rule_refused(tmp_path, fmu_path, step_size, stop_time,
                                                                       old_refusal):
    scene = cheap_scene(tmp_path, stop_time=stop_time, step_size=step_size, output_interval=1.0)
    out = tmp_path / "out"
    done = finish(scene, "--fmu", fmu_path, "--out", out, "--quiet", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    t = pq.read_table(out / "cheap.parquet", columns=["time"]).column("time").to_numpy()
    assert len(t) == round(stop_time / step_size) + 1 and t[-1] > old_refusal
    assert json.loads((out / "cheap_run.json").read_text())["status"] == "complete"
