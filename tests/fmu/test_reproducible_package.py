"""Packaging an FMU is reproducible (scripts/package_fmu.py): the same staged files give the same zip,
byte for byte, whenever they are packaged. `cmake -E tar --format=zip` wrote each file's modification,
access and change times into the zip, so the FMU's sha256 changed at every repackaging of the same
files (issue 46), and a sweep's fmu_sha256 column took an unchanged FMU for a new one."""
import hashlib
import os
import pathlib
import shutil
import subprocess
import sys
import zipfile

import pytest

# Zips and hashes: its time goes to Python.
pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "package_fmu.py"
# What fmu_src/CMakeLists.txt packs of the gimbal's FMI 2.0 staging folder.
GIMBAL_ENTRIES = ["modelDescription.xml", "binaries", "documentation", "model.png", "sources", "extra"]


def package(out: pathlib.Path, staging: pathlib.Path, entries: list[str], **env) -> str:
    subprocess.run([sys.executable, str(SCRIPT), str(out), str(staging), *entries], check=True, timeout=300,
                   env={**os.environ, **env})
    return hashlib.sha256(out.read_bytes()).hexdigest()


def test_packaging_twice_gives_the_same_sha256_whatever_the_files_times(build_dir, tmp_path):
    staging = tmp_path / "staging"
    shutil.copytree(build_dir / "fmu_staging", staging)
    first = package(tmp_path / "first.fmu", staging, GIMBAL_ENTRIES)
    for path in staging.rglob("*"):   # as a rebuild that stages the same files again leaves them
        os.utime(path, (1_900_000_000, 1_900_000_000))
    second = package(tmp_path / "second.fmu", staging, GIMBAL_ENTRIES)
    assert first == second
    with zipfile.ZipFile(tmp_path / "first.fmu") as archive:
        members = archive.infolist()
    assert [m.filename for m in members] == sorted(m.filename for m in members)
    assert {m.date_time for m in members} == {(1980, 1, 1, 0, 0, 0)}
    assert all(not m.extra for m in members), "extra fields (times, owners) of the packaging machine"
    # SOURCE_DATE_EPOCH, the reproducible-builds convention, sets the one time instead
    dated = package(tmp_path / "dated.fmu", staging, GIMBAL_ENTRIES, SOURCE_DATE_EPOCH="1764547200")
    assert dated != first
    with zipfile.ZipFile(tmp_path / "dated.fmu") as archive:
        assert {m.date_time for m in archive.infolist()} == {(2025, 12, 1, 0, 0, 0)}


def test_the_builds_fmu_is_its_staging_folder_packaged_so(build_dir, tmp_path):
    """The build packs with the script: its FMU is the zip the script makes of the staged files, and
    holds every staged file with its permissions."""
    fmu = build_dir / "Gimbal2Axis.fmu"
    again = package(tmp_path / "again.fmu", build_dir / "fmu_staging", GIMBAL_ENTRIES)
    assert hashlib.sha256(fmu.read_bytes()).hexdigest() == again
    with zipfile.ZipFile(fmu) as archive:
        so = archive.getinfo("binaries/linux64/Gimbal2Axis.so")
        assert (so.external_attr >> 16) & 0o777 == 0o755
        assert (archive.getinfo("modelDescription.xml").external_attr >> 16) & 0o777 == 0o644


def test_a_missing_entry_is_refused_and_leaves_no_half_fmu(tmp_path):
    (tmp_path / "staging").mkdir()
    done = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path / "x.fmu"), str(tmp_path / "staging"),
                           "modelDescription.xml"], capture_output=True, text=True, timeout=60)
    assert done.returncode != 0 and "does not exist" in done.stderr
    assert list(tmp_path.glob("x.fmu*")) == []
