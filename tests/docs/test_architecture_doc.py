"""docs/architecture.md against the code (issue 46.5): its counts, its tables and the paths it names.

- every "<n> continuous states" is GIMBAL_CONTINUOUS_STATES of gimbal_c_api.h, every "<n> event
  indicators" the sum of instances x guards over the ELEMENT rows of switching_elements.def, and
  "There are <n> kinds" the number of those rows;
- the switching-element table has one row per ELEMENT row, in the declaration's order, each with the
  row's guards and its indicators' range (after every kind declared before it);
- the decision order names every declared element once (and, where the registry spells the order out
  in its constructor, in that order);
- the folder table ("What lives where") names every source and header of each layer folder, and
  nothing that is not there;
- every file path the page names outside "Adding a switching element" (which records history, and
  whose derivations another test keeps) is a file of the repository.

Each check is a function of the page's text, so that the tests below also plant a stale claim and see
it refused.
"""
import os
import pathlib
import re

import pytest

# Reads docs and code: its time goes to Python.
pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]
DOC = REPO / "docs" / "architecture.md"
GIMBAL_INCLUDE = REPO / "model_core" / "include" / "gimbal"
CORE_SOURCES = REPO / "model_core" / "src"
DECLARATION = GIMBAL_INCLUDE / "switching_elements.def"
C_API = GIMBAL_INCLUDE / "gimbal_c_api.h"
REGISTRY = CORE_SOURCES / "switching_elements" / "element_registry.cpp"

NUMBER_WORDS = {word: n for n, word in enumerate(
    "zero one two three four five six seven eight nine ten eleven twelve".split())}
ELEMENT_ROW = re.compile(r"^\s*ELEMENT\(\s*(\w+)\s*,\s*(\d+)\s*,\s*(\d+)\s*,", re.MULTILINE)
SOURCE_SUFFIXES = {".c", ".h", ".cpp", ".hpp", ".def"}
# A file path in the page: a name with a source, script or document suffix, with or without folders.
PATH_TOKEN = re.compile(r"(?<![\w./*-])((?:[\w.-]+/)*[\w-]+\.(?:cpp|hpp|c|h|def|py|cmake|md|map))(?![\w/])")
# Named in the page, not in the repository: the standard's header and the build's generated one.
NOT_IN_THE_REPOSITORY = {"fmi2Functions.h", "gimbal_guid.h"}


def declared_elements() -> list[tuple[str, int, int]]:
    """(identifier, instances, guards) of each ELEMENT row, in the declaration's order."""
    text = re.sub(r"//[^\n]*", "", DECLARATION.read_text(encoding="utf-8"))
    rows = [(name, int(instances), int(guards)) for name, instances, guards in ELEMENT_ROW.findall(text)]
    assert rows, f"no ELEMENT row in {DECLARATION}"
    return rows


def continuous_state_count() -> int:
    found = re.search(r"^#define GIMBAL_CONTINUOUS_STATES (\d+)", C_API.read_text(encoding="utf-8"), re.MULTILINE)
    assert found, f"no GIMBAL_CONTINUOUS_STATES in {C_API}"
    return int(found.group(1))


def section(text: str, title: str) -> str:
    """The text of the "## <title>" section, up to the next "## " heading."""
    found = re.search(rf"^## {re.escape(title)}\n(.*?)(?=^## |\Z)", text, re.MULTILINE | re.DOTALL)
    assert found, f"docs/architecture.md has no section '## {title}'"
    return found.group(1)


def table_rows(text: str) -> list[list[str]]:
    """The cells of each body row of the first Markdown table in `text`."""
    lines = [line for line in text.splitlines() if line.startswith("|")]
    return [[cell.strip() for cell in line.strip("|").split("|")] for line in lines[2:]]


def backticked(text: str) -> list[str]:
    return re.findall(r"`([^`]+)`", text)


# ---------------------------------------------------------------- the checks, each a list of what is wrong


def count_problems(text: str) -> list[str]:
    states, elements = continuous_state_count(), declared_elements()
    indicators = sum(instances * guards for _, instances, guards in elements)
    wrong = []
    for pattern, expected, what in ((r"(\d+) continuous states", states, "GIMBAL_CONTINUOUS_STATES"),
                                    (r"(\d+) event indicators", indicators, "the declaration's indicators")):
        stated = [int(n) for n in re.findall(pattern, text)]
        if not stated:
            wrong.append(f"the page states no '{pattern}'")
        wrong += [f"'{n} {pattern.split(' ', 1)[1]}': {what} is {expected}" for n in stated if n != expected]
    kinds = re.findall(r"There are (\w+) kinds", text)
    if not kinds:
        wrong.append("the page states no 'There are <n> kinds'")
    wrong += [f"'There are {word} kinds': switching_elements.def declares {len(elements)}"
              for word in kinds if NUMBER_WORDS.get(word.lower()) != len(elements)]
    return wrong


def element_table_problems(text: str) -> list[str]:
    rows = [row for row in table_rows(section(text, "A switching element")) if row[0].startswith("`")]
    named = [row[0].strip("`") for row in rows]
    expected = [name for name, _, _ in declared_elements()]
    if named != expected:
        return [f"the element table's rows {named} are not the declaration's {expected}"]
    wrong, first = [], 0
    for row, (name, instances, guards) in zip(rows, declared_elements()):
        last = first + instances * guards - 1
        cell = row[5]
        if cell != f"{guards} ({first}-{last})":
            wrong.append(f"{name}: guards '{cell}', declared {guards} ({first}-{last})")
        first = last + 1
    return wrong


def decision_order_problems(text: str) -> list[str]:
    found = re.search(r"decides the modes in dependency order:(.*?)\.(?:\s|$)", text, re.DOTALL)
    if not found:
        return ["the page states no 'decides the modes in dependency order: ...'"]
    declared = {name for name, _, _ in declared_elements()}
    stated = [name for name in backticked(found.group(1)) if name in declared]
    wrong = []
    if sorted(stated) != sorted(declared):
        wrong.append(f"the decision order names {stated}, the declaration {sorted(declared)}")
    spelt = registry_decision_order()
    if spelt is not None and stated != spelt:
        wrong.append(f"the decision order {stated} is not the registry's {spelt} ({REGISTRY.name})")
    return wrong


def registry_decision_order() -> list[str] | None:
    """The kinds in the order the registry's constructor adds them, when it names each declared kind
    (add<ElementKind::name>); None when it derives them (from the declaration, by stage)."""
    declared = {name for name, _, _ in declared_elements()}
    constructor = re.search(r"SwitchingElementSet::SwitchingElementSet\(.*?\n}\n", REGISTRY.read_text(encoding="utf-8"),
                            re.DOTALL)
    spelt = [kind for kind in re.findall(r"add<ElementKind::(\w+)", constructor.group(0) if constructor else "")
             if kind in declared]
    return spelt if sorted(spelt) == sorted(declared) else None


def layer_files(folder: str) -> set[pathlib.Path]:
    return {path for base in (CORE_SOURCES, GIMBAL_INCLUDE) for path in (base / folder).glob("*")
            if path.suffix in SOURCE_SUFFIXES}


def folder_table_problems(text: str) -> list[str]:
    rows = table_rows(section(text, "What lives where"))
    assert rows, "no table in 'What lives where'"
    wrong = []
    listed_folders = set()
    for row in rows:
        folder = row[0].strip("`/")
        listed_folders.add(folder)
        files = layer_files(folder)
        if not files:
            wrong.append(f"the folder table names {folder}/, which has no sources")
            continue
        named = set(backticked(row[1]))
        for name in sorted(named):
            if not any(path.name == name or path.stem == name for path in files):
                wrong.append(f"{folder}/: the table names {name}, which is no file there")
        for path in sorted(files):
            if path.name not in named and path.stem not in named:
                wrong.append(f"{folder}/: {path.relative_to(REPO)} is not in the table")
    layers = {path.name for base in (CORE_SOURCES, GIMBAL_INCLUDE) for path in base.iterdir() if path.is_dir()}
    wrong += [f"the folder table has no row of {layer}/" for layer in sorted(layers - listed_folders)]
    return wrong


def repository_files() -> list[str]:
    """The repository's files as paths relative to it (no build, virtual environment or VCS folders)."""
    files = []
    for root, folders, names in os.walk(REPO):
        folders[:] = [f for f in folders if not f.startswith((".", "build", "__pycache__"))]
        relative = pathlib.Path(root).relative_to(REPO)
        files += [(relative / name).as_posix() for name in names]
    return files


def path_problems(text: str, files: list[str]) -> list[str]:
    """Every path token of `text` that no repository file is, or ends with (at a folder boundary)."""
    names = {pathlib.PurePosixPath(f).name for f in files}
    wrong = []
    for token in sorted(set(PATH_TOKEN.findall(text))):
        token = token.removeprefix("sources/")   # the source FMU's folder keeps the core's layer folders
        if token in NOT_IN_THE_REPOSITORY:
            continue
        if "/" not in token:
            found = token in names
        else:
            found = any(f == token or f.endswith("/" + token) for f in files)
        if not found:
            wrong.append(f"the page names {token}, which is no file of the repository")
    return wrong


def checked_for_paths(text: str) -> str:
    """The page without the section "Adding a switching element" (with its subsections): it records
    what an addition touched then, files that may since have been renamed."""
    return re.sub(r"^## Adding a switching element\n.*?(?=^## |\Z)", "", text, flags=re.MULTILINE | re.DOTALL)


# ---------------------------------------------------------------- the tests


@pytest.fixture(scope="module")
def page() -> str:
    return DOC.read_text(encoding="utf-8")


def test_the_counts_are_the_codes(page):
    assert count_problems(page) == []


def test_the_element_table_is_the_declaration(page):
    assert element_table_problems(page) == []


def test_the_decision_order_names_every_element(page):
    assert decision_order_problems(page) == []


def test_the_folder_table_names_every_file_of_each_layer(page):
    assert folder_table_problems(page) == []


def test_every_path_the_page_names_exists(page):
    assert path_problems(checked_for_paths(page), repository_files()) == []


@pytest.mark.parametrize("stale, replacement, check", [
    ("19 continuous states", "17 continuous states", count_problems),
    ("42 event indicators", "36 event indicators", count_problems),
    ("There are six kinds", "There are five kinds", count_problems),
    ("| 2 (38-41) |", "| 2 (38-40) |", element_table_problems),
    ("| `amplifier_saturation` |", "| `amplifier` |", element_table_problems),
    (", `axis_stop`, `amplifier_saturation`, `element_registry` |", ", `axis_stop`, `element_registry` |",
     folder_table_problems),
    ("`probe_api.cpp`, `fmu_model_table.cpp`,", "`probe_api.cpp`, `fmu_table.cpp`,", folder_table_problems),
])
def test_a_stale_claim_is_refused(page, stale, replacement, check):
    """Each check on the page with one claim made stale (the count before the amplifier, a missing row
    or file, a file that does not exist)."""
    assert stale in page, stale
    assert check(page.replace(stale, replacement, 1)) != []


def test_a_decision_order_without_an_element_is_refused(page):
    found = re.search(r"decides the modes in dependency order:(.*?)\.(?:\s|$)", page, re.DOTALL)
    without = page.replace(found.group(1), found.group(1).replace("`amplifier_saturation`", "the amplifiers"), 1)
    assert decision_order_problems(without) != []
    swapped = page.replace(found.group(1), found.group(1).replace("`gear_backlash`", "`GEAR`")
                           .replace("`elevation_stop`", "`gear_backlash`").replace("`GEAR`", "`elevation_stop`"), 1)
    assert (decision_order_problems(swapped) != []) == (registry_decision_order() is not None)


def test_a_path_of_no_file_is_refused():
    files = ["model_core/src/simulation/fmu_model_table.cpp", "fmu_src/fmi_layer/fmu_state.c"]
    assert path_problems("`simulation/fmu_model_table.cpp`, `fmi_layer/fmu_state.c`, fmu_state.c", files) == []
    assert len(path_problems("`fmu_src/gimbal_fmu/gimbal_model.h` and gimbal_variables.c", files)) == 2
