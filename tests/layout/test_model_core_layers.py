"""model_core's layers include one way (docs/architecture.md, "The layers"): every `#include "..."` of a
header or source under model_core/include/gimbal/ and model_core/src/ is resolved to the file it names,
and a file may include only files of its own layer or of a lower one. The order is the one
docs/architecture.md states, so that the page and this test cannot drift apart."""
import pathlib
import re

import pytest

pytestmark = pytest.mark.python_bound

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORE = ROOT / "model_core"
ARCHITECTURE = ROOT / "docs" / "architecture.md"

# Bottom to top. A layer is a folder of include/gimbal/ and src/, except model/variables.hpp (the
# variable tables' enumerations, in the shared base) and model/model_types.hpp: the
# parameter, state and mode types sit below the switching elements (which read them), the dynamics
# of model/ above (which call the elements). The files at include/gimbal/ itself (the C interface,
# the variable tables, function_ref.hpp, hot_path.hpp) are the shared base: they include no layer.
LAYERS = ["shared", "multibody", "model/model_types.hpp", "switching_elements", "model", "hybrid_system",
          "integrators", "simulation"]
RANK = {layer: rank for rank, layer in enumerate(LAYERS)}

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)


def layer_of(path: pathlib.Path, core: pathlib.Path = CORE) -> str:
    """The layer of a file under core/include/gimbal/ or core/src/."""
    for base in (core / "include" / "gimbal", core / "src"):
        if base in path.parents:
            parts = path.relative_to(base).parts
            if len(parts) == 1:
                return "shared"
            if parts[:2] == ("model", "variables.hpp"):   # the .def tables' enumerations: no layer included
                return "shared"
            if parts[:2] == ("model", "model_types.hpp"):
                return "model/model_types.hpp"
            if parts[0] not in RANK:
                raise ValueError(f"{path}: folder {parts[0]} is no layer of {LAYERS}")
            return parts[0]
    raise ValueError(f"{path} is not under {core}/include/gimbal or {core}/src")


# The FMU's model table (simulation/fmu_model_table.cpp, compiled into the FMU only) includes the FMI
# layer's headers and the build's GUID header besides the core's: those are no layer of the core
# (tests/layout/test_include_directions.py keeps which it may include).
FMU_MODEL_TABLE_OUTSIDE = re.compile(r"^(fmi_layer/[\w.]+\.h|gimbal_guid\.h)$")


def resolve(included: str, includer: pathlib.Path, core: pathlib.Path = CORE) -> pathlib.Path | None:
    """The file an `#include "included"` in `includer` names: beside the includer first (as the
    compiler looks), then on the core's include path; None for the FMU model table's headers of the FMI
    layer."""
    for candidate in (includer.parent / included, core / "include" / included):
        if candidate.is_file():
            return candidate.resolve()
    if includer.name == "fmu_model_table.cpp" and FMU_MODEL_TABLE_OUTSIDE.match(included):
        return None
    raise FileNotFoundError(f"{includer}: #include \"{included}\" names no file of {core}")


def upward_includes(core: pathlib.Path = CORE) -> list[str]:
    """Every include of a higher layer in the core at `core`, as 'file:line: layer includes file (layer)'."""
    sources = sorted(p for folder in (core / "include" / "gimbal", core / "src") for p in folder.rglob("*")
                     if p.suffix in {".h", ".hpp", ".c", ".cpp", ".def"})
    assert sources, f"no sources under {core}"
    broken = []
    for source in sources:
        text = source.read_text()
        own = layer_of(source, core)
        for match in INCLUDE.finditer(text):
            target = resolve(match.group(1), source, core)
            if target is None:
                continue
            theirs = layer_of(target, core)
            if RANK[theirs] > RANK[own]:
                line = text.count("\n", 0, match.start()) + 1
                broken.append(f"{source.relative_to(core)}:{line}: {own} includes {match.group(1)} ({theirs})")
    return broken


def test_no_layer_includes_a_higher_one():
    assert upward_includes() == []


def test_a_planted_upward_include_is_caught(tmp_path):
    """The checker on a small tree of the core's shape: an integrator header including the hybrid system
    passes; an event-handling source including the integrators (issue 35's crossing) is caught."""
    core = tmp_path / "model_core"
    for relative in ("include/gimbal/integrators/integrator.hpp", "include/gimbal/hybrid_system/hybrid_system.hpp",
                     "src/hybrid_system/event_handling.cpp"):
        (core / relative).parent.mkdir(parents=True, exist_ok=True)
        (core / relative).write_text("")
    (core / "include/gimbal/integrators/integrator.hpp").write_text('#include "gimbal/hybrid_system/hybrid_system.hpp"\n')
    assert upward_includes(core) == []
    (core / "src/hybrid_system/event_handling.cpp").write_text(
        '#include "gimbal/hybrid_system/hybrid_system.hpp"\n#include "gimbal/integrators/integrator.hpp"\n')
    assert upward_includes(core) == [
        "src/hybrid_system/event_handling.cpp:2: hybrid_system includes gimbal/integrators/integrator.hpp (integrators)"]


def test_an_include_of_no_file_is_refused(tmp_path):
    """A misspelt include would otherwise be skipped, and the direction it breaks unseen."""
    core = tmp_path / "model_core"
    (core / "src" / "model").mkdir(parents=True)
    (core / "include" / "gimbal").mkdir(parents=True)
    (core / "src" / "model" / "jacobian.cpp").write_text('#include "gimbal/model/no_such_header.hpp"\n')
    with pytest.raises(FileNotFoundError):
        upward_includes(core)


def test_the_architecture_page_states_this_order():
    """docs/architecture.md's line "Layer order, bottom to top: ..." names the layers above the shared
    base in this order."""
    stated = re.search(r"^Layer order, bottom to top: (.+?)\.$", ARCHITECTURE.read_text(), re.MULTILINE)
    assert stated, "docs/architecture.md has no line 'Layer order, bottom to top: ...'"
    named = [name.strip("`/") for name in re.findall(r"`[^`]+`", stated.group(1))]
    assert named == LAYERS[1:]
