"""Shared fixtures: where the build lives and the artefacts the tests drive."""
import os
import pathlib
import sys

import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]
BUILD_DIR = pathlib.Path(os.environ.get("GIMBAL_BUILD_DIR", REPO_ROOT / "build")).resolve()

# Test modules import one another by name (`from test_linearization import RICH_POINT`), across the
# folders (tests/README.md): every folder of test files is on sys.path, whichever of them a run collects
# (pytest's default import mode adds only the folders of the files it collects). File names are unique.
for _folder in sorted({path.parent for path in pathlib.Path(__file__).parent.rglob("test_*.py")}):
    if str(_folder) not in sys.path:
        sys.path.append(str(_folder))

# The package finds the build through these when not told (gimbal2axis/locations.py): the tests' build,
# GIMBAL_BUILD_DIR's (the sanitizer pass's), not the one the package was configured with; set here, they
# also reach the commands the tests start.
os.environ["GIMBAL2AXIS_FMU"] = str(BUILD_DIR / "Gimbal2Axis.fmu")
os.environ["GIMBAL2AXIS_PROBE_LIBRARY"] = str(BUILD_DIR / "libgimbal_probe.so")


@pytest.fixture(scope="session")
def build_dir() -> pathlib.Path:
    if not BUILD_DIR.is_dir():
        pytest.fail(f"build directory {BUILD_DIR} does not exist: build the project first (scripts/test.sh does)")
    return BUILD_DIR


@pytest.fixture(scope="session")
def fmu_path(build_dir) -> pathlib.Path:
    path = build_dir / "Gimbal2Axis.fmu"
    if not path.is_file():
        pytest.fail(f"{path} is missing: the build did not package the FMU")
    return path


@pytest.fixture(scope="session")
def probe_lib_path(build_dir) -> pathlib.Path:
    path = build_dir / "libgimbal_probe.so"
    if not path.is_file():
        pytest.fail(f"{path} is missing: the build did not produce the probe library")
    return path


@pytest.fixture(scope="session")
def gimbal_fmu(fmu_path):
    """The packaged FMU, extracted once for the whole session."""
    from gimbal2axis.fmu import FMU

    with FMU(fmu_path) as fmu:
        yield fmu


@pytest.fixture(scope="module")
def client():
    """A local Dask cluster of 2 worker processes (the product's default), 1 thread each."""
    from gimbal2axis.sweep import make_client

    client, cluster = make_client(workers=2, processes=True)
    client.wait_for_workers(2, timeout=60)
    yield client
    client.close()
    cluster.close()


@pytest.fixture(scope="session")
def ship_scene():
    """scenes/ship_stabilization.toml: the PID loop the linear predictions (gimbal2axis.analysis.isolation_prediction)
    are checked on; they assume ideal sensors."""
    from gimbal2axis import load_scene

    scene = load_scene(REPO_ROOT / "scenes" / "ship_stabilization.toml")
    assert scene.sensors().ideal, "the prediction assumes ideal sensors"
    return scene


@pytest.fixture(scope="session")
def ship_linear_loop(ship_scene, gimbal_fmu):
    """The ship loop's linear sampled-data model without backlash and dry friction."""
    from gimbal2axis.analysis import isolation_prediction
    from gimbal2axis.analysis.frequency_response import LINEAR_FIDELITY

    return isolation_prediction.build_loop(ship_scene, gimbal_fmu, LINEAR_FIDELITY)
