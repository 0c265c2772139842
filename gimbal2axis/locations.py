"""Where the built FMU (Gimbal2Axis.fmu) and the analysis library (libgimbal_probe.so, which the
linearization loads) are. Each is taken from, in this order:

1. the caller: a command's --fmu (linearize's --build-dir for the probe library), a function's argument;
2. the environment: GIMBAL2AXIS_FMU, GIMBAL2AXIS_PROBE_LIBRARY (paths of the files);
3. the package's configured location: build_locations.json in the package folder, {"fmu": PATH,
   "probe_library": PATH}, which configuring the repository's CMake build writes (git-ignored; the
   sanitizer build does not, its binaries need the sanitizer runtime preloaded). A wheel does not
   carry it: an installed package has it only when someone puts it there.

Nothing is derived from where this file lies in a source tree: an installed package knows only what
it was told. When none of the three gives a path, the error names all three.
"""
from __future__ import annotations

import importlib.resources
import json
import os
import pathlib

from .errors import SceneError

FMU_ENVIRONMENT = "GIMBAL2AXIS_FMU"
PROBE_LIBRARY_ENVIRONMENT = "GIMBAL2AXIS_PROBE_LIBRARY"
CONFIGURED_FILE = "build_locations.json"
PROBE_LIBRARY_NAME = "libgimbal_probe.so"


class BuildNotFound(SceneError):
    """The FMU or the probe library was given nowhere, or where it was given there is no such file."""


def configured_file() -> pathlib.Path:
    """build_locations.json in the package folder (present or not)."""
    return pathlib.Path(str(importlib.resources.files(__package__))) / CONFIGURED_FILE


def _configured(key: str) -> pathlib.Path | None:
    path = configured_file()
    if not path.is_file():
        return None
    try:
        locations = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise BuildNotFound(f"{path}: not a readable JSON object of build locations ({exc}); configure the build "
                            f"again (cmake -S . -B build) or delete the file") from None
    value = locations.get(key) if isinstance(locations, dict) else None
    return pathlib.Path(value) if isinstance(value, str) and value else None


def _existing(path: pathlib.Path, origin: str, build_hint: str) -> pathlib.Path:
    if not path.is_file():
        raise BuildNotFound(f"{path} (from {origin}) does not exist: {build_hint}")
    return path


def fmu_path(given: str | os.PathLike | None = None) -> pathlib.Path:
    """The FMU to run: `given`, else $GIMBAL2AXIS_FMU, else the configured one."""
    if given is not None:
        return pathlib.Path(given)   # FMU() refuses a missing file with its own message
    hint = "build it (cmake --build build --target fmu, or bash scripts/setup.sh)"
    if os.environ.get(FMU_ENVIRONMENT):
        return _existing(pathlib.Path(os.environ[FMU_ENVIRONMENT]), f"${FMU_ENVIRONMENT}", hint)
    configured = _configured("fmu")
    if configured is not None:
        return _existing(configured, str(configured_file()), hint)
    raise BuildNotFound(f"no FMU given: pass --fmu PATH, set {FMU_ENVIRONMENT}=PATH, or configure a build of the "
                        f"repository (cmake -S . -B build; it records its FMU in {configured_file()})")


def fmu_directory(given: str | os.PathLike | None = None) -> pathlib.Path:
    """The build directory whose FMUs a system is made of: `given`, else the folder of the FMU that
    fmu_path() finds (so `gimbal2axis system` run outside the repository finds the build that
    configured the package, as `run` does)."""
    if given is not None:
        return pathlib.Path(given)
    return fmu_path().parent


def probe_library_path(build_dir: str | os.PathLike | None = None) -> pathlib.Path:
    """libgimbal_probe.so: in `build_dir`, else $GIMBAL2AXIS_PROBE_LIBRARY, else the configured one."""
    hint = "build it (cmake --build build --target gimbal_probe, or bash scripts/setup.sh)"
    if build_dir is not None:
        return _existing(pathlib.Path(build_dir) / PROBE_LIBRARY_NAME, "the build directory given", hint)
    if os.environ.get(PROBE_LIBRARY_ENVIRONMENT):
        return _existing(pathlib.Path(os.environ[PROBE_LIBRARY_ENVIRONMENT]), f"${PROBE_LIBRARY_ENVIRONMENT}", hint)
    configured = _configured("probe_library")
    if configured is not None:
        return _existing(configured, str(configured_file()), hint)
    raise BuildNotFound(f"no {PROBE_LIBRARY_NAME} given: pass the build directory that has it (linearize "
                        f"--build-dir DIR), set {PROBE_LIBRARY_ENVIRONMENT}=PATH, or configure a build of the "
                        f"repository (cmake -S . -B build; it records its library in {configured_file()})")
