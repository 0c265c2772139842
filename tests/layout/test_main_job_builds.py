"""The main job (scripts/run.sh, through setup.sh's run set-up) builds every FMU the README and the
commands name: after it, `gimbal2axis system` finds the ship-motion and controller FMUs and the README's
host table finds build/Gimbal2Axis-fmi3.fmu (issue 34: it built the FMI 2.0 FMU alone).

Asked of the build's own Ninja graph: the commands that the run set-up's targets execute must write
each file."""
import pathlib
import re
import shutil
import subprocess

import pytest

from gimbal2axis.system.from_scene import FMUS

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]


def run_setup_targets() -> list[str]:
    setup = (REPO / "scripts" / "setup.sh").read_text()
    run_branch = setup[setup.index('if [ "$setup_for" = test ]; then\n  cmake --build'):]
    targets = re.search(r"^\s*cmake --build \"\$build_dir\" --target (.+)$", run_branch, re.M)
    assert targets, "setup.sh's run set-up builds no named targets"
    return targets.group(1).split()


def files_the_readme_names() -> set[str]:
    return set(re.findall(r"build/(Gimbal2Axis[\w-]*\.fmu)", (REPO / "README.md").read_text()))


def test_the_readme_names_the_fmus_it_relies_on():
    assert {"Gimbal2Axis.fmu", "Gimbal2Axis-fmi3.fmu", "Gimbal2Axis-ShipMotion-fmi3.fmu",
            "Gimbal2Axis-Controller-fmi3.fmu"} <= files_the_readme_names()


def test_the_run_setup_builds_every_fmu_named(build_dir):
    if not (build_dir / "build.ninja").is_file() or shutil.which("ninja") is None:
        pytest.skip("asks Ninja's build graph; this build is not a Ninja build")
    commands = subprocess.run(["ninja", "-C", str(build_dir), "-t", "commands", *run_setup_targets()],
                              capture_output=True, text=True, check=True, timeout=120).stdout
    needed = files_the_readme_names() | set(FMUS.values()) | {"libgimbal_probe.so"}
    needed |= {name.replace(".fmu", "-fmi3.fmu") for name in FMUS.values()}   # every FMU for FMI 3.0 too
    missing = sorted(name for name in needed if name not in commands)
    assert not missing, f"the main job does not build {missing} (targets {run_setup_targets()})"


def test_the_main_job_installs_the_engine_the_systems_page_runs_with():
    """docs/systems.md runs a scene's system in libcosim (libcosimpy): the main job's set-up installs it
    (requirements-run.txt) and checks it is importable, as it does the other packages running needs."""
    run_requirements = (REPO / "requirements-run.txt").read_text()
    assert re.search(r"^libcosimpy==", run_requirements, re.M)
    assert "libcosimpy" in (REPO / "docs" / "systems.md").read_text()
    setup = (REPO / "scripts" / "setup.sh").read_text()
    run_modules = re.search(r'^\s*requirements="\$repo/requirements-run.txt"\n.*?modules="([^"]+)"', setup, re.M | re.S)
    assert run_modules and "libcosimpy" in run_modules.group(1).split(", ")
