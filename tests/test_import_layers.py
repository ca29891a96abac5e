"""The package's import graph keeps its layers: no module imports itself back through
others (every import counts: module level, inside functions, and under TYPE_CHECKING),
the JCCL layer does not reach into the input manager or anything built on it, and only
the command-line layer imports typer and rich.

The graph is read from the sources with ``ast``; nothing is imported.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "gadgetctl"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported_names(path: Path, module: str) -> set[str]:
    """Every module name an import statement of ``path`` can refer to (``from a import b``
    gives ``a`` and ``a.b``, since ``b`` may be a submodule)."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                origin = ".".join(base + ([node.module] if node.module else []))
            else:
                origin = node.module or ""
            names.add(origin)
            names.update(f"{origin}.{alias.name}" for alias in node.names)
    return names


def import_graph() -> dict[str, set[str]]:
    modules = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    return {
        name: {m for m in imported_names(path, name) if m in modules and m != name}
        for name, path in modules.items()
    }


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
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
    return found


def test_the_cycle_finder_finds_a_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(graph) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_relative_imports_are_resolved(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("from . import sibling\nfrom .sub import thing\n", encoding="utf-8")
    assert imported_names(module, "pkg.m") == {"pkg", "pkg.sibling", "pkg.sub", "pkg.sub.thing"}


def test_no_import_cycles():
    graph = import_graph()
    assert len(graph) > 100  # the whole package was read
    assert cycles(graph) == []


FORBIDDEN_BELOW = {
    # layer: packages it must not import (they build on it)
    "gadgetctl.jccl": (
        "gadgetctl.input",
        "gadgetctl.monitor",
        "gadgetctl.doctor",
        "gadgetctl.scaffold",
        "gadgetctl.cli",
    ),
    "gadgetctl.diagnostics": (
        "gadgetctl.jccl",
        "gadgetctl.input",
        "gadgetctl.monitor",
        "gadgetctl.cli",
    ),
    "gadgetctl.input": ("gadgetctl.monitor", "gadgetctl.doctor", "gadgetctl.cli"),
}


def test_lower_layers_do_not_import_higher_ones():
    graph = import_graph()
    wrong = sorted(
        f"{module} imports {target}"
        for layer, forbidden in FORBIDDEN_BELOW.items()
        for module, targets in graph.items()
        if module == layer or module.startswith(layer + ".")
        for target in targets
        if any(target == f or target.startswith(f + ".") for f in forbidden)
    )
    assert wrong == []


def test_only_the_cli_imports_typer_and_rich():
    wrong = []
    for path in PACKAGE.rglob("*.py"):
        name = module_name(path)
        if name.startswith("gadgetctl.cli"):
            continue
        roots = {n.split(".")[0] for n in imported_names(path, name)}
        wrong.extend(f"{name} imports {lib}" for lib in ("typer", "rich") if lib in roots)
    assert wrong == []


def test_one_suggestion_helper():
    """ "Did you mean" comes from gadgetctl.suggest everywhere (validate, the commands)."""

    def suggests(path: Path) -> bool:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        return any(
            (isinstance(node, ast.Name) and node.id == "get_close_matches")
            or (isinstance(node, ast.Attribute) and node.attr == "get_close_matches")
            or (isinstance(node, ast.alias) and node.name == "get_close_matches")
            for node in ast.walk(tree)
        )

    users = sorted(module_name(path) for path in PACKAGE.rglob("*.py") if suggests(path))
    assert users == ["gadgetctl.suggest"]
