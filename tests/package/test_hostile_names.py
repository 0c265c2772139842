"""Names a user did not mean as syntax: scene and sweep files whose names carry `&`, `"`, `<`, `>` or
`../` give valid files in the folder asked for, or are refused (issue 34). The SSP and OSP files are
checked in tests/package/system/test_system.py."""
import json
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
COMMAND = [str(REPO / ".venv" / "bin" / "gimbal2axis")]

pytestmark = [pytest.mark.python_bound,
              pytest.mark.skipif(not pathlib.Path(COMMAND[0]).exists(), reason="the package's command is not installed")]

HOSTILE = 'R&D "<probe>"'


def test_a_scene_file_with_markup_in_its_name_writes_its_files_in_the_folder_asked_for(tmp_path):
    scene = tmp_path / "scenes" / f"{HOSTILE}.toml"
    scene.parent.mkdir()
    text = (REPO / "scenes" / "free_swing.toml").read_text()
    # the plot title too: a name key with a path and markup in it is a title, never a path
    scene.write_text(text.replace('name = "free_swing"', 'name = "../../escaped <&\\"> title"'))
    out = tmp_path / "out"
    done = subprocess.run(COMMAND + ["run", str(scene), "--out", str(out), "--stop-time", "0.05", "--quiet"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    written = sorted(p.name for p in out.iterdir())
    # No lock file is left behind (the run removes it while it holds it).
    assert written == sorted(f"{HOSTILE}{suffix}" for suffix in (".csv", ".parquet", ".png", "_run.json")), written
    assert not any("escaped" in p.name for p in tmp_path.rglob("*")), "the title became a path"
    status = json.loads((out / f"{HOSTILE}_run.json").read_text())
    assert status["scene"] == HOSTILE and status["files"] == [f"{HOSTILE}{s}" for s in (".csv", ".parquet", ".png")]
    header = (out / f"{HOSTILE}.csv").read_text().splitlines()[0]
    assert header.startswith("time [s],"), header


@pytest.mark.parametrize("name", ["../../escaped", 'gains<&">', "a/b"])
def test_a_sweep_name_that_is_not_a_plain_word_is_refused_before_anything_runs(tmp_path, name):
    sweep = tmp_path / "hostile.toml"
    sweep.write_text(f'name = {json.dumps(name)}\ncases = 2\nstop_time = 0.05\n'
                     '[grid]\n"controller.azimuth.kp" = [100.0, 200.0]\n')
    done = subprocess.run(COMMAND + ["sweep", str(REPO / "scenes" / "ship_stabilization.toml"), str(sweep), "--serial",
                                     "--out", str(tmp_path / "out"), "--quiet"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and "'name'" in done.stderr and "names the result files" in done.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    assert not any(p.name.startswith("escaped") for p in tmp_path.parent.iterdir())
