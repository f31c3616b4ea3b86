"""The mutation check (:mod:`benchmarks.mutation`) on a tiny project of its own: the operators, the
seeded sample, the classification of a mutant's run, and the working files never written.

The end-to-end test runs three mutants, each in a child ``pytest`` (a few seconds in all).
"""

from __future__ import annotations

import ast
import json
import sys
import textwrap
from pathlib import Path

import pytest

from benchmarks.mutation.operators import apply_mutant, find_mutants
from benchmarks.mutation.runner import CheckConfig, list_mutants, run_check, sample_mutants
from benchmarks.mutation.sandbox import Sandbox

CALC = textwrap.dedent(
    '''
    """A module to mutate."""
    from typing import TYPE_CHECKING

    if TYPE_CHECKING:
        import os

    __all__ = ["clamp", "count_up", "untested"]
    LIMIT = 10


    def clamp(x: int, lo: int, hi: int) -> int:
        """Clamp ``x`` into ``[lo, hi]``."""
        if x < lo:
            return lo
        if x > hi:
            return hi
        return x


    def count_up(n: int) -> int:
        i = 0
        while i < n:
            i += 1
        return i


    def untested(x: int) -> str:
        return f"{x + 1}"
    '''
).lstrip()

TESTS = textwrap.dedent(
    """
    from fakepkg.calc import clamp, count_up


    def test_clamp_low():
        assert clamp(-5, 0, 3) == 0


    def test_clamp_inside():
        assert clamp(2, 0, 3) == 2


    def test_count_up():
        assert count_up(3) == 3


    def test_broken_whatever_the_code():
        assert clamp(1, 0, 3) == 99  # fails on the original: never used to judge a mutant
    """
).lstrip()


@pytest.fixture
def project(tmp_path: Path) -> Path:
    root = tmp_path / "project"
    (root / "fakepkg").mkdir(parents=True)
    (root / "tests").mkdir()
    (root / "fakepkg" / "__init__.py").write_text("")
    (root / "fakepkg" / "calc.py").write_text(CALC)
    (root / "tests" / "test_calc.py").write_text(TESTS)
    return root


def _by_place(mutants: list, line_text: str) -> dict[str, str]:
    line = next(i for i, text in enumerate(CALC.splitlines(), 1) if text.strip() == line_text)
    return {m.operator: m.replacement for m in mutants if m.line == line}


def test_operators_change_one_node_and_leave_docstrings_annotations_and_type_checking_alone() -> None:
    mutants = find_mutants(CALC, "fakepkg.calc", "fakepkg/calc.py")
    assert _by_place(mutants, "if x < lo:") == {"compare": "(x >= lo)"}
    assert _by_place(mutants, "return lo") == {"return": "return None"}
    assert _by_place(mutants, "LIMIT = 10") == {"constant": "11"}
    assert _by_place(mutants, "i += 1") == {"arith": "i -= 1", "statement": "pass", "constant": "0"}
    assert _by_place(mutants, "i = 0") == {"constant": "1"}  # the assignment to a name is kept
    # f-strings, docstrings, __all__, annotations and the TYPE_CHECKING block give no mutant
    assert _by_place(mutants, 'return f"{x + 1}"') == {"return": "return None"}
    assert min(m.line for m in mutants) == CALC.splitlines().index("LIMIT = 10") + 1
    for mutant in mutants:
        mutated = apply_mutant(CALC, mutant)
        assert ast.dump(ast.parse(mutated)) != ast.dump(ast.parse(CALC))
        changed = [a for a, b in zip(CALC.splitlines(), mutated.splitlines(), strict=True) if a != b]
        assert len(changed) == 1, mutant  # every other line as it was


def test_the_sample_is_seeded_and_sized(project: Path) -> None:
    mutants = list_mutants(project, ["fakepkg"])
    config = CheckConfig(root=project, modules=["fakepkg"], tests=["tests"], out=project / "out",
                         max_mutants=4)
    first = sample_mutants(mutants, config)
    assert len(first) == 4 and first == sample_mutants(mutants, config)
    others = [sample_mutants(mutants, CheckConfig(**{**config.__dict__, "seed": s})) for s in range(1, 6)]
    assert any(o != first for o in others)
    named = CheckConfig(**{**config.__dict__, "mutant_ids": [mutants[2].id]})
    assert sample_mutants(mutants, named) == [mutants[2]]


def test_a_mutant_in_the_sandbox_is_undone_on_interrupt_and_never_reaches_the_working_file(
    project: Path,
) -> None:
    mutant = find_mutants(CALC, "fakepkg.calc", "fakepkg/calc.py")[0]
    with Sandbox(project) as box:
        copy = box.tree / "fakepkg" / "calc.py"
        with pytest.raises(KeyboardInterrupt), box.mutated(mutant):
            assert copy.read_text() == apply_mutant(CALC, mutant) != CALC
            raise KeyboardInterrupt
        assert copy.read_text() == CALC
    assert not box.path.exists()
    assert (project / "fakepkg" / "calc.py").read_text() == CALC


def test_caught_survived_untested_and_timed_out_mutants_are_told_apart(project: Path) -> None:
    mutants = list_mutants(project, ["fakepkg"])
    line = {text.strip(): i for i, text in enumerate(CALC.splitlines(), 1)}

    def pick(text: str, operator: str) -> str:
        return next(m.id for m in mutants if m.line == line[text] and m.operator == operator)

    chosen = {
        pick("if x < lo:", "compare"): ("caught", "tests/test_calc.py::test_"),
        pick("LIMIT = 10", "constant"): ("survived", ""),  # no passing test reads LIMIT
        pick("return hi", "return"): ("survived", "no test runs it"),
        pick("i += 1", "statement"): ("timeout", ""),  # the loop never ends
    }
    out = project.parent / "out"
    config = CheckConfig(root=project, modules=["fakepkg"], tests=["tests"], out=out, mutant_ids=list(chosen),
                         timeout_base=6.0, python=sys.executable)
    summary = run_check(config, log=lambda _: None)
    got = {r["id"]: (r["status"], r["detail"]) for r in summary["mutants"]}
    for mutant_id, (status, detail) in chosen.items():
        assert got[mutant_id][0] == status, (mutant_id, got[mutant_id])
        assert got[mutant_id][1].startswith(detail), (mutant_id, got[mutant_id])
    assert summary["counts"] == {"caught": 1, "survived": 2, "timeout": 1, "error": 0, "not run": 0}
    assert summary["map"]["tests"] == 4 and summary["map"]["tests_passed"] == 3
    assert summary["working_files_untouched"]
    assert (project / "fakepkg" / "calc.py").read_text() == CALC
    report = (out / "report.md").read_text()
    assert "1 caught, 2 survived (1 run by no test), 1 timed out" in report
    assert json.loads((out / "results.json").read_text())["tried"] == 4
    assert len((out / "mutants.jsonl").read_text().splitlines()) == 4
    assert "of which the map run" in report and "reused" not in report
    # a second run on the same tree reuses the map, and says so
    again = run_check(CheckConfig(**{**config.__dict__, "mutant_ids": list(chosen)[:1]}), log=lambda _: None)
    assert again["map"]["reused"] and again["counts"]["caught"] == 1
    assert "the map was reused from an earlier run" in (out / "report.md").read_text()


KERNEL = textwrap.dedent(
    '''
    """A module with a "compiled" kernel (the decorator's name is what marks it)."""


    def njit(func):
        return func


    @njit
    def double(x):
        return 2 * x
    '''
).lstrip()


def test_a_compiled_kernel_is_judged_by_the_tests_that_import_it(project: Path) -> None:
    (project / "fakepkg" / "kern.py").write_text(KERNEL)
    (project / "tests" / "test_kern.py").write_text(
        "from fakepkg.kern import double\n\n\ndef test_double():\n    assert double(3) == 6\n"
    )
    mutant = next(m for m in list_mutants(project, ["fakepkg.kern"]) if m.operator == "arith")
    assert mutant.scope == "compiled"  # a tracer never sees its lines: no module of fakepkg imports it
    config = CheckConfig(root=project, modules=["fakepkg"], tests=["tests"], out=project.parent / "out",
                         mutant_ids=[mutant.id], python=sys.executable)
    summary = run_check(config, log=lambda _: None)
    (record,) = summary["mutants"]
    assert (record["status"], record["detail"]) == ("caught", "tests/test_kern.py::test_double")
    assert (record["tests_covering"], record["tests_run"]) == (1, 1)
