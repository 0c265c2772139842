"""The physics page (docs/physics.md), its figures, and the documentation the FMU carries.

- The built FMU has documentation/index.html (FMI 2.0's entry point) whose links and images all
  resolve inside the archive's documentation/ folder, made from this checkout's docs/physics.md, and
  an icon model.png of a sensible size.
- Every equation number the variable descriptions cite, e.g. "(2.81)", is in the page's table of
  equation numbers, so the table cannot go stale when descriptions change.
- The figures' script runs, and user-facing files point to docs/physics.md, not to files outside
  the repository.
"""
import html.parser
import importlib.util
import pathlib
import posixpath
import re
import struct
import subprocess
import sys
import zipfile

import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]
PHYSICS = REPO / "docs" / "physics.md"
DEF_FILES = sorted((REPO / "model_core" / "include" / "gimbal").glob("*_variables.def"))
# "2.81", or a range "2.94-2.97" / "2.63 - 2.69" / "2.142–2.145"
EQUATION = re.compile(r"(?<![\d.])2\.(\d{1,3})(?![\d])(?:\s*[-–]\s*2\.(\d{1,3})(?![\d]))?")


def _load_converter():
    spec = importlib.util.spec_from_file_location("markdown_to_html", REPO / "scripts" / "markdown_to_html.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG file"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


class _Page(html.parser.HTMLParser):
    """Ids, link targets and image sources of a page, and whether its elements nest properly."""
    VOID = {"meta", "img", "br", "hr", "link", "input"}

    def __init__(self):
        super().__init__()
        self.ids, self.hrefs, self.srcs, self.stack, self.errors = set(), [], [], [], []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        if tag == "a" and "href" in attrs:
            self.hrefs.append(attrs["href"])
        if tag == "img":
            self.srcs.append(attrs.get("src", ""))
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:] or 'nothing'}")
        else:
            self.stack.pop()


@pytest.fixture(scope="module")
def archive(fmu_path):
    with zipfile.ZipFile(fmu_path) as z:
        yield {name: z.read(name) for name in z.namelist() if not name.endswith("/")}


def test_fmu_documentation_entry_point_and_its_links_resolve_inside_the_archive(archive):
    assert "documentation/index.html" in archive, sorted(archive)
    page = _Page()
    page.feed(archive["documentation/index.html"].decode("utf-8"))
    page.close()
    assert page.errors == [] and page.stack == [], (page.errors, page.stack)
    assert page.srcs, "the page shows no figure"
    assert len(page.hrefs) > 10
    for target in page.hrefs + page.srcs:
        if target.startswith("#"):
            assert target[1:] in page.ids, f"link to {target}, which is no id of the page"
            continue
        assert not re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) and not target.startswith("/"), \
            f"{target}: documentation must link only into the archive"
        resolved = posixpath.normpath(posixpath.join("documentation", target.split("#")[0]))
        assert resolved.startswith("documentation/"), f"{target} leaves documentation/"
        assert resolved in archive, f"{target} is not in the archive"
    for src in page.srcs:
        width, height = png_size(archive[posixpath.normpath(posixpath.join("documentation", src))])
        assert width >= 300 and height >= 200, (src, width, height)


def test_fmu_documentation_is_this_checkouts_physics_page(archive, tmp_path):
    """The build converted docs/physics.md as it is now (ninja rebuilds it when the page changes)."""
    converter = _load_converter()
    body = converter.Converter(PHYSICS, tmp_path).convert(PHYSICS.read_text(encoding="utf-8"))
    packaged = archive["documentation/index.html"].decode("utf-8")
    # The packaged page inserts a subtitle after the title; compare what follows it.
    assert body.split("</h1>", 1)[1].strip() in packaged


def test_the_fmu_carries_the_licences_of_the_code_in_its_binaries(archive):
    # the project's own, SUNDIALS' (linked statically into linux64) and Eigen's (compiled into every
    # binary): BSD-3-Clause, BSD-3-Clause, MPL-2.0
    licences = {name.rsplit("/", 1)[-1]: data.decode("utf-8", "replace")
                for name, data in archive.items() if name.startswith("documentation/licenses/")}
    assert (REPO / "LICENSE").read_text() == licences["Gimbal2Axis.txt"]
    assert "Redistribution and use in source and binary forms" in licences["SUNDIALS.txt"]
    assert "Mozilla Public License" in licences["Eigen.txt"]


def test_fmu_icon_is_a_png_of_sensible_size(archive):
    assert "model.png" in archive
    width, height = png_size(archive["model.png"])
    assert 64 <= width <= 512 and 64 <= height <= 512, (width, height)
    assert max(width, height) <= 1.5 * min(width, height), (width, height)


def _expand(match: re.Match) -> set[int]:
    first = int(match.group(1))
    last = int(match.group(2)) if match.group(2) else first
    assert first <= last, match.group(0)
    return set(range(first, last + 1))


def _cited_equations() -> dict[int, list[str]]:
    """Equation number -> the variables whose descriptions cite it."""
    cited: dict[int, list[str]] = {}
    for path in DEF_FILES:
        for line in path.read_text(encoding="utf-8").splitlines():
            if not line.startswith("X("):
                continue
            name = re.match(r'X\(\w+,\s*"([^"]+)"', line).group(1)
            description = re.search(r'"((?:[^"\\]|\\.)*)"\s*\)\s*$', line).group(1)
            for match in EQUATION.finditer(description):
                for number in _expand(match):
                    cited.setdefault(number, []).append(name)
    return cited


def _table_equations() -> set[int]:
    text = PHYSICS.read_text(encoding="utf-8")
    section = text.split("\n## 8. Equation numbers", 1)[1].split("\n## ", 1)[0]
    numbers: set[int] = set()
    for row in section.splitlines():
        if row.startswith("| 2."):
            first_cell = row.split("|")[1]
            matches = list(EQUATION.finditer(first_cell))
            assert matches, row
            for match in matches:
                overlap = numbers & _expand(match)
                assert not overlap, f"equations {sorted(overlap)} appear in two rows of the table"
                numbers |= _expand(match)
    return numbers


def test_every_equation_cited_in_the_variable_descriptions_is_in_the_physics_table():
    cited = _cited_equations()
    assert {59, 81, 104} <= set(cited), "the .def descriptions were expected to cite equations"
    table = _table_equations()
    missing = {f"2.{n}": names for n, names in sorted(cited.items()) if n not in table}
    assert not missing, f"cited in variable descriptions but not in docs/physics.md's table: {missing}"


def test_the_physics_table_covers_every_equation_of_the_chapter():
    assert _table_equations() == set(range(1, 146))


def test_the_figure_script_draws_the_figures_and_the_icon(tmp_path):
    done = subprocess.run([sys.executable, str(REPO / "scripts" / "draw_gimbal_frames.py"), "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert png_size((tmp_path / "model.png").read_bytes()) == (256, 256)
    for name in ("gimbal_frames.png", "drive_train.png"):
        fresh = png_size((tmp_path / name).read_bytes())
        committed = png_size((REPO / "docs" / "figures" / name).read_bytes())
        assert fresh == committed, f"docs/figures/{name} is {committed}, the script draws {fresh}: rerun it"


@pytest.mark.parametrize("markdown, message", [
    ("- item\n  - nested\n", "nested lists"),
    ("See [there](#nowhere).\n", "no heading"),
    ("> quoted\n", "unsupported"),
    ("a * b\n", "'*'"),
    ("| a | b |\n|---|---|\n| 1 |\n", "cells"),
])
def test_the_converter_refuses_what_it_cannot_render(tmp_path, markdown, message):
    converter = _load_converter()
    page = tmp_path / "page.md"
    page.write_text("# Title\n\n" + markdown, encoding="utf-8")
    with pytest.raises(converter.MarkdownError, match=re.escape(message)):
        converter.convert_file(page, tmp_path / "out" / "index.html", "t")


def test_user_facing_files_point_to_the_physics_page_not_outside_the_repository():
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert "docs/physics.md" in readme
    files = [REPO / "README.md", *(REPO / "docs").glob("*.md"), *(REPO / "scripts").rglob("*.py"),
             *(REPO / "gimbal2axis").rglob("*.py"),
             *(REPO / "examples").glob("*"), *(REPO / "scenes").glob("*.toml")]
    offenders = [str(f.relative_to(REPO)) for f in files
                 if f.is_file() and re.search(r"shared/(spec|seed)", f.read_text(encoding="utf-8", errors="replace"))]
    assert offenders == [], f"references to files outside the repository: {offenders}"


# How the pages state the number of event indicators, and what each says it is, from the count n.
EVENT_INDICATOR_CLAIMS = {
    r"(\d+) (?:scalar )?event indicators": lambda n: n,
    r"event indicators \((\d+)": lambda n: n,
    r'numberOfEventIndicators="(\d+)"': lambda n: n,
    r"the (\d+) `<EventIndicator>`s": lambda n: n,
    r"3002 \.\. (\d+)": lambda n: 3001 + n,   # FMI 3.0's value references of the indicators
}


def test_every_page_states_the_event_indicator_count_of_the_built_model_descriptions(fmu_path, build_dir):
    """The count is the generator's (model_core's switching_elements.def, docs/architecture.md): the
    pages are checked against the model descriptions the build wrote, so no number goes stale."""
    from fmpy import read_model_description
    count = read_model_description(str(fmu_path)).numberOfEventIndicators
    fmi3 = read_model_description(str(build_dir / "Gimbal2Axis-fmi3.fmu"))
    indicators = [v for v in fmi3.modelVariables if v.name.startswith("event_indicators[")]
    assert len(fmi3.eventIndicators) == len(indicators) == count
    assert [v.valueReference for v in indicators] == list(range(3002, 3002 + count))
    wrong, stated = [], 0
    for page in sorted((REPO / "docs").glob("*.md")):
        text = " ".join(page.read_text(encoding="utf-8").split())   # a claim may span lines
        for pattern, expected in EVENT_INDICATOR_CLAIMS.items():
            for match in re.finditer(pattern, text):
                stated += 1
                if int(match.group(1)) != expected(count):
                    wrong.append(f"{page.name}: '{match.group(0)}' (the build's: {expected(count)})")
        for index in re.findall(r"`event_indicators\[(\d+)\]`", text):
            stated += 1
            if int(index) not in (1, count):
                wrong.append(f"{page.name}: `event_indicators[{index}]` (the last is [{count}])")
    assert wrong == [], wrong
    assert stated >= 8   # the pages do state it (fmi_interfaces.md, interface.md, fmi_behaviour.md)
