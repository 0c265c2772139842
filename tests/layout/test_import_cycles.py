"""No two modules of the package import each other, directly or through others: every import
statement counts, at module level or inside a function (an import moved into a function only hides a
cycle; it does not remove it).

The graph: module -> every package module its imports name. `from X import y` names X.y when that is
a module, else X (a package's __init__ too); the parent packages a dotted name passes through are not
counted (Python runs their __init__ first, without coming back to the importer)."""
from __future__ import annotations

import ast
import pathlib

import pytest

# Parses the package's modules: its time goes to Python.
pytestmark = pytest.mark.python_bound

PACKAGE = pathlib.Path(__file__).resolve().parents[2] / "gimbal2axis"


def package_modules(root: pathlib.Path) -> dict:
    """{dotted name: (path, is a package's __init__)} of every module under `root`."""
    modules = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        modules[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return modules


def imported(module: str, is_package: bool, source: str, modules: dict) -> set:
    """The package modules `source` (of `module`) imports, anywhere in it."""
    names = set()
    here = module.split(".") if is_package else module.split(".")[:-1]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names if alias.name in modules)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = here[:len(here) - (node.level - 1)]
                base = ".".join(anchor + ([node.module] if node.module else []))
            for alias in node.names:
                name = f"{base}.{alias.name}"
                if name in modules:
                    names.add(name)
                elif base in modules:
                    names.add(base)
    return names - {module}


def import_graph(root: pathlib.Path) -> dict:
    modules = package_modules(root)
    return {module: imported(module, is_package, path.read_text(encoding="utf-8"), modules)
            for module, (path, is_package) in modules.items()}


def cycles(graph: dict) -> list:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(start):
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, successors = work[-1]
            for successor in successors:
                if successor not in index:
                    index[successor] = low[successor] = len(index)
                    stack.append(successor)
                    on_stack.add(successor)
                    work.append((successor, iter(sorted(graph[successor]))))
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index[successor])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))

    for module in sorted(graph):
        if module not in index:
            visit(module)
    return sorted(found)


def test_the_package_has_no_import_cycle():
    found = cycles(import_graph(PACKAGE))
    assert found == [], "modules that import each other (directly or through others):\n" + \
        "\n".join(" <-> ".join(component) for component in found)


def write_package(root: pathlib.Path, files: dict) -> pathlib.Path:
    package = root / "pkg"
    for name, source in files.items():
        path = package / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(source)
    return package


@pytest.mark.parametrize("files, expected", [
    # module level, relative
    ({"__init__.py": "", "a.py": "from .b import f\n", "b.py": "from . import a\n"}, [["pkg.a", "pkg.b"]]),
    # one side inside a function, absolute: still a cycle
    ({"__init__.py": "", "a.py": "import pkg.b\n", "b.py": "def g():\n    from pkg.a import f\n"},
     [["pkg.a", "pkg.b"]]),
    # through a third module and a subpackage
    ({"__init__.py": "", "a.py": "from .sub import c\n", "sub/__init__.py": "", "sub/c.py": "from ..b import x\n",
      "b.py": "def g():\n    from .a import y\n"}, [["pkg.a", "pkg.b", "pkg.sub.c"]]),
    # one way only
    ({"__init__.py": "from .a import f\n", "a.py": "from .b import g\n", "b.py": "import os\n"}, []),
])
def test_the_check_finds_a_cycle(tmp_path, files, expected):
    assert cycles(import_graph(write_package(tmp_path, files))) == expected
