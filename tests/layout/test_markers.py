"""The markers that keep tests out of the sanitizer pass (tests/README.md): the pass's -m expression in
scripts/test.sh names only registered markers, each of them on some test file. pytest itself refuses an
unregistered marker on a test (--strict-markers in pyproject.toml), but not in an -m expression, where a
misspelt or renamed one would silently select every test."""
import ast
import pathlib
import re
import tomllib

import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]
BUILTIN = {"parametrize", "skip", "skipif", "xfail", "usefixtures", "filterwarnings"}


def registered() -> set[str]:
    options = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["pytest"]["ini_options"]
    assert "--strict-markers" in options["addopts"].split()
    return {line.split(":")[0].strip() for line in options["markers"]}


def sanitizer_expression() -> str:
    script = (REPO / "scripts" / "test.sh").read_text(encoding="utf-8")
    (expression,) = re.findall(r'-m "([^"]+)"', script)
    return expression


def markers_used(path: pathlib.Path) -> set[str]:
    """The pytest.mark.<name> of a test file, at module level or on a test."""
    return {node.attr for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Attribute)
            and node.value.attr == "mark" and isinstance(node.value.value, ast.Name) and node.value.value.id == "pytest"}


def test_the_sanitizer_pass_names_only_registered_markers_each_on_a_test_file():
    expression = sanitizer_expression()
    names = set(re.findall(r"\b(?!not\b|and\b|or\b)\w+", expression))
    assert names, expression
    assert names <= registered(), f"{expression!r} names {sorted(names - registered())}, not registered"
    used = set().union(*(markers_used(path) for path in (REPO / "tests").rglob("test_*.py")))
    assert names <= used, f"no test file carries {sorted(names - used)}"


def test_every_marker_a_test_uses_is_builtin_or_registered():
    unknown = {f"{path.relative_to(REPO)}: {name}" for path in (REPO / "tests").rglob("test_*.py")
               for name in markers_used(path) - BUILTIN - registered()}
    assert unknown == set()
