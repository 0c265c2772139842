"""A sweep on the workers of an existing Dask scheduler (gimbal2axis sweep --scheduler), as on a cluster
of other machines: a `dask scheduler` and `dask worker` processes started here on 127.0.0.1, the
workers in a fresh virtual environment that has the package's dependencies from PyPI but not the
package (nor the repository). The sweep sends them the package, compiled kernel included
(gimbal2axis/sweep/worker_package.py), and the FMU as bytes; its table equals a local cluster's bit
for bit. A scheduler without workers, and workers that cannot run the package, are refused in one
line before any case runs.

Cost: creating the workers' environment takes about 30 s (pip downloading and unpacking numpy,
scipy, fmpy, Dask), once per test session; the tests themselves about 30 s on 2 cores."""
import json
import math
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from gimbal2axis.sweep.runner import version_difference, worker_refusal  # noqa: E402
from gimbal2axis.sweep.table import read_rows  # noqa: E402

SCENE = REPO / "scenes" / "ship_stabilization.toml"
SWEEP = [sys.executable, "-m", "gimbal2axis", "sweep"]
# What a worker imports to run cases (numpy, scipy, fmpy, tqdm) and Dask itself, at the versions the
# package pins (requirements-run.txt), so that the workers compute what the local cluster computes.
WORKER_REQUIREMENTS = ["dask", "distributed", "numpy", "scipy", "fmpy", "tqdm"]
# The columns that say where and how fast a case ran, not what it computed.
RUN_COLUMNS = {"wall_time_s", "cpu_time_s", "worker", "instance_use"}

# 8 short cases: a structural switch, a controller gain, and per sample a random sea state and
# payload mass (as in tests/package/sweep/test_sweep.py).
SMALL = """
name = "small"
seed = 5
samples = 2
stop_time = 0.06
metrics_from_s = 0.02
[grid]
"gear1.model" = [2, 0]
"controller.azimuth.kp" = [200.0, 800.0]
[random]
"base_motion.seed" = { integers = [0, 9999] }
"body2.m" = { uniform = [1.5, 3.0] }
"""

pytestmark = [pytest.mark.dask_workers,
              pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                 reason="Dask processes under AddressSanitizer test nothing the release pass does not")]


def pinned(names: list[str]) -> list[str]:
    """The requirement lines of requirements-run.txt for these distributions (extras kept)."""
    lines = [line.split("#")[0].strip() for line in (REPO / "requirements-run.txt").read_text().splitlines()]
    chosen = [line for line in lines if re.split(r"[\[=<>~ ]", line, maxsplit=1)[0].lower() in names]
    assert len(chosen) == len(names), (names, chosen)
    return chosen


def clean_environment() -> dict:
    """The environment of the workers: nothing that would point them at this checkout or its build."""
    return {name: value for name, value in os.environ.items()
            if name not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "GIMBAL2AXIS_FMU", "GIMBAL2AXIS_PROBE_LIBRARY")}


@pytest.fixture(scope="session")
def worker_venv(tmp_path_factory) -> pathlib.Path:
    """A new virtual environment with the workers' dependencies from PyPI; without pip of its own (this
    environment's pip installs into it: faster than ensurepip) and without the repository."""
    venv = tmp_path_factory.mktemp("worker_venv") / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    # --no-compile: writing the .pyc files of numpy, scipy and Dask took half the time; the workers
    # compile only what they import
    done = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-compile",
                           "--only-binary", ":all:", *pinned(WORKER_REQUIREMENTS)], capture_output=True, text=True,
                          timeout=600, env=clean_environment())
    if done.returncode != 0:
        pytest.fail(f"could not install the workers' dependencies from PyPI: {done.stderr.strip()[-2000:]}")
    return venv


class Processes:
    """Processes started for a test, each in a session of its own; stop() ends them and their children
    (a `dask worker --nworkers 2` is a parent of nannies and workers)."""

    def __init__(self):
        self.started: list = []

    def start(self, args, log: pathlib.Path, **kwargs) -> subprocess.Popen:
        process = subprocess.Popen(args, stdout=log.open("w"), stderr=subprocess.STDOUT, start_new_session=True,
                                   **kwargs)
        self.started.append(process)
        return process

    def stop(self):
        for process in reversed(self.started):   # workers first, then their scheduler
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGTERM)
                try:
                    process.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    os.killpg(process.pid, signal.SIGKILL)
                    process.wait()


def start_scheduler(processes: Processes, bin_dir: pathlib.Path, folder: pathlib.Path) -> str:
    """A `dask scheduler` on 127.0.0.1 (a free port); its address."""
    scheduler_file = folder / "scheduler.json"
    processes.start([str(bin_dir / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                     "--scheduler-file", str(scheduler_file)], folder / "scheduler.log", cwd=folder,
                    env=clean_environment())
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            return json.loads(scheduler_file.read_text())["address"]
        except (OSError, ValueError, KeyError):
            time.sleep(0.2)
    raise AssertionError(f"the scheduler did not start: {(folder / 'scheduler.log').read_text()}")


@pytest.fixture(scope="module")
def cluster(worker_venv, tmp_path_factory):
    """A scheduler and 2 workers of one thread each, all in the fresh environment, on 127.0.0.1: the
    scheduler's address and the workers' python."""
    from distributed import Client

    folder = tmp_path_factory.mktemp("cluster")
    processes = Processes()
    try:
        address = start_scheduler(processes, worker_venv / "bin", folder)
        processes.start([str(worker_venv / "bin" / "dask"), "worker", address, "--nworkers", "2", "--nthreads", "1",
                         "--host", "127.0.0.1", "--no-dashboard", "--local-directory", str(folder / "workers")],
                        folder / "workers.log", cwd=folder, env=clean_environment())
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=120)
        yield {"address": address, "python": worker_venv / "bin" / "python", "folder": folder}
    finally:
        processes.stop()


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b and type(a) is type(b)


def test_the_workers_environment_cannot_import_the_package(cluster):
    done = subprocess.run([str(cluster["python"]), "-c", "import gimbal2axis"], capture_output=True, text=True,
                          cwd=cluster["folder"], env=clean_environment(), timeout=60)
    assert done.returncode != 0 and "No module named 'gimbal2axis'" in done.stderr, done.stderr


def test_a_sweep_on_workers_without_the_package_equals_the_local_clusters_bit_for_bit(cluster, fmu_path, tmp_path):
    from distributed import Client

    sweep = tmp_path / "small.toml"
    sweep.write_text(SMALL)
    remote = subprocess.run([*SWEEP, str(SCENE), str(sweep), "--fmu", str(fmu_path), "--out", str(tmp_path / "remote"),
                             "--scheduler", cluster["address"]], capture_output=True, text=True,
                            cwd=tmp_path, timeout=300)   # not --quiet: the summary line
    assert remote.returncode == 0, remote.stderr
    assert "8 cases (8 run, 0 already done): 8 ok, 0 failed" in remote.stdout, remote.stdout
    assert "warning" not in remote.stderr   # e.g. of workers with other versions of numpy, scipy, fmpy
    local = subprocess.run([*SWEEP, str(SCENE), str(sweep), "--fmu", str(fmu_path), "--out", str(tmp_path / "local"),
                            "--workers", "2", "--quiet"], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert local.returncode == 0, local.stderr

    with Client(cluster["address"], timeout="30s") as client:
        workers = set(client.scheduler_info()["workers"])
        # what the workers imported: the package they were sent, unpacked in their own directories
        imported = client.run(lambda: __import__("gimbal2axis").__file__)
    assert len(workers) == 2
    assert all("gimbal2axis-package-" in path and not path.startswith(str(REPO)) for path in imported.values()), \
        imported

    name = "small__ship_stabilization.parquet"
    rows = {r["case_id"]: r for r in read_rows(tmp_path / "remote" / name)}
    reference = {r["case_id"]: r for r in read_rows(tmp_path / "local" / name)}
    assert set(rows) == set(reference) and len(rows) == 8
    assert {r["worker"] for r in rows.values()} <= workers   # the cases ran on the fresh environment's workers
    assert len({r["los_rms_mrad"] for r in rows.values()}) == 8   # the cases differ from each other
    for case_id, expected in reference.items():
        assert set(rows[case_id]) == set(expected)
        for column, value in expected.items():
            if column not in RUN_COLUMNS:   # bitwise: the same kernel, FMU and arithmetic
                assert _same(rows[case_id][column], value), (case_id, column, rows[case_id][column], value)


USER_GAINS = """
name = "user_gains"
stop_time = 0.1
metrics_from_s = 0.02
[grid]
"controller.options.kp" = [100.0, 400.0]
"controller.options.k_gyro" = [2.0, 8.0]
"""


def test_a_user_controller_named_by_a_relative_path_reaches_workers_in_another_directory(cluster, fmu_path,
                                                                                          tmp_path):
    # examples/user_controller.toml names examples/gyro_stabilizer.py beside it; the command runs in
    # the repository with a relative scene path, the workers in a directory of their own.
    sweep = tmp_path / "user_gains.toml"
    sweep.write_text(USER_GAINS)
    scene = pathlib.Path("examples") / "user_controller.toml"
    outcomes = {}
    for where, how in (("remote", ["--scheduler", cluster["address"]]), ("serial", ["--serial"])):
        done = subprocess.run([*SWEEP, str(scene), str(sweep), "--fmu", str(fmu_path), "--out", str(tmp_path / where),
                               *how, "--quiet"], capture_output=True, text=True, cwd=REPO, timeout=300)
        assert done.returncode == 0, (where, done.stdout, done.stderr)
        outcomes[where] = {r["case_id"]: r for r in read_rows(tmp_path / where / "user_gains__user_controller.parquet")}
    assert len(outcomes["remote"]) == 4 and set(outcomes["remote"]) == set(outcomes["serial"])
    for case_id, expected in outcomes["serial"].items():
        for column, value in expected.items():
            if column not in RUN_COLUMNS:
                assert _same(outcomes["remote"][case_id][column], value), (case_id, column)


def test_a_scheduler_without_workers_is_refused_in_one_line_before_any_case_runs(fmu_path, tmp_path):
    processes = Processes()
    try:
        address = start_scheduler(processes, pathlib.Path(sys.executable).parent, tmp_path)
        sweep = tmp_path / "small.toml"
        sweep.write_text(SMALL)
        done = subprocess.run([*SWEEP, str(SCENE), str(sweep), "--fmu", str(fmu_path), "--out", str(tmp_path / "out"),
                               "--scheduler", address, "--quiet"], capture_output=True, text=True, cwd=tmp_path,
                              timeout=120)
    finally:
        processes.stop()
    assert done.returncode == 2
    assert done.stderr.splitlines() == [f"gimbal2axis sweep: error: no Dask worker is connected to the scheduler at "
                                        f"{address} (waited 5 s); start some: dask worker {address} --nthreads 1"]
    assert read_rows(tmp_path / "out" / "small__ship_stabilization.parquet") == []


def test_workers_that_cannot_run_the_package_are_refused_in_one_line_naming_one_and_why():
    reports = {"tcp://10.0.0.7:4001": {"ok": True},
               "tcp://10.0.0.8:4001": {"ok": False, "reason": "cannot import the gimbal2axis package "
                                                              "(ModuleNotFoundError: No module named 'scipy'; "
                                                              "Python 3.11.7 on linux-x86_64)"},
               "tcp://10.0.0.9:4001": RuntimeError("worker died\nwith a long story")}
    refusal = worker_refusal(reports, "tcp://10.0.0.5:8786")
    assert "\n" not in refusal
    assert refusal.startswith("worker tcp://10.0.0.8:4001 of tcp://10.0.0.5:8786 (and 1 more of the 3 workers) "
                              "cannot run the cases: cannot import the gimbal2axis package (ModuleNotFoundError: "
                              "No module named 'scipy'")
    assert "requirements-run.txt" in refusal
    assert worker_refusal({"tcp://10.0.0.7:4001": {"ok": True}}, "tcp://10.0.0.5:8786") is None


def test_a_worker_with_other_versions_of_the_dependencies_is_named_in_a_warning():
    here = {"numpy": "2.4.6", "scipy": "1.17.1", "fmpy": "0.3.32"}
    same = {"ok": True, "versions": dict(here)}
    older = {"ok": True, "versions": dict(here, numpy="2.3.0")}
    assert version_difference({"tcp://10.0.0.7:4001": same}, here) is None
    warning = version_difference({"tcp://10.0.0.7:4001": same, "tcp://10.0.0.8:4001": older}, here)
    assert warning.startswith("worker tcp://10.0.0.8:4001 has numpy 2.3.0 (here 2.4.6): ") and "\n" not in warning
