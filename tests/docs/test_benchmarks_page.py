"""docs/benchmarks.md is what scripts/benchmarks_page.py writes from benchmarks/page_template.md and the
committed results files (so no figure on it is typed by hand or older than its file); its tables
follow their files; every benchmark script is on it; and every section other files cite by name is
there."""
import importlib.util
import json
import pathlib
import re
import shutil

import pytest

# Reads results files and renders a page: its time goes to Python.
pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]
PAGE = REPO / "docs" / "benchmarks.md"


def page_script():
    spec = importlib.util.spec_from_file_location("benchmarks_page", REPO / "scripts" / "benchmarks_page.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_page_is_the_rendered_one():
    assert PAGE.read_text() == page_script().render(), \
        "docs/benchmarks.md is out of date: run .venv/bin/python scripts/benchmarks_page.py"


@pytest.mark.parametrize("name, path, value, shown", [
    ("results.json", ("at_target_error", 0, "rtf"), 123456.0, "| 120,000 |"),
    ("scene_runner.json", ("python", "real_time_factor_cpu"), 54321.0, "| 54,000 |"),
    ("record_cost.json", ("runs", "memory", "peak_rss_mb"), 987.6, "| 988 |"),
    ("current_drive.json", ("variants", "voltage", "counters", "solver.steps"), 4242424, "| 4,242,424 |"),
])
def test_a_table_shows_what_its_file_says(tmp_path, name, path, value, shown):
    """A figure changed in a results file changes the page: the tables are read, not written."""
    for file in (REPO / "benchmarks" / "results").glob("*.json"):
        shutil.copy(file, tmp_path)
    data = json.loads((tmp_path / name).read_text())
    node = data
    for key in path[:-1]:
        node = node[key]
    assert shown not in page_script().render(folder=tmp_path)
    node[path[-1]] = value
    (tmp_path / name).write_text(json.dumps(data))
    assert shown in page_script().render(folder=tmp_path)


def test_the_template_uses_every_table_once_and_no_unknown_one():
    script = page_script()
    with pytest.raises(ValueError, match="unknown"):
        script.render(script.TEMPLATE.read_text() + "\n{{no_such_table}}\n")
    with pytest.raises(ValueError, match="unused"):
        script.render(script.TEMPLATE.read_text().replace("{{record_cost}}", ""))


def test_every_benchmark_script_is_on_the_page():
    text = PAGE.read_text()
    scripts = [p for p in (REPO / "benchmarks").iterdir() if p.suffix in {".py", ".sh"}]
    missing = [p.name for p in scripts if f"benchmarks/{p.name}" not in text]
    assert scripts and not missing, f"benchmarks without their command on docs/benchmarks.md: {missing}"


def _cited_sections() -> set[str]:
    """Section names other files cite as docs/benchmarks.md ("Name") or docs/benchmarks.md, "Name"."""
    cited = set()
    folders = ["docs", "tests", "gimbal2axis", "scripts", "benchmarks", "model_core", "fmu_src", "c_kernel"]
    files = [REPO / "README.md", *(p for folder in folders for p in (REPO / folder).rglob("*")
                                   if p.suffix in {".md", ".py", ".cpp", ".hpp", ".c", ".h"})]
    for path in files:
        if path in (PAGE, pathlib.Path(__file__).resolve()):
            continue
        # comments broken over lines: join them, without their comment markers
        text = re.sub(r"\s*\n\s*(?://|#)?\s*", " ", path.read_text(encoding="utf-8", errors="replace"))
        cited.update(re.findall(r'benchmarks\.md`?(?: \(|, )"([^"]{3,80})"', text))
    return cited


def test_every_section_cited_elsewhere_is_on_the_page():
    headings = [line.lstrip("#").strip() for line in PAGE.read_text().splitlines() if line.startswith("#")]
    cited = _cited_sections()
    assert len(cited) >= 4   # the physics page, the speed page, the switch rule's code, the allocation test
    missing = [name for name in cited if not any(heading.startswith(name) for heading in headings)]
    assert not missing, f"cited sections not on docs/benchmarks.md: {missing}"
