"""docs/controller_api.md is what scripts/controller_api_page.py renders from the code's own
definitions (so it cannot drift from them), and every helper's example on it runs as written."""
import importlib.util
import pathlib

import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]


def page_script():
    spec = importlib.util.spec_from_file_location("controller_api_page", REPO / "scripts" / "controller_api_page.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_page_is_the_rendered_one():
    script = page_script()
    assert script.PAGE.read_text() == script.render(), \
        "docs/controller_api.md is out of date: run .venv/bin/python scripts/controller_api_page.py"


def test_the_page_lists_every_attribute_the_controller_gets():
    from gimbal2axis.scene.controllers import ControllerContext, Measurements

    text = (REPO / "docs" / "controller_api.md").read_text()
    for name in ControllerContext.__slots__ + Measurements.__slots__:
        assert f"| `{name}` |" in text, name
    # the measurements in the order the class stores them: base_attitude is (delta, psi, gamma)
    rows = [line.split("|")[2].strip(" `") for line in text.splitlines() if line.startswith("| 1 |") or
            line[:4] in {f"| {i} " for i in range(2, 10)}]
    assert rows == list(Measurements.__slots__)
    assert "pitch (delta" in text and "yaw (psi" in text and "roll (gamma" in text


@pytest.mark.parametrize("module, function, example", page_script().HELPERS, ids=lambda v: str(v)[:30])
def test_each_helpers_example_runs(module, function, example):
    assert f"from {module} import {function}" in example
    exec(compile(example, f"<example of {function}>", "exec"), {})
