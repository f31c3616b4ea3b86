"""No import cycle inside the toolkit's packages, and dependencies point one way.

The graph is read from the source (:mod:`import_graph`, ``ast``; nothing is imported). A
module-level cycle anywhere fails; the cycles that function-level imports close are reported
(a warning with the list) and fail only inside ``benchmarks``, whose registry and runner were
built not to have any.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from import_graph import (
    ALLOWED,
    ImportGraph,
    build_graph,
    forbidden_edges,
    module_files,
    report,
    strongly_connected,
)


@pytest.fixture(scope="module")
def graph() -> ImportGraph:
    return build_graph()


def test_the_graph_sees_every_module_and_sorts_imports_by_level(graph: ImportGraph) -> None:
    assert len(graph.files) == len(module_files()) > 100
    # benchmarks.cli imports its sub-commands inside functions; the scenario imports the registry on load
    assert "benchmarks.core.registry" in graph.targets("benchmarks.core.scenario", ["module"])
    assert "benchmarks.suites.paper" in graph.targets("benchmarks.cli", ["function"])
    assert "benchmarks.suites.paper" not in graph.targets("benchmarks.cli", ["module"])
    assert "benchmarks.timing.config" in graph.targets("benchmarks.timing.rmpc", ["typing"])


def test_no_module_level_import_cycle(graph: ImportGraph) -> None:
    text = report(graph)
    function_cycles = [c for c in graph.cycles(["module", "function"]) if c not in graph.cycles(["module"])]
    if function_cycles:
        warnings.warn("import cycles closed inside functions:\n" + text, stacklevel=1)
    assert graph.cycles(["module"]) == [], text


def test_benchmarks_has_no_cycle_even_through_function_level_imports(graph: ImportGraph) -> None:
    cycles = [c for c in graph.cycles(["module", "function"]) if c[0].startswith("benchmarks")]
    assert cycles == [], report(graph)


def test_dependencies_point_one_way(graph: ImportGraph) -> None:
    # benchmarks -> rmpc -> lmi, models; lmi and models never import each other; toolkit_common none of ours
    assert ALLOWED["models"] == ALLOWED["lmi"] == {"toolkit_common"}
    assert "benchmarks" not in ALLOWED["rmpc"] and ALLOWED["toolkit_common"] == frozenset()
    assert forbidden_edges(graph) == [], report(graph)


def test_family_modules_import_only_the_protocol_and_metrics_of_the_core(graph: ImportGraph) -> None:
    core_used = {
        target
        for module in graph.files
        if module.startswith("benchmarks.families")
        for target in graph.targets(module)
        if target.startswith("benchmarks.core")
    }
    assert core_used <= {"benchmarks.core", "benchmarks.core.family", "benchmarks.core.metrics"}


def test_the_checks_fail_on_what_they_guard(tmp_path: Path) -> None:
    pkg = tmp_path / "models"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from models.a import x\n")
    (pkg / "a.py").write_text("from models.sub import b\nx = 1\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import lmi\n"
        "def f():\n    from .. import a\n    import rmpc.anything\n"
    )
    (tmp_path / "rmpc").mkdir()
    (tmp_path / "rmpc" / "__init__.py").write_text("import lmi\n")
    (tmp_path / "lmi").mkdir()
    (tmp_path / "lmi" / "__init__.py").write_text("")
    g = build_graph(tmp_path, ("models", "rmpc", "lmi"))
    assert g.targets("models.sub.b", ["typing"]) == {"lmi"}
    assert g.targets("models.sub.b", ["function"]) == {"models.a", "rmpc"}
    assert g.cycles(["module"]) == []
    assert g.cycles(["module", "function"]) == [["models.a", "models.sub.b"]]
    assert ("models.sub.b", "lmi", "typing") in forbidden_edges(g)
    assert ("models.sub.b", "rmpc", "function") in forbidden_edges(g)
    (pkg / "sub" / "b.py").write_text("import models\n")
    assert build_graph(tmp_path, ("models",)).cycles(["module"]) == [["models", "models.a", "models.sub.b"]]


def test_strongly_connected_finds_every_cycle_and_ignores_chains() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"f"}, "f": {"e"}, "g": {"a"}}
    assert strongly_connected(graph) == [["a", "b", "c"], ["e", "f"]]
