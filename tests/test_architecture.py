"""The layout's rules (README.md, 'Layout'), checked on the source: data flows one way,
no import cycle, planning meets identification only at the torque-model interface, package
roots import nothing, the paper's reproduction (harness.paper) is imported by nothing
outside it (the product names it lazily: harness.robots.extras, harness.studies), modules
stay small."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("harness", "identification", "planning", "models")
MAX_LINES = 300  # modules stay small


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


MODULES = _modules()


def _imports(path: Path) -> set[str]:
    """Project modules imported anywhere in the file (top level or inside functions)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        found.update(n for n in names if n in MODULES)
    return found


GRAPH = {name: _imports(path) for name, path in MODULES.items()}


def test_the_layout_exists():
    for pkg in ("harness.robots", "harness.data", "harness.identify", "harness.plan",
                "harness.replay", "harness.closeloop", "harness.report", "harness.bench",
                "harness.studies", "harness.paper", "harness.robots.arm",
                "identification.library", "identification.regression",
                "identification.closeloop", "identification.torque_model"):
        assert pkg in MODULES, pkg


@pytest.mark.parametrize("pkg", ["identification", "planning"])
def test_identification_and_planning_never_import_harness(pkg):
    bad = {m: sorted(i for i in deps if i.split(".")[0] == "harness")
           for m, deps in GRAPH.items() if m.split(".")[0] == pkg}
    assert not {m: d for m, d in bad.items() if d}


def test_planning_imports_only_the_torque_model_interface_of_identification():
    used = {i for m, deps in GRAPH.items() if m.split(".")[0] == "planning"
            for i in deps if i.split(".")[0] == "identification"}
    assert used <= {"identification.torque_model"}, used


def test_package_roots_load_nothing():
    """Importing identification.torque_model must not load the rest of identification."""
    for pkg in ("identification", "planning", "harness.paper"):
        assert not GRAPH[pkg], (pkg, GRAPH[pkg])


def test_nothing_outside_the_paper_imports_it():
    bad = {m: sorted(i for i in deps if i.startswith("harness.paper"))
           for m, deps in GRAPH.items() if not m.startswith("harness.paper")}
    assert not {m: d for m, d in bad.items() if d}


def test_no_import_cycle():
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for dep in GRAPH[node]:
            if state.get(dep) == 1:
                cycle = stack[stack.index(dep):] + [dep]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if dep not in state:
                visit(dep)
        stack.pop()
        state[node] = 2

    for name in sorted(GRAPH):
        if name not in state:
            visit(name)


def test_modules_stay_small():
    big = {str(p.relative_to(ROOT)): n for p in MODULES.values()
           if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not big
