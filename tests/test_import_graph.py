"""No import cycle inside the toolkit's packages, and dependencies point one way.

The graph is read from the source (:mod:`import_graph`, ``ast``; nothing is imported). A cycle
anywhere fails, whether its imports run on load, inside a function or only for type hints
(``if TYPE_CHECKING:``): the same circles ``farm-studio look`` draws.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from import_graph import (
    ALLOWED,
    LEVELS,
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
    assert graph.cycles(["module"]) == [], report(graph)


def test_no_import_cycle_even_through_function_level_or_typing_imports(graph: ImportGraph) -> None:
    # the plant-family protocol once named the scenario in a type hint (the scenario imports the
    # registry, which imports the families, which import the protocol), and the solver's phase
    # one named the solver (which imports it): cycles no import at run time closes
    assert graph.cycles(LEVELS) == [], report(graph)


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


def test_a_cycle_through_a_type_hint_or_a_package_init_is_a_cycle(tmp_path: Path) -> None:
    # the two shapes of the cycles this test file once missed or must not miss
    pkg = tmp_path / "models"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from models.protocol import Family\n")
    (pkg / "protocol.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from models.scenario import Scenario\n"
        "class Family:\n    pass\n"
    )
    (pkg / "scenario.py").write_text("from models.protocol import Family\nclass Scenario:\n    pass\n")
    (pkg / "registry.py").write_text("def shipped():\n    from models import Family\n    return Family\n")
    (pkg / "family.py").write_text("from models.registry import shipped\n")
    g = build_graph(tmp_path, ("models",))
    assert g.targets("models.protocol", ["typing"]) == {"models.scenario"}
    assert g.cycles(["module", "function"]) == []
    assert g.cycles(LEVELS) == [["models.protocol", "models.scenario"]]
    # ``from models import Family`` is an edge to the package, whose __init__ loads the protocol
    (pkg / "protocol.py").write_text("from models.family import x\nclass Family:\n    pass\n")
    g = build_graph(tmp_path, ("models",))
    assert g.targets("models.registry", ["function"]) == {"models"}
    assert g.cycles(["module"]) == []
    ring = ["models", "models.family", "models.protocol", "models.registry"]
    assert g.cycles(["module", "function"]) == [ring]
    assert "closed by function-level imports: 1" in report(g)


def test_strongly_connected_finds_every_cycle_and_ignores_chains() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"f"}, "f": {"e"}, "g": {"a"}}
    assert strongly_connected(graph) == [["a", "b", "c"], ["e", "f"]]
