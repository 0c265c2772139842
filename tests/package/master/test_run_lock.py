"""Two runs of one scene into one folder: the second is refused while the first writes, instead of
both writing the same CSV, Parquet and plot files at once (scene_files.only_writer)."""
import fcntl
import pathlib
import subprocess
import sys

import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]
SCENE = REPO / "scenes" / "free_swing.toml"


def run(out: pathlib.Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gimbal2axis", "run", str(SCENE), "--out", str(out), "--stop-time", "0.05",
                           "--quiet"], capture_output=True, text=True, timeout=300)


def test_a_second_run_of_the_same_scene_into_the_same_folder_is_refused_while_the_first_writes(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    with open(out / ".free_swing.run.lock", "a+b") as first_run:   # as a run in progress holds it
        fcntl.flock(first_run, fcntl.LOCK_EX | fcntl.LOCK_NB)
        refused = run(out)
        assert refused.returncode == 2, refused.stderr
        assert refused.stderr.count("\n") == 1 and "another gimbal2axis run is writing free_swing's files" in refused.stderr
        assert sorted(p.name for p in out.iterdir()) == [".free_swing.run.lock"], "the refused run wrote files"
        other_folder = run(tmp_path / "elsewhere")   # another --out is free
        assert other_folder.returncode == 0, other_folder.stderr
    done = run(out)   # the first run ended: its lock went with it
    assert done.returncode == 0, done.stderr
    assert (out / "free_swing.csv").is_file() and (out / "free_swing_run.json").is_file()
    assert not (out / ".free_swing.run.lock").exists(), "the run left its empty lock file"


def test_a_run_waiting_on_a_removed_lock_file_locks_the_one_at_the_path(tmp_path, monkeypatch):
    """The lock file is removed at the end of a run, while held. A run that opened it before the
    removal holds a file no longer at the path; it must lock the path's file instead, or a third run
    could lock a new file and write at the same time."""
    import os

    from gimbal2axis.master import scene_files

    path = tmp_path / ".s.run.lock"
    opened = []
    real_open = open

    def open_then_removed(file, *args, **kwargs):   # the first open sees the file the run before removes
        handle = real_open(file, *args, **kwargs)
        if not opened:
            os.unlink(file)
        opened.append(handle)
        return handle

    monkeypatch.setattr(scene_files, "open", open_then_removed, raising=False)
    with scene_files.only_writer(tmp_path, "s"):
        assert len(opened) == 2 and path.exists()
        assert os.path.samestat(os.fstat(opened[1].fileno()), os.stat(path))
    assert not path.exists()

