"""`gimbal2axis system` run as a user runs it: from any folder, without --build-dir, it takes the FMUs of
the build `run` would use (the folder of $GIMBAL2AXIS_FMU, else of the configured FMU), not ./build."""
import os
import pathlib
import subprocess
import sys
import zipfile

import pytest

from gimbal2axis.locations import FMU_ENVIRONMENT, fmu_directory

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]
SCENE = REPO / "scenes" / "ship_stabilization.toml"


def _system(cwd, env_fmu, *extra):
    env = {**os.environ, FMU_ENVIRONMENT: str(env_fmu)}
    return subprocess.run([sys.executable, "-m", "gimbal2axis", "system", str(SCENE), "--out", "out", *extra],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=120)


def test_the_build_directory_defaults_to_the_fmus_folder(build_dir, tmp_path):
    done = _system(tmp_path, pathlib.Path(build_dir) / "Gimbal2Axis.fmu")
    assert done.returncode == 0, done.stderr
    with zipfile.ZipFile(tmp_path / "out" / "ship_stabilization" / "ship_stabilization.ssp") as archive:
        names = archive.namelist()
    assert any(name.endswith("Gimbal2Axis.fmu") for name in names), names


def test_each_scene_has_its_own_system_and_a_namesake_from_elsewhere_is_refused(build_dir, tmp_path):
    """Two scenes into one --out each get their folder (the README writes two); a scene file of the same
    name from another folder would replace the first's FMUs and structure, and is refused."""
    fmu = pathlib.Path(build_dir) / "Gimbal2Axis.fmu"
    flyby = REPO / "scenes" / "track_flyby_keyhole.toml"
    for scene in (SCENE, flyby):
        done = subprocess.run([sys.executable, "-m", "gimbal2axis", "system", str(scene), "--out", "out"], cwd=tmp_path,
                              env={**os.environ, FMU_ENVIRONMENT: str(fmu)}, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
    structures = {scene: (tmp_path / "out" / scene / "osp" / "OspSystemStructure.xml").read_bytes()
                  for scene in ("ship_stabilization", "track_flyby_keyhole")}
    assert structures["ship_stabilization"] != structures["track_flyby_keyhole"]
    namesake = tmp_path / "elsewhere" / "ship_stabilization.toml"
    namesake.parent.mkdir()
    namesake.write_text(SCENE.read_text())
    refused = subprocess.run([sys.executable, "-m", "gimbal2axis", "system", str(namesake), "--out", "out"],
                             cwd=tmp_path, env={**os.environ, FMU_ENVIRONMENT: str(fmu)}, capture_output=True,
                             text=True, timeout=120)
    assert refused.returncode == 2 and "holds the system of another scene file" in refused.stderr, refused.stderr
    assert (tmp_path / "out" / "ship_stabilization" / "osp" / "OspSystemStructure.xml").read_bytes() == \
        structures["ship_stabilization"]
    again = _system(tmp_path, fmu)   # the same scene file again: its own folder, rewritten
    assert again.returncode == 0, again.stderr


def test_without_the_fmus_the_message_names_the_folder_it_looked_in(tmp_path):
    empty = tmp_path / "elsewhere"
    empty.mkdir()
    done = _system(tmp_path, empty / "Gimbal2Axis.fmu")
    assert done.returncode != 0
    assert str(empty) in done.stderr and "Traceback" not in done.stderr


def test_an_explicit_build_directory_is_taken_as_given(tmp_path):
    assert fmu_directory(tmp_path) == tmp_path
