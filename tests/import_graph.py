"""The import graph of the toolkit's packages, read from the source with :mod:`ast` (nothing is imported).

Each ``import`` statement is an edge from the module that holds it to the module it loads, and
is sorted by where it stands:

- ``module``: executed when the module is imported (top level, class bodies, ``try`` / ``if``
  blocks at top level);
- ``function``: inside a function or lambda, executed only when that runs;
- ``typing``: under ``if TYPE_CHECKING:``, never executed.

``from pkg import name`` points at ``pkg.name`` when that is a module, else at ``pkg`` (the
package's ``__init__``, which may itself import the module that asks: a real cycle). A cycle is
a cycle at any level, ``typing`` included: a type hint that names a module which imports back
is a circle in the design even if it never runs (``farm-studio look`` counts it too).

Run as ``python tests/import_graph.py`` for a report of the cycles at each level and the edges
between packages.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

#: The packages of the toolkit, in their allowed dependency order (see :data:`ALLOWED`).
PACKAGES = ("toolkit_common", "models", "lmi", "rmpc", "benchmarks")
ROOT = Path(__file__).resolve().parents[1]
LEVELS = ("module", "function", "typing")

#: Which of our packages each package may import (any level): benchmarks -> rmpc -> lmi, models;
#: lmi and models never import each other; toolkit_common imports none of ours.
ALLOWED: dict[str, frozenset[str]] = {
    "toolkit_common": frozenset(),
    "models": frozenset({"toolkit_common"}),
    "lmi": frozenset({"toolkit_common"}),
    "rmpc": frozenset({"toolkit_common", "models", "lmi"}),
    "benchmarks": frozenset({"toolkit_common", "models", "lmi", "rmpc"}),
}


@dataclass
class ImportGraph:
    """Modules and their import edges, per level."""

    files: dict[str, Path]
    edges: dict[str, dict[str, set[str]]] = field(default_factory=dict)

    def targets(self, module: str, levels: Iterable[str] = LEVELS) -> set[str]:
        """The modules ``module`` imports at the given levels."""
        return set().union(*(self.edges[level].get(module, set()) for level in levels))

    def cycles(self, levels: Iterable[str]) -> list[list[str]]:
        """The import cycles using edges of ``levels`` (strongly connected sets, each sorted)."""
        levels = tuple(levels)
        return strongly_connected({m: self.targets(m, levels) for m in self.files})


def module_files(root: Path = ROOT, packages: Iterable[str] = PACKAGES) -> dict[str, Path]:
    """Module name -> source file for every ``.py`` file of ``packages`` (a package is its ``__init__``)."""
    out: dict[str, Path] = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            out[".".join(parts)] = path
    return out


def _is_type_checking(test: ast.expr) -> bool:
    if isinstance(test, ast.Name):
        return test.id == "TYPE_CHECKING"
    return isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"


def _imports(tree: ast.AST) -> Iterator[tuple[ast.Import | ast.ImportFrom, str]]:
    """Every import statement of ``tree`` with its level."""

    def walk(node: ast.AST, level: str) -> Iterator[tuple[ast.Import | ast.ImportFrom, str]]:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import | ast.ImportFrom):
                yield child, level
            elif isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
                yield from walk(child, "function" if level == "module" else level)
            elif isinstance(child, ast.If) and _is_type_checking(child.test):
                for stmt in child.body:
                    yield from walk(ast.Module(body=[stmt], type_ignores=[]), "typing")
                for stmt in child.orelse:
                    yield from walk(ast.Module(body=[stmt], type_ignores=[]), level)
            else:
                yield from walk(child, level)

    yield from walk(tree, "module")


def _known(name: str, modules: dict[str, Path]) -> str | None:
    """``name`` or its closest enclosing module that is one of ours (``None`` if outside)."""
    parts = name.split(".")
    while parts:
        candidate = ".".join(parts)
        if candidate in modules:
            return candidate
        parts.pop()
    return None


def _targets(node: ast.Import | ast.ImportFrom, module: str, modules: dict[str, Path]) -> set[str]:
    if isinstance(node, ast.Import):
        found = (_known(alias.name, modules) for alias in node.names)
        return {name for name in found if name is not None}
    if node.level:
        is_package = modules[module].name == "__init__.py"
        package = module.split(".")
        package = package if is_package else package[:-1]
        base_parts = package[: len(package) - (node.level - 1)]
        base = ".".join([*base_parts, *([node.module] if node.module else [])])
    else:
        base = node.module or ""
    found = (_known(base if alias.name == "*" else f"{base}.{alias.name}", modules) for alias in node.names)
    return {name for name in found if name is not None}


def build_graph(root: Path = ROOT, packages: Iterable[str] = PACKAGES) -> ImportGraph:
    """The import graph of ``packages`` under ``root``."""
    files = module_files(root, packages)
    graph = ImportGraph(files, {level: {} for level in LEVELS})
    for module, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node, level in _imports(tree):
            for target in _targets(node, module, files):
                if target != module:
                    graph.edges[level].setdefault(module, set()).add(target)
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one node, each sorted, the list sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0

    def visit(start: str) -> None:
        nonlocal counter
        work = [(start, iter(sorted(graph.get(start, ()))))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in graph:
                    continue
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
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

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return sorted(found)


def package_of(module: str) -> str:
    """The top-level package of ``module``."""
    return module.split(".", 1)[0]


def forbidden_edges(graph: ImportGraph) -> list[tuple[str, str, str]]:
    """Edges (any level) that break :data:`ALLOWED`: ``(module, target, level)``."""
    out = []
    for level in LEVELS:
        for module, targets in graph.edges[level].items():
            for target in targets:
                source, dest = package_of(module), package_of(target)
                if source != dest and dest not in ALLOWED[source]:
                    out.append((module, target, level))
    return sorted(out)


def report(graph: ImportGraph) -> str:
    """The cycles at module level, the further ones that function-level and then typing-only
    imports add, and bad edges."""
    module_cycles = graph.cycles(["module"])
    runtime_cycles = [c for c in graph.cycles(["module", "function"]) if c not in module_cycles]
    typing_cycles = [c for c in graph.cycles(LEVELS) if c not in module_cycles + runtime_cycles]
    lines = [f"{len(graph.files)} modules in {', '.join(PACKAGES)}"]
    lines.append(f"module-level cycles: {len(module_cycles)}")
    lines += ["  " + " <-> ".join(c) for c in module_cycles]
    lines.append(f"cycles closed by function-level imports: {len(runtime_cycles)}")
    lines += ["  " + " <-> ".join(c) for c in runtime_cycles]
    lines.append(f"cycles closed by typing-only imports: {len(typing_cycles)}")
    lines += ["  " + " <-> ".join(c) for c in typing_cycles]
    bad = forbidden_edges(graph)
    lines.append(f"imports against the dependency direction: {len(bad)}")
    lines += [f"  {m} -> {t} ({level})" for m, t, level in bad]
    return "\n".join(lines)


if __name__ == "__main__":
    print(report(build_graph()))
