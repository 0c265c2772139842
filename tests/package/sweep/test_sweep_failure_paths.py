"""A sweep or tuning whose user controller ends its case by a BaseException (sys.exit, SystemExit(3),
KeyboardInterrupt, GeneratorExit, an exception class of its own) records that case as failed, naming
the controller and what it raised, and runs the others; only a signal to the process itself (Ctrl-C,
SIGTERM) stops it, keeping the rows finished (issue 44, item 4). A metrics window that starts after
the runs' stop time is refused (item 10); temporary files of killed writers are removed (item 15)."""
import json
import os
import pathlib
import subprocess
import sys

import pytest

from gimbal2axis.sweep import SweepError, SweepOptions, load_sweep, run_sweep, store
from gimbal2axis.sweep.runner import plan_sweep
from gimbal2axis.sweep.table import read_rows

pytestmark = pytest.mark.dask_workers

ROOT = pathlib.Path(__file__).resolve().parents[3]
COMMAND = [sys.executable, "-m", "gimbal2axis"]

CONTROLLER = '''
import os
import signal
import sys
import time

import numpy as np


class Escape(BaseException):
    """Neither an Exception nor one of Python's own."""


def escape(how):
    if how == "sys_exit":
        sys.exit(0)
    if how == "exit3":
        raise SystemExit(3)
    if how == "interrupt":
        raise KeyboardInterrupt
    if how == "generator_exit":
        raise GeneratorExit
    if how == "custom":
        raise Escape("out of here")
    if how in ("sigint", "sigterm"):   # the signal to the sweep itself, while the controller's code runs
        os.kill(os.getpid(), signal.SIGINT if how == "sigint" else signal.SIGTERM)
        time.sleep(2.0)
    if how == "sigint_swallowed":
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(2.0)
        except BaseException:
            pass


class Hostile:
    def __init__(self, how="ok", where="step", gain=0.0):
        self.how, self.where = ("sys_exit" if gain > 0.58 else how), where

    def reset(self, context):
        self.fired = False
        if self.where == "reset":
            escape(self.how)

    def step(self, t, m):
        if t > 0.02 and not self.fired:
            self.fired = True
            if self.where == "step":
                escape(self.how)
        return (0.0, 0.0)

    @property
    def reference(self):   # read after each step, outside the call to step()
        if self.where == "reference" and self.fired:
            sys.exit(7)
        return (0.0, 0.0)


class BatchHostile:
    batch = True

    def __init__(self, gain=1.0):
        pass

    def reset(self, context):
        self.cases = context.cases

    def step(self, t, m):
        if t > 0.02:
            sys.exit(0)
        return np.zeros((self.cases, 2))
'''


def write_scene(folder: pathlib.Path, cls: str = "Hostile", options: str = '{ how = "ok" }',
                name: str = "hostile") -> pathlib.Path:
    """examples/user_controller.toml with the controller above."""
    text = (ROOT / "examples" / "user_controller.toml").read_text()
    for old, new in (('file = "gyro_stabilizer.py"', 'file = "hostile.py"'),
                     ('class = "GyroStabilizer"', f'class = "{cls}"'),
                     ("options = { kp = 400.0, ki = 8000.0, k_gyro = 8.0 }", f"options = {options}")):
        assert old in text
        text = text.replace(old, new)
    (folder / "hostile.py").write_text(CONTROLLER)
    scene = folder / f"{name}.toml"
    scene.write_text(text)
    return scene


def write_sweep(folder: pathlib.Path, body: str, name: str = "sweep") -> pathlib.Path:
    path = folder / f"{name}.toml"
    path.write_text(body)
    return path


def sweep_command(scene, sweep, out, *options):
    return subprocess.run([*COMMAND, "sweep", str(scene), str(sweep), "--out", str(out), "--quiet", *options],
                          capture_output=True, text=True, timeout=120)


def table(out: pathlib.Path, stem: str) -> dict:
    return {(r.get("controller.options.how"), r.get("controller.options.where")): r
            for r in read_rows(out / f"{stem}.parquet")}


ESCAPES = {"sys_exit": "SystemExit: 0", "exit3": "SystemExit: 3", "interrupt": "KeyboardInterrupt",
           "generator_exit": "GeneratorExit", "custom": "Escape: out of here"}


def test_a_serial_sweep_records_each_controller_escape_as_a_failed_case_and_runs_the_others(tmp_path):
    scene = write_scene(tmp_path)
    hows = ["ok"] + list(ESCAPES)
    sweep = write_sweep(tmp_path, f'stop_time = 0.1\n[grid]\n"controller.options.how" = {json.dumps(hows)}\n'
                                  '"controller.options.where" = ["reset", "step"]\n')
    done = sweep_command(scene, sweep, tmp_path / "out", "--serial")
    assert done.returncode == 1, done.stderr
    assert "Traceback" not in done.stderr and "failed" in done.stderr
    rows = table(tmp_path / "out", "sweep__hostile")
    assert len(rows) == 2 * len(hows)
    for where in ("reset", "step"):
        assert rows[("ok", where)]["status"] == "ok"
        for how, raised in ESCAPES.items():
            row = rows[(how, where)]
            assert row["status"] == "failed", row
            assert f"Hostile ({tmp_path / 'hostile.py'}): {where}() raised {raised}" in row["message"], row["message"]


def test_an_escape_from_the_controllers_reference_property_is_a_failed_case_naming_the_controller(tmp_path):
    scene = write_scene(tmp_path)
    sweep = write_sweep(tmp_path, 'stop_time = 0.1\n[grid]\n"controller.options.where" = ["reference", "step"]\n')
    outcome = run_sweep(scene, sweep, os.environ["GIMBAL2AXIS_FMU"], tmp_path / "out",
                        SweepOptions(serial=True, progress=False, plot=False))
    rows = {r["controller.options.where"]: r for r in outcome.rows}
    assert outcome.failed == 1 and rows["step"]["status"] == "ok"
    assert rows["reference"]["status"] == "failed"
    message = rows["reference"]["message"]
    assert "Hostile (" in message and "reference raised SystemExit: 7" in message and "hostile.py:" in message, message


def test_a_batch_controller_that_calls_sys_exit_fails_its_cases(tmp_path):
    scene = write_scene(tmp_path, "BatchHostile", "{ gain = 1.0 }")
    sweep = write_sweep(tmp_path, 'stop_time = 0.1\n[grid]\n"controller.options.gain" = [1.0, 2.0]\n')
    outcome = run_sweep(scene, sweep, os.environ["GIMBAL2AXIS_FMU"], tmp_path / "out",
                        SweepOptions(serial=True, progress=False, plot=False))
    assert outcome.failed == 2
    for row in outcome.rows:
        assert "BatchHostile" in row["message"] and "step() raised SystemExit: 0" in row["message"], row["message"]


def test_on_dask_workers_a_controller_escape_is_a_failed_case_not_a_cancelled_task(tmp_path, client):
    scene = write_scene(tmp_path)
    sweep = write_sweep(tmp_path, 'stop_time = 0.1\n[grid]\n"controller.options.how" = ["ok", "sys_exit", "custom"]\n')
    outcome = run_sweep(scene, sweep, os.environ["GIMBAL2AXIS_FMU"], tmp_path / "out",
                        SweepOptions(client=client, progress=False, plot=False))
    rows = {r["controller.options.how"]: r for r in outcome.rows}
    assert rows["ok"]["status"] == "ok" and outcome.failed == 2
    for how in ("sys_exit", "custom"):
        assert f"step() raised {ESCAPES[how]}" in rows[how]["message"], rows[how]["message"]
        assert "Cancelled" not in rows[how]["message"]


@pytest.mark.parametrize("how, status", [("sigint", 130), ("sigterm", 143), ("sigint_swallowed", 130)])
def test_only_a_signal_to_the_sweep_stops_it_even_while_the_controller_runs(tmp_path, how, status):
    scene = write_scene(tmp_path)
    sweep = write_sweep(tmp_path, f'stop_time = 0.1\n[grid]\n"controller.options.how" = ["ok", "{how}", "custom"]\n')
    done = sweep_command(scene, sweep, tmp_path / "out", "--serial")
    assert done.returncode == status, done.stderr
    assert "Traceback" not in done.stderr and "the 1 cases finished in this run are kept" in done.stderr
    rows = table(tmp_path / "out", "sweep__hostile")
    assert list(rows) == [("ok", None)] and rows[("ok", None)]["status"] == "ok"   # the interrupted case: no row


def test_a_serial_tuning_records_a_controller_escape_as_a_failed_evaluation(tmp_path):
    from gimbal2axis.tune.engine import TuneOptions, plan, run_tuning

    scene = write_scene(tmp_path, options="{ gain = 0.0 }")
    tuning = tmp_path / "gain.toml"
    tuning.write_text('stop_time = 0.1\n[parameters]\n"controller.options.gain" = { bounds = [0.0, 1.0] }\n'
                      '[optimizer]\nsampler = "random"\ntrials = 4\nbatch = 4\n')
    problem = plan(scene, tuning, os.environ["GIMBAL2AXIS_FMU"], tmp_path / "out")
    try:
        run_tuning(problem, TuneOptions(serial=True, progress=False))
    finally:
        problem.fmu.close()
    rows = read_rows(problem.evaluations.parquet)
    assert len(rows) == 4
    exited = [r for r in rows if r["controller.options.gain"] > 0.58]
    assert exited and len(exited) < 4   # the seed draws both kinds
    for row in rows:
        if row in exited:
            assert row["status"] == "failed" and "step() raised SystemExit: 0" in row["message"], row
        else:
            assert row["status"] == "ok", row


# item 10: the metrics window [metrics_from_s, end] of every case ends after it starts


def test_a_sweep_whose_metrics_window_starts_after_its_stop_time_is_refused(tmp_path):
    sweep = write_sweep(tmp_path, 'stop_time = 0.1\nmetrics_from_s = 5\n[grid]\n"body2.m" = [1.0]\n')
    with pytest.raises(SweepError, match=r"'metrics_from_s' = 5 must be below stop_time = 0.1"):
        load_sweep(sweep)


@pytest.mark.parametrize("body, culprit", [
    ('metrics_from_s = 0.15\n[grid]\n"stop_time" = [0.2, 0.1]\n', "the stop time of case 1 = 0.1"),
    ('metrics_from_s = 20\n[grid]\n"controller.options.how" = ["ok"]\n', "the stop time of case 0 = 10"),
])
def test_a_sweep_is_refused_when_a_case_stops_before_its_metrics_window(tmp_path, body, culprit):
    scene = write_scene(tmp_path)
    sweep = write_sweep(tmp_path, body)
    with pytest.raises(SweepError, match=f"sweep.toml: 'metrics_from_s' = .* must be below {culprit}"):
        plan_sweep(scene, sweep, os.environ["GIMBAL2AXIS_FMU"], tmp_path / "out")
    assert not (tmp_path / "out").exists()   # refused before anything was written


def test_a_tuning_whose_runs_stop_before_its_metrics_window_is_refused(tmp_path):
    from gimbal2axis.tune.engine import plan
    from gimbal2axis.tune.spec import TuneError

    scene = write_scene(tmp_path, options="{ gain = 0.0 }")   # stop_time = 10 s
    tuning = tmp_path / "late.toml"
    tuning.write_text('metrics_from_s = 20\n[parameters]\n"controller.options.gain" = { bounds = [0.0, 1.0] }\n')
    refusal = "late.toml: 'metrics_from_s' = 20 must be below the stop time of its runs = 10"
    with pytest.raises(TuneError, match=refusal):
        plan(scene, tuning, os.environ["GIMBAL2AXIS_FMU"], tmp_path / "out")


# item 15: temporary files of a writer that was killed


def test_the_temporary_files_of_a_killed_writer_are_removed_and_those_being_written_kept(tmp_path):
    files = store.TableFiles.of(tmp_path, "sweep__scene")
    ended = subprocess.Popen(["true"])
    ended.wait()
    running, host = os.getpid(), store.HOST
    removed = [f".sweep__scene.parquet.{ended.pid}@{host}.0123456789ab.tmp",   # only lock holders write these
               f".sweep__scene.csv.{running}@{host}.0123456789ab.tmp",
               f".sweep__scene.csv.{running}.0123456789ab.tmp",                 # named by an earlier version
               f".sweep__scene.png.{ended.pid}@{host}.0123456789ab.tmp",       # its writer has ended
               f".tuning__scene_report.html.{ended.pid}@{host}.0123456789ab.tmp"]
    kept = [f".sweep__scene.png.{running}@{host}.0123456789ab.tmp",            # being written
            f".sweep__scene.png.{ended.pid}@other-host.0123456789ab.tmp",      # a pid of another machine
            f".sweep__scene.parquet.x.parquet.{running}@{host}.0123456789ab.tmp",   # another table's
            "sweep__scene.csv"]
    for name in removed + kept:
        (tmp_path / name).touch()
    store.claim(files, ["body2.m"])
    left = {p.name for p in tmp_path.iterdir()}
    assert not left & set(removed)
    assert set(kept) <= left


def test_a_sweep_leaves_no_temporary_file_of_its_own(tmp_path):
    files = store.TableFiles.of(tmp_path, "s__x")
    store.claim(files, ["body2.m"])
    store.save(files, [{"case_id": "a", "case": 0, "status": "ok", "body2.m": 1.0}], ["body2.m"])
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
