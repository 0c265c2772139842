"""The package as a user installs it: a wheel built from an sdist of the sources (so the sdist carries
everything the build reads, the C kernel's sources and headers in c_kernel/ included), installed into a
fresh virtual environment (neither the source tree nor the repository's editable install on its path), and its command
run from a scratch directory: `--help` of the command and of each subcommand, one line on stderr and exit
status 2 for a bad argument, `python -m gimbal2axis`, and a short run of a scene."""
import os
import pathlib
import shutil
import subprocess
import sys
import sysconfig
import tarfile

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
# What building the sdist reads: the package, the C kernel it compiles, its build description and what
# its metadata names.
BUILD_INPUTS = ["pyproject.toml", "setup.py", "MANIFEST.in", "CMakeLists.txt", "README.md", "LICENSE",
                "requirements-run.txt"]
BUILD_INPUT_FOLDERS = ["gimbal2axis", "c_kernel"]
SUBCOMMANDS = ["run", "sweep", "linearize", "freqresp", "bench"]
BAD_ARGUMENTS = {
    "run": ["--stop-time", "soon"],
    "sweep": ["scene.toml", "sweep.toml", "--workers", "0"],
    "linearize": ["--fmin", "low"],
    "freqresp": ["sideways"],
    "bench": ["--repeat", "0"],
}

pytestmark = [pytest.mark.python_bound,
              pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                 reason="building and installing a wheel under the preloaded sanitizer runtime tests "
                                        "nothing more")]


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> dict:
    """The wheel installed in a new virtual environment: its python, its gimbal2axis command, and the
    environment to run them in (without the tests' locations of the build)."""
    work = tmp_path_factory.mktemp("installed_package")
    # A copy of the sources, so that the build's by-products (build/, *.egg-info) stay out of the
    # repository, and so that nothing but the package's own files (no compiled kernels, no
    # build_locations.json of this checkout) can end up in the wheel.
    sources = work / "sources"
    sources.mkdir()
    for name in BUILD_INPUTS:
        shutil.copy2(REPO / name, sources / name)
    for name in BUILD_INPUT_FOLDERS:
        shutil.copytree(REPO / name, sources / name,
                        ignore=shutil.ignore_patterns("__pycache__", "*.so", "build_locations.json"))
    # The sdist through setuptools' PEP 517 backend (what `python -m build --sdist` calls), then the
    # wheel from the unpacked sdist alone: a file the sdist leaves out fails the build here.
    sdists = work / "sdists"
    built = subprocess.run([sys.executable, "-c", "import sys; from setuptools import build_meta; "
                                                  "print(build_meta.build_sdist(sys.argv[1]))", str(sdists)],
                           cwd=sources, check=True, capture_output=True, text=True, timeout=300)
    with tarfile.open(sdists / built.stdout.splitlines()[-1]) as archive:
        archive.extractall(work / "unpacked", filter="data")
    unpacked = next((work / "unpacked").iterdir())
    wheels = work / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(unpacked), "--no-deps", "--no-build-isolation", "-q",
                    "-w", str(wheels)], check=True, capture_output=True, text=True, timeout=300)
    wheel = next(wheels.glob("gimbal2axis-*.whl"))

    venv = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    site = pathlib.Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                                       check=True, capture_output=True, text=True).stdout.strip())
    # The dependencies (numpy, fmpy, ...) from the test environment's site-packages, added as a plain
    # path: Python reads .pth files only in its own site directories, so the editable install of the
    # repository there (a .pth that installs an import hook) stays out of this environment.
    (site / "test_dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "-q", str(wheel)],
                   check=True, capture_output=True, text=True, timeout=300)

    environment = {name: value for name, value in os.environ.items()
                   if name not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "GIMBAL2AXIS_FMU",
                                   "GIMBAL2AXIS_PROBE_LIBRARY")}
    scratch = work / "scratch"
    scratch.mkdir()
    return {"python": python, "command": venv / "bin" / "gimbal2axis", "env": environment, "cwd": scratch,
            "venv": venv}


def run(installed, *args, executable=None):
    return subprocess.run([str(executable or installed["command"]), *map(str, args)], capture_output=True, text=True,
                          cwd=installed["cwd"], env=installed["env"], timeout=120)


def test_the_package_is_the_installed_one_with_its_compiled_kernels(installed):
    done = run(installed, "-c", "import gimbal2axis, gimbal2axis.native as n; print(gimbal2axis.__file__); "
                                "print(n.why_not())", executable=installed["python"])
    assert done.returncode == 0, done.stderr
    location, why_not = done.stdout.splitlines()
    assert pathlib.Path(location).is_relative_to(installed["venv"]), location
    assert why_not == "None"


def test_the_command_and_every_subcommand_have_help(installed):
    done = run(installed, "--help")
    assert done.returncode == 0, done.stderr
    assert all(name in done.stdout for name in SUBCOMMANDS)
    for name in SUBCOMMANDS:
        done = run(installed, name, "--help")
        assert done.returncode == 0, (name, done.stderr)
        assert done.stdout.startswith(f"usage: gimbal2axis {name}"), (name, done.stdout)
    done = run(installed, "-m", "gimbal2axis", "--help", executable=installed["python"])
    assert done.returncode == 0 and all(name in done.stdout for name in SUBCOMMANDS), done.stderr


def test_the_version_is_the_projects(installed):
    """`gimbal2axis --version` and gimbal2axis.__version__ both give CMakeLists.txt's project VERSION,
    from the installed package's metadata."""
    import re

    declared = re.search(r"project\(\s*Gimbal2Axis\s+VERSION\s+([0-9.]+)",
                         (REPO / "CMakeLists.txt").read_text()).group(1)
    done = run(installed, "--version")
    assert done.returncode == 0 and done.stdout == f"gimbal2axis {declared}\n", (done.stdout, done.stderr)
    done = run(installed, "-c", "import gimbal2axis; print(gimbal2axis.__version__)", executable=installed["python"])
    assert done.returncode == 0 and done.stdout.strip() == declared, (done.stdout, done.stderr)


@pytest.mark.parametrize("name", SUBCOMMANDS)
def test_a_bad_argument_is_one_line_and_status_2(installed, name):
    done = run(installed, name, *BAD_ARGUMENTS[name])
    assert done.returncode == 2, (done.stdout, done.stderr)
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"gimbal2axis {name}: error: "), done.stderr


def test_a_short_run_of_a_scene(installed, fmu_path, tmp_path):
    done = run(installed, "run", REPO / "scenes" / "free_swing.toml", "--stop-time", "0.05", "--fmu", fmu_path,
               "--out", tmp_path, "--quiet")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "free_swing.csv").stat().st_size > 0 and (tmp_path / "free_swing.png").stat().st_size > 0


def test_without_an_fmu_the_error_names_the_three_ways_to_give_one(installed):
    done = run(installed, "run", REPO / "scenes" / "free_swing.toml", "--stop-time", "0.05")
    assert done.returncode == 2
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    assert "--fmu" in lines[0] and "GIMBAL2AXIS_FMU" in lines[0] and "build_locations.json" in lines[0]
