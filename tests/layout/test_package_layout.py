"""The package's import direction (gimbal2axis/__init__.py draws it): cli -> sweep | analysis -> master ->
scene -> fmu -> the leaf modules, read from the source with ast (every import, also those inside
functions), and no module deriving paths from where its own file lies; what the package and its command
line import at start (nothing heavy: --help answers at once), and what `gimbal2axis run` does without."""
import ast
import pathlib

import numpy as np
import pytest

pytestmark = pytest.mark.python_bound

PACKAGE = pathlib.Path(__file__).resolve().parents[2] / "gimbal2axis"
ROOT = "gimbal2axis"

# A module may import from its own part and from parts of a lower rank; parts of the same rank (sweep,
# analysis, report, system) not from each other. __init__ (the package's front: its public API) and __main__ (the
# command) are the package file's own.
RANK = {"errors": 0, "limits": 0.5, "version": 0, "progress": 1, "native": 1, "locations": 1, "fmu": 2, "target": 2.5, "scene": 3, "master": 4,
        "__init__": 4.5, "analysis": 5, "sweep": 5, "report": 5, "system": 5, "tune": 5.5, "cli": 6, "__main__": 7}


def module_name(path: pathlib.Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def is_module(name: str) -> bool:
    """Whether `name` (gimbal2axis....) is a module or package of the source tree."""
    relative = pathlib.Path(*name.split("."))
    return (PACKAGE.parent / relative.with_suffix(".py")).is_file() or (PACKAGE.parent / relative / "__init__.py").is_file()


def part_of(name: str, path: pathlib.Path | None = None) -> str:
    """errors, fmu, scene, ... for gimbal2axis.<part>...; '__init__' for the package itself."""
    pieces = name.split(".")
    if len(pieces) == 1:
        return "__main__" if path is not None and path.name == "__main__.py" else "__init__"
    return pieces[1]


def imported_modules(source: str, importer: str, is_package: bool) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import of the package's own modules in `source`."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names if alias.name.split(".")[0] == ROOT]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = importer.split(".") if is_package else importer.split(".")[:-1]
                base = base[:len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if module.split(".")[0] != ROOT:
                continue
            for alias in node.names:   # `from . import native` imports a module, `from .x import f` x itself
                candidate = f"{module}.{alias.name}"
                found.append((node.lineno, candidate if is_module(candidate) else module))
    return found


def violations(path: pathlib.Path, source: str) -> list[str]:
    importer = module_name(path)
    own = part_of(importer, path)
    where = path.relative_to(PACKAGE.parent)
    wrong = []
    for line, target in imported_modules(source, importer, path.name == "__init__.py"):
        if target == ROOT:   # a name of the package's front, which imports the whole public API
            wrong += [] if own == "__init__" else [f"{where}:{line}: imports from the package's front, {ROOT}"]
            continue
        other = part_of(target)
        if other != own and RANK[other] >= RANK[own]:
            wrong.append(f"{where}:{line}: {own} imports {target} ({other})")
    return wrong


def package_files() -> list[pathlib.Path]:
    return sorted(PACKAGE.rglob("*.py"))


def test_every_part_of_the_package_has_a_rank():
    parts = {part_of(module_name(path), path) for path in package_files()}
    assert parts == set(RANK), f"parts without a rank, or ranks of no part: {parts ^ set(RANK)}"


def test_imports_go_one_way():
    wrong = [line for path in package_files() for line in violations(path, path.read_text(encoding="utf-8"))]
    assert wrong == [], "imports against the direction cli -> sweep | analysis -> master -> scene -> fmu -> leaves:\n" \
                        + "\n".join(wrong)


@pytest.mark.parametrize("where, source", [
    ("scene/scene.py", "from ..master import run\n"),                 # upwards
    ("fmu/fmu.py", "def f():\n    from gimbal2axis.scene import load_scene\n"),   # inside a function, absolute
    ("analysis/linearization.py", "from ..sweep import make_client\n"),   # sideways
    ("sweep/runner.py", "import gimbal2axis\n"),                      # the front, which imports everything
    ("errors.py", "from . import progress\n"),                        # between leaves, upwards
])
def test_the_check_refuses_a_wrong_import(where, source):
    assert violations(PACKAGE / where, source)


def test_no_module_derives_paths_from_its_own_file():
    """The FMU and the probe library are found through options, the environment or the configured
    location (gimbal2axis/locations.py), never relative to the source tree."""
    offenders = [f"{path.relative_to(PACKAGE.parent)}:{node.lineno}" for path in package_files()
                 for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
                 if isinstance(node, ast.Name) and node.id == "__file__"]
    assert offenders == []


# What `gimbal2axis --help`, `--version` and a refused argument must answer without: each takes 0.1 to
# 0.8 s to import (benchmarks/cli_latency.py measures the command).
HEAVY = ["numpy", "fmpy", "scipy", "matplotlib", "pyarrow", "dask", "distributed", "control", "tqdm"]


def modules_imported_by(code: str, cwd: pathlib.Path | None = None) -> set:
    """The HEAVY modules in sys.modules after running `code` in a fresh interpreter."""
    import json
    import subprocess
    import sys

    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300, cwd=cwd)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.splitlines()[-1]))


@pytest.mark.parametrize("code", ["import gimbal2axis", "import gimbal2axis.cli.main",
                                  "from gimbal2axis.cli.main import build_parser; build_parser()"])
def test_the_package_and_the_command_line_import_nothing_heavy(code):
    assert modules_imported_by(code) == set()


def test_the_public_api_is_still_there_when_asked_for():
    """gimbal2axis imports FMU, load_scene, run, ... on first use (its module __getattr__)."""
    assert modules_imported_by("from gimbal2axis import FMU, Scene, load_scene, run, run_scene_file, "
                               "check_against_fmu, SceneError, __version__") >= {"numpy"}
    import gimbal2axis
    for name in gimbal2axis.__all__:
        assert getattr(gimbal2axis, name) is not None
    with pytest.raises(AttributeError):
        gimbal2axis.no_such_name


def test_run_imports_neither_dask_nor_control_nor_scipy_signal(fmu_path, tmp_path):
    """`gimbal2axis run` of the ship scene (a target, a moving base: spectra and isolation estimates)
    without the modules only other subcommands need; scipy.signal alone took 0.5 s to import."""
    code = (f"import sys\nfrom gimbal2axis.cli.main import main\n"
            f"assert main(['run', 'scenes/ship_stabilization.toml', '--stop-time', '2', '--quiet', "
            f"'--out', {str(tmp_path)!r}, '--fmu', {str(fmu_path)!r}]) == 0\n"
            f"assert 'scipy.signal' not in sys.modules, 'scipy.signal imported'")
    imported = modules_imported_by(code, cwd=PACKAGE.parent)
    assert not imported & {"dask", "distributed", "control"}, imported
    assert (tmp_path / "ship_stabilization_spectrum.png").is_file()   # the spectra were made, without scipy.signal


@pytest.mark.parametrize("length", [2, 3, 4, 5, 64, 100, 1001, 2000, 4096, 10000, 65537])
def test_the_welch_window_is_scipys_bit_for_bit(length):
    """master/spectra.py's Hann window, made without importing scipy.signal, is the one welch uses."""
    from scipy.signal import get_window

    from gimbal2axis.master import spectra
    assert np.array_equal(spectra.hann_window(length), get_window(spectra.WINDOW, length))
