"""The source FMU: sources/ and the <SourceFiles> of modelDescription.xml build, away from this
repository, with fmpy's build helper (fmpy.build.build_platform_binary: CMake over the listed files,
include path sources/ and fmpy's FMI headers), into a binary that runs the scene of
tests/fmu/fmu_scene_driver.c exactly as the shipped linux64 binary does."""
import os
import re
import subprocess
import zipfile

import fmpy
import pytest
from fmpy.build import build_platform_binary

from conftest import REPO_ROOT

SUNDIALS_SOURCES = {"sundials_integrator.cpp", "cvode_backend.cpp", "arkode_backend.cpp"}


def source_files(fmu_path):
    configurations = fmpy.read_model_description(str(fmu_path)).buildConfigurations
    assert len(configurations) == 1 and configurations[0].modelIdentifier == "Gimbal2Axis"
    return configurations[0].sourceFileSets[0].sourceFiles


def test_listed_sources_are_shipped_without_sundials(fmu_path):
    files = source_files(fmu_path)
    names = set(zipfile.ZipFile(fmu_path).namelist())
    # The core's sources keep their layer folder below sources/ (simulation/gimbal_instance.cpp, ...).
    basenames = {os.path.basename(f) for f in files}
    assert {"fmi2_functions.c", "fmu_model_table.cpp", "fmi_instance.c", "fmu_state.c", "gimbal_instance.cpp", "one_step_integrator.cpp"} <= basenames
    assert [f for f in files if f"sources/{f}" not in names] == []
    assert SUNDIALS_SOURCES.isdisjoint(basenames)
    assert not any(n.startswith("sources/") and os.path.basename(n) in SUNDIALS_SOURCES for n in names)
    # The generated GUID header, the core's headers and the Eigen headers they include come along
    # (Eigen with its licence); the FMI headers are the importer's.
    assert {"sources/gimbal_guid.h", "sources/gimbal/gimbal_c_api.h", "sources/Eigen/Core",
            "sources/Eigen/COPYING.MPL2"} <= names
    # (The standard's headers are fmi2Functions.h, fmi2FunctionTypes.h, fmi2TypesPlatform.h; the FMI
    # layer's fmi_layer/fmi2_face.h is the FMU's own.)
    assert not any(re.match(r"fmi[23][A-Z]\w*\.h$", os.path.basename(n)) for n in names)


@pytest.fixture(scope="module")
def source_build(fmu_path, tmp_path_factory):
    """The FMU extracted into a fresh directory, its binaries deleted, then built from sources/."""
    work = tmp_path_factory.mktemp("source_fmu")
    assert REPO_ROOT not in work.parents
    unzipdir = work / "fmu"
    with zipfile.ZipFile(fmu_path) as fmu:
        fmu.extractall(unzipdir, [n for n in fmu.namelist() if not n.startswith("binaries/")])
    (work / "build").mkdir()
    parallel = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL")
    os.environ["CMAKE_BUILD_PARALLEL_LEVEL"] = str(os.cpu_count() or 2)
    try:
        build_platform_binary(unzipdir, build_dir=work / "build")
    finally:
        if parallel is None:
            del os.environ["CMAKE_BUILD_PARALLEL_LEVEL"]
        else:
            os.environ["CMAKE_BUILD_PARALLEL_LEVEL"] = parallel
    binary = unzipdir / "binaries" / "linux64" / "Gimbal2Axis.so"
    assert binary.is_file(), "fmpy's build helper made no binaries/linux64/Gimbal2Axis.so"
    cache = (work / "build" / "CMakeCache.txt").read_text()
    assert str(REPO_ROOT / "model_core") not in cache and str(REPO_ROOT / "fmu_src") not in cache
    return work, binary


def run_scene(build_dir, binary, csv, *refused):
    guid = fmpy.read_model_description(str(build_dir / "fmu_staging" / "modelDescription.xml")).guid
    run = subprocess.run([str(build_dir / "fmu_scene_driver"), str(binary), guid, str(csv)] + [str(m) for m in refused],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    return run.stdout


@pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                    reason="the build from sources uses fmpy's compiler flags, not the sanitizers; the release pass runs it")
def test_binary_built_from_sources_runs_the_scene_bit_for_bit(build_dir, source_build):
    work, binary = source_build
    shipped = build_dir / "fmu_staging" / "binaries" / "linux64" / "Gimbal2Axis.so"
    run_scene(build_dir, shipped, work / "shipped.csv")
    log = run_scene(build_dir, binary, work / "from_sources.csv", 0)
    # The same compiler with the same optimization (CMake's Release: -O3) and no reassociation of
    # floating-point sums: the same bits, though the shipped binary links its C++ runtime statically.
    assert (work / "from_sources.csv").read_bytes() == (work / "shipped.csv").read_bytes()
    # Built without SUNDIALS: its methods are refused.
    assert "solver.method = 0 is not available in this binary: it was built without SUNDIALS" in log, log
    assert "refusal: solver.method = 0 status = 3" in log, log
