"""Which build the package runs: configuring a second build folder must not take
gimbal2axis/build_locations.json over silently (issue 34: the sanitizer build, a benchmark build).
The decision (cmake/record_build_location.cmake) runs here in CMake's script mode on files of the
test's own, so the checkout's file is never touched."""
import pathlib
import subprocess

import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]
DECISION = REPO / "cmake" / "record_build_location.cmake"


def decide(locations: pathlib.Path, binary_dir: pathlib.Path, mode: str = "AUTO") -> str:
    done = subprocess.run(["cmake", f"-DLOCATIONS_FILE={locations}", f"-DBINARY_DIR={binary_dir}", f"-DMODE={mode}",
                           "-P", str(DECISION)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stderr.strip()   # message() without a mode writes to stderr


def a_build(folder: pathlib.Path) -> pathlib.Path:
    folder.mkdir()
    (folder / "CMakeCache.txt").write_text("# configured\n")
    return folder


def recorded(locations: pathlib.Path, build: pathlib.Path) -> pathlib.Path:
    locations.write_text(f'{{\n  "fmu": "{build}/Gimbal2Axis.fmu",\n  "probe_library": "{build}/libgimbal_probe.so"\n}}\n')
    return locations


def test_the_first_build_is_recorded(tmp_path):
    assert decide(tmp_path / "build_locations.json", a_build(tmp_path / "build")) == "record"


def test_the_recorded_build_configured_again_is_recorded_again(tmp_path):
    build = a_build(tmp_path / "build")
    assert decide(recorded(tmp_path / "build_locations.json", build), build) == "record"


def test_a_second_build_folder_leaves_the_first_and_says_how_to_choose_it(tmp_path):
    first = a_build(tmp_path / "build")
    second = a_build(tmp_path / "build-bench")
    said = decide(recorded(tmp_path / "build_locations.json", first), second)
    assert said.startswith("keep:"), said
    assert str(first) in said and "GIMBAL_RECORD_BUILD_IN_PACKAGE=ON" in said and "GIMBAL2AXIS_FMU" in said


def test_asked_for_the_second_build_folder_takes_it(tmp_path):
    first, second = a_build(tmp_path / "build"), a_build(tmp_path / "build-bench")
    assert decide(recorded(tmp_path / "build_locations.json", first), second, "ON") == "record"


def test_a_build_that_is_gone_is_replaced(tmp_path):
    gone = tmp_path / "deleted-build"   # never configured, or removed since
    assert decide(recorded(tmp_path / "build_locations.json", gone), a_build(tmp_path / "build")) == "record"


@pytest.mark.parametrize("mode", ["OFF", "off"])
def test_off_never_records(tmp_path, mode):
    assert decide(tmp_path / "build_locations.json", a_build(tmp_path / "build"), mode).startswith("keep:")


def test_a_misspelt_mode_is_refused(tmp_path):
    done = subprocess.run(["cmake", f"-DLOCATIONS_FILE={tmp_path / 'x.json'}", f"-DBINARY_DIR={tmp_path}",
                           "-DMODE=AUTOMATIC", "-P", str(DECISION)], capture_output=True, text=True, timeout=60)
    assert done.returncode != 0 and "AUTO, ON or OFF" in done.stderr
