"""The package's modules import each other one way only: every import between them —
at module level, inside a function, or under ``TYPE_CHECKING`` — points down a DAG, so
that no module needs another that needs it back (``client.py`` used to import ``axis``,
``jog``, ``signal`` and ``remote``, each of which imported ``client``)."""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Dict, List, Optional, Set

import motiond

PACKAGE = Path(motiond.__file__).resolve().parent


def imports_of(path: Path) -> Set[str]:
    """The package modules ``path`` imports (relative imports and ``motiond.x``), anywhere
    in the file."""
    found: Set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1 and node.module:
                found.add(node.module.split(".")[0])
            elif node.level == 1:
                found.update(alias.name for alias in node.names)
            elif node.level == 0 and (node.module or "").startswith("motiond."):
                found.add(node.module.split(".")[1])
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("motiond."):
                    found.add(alias.name.split(".")[1])
    return found


def graph() -> Dict[str, Set[str]]:
    modules = {path.stem: path for path in PACKAGE.glob("*.py") if path.stem != "__init__"}
    return {name: imports_of(path) & set(modules) for name, path in modules.items()}


def find_cycle(edges: Dict[str, Set[str]]) -> Optional[List[str]]:
    """A cycle of ``edges`` as the list of its modules, or ``None``."""
    state: Dict[str, int] = {}  # 1: on the current path, 2: done
    path: List[str] = []

    def visit(module: str) -> Optional[List[str]]:
        state[module] = 1
        path.append(module)
        for imported in sorted(edges[module]):
            if state.get(imported) == 1:
                return path[path.index(imported) :] + [imported]
            if imported not in state:
                cycle = visit(imported)
                if cycle:
                    return cycle
        path.pop()
        state[module] = 2
        return None

    for module in sorted(edges):
        if module not in state:
            cycle = visit(module)
            if cycle:
                return cycle
    return None


def test_the_package_imports_form_a_dag() -> None:
    edges = graph()
    assert {"client", "axis", "jog", "signal", "remote", "session"} <= set(edges)
    cycle = find_cycle(edges)
    assert cycle is None, "import circle: " + " -> ".join(cycle or [])


def test_the_handles_know_their_client_only_as_a_session() -> None:
    edges = graph()
    for handle in ("axis", "jog", "signal", "session"):
        assert "client" not in edges[handle], f"{handle}.py imports client.py"
        assert "remote" not in edges[handle], f"{handle}.py imports remote.py"
    assert "remote" not in edges["client"], "client.py imports remote.py"


def test_the_cycle_finder_finds_a_circle() -> None:
    # The finder itself: a circle of three and a self-import are found, a DAG is not.
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"a"}}) == ["a", "a"]
    assert find_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None
