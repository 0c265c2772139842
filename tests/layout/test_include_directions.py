"""Which code may include which (issue 35): the C kernel (c_kernel/) is a library of its own that
includes only itself and the C standard library (no FMI, no C++ core, no Python); the Python package's
C glue (gimbal2axis/native/module.c, the extension's module) may include the kernel; the FMI wrappers
(fmu_src/) the kernel and model_core's C interface (the .h and .def files at model_core/include/gimbal/
itself, not the layers behind it); model_core only itself, but for the FMU's model table
(model_core/src/simulation/fmu_model_table.cpp), the core's one file that knows the FMI layer: it may
include fmu_src/'s headers, and is compiled into the FMU's binaries only, never into a core library. tests/layout/test_package_layout.py keeps the
Python imports' direction; the direction between model_core's own layer folders is another test's.

Two things decide what code can include, and both are read:
- every #include line of the four folders (quoted and angled), resolved as the compiler does (a quoted
  one first beside its file, then through the include directories; one that resolves nowhere is
  looked up in the other folders' include directories too, so that a header reachable only once its
  folder is added as an include directory is refused already);
- the include directories each CMake target of the four folders is compiled with, read from the
  build's build.ninja (so what a target inherits from the libraries it links counts too), and the
  Python extension's (setup.py, read by running it with setuptools' setup() replaced).
"""
import contextlib
import pathlib
import re
import runpy
import shlex
from unittest import mock

import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]

# The folders whose direction is kept, by the names the rules use.
FOLDERS = {"c_kernel": "c_kernel", "model_core": "model_core", "fmu_src": "fmu_src", "package": "gimbal2axis"}
C_INTERFACE = "model_core's C interface"
C_LIBRARY = "the C standard library"
OUTSIDE = "outside the sources"   # system and third-party headers: Eigen, SUNDIALS, FMI (fmpy's, in .venv), Python.h
GENERATED = "the build's generated headers"
# What each folder's code may include and be given as include directories.
MAY_USE = {
    "c_kernel": {"c_kernel", C_LIBRARY},
    "package": {"package", "c_kernel", C_LIBRARY, OUTSIDE},
    "fmu_src": {"fmu_src", "c_kernel", C_INTERFACE, C_LIBRARY, OUTSIDE, GENERATED},
    "model_core": {"model_core", C_INTERFACE, C_LIBRARY, OUTSIDE, GENERATED},
}
C_INTERFACE_FOLDER = pathlib.Path("model_core/include/gimbal")
# The FMI faces' table of the gimbal, filled over the core: the one file of model_core that may include
# fmu_src/ (the FMI layer), compiled by fmu_src/'s targets only.
FMU_MODEL_TABLE = pathlib.Path("model_core/src/simulation/fmu_model_table.cpp")
C_STANDARD_HEADERS = {f"{name}.h" for name in (
    "assert complex ctype errno fenv float inttypes iso646 limits locale math setjmp signal stdalign stdarg "
    "stdatomic stdbool stddef stdint stdio stdlib stdnoreturn string tgmath threads time uchar wchar wctype").split()}
SOURCE_SUFFIXES = {".c", ".h", ".cpp", ".hpp", ".cc", ".def", ".inc"}
INCLUDE_LINE = re.compile(r'^[ \t]*#[ \t]*include[ \t]*([<"])([^">\n]+)[">]', re.MULTILINE)
EXTENSION = "gimbal2axis.native._native (setup.py)"


def classify(path: pathlib.Path, build_dir: pathlib.Path) -> str:
    """Whose a header (or an include directory) is: a folder's name of FOLDERS, C_INTERFACE, GENERATED,
    OUTSIDE, or `<folder>/` for any other folder of the repository (tests/, scripts/: nobody's to use)."""
    path = path.resolve()
    if path.is_relative_to(build_dir):
        return GENERATED
    if not path.is_relative_to(REPO):
        return OUTSIDE
    relative = path.relative_to(REPO)
    if not relative.parts or relative.parts[0].startswith("."):   # .venv (fmpy's FMI headers), .git
        return OUTSIDE
    # The C interface's folder as an include directory, or one of its files: the layer folders under
    # it are model_core's own (an #include of one is refused, the directory is needed for the interface).
    if relative == C_INTERFACE_FOLDER.parent or (relative.parent == C_INTERFACE_FOLDER
                                                 and relative.suffix in (".h", ".def")):
        return C_INTERFACE
    for name, folder in FOLDERS.items():
        if relative.parts[0] == folder:
            return name
    return f"{relative.parts[0]}/"


def is_fmu_model_table(path: pathlib.Path) -> bool:
    return path.resolve() == (REPO / FMU_MODEL_TABLE).resolve()


def folder_of(path: pathlib.Path) -> str | None:
    relative = path.resolve().relative_to(REPO)
    return next((name for name, folder in FOLDERS.items() if relative.parts[0] == folder), None)


def source_files() -> dict[pathlib.Path, str]:
    """{path: text} of the C and C++ files of the four folders."""
    return {path: path.read_text(encoding="utf-8", errors="replace")
            for folder in FOLDERS.values() for path in sorted((REPO / folder).rglob("*"))
            if path.suffix in SOURCE_SUFFIXES and path.is_file() and "__pycache__" not in path.parts}


def resolve(including: pathlib.Path, name: str, quoted: bool, search: list[pathlib.Path]) -> pathlib.Path | None:
    for directory in ([including.parent] if quoted else []) + search:
        if (directory / name).is_file():
            return (directory / name).resolve()
    return None


def include_violations(files: dict[pathlib.Path, str], search_paths: dict[str, list[pathlib.Path]],
                       build_dir: pathlib.Path) -> list[str]:
    """Every #include in `files` ({path: text}) that reaches what its folder may not use. search_paths:
    {folder name: the include directories its code is compiled with}."""
    every_directory = [d for directories in search_paths.values() for d in directories
                       if classify(d, build_dir) in FOLDERS or classify(d, build_dir) == C_INTERFACE]
    wrong = []
    for path, text in files.items():
        owner = folder_of(path)
        allowed = MAY_USE[owner] | ({"fmu_src"} if is_fmu_model_table(path) else set())
        for match in INCLUDE_LINE.finditer(text):
            quoted, name = match.group(1) == '"', match.group(2).strip()
            found = resolve(path, name, quoted, search_paths.get(owner, []))
            if found is not None:
                what = classify(found, build_dir)
            elif name in C_STANDARD_HEADERS:
                what = C_LIBRARY
            else:   # not reachable now: whose it would be, were the folder holding it made an include directory
                elsewhere = resolve(path, name, False, every_directory)
                what = classify(elsewhere, build_dir) if elsewhere is not None else OUTSIDE
            if what not in allowed:
                line = text.count("\n", 0, match.start()) + 1
                wrong.append(f"{path.relative_to(REPO)}:{line}: includes {name} ({what}); {owner} may use only "
                             f"{', '.join(sorted(allowed))}")
    return wrong


def ninja_compile_targets(text: str, build_dir: pathlib.Path) -> dict[str, dict]:
    """{target: {"folder": where CMake defines it (relative to the sources), "include_directories": [...],
    "sources": [...]}} from the compile statements of a build.ninja."""
    targets: dict[str, dict] = {}
    for block in re.split(r"\n\s*\n", text):
        statement = re.search(r"^build (\S+?): C(?:XX)?_COMPILER__\S+ (\S+)", block, re.MULTILINE)
        if statement is None:
            continue
        where = re.match(r"(?:(.*)/)?CMakeFiles/([^/]+)\.dir/", statement.group(1))
        if where is None:
            continue
        target = targets.setdefault(where.group(2), {"folder": where.group(1) or "", "include_directories": [],
                                                     "sources": []})
        target["sources"].append(pathlib.Path(statement.group(2)))
        includes = re.search(r"^\s+INCLUDES = (.*)$", block, re.MULTILINE)
        tokens = shlex.split(includes.group(1)) if includes else []
        for index, token in enumerate(tokens):
            for flag in ("-isystem", "-iquote", "-idirafter", "-I"):
                if token.startswith(flag):
                    value = token[len(flag):] or (tokens[index + 1] if index + 1 < len(tokens) else "")
                    directory = (build_dir / value).resolve()
                    if directory not in target["include_directories"]:
                        target["include_directories"].append(directory)
                    break
    return targets


def include_directory_violations(targets: dict[str, dict], build_dir: pathlib.Path) -> list[str]:
    """Every include directory a target of the four folders is given that reaches what its folder may not use."""
    wrong = []
    for name, target in targets.items():
        owner = next((key for key, folder in FOLDERS.items() if target["folder"].split("/")[0] == folder), None)
        if owner is None:
            continue   # tests/, benchmarks/: they may use anything
        for directory in target["include_directories"]:
            what = classify(directory, build_dir)
            if what not in MAY_USE[owner]:
                wrong.append(f"{name} ({target['folder']}/) is given the include directory {directory} ({what}); "
                             f"{owner} may use only {', '.join(sorted(MAY_USE[owner]))}")
        for source in target["sources"]:
            what = classify(source, build_dir)
            if owner == "model_core" and is_fmu_model_table(source):
                wrong.append(f"{name} ({target['folder']}/) compiles {source}: the FMU's model table, which only "
                             "the FMU's binaries may compile")
            elif what not in MAY_USE[owner] and not (owner == "fmu_src" and is_fmu_model_table(source)):
                wrong.append(f"{name} ({target['folder']}/) compiles {source} ({what})")
    return wrong


def search_paths(targets: dict[str, dict]) -> dict[str, list[pathlib.Path]]:
    """{folder name: the include directories of all its targets}, in their order."""
    paths: dict[str, list[pathlib.Path]] = {name: [] for name in FOLDERS}
    for target in targets.values():
        owner = next((key for key, folder in FOLDERS.items() if target["folder"].split("/")[0] == folder), None)
        if owner is not None:
            paths[owner] += [d for d in target["include_directories"] if d not in paths[owner]]
    return paths


@pytest.fixture(scope="module")
def build_targets(build_dir) -> dict[str, dict]:
    ninja = build_dir / "build.ninja"
    if not ninja.is_file():
        pytest.fail(f"{ninja} is missing: the include directories are read from a Ninja build (cmake -G Ninja)")
    return ninja_compile_targets(ninja.read_text(encoding="utf-8"), build_dir.resolve())


@pytest.fixture(scope="module")
def python_extension() -> dict:
    """The Python extension as setup.py declares it, as a target of the package's folder."""
    declared = {}
    with contextlib.chdir(REPO), mock.patch("setuptools.setup", lambda **arguments: declared.update(arguments)):
        runpy.run_path(str(REPO / "setup.py"), run_name="__main__")
    (extension,) = declared["ext_modules"]
    return {"folder": FOLDERS["package"], "sources": [(REPO / s).resolve() for s in extension.sources],
            "include_directories": [(REPO / d).resolve() for d in extension.include_dirs]}


@pytest.fixture(scope="module")
def every_target(build_targets, python_extension) -> dict[str, dict]:
    return {**build_targets, EXTENSION: python_extension}


def test_the_build_has_targets_in_each_folder(every_target):
    """The checks below see something: a target of each folder, with include directories."""
    folders = {target["folder"].split("/")[0] for target in every_target.values() if target["include_directories"]}
    assert set(FOLDERS.values()) <= folders, f"no compiled target found in {set(FOLDERS.values()) - folders}"


def test_every_include_goes_the_allowed_way(every_target, build_dir):
    wrong = include_violations(source_files(), search_paths(every_target), build_dir.resolve())
    assert wrong == [], "includes against the direction:\n" + "\n".join(wrong)


def test_every_include_directory_goes_the_allowed_way(every_target, build_dir):
    wrong = include_directory_violations(every_target, build_dir.resolve())
    assert wrong == [], "include directories against the direction:\n" + "\n".join(wrong)


def test_the_fmu_model_table_is_compiled_into_the_fmus_binaries_only(build_targets):
    """The core's one file that knows the FMI layer is compiled by the gimbal FMU's binaries (FMI 2.0
    and 3.0), by no core library (a core library compiling it is refused above, naming it)."""
    compiling = {name: target["folder"] for name, target in build_targets.items()
                 if any(is_fmu_model_table(source) for source in target["sources"])}
    assert len(compiling) >= 2 and all(folder.split("/")[0] == "fmu_src" for folder in compiling.values()), compiling


def test_the_extension_and_the_cmake_libraries_compile_the_same_kernel(build_targets, python_extension):
    """One kernel: every source of c_kernel/src/ in the CMake libraries and in the Python extension."""
    everything = sorted((REPO / "c_kernel" / "src").glob("*.c"))
    in_cmake = sorted({source.resolve() for target in build_targets.values() if target["folder"] == "c_kernel"
                       for source in target["sources"]})
    in_extension = sorted(source for source in python_extension["sources"] if folder_of(source) == "c_kernel")
    assert in_cmake == everything and in_extension == everything, (in_cmake, in_extension)


@pytest.mark.parametrize("where, planted", [
    ("c_kernel/src/controllers.c", '#include "../../model_core/include/gimbal/gimbal_c_api.h"'),  # a relative path
    ("c_kernel/src/controllers.c", '#include "gimbal/gimbal_c_api.h"'),   # the core, were its folder added
    ("c_kernel/include/gimbal_kernel/sensors.h", "#include <Python.h>"),   # CPython
    ("c_kernel/src/sea_state.c", '#  include "fmi2Functions.h"'),         # FMI
    ("c_kernel/src/gyro.c", '#include "../../gimbal2axis/native/module.c"'),   # the package
    ("c_kernel/src/layout.c", '#include "../../fmu_src/fmi_layer/fmi_instance.h"'),   # the wrappers
    ("fmu_src/controller/controller_model.c", '#include "gimbal/model/gimbal_model.hpp"'),   # behind the C interface
    ("fmu_src/ship_motion/ship_motion.c", '#include "../../model_core/src/integrators/tableaus.hpp"'),
    ("model_core/src/simulation/c_api.cpp", '#include "gimbal_kernel/controllers.h"'),   # the kernel
    ("model_core/include/gimbal/gimbal_c_api.h", '#include "../../../fmu_src/fmi_layer/fmi_instance.h"'),   # the wrappers
    ("model_core/src/simulation/c_api.cpp", "#include <fmi_layer/fmu_state.h>"),
    ("model_core/src/simulation/c_api.cpp", '#include "fmi_layer/fmu_model.h"'),   # only the FMU's table may
    ("model_core/src/simulation/fmu_model_table.cpp", '#include "gimbal_kernel/controllers.h"'),   # the kernel
    ("gimbal2axis/native/module.c", '#include "../../fmu_src/fmi_layer/fmi_instance.h"'),   # the package's glue, the wrappers
    ("gimbal2axis/native/module.c", '#include "gimbal/gimbal_c_api.h"'),         # and the core
])
def test_the_check_refuses_a_wrong_include(every_target, build_dir, where, planted):
    path = REPO / where
    text = path.read_text(encoding="utf-8")
    paths = search_paths(every_target)
    assert include_violations({path: text}, paths, build_dir.resolve()) == []
    wrong = include_violations({path: f"{text}\n{planted}\n"}, paths, build_dir.resolve())
    assert len(wrong) == 1 and wrong[0].startswith(f"{where}:"), wrong


@pytest.mark.parametrize("target, planted", [
    ("gimbal_master_kernel", "model_core/include"),        # the core's interface, into the kernel
    ("gimbal_sea_state_kernel", "gimbal2axis/native"),     # the package, into the kernel
    ("gimbal_recorded_motion_kernel", "fmu_src/common"),   # the wrappers, into the kernel
    ("gimbal_core", "c_kernel/include"),                   # the kernel, into the core
    ("gimbal_core", "fmu_src"),                            # the wrappers, into the core
    ("Gimbal2AxisController", "model_core/src"),           # the core's insides, into a wrapper
    (EXTENSION, "model_core/include"),                     # the core, into the Python extension
])
def test_the_check_refuses_a_wrong_include_directory(every_target, build_dir, target, planted):
    """A directory planted into the real build's build.ninja text (the extension: into setup.py's list)."""
    directory = REPO / planted
    if target == EXTENSION:
        targets = {target: {**every_target[target],
                            "include_directories": every_target[target]["include_directories"] + [directory]}}
    else:
        ninja = (build_dir / "build.ninja").read_text(encoding="utf-8")
        blocks = [block for block in re.split(r"\n\s*\n", ninja)
                  if re.search(rf"^build \S*CMakeFiles/{re.escape(target)}\.dir/\S+: C(?:XX)?_COMPILER__", block,
                               re.MULTILINE)]
        assert blocks, f"no compile statement of {target} in build.ninja"
        planted_block = re.sub(r"^(\s+INCLUDES = .*)$", lambda line: f"{line.group(1)} -I{directory}", blocks[0],
                               count=1, flags=re.MULTILINE)
        targets = ninja_compile_targets(blocks[0], build_dir.resolve())
        assert include_directory_violations(targets, build_dir.resolve()) == []
        targets = ninja_compile_targets(planted_block, build_dir.resolve())
    wrong = include_directory_violations(targets, build_dir.resolve())
    assert len(wrong) == 1 and wrong[0].startswith(f"{target} ") and str(directory) in wrong[0], wrong
