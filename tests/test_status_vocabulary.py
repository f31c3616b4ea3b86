"""One status vocabulary: the LMI and QP back-ends and every controller report its words.

:class:`toolkit_common.status.Status` is the vocabulary; :data:`~toolkit_common.status.STATUS_TABLE`
says what each word means, whether it is usable and what the controllers do with it, and the
documentation's table is generated from it. A word outside the vocabulary cannot be reported
(``StepInfo`` and ``QPResult`` convert and check), records hold the plain word, and no module of
``rmpc`` or ``benchmarks`` builds a step's info with a word the vocabulary lacks.
"""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import lmi
from benchmarks.core.metrics import FAILURE_FREE_STATUSES
from lmi import status as lmi_status
from models import RigidSatellite
from rmpc import LQR, Status, StepInfo, simulate
from rmpc.qp import BACKENDS, STATUSES, QPResult, SolverResiduals
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.status import (
    FAILURE_STATUSES,
    SOLVER_STATUSES,
    STATUS_TABLE,
    USABLE_STATUSES,
    as_status,
    describe,
    is_usable,
)

ROOT = Path(__file__).resolve().parent.parent
WORDS = {s.value for s in Status}


def test_the_table_describes_every_word_once() -> None:
    assert [row.status for row in STATUS_TABLE] == list(Status)  # every word, in the enum's order
    for row in STATUS_TABLE:
        assert row.source in ("solver", "controller")
        assert row.meaning.strip() and row.action.strip(), row.status
        assert describe(row.status.value) is row and is_usable(row.status.value) is row.usable
    assert USABLE_STATUSES == {"optimal", "inaccurate", "reused", "ok"}
    assert FAILURE_STATUSES == frozenset(Status) - USABLE_STATUSES
    # the benchmarks' failure count keeps the words it always counted as no failure
    assert FAILURE_FREE_STATUSES == USABLE_STATUSES


def test_a_word_outside_the_vocabulary_is_an_error_naming_the_field() -> None:
    with pytest.raises(InvalidArgumentError, match=r"^StepInfo\.status: .*'optimal'.*'bogus'"):
        StepInfo("bogus")
    with pytest.raises(ArgumentTypeError, match=r"^StepInfo\.status:"):
        StepInfo(None)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match=r"^QPResult\.status:"):
        QPResult(np.zeros(1), 0.0, "solved", 1, 0.0, SolverResiduals(), np.zeros(0), np.zeros(1), "x", "test")
    assert as_status("reused") is Status.REUSED and StepInfo("ok").status is Status.OK


def test_lmi_names_are_words_of_the_vocabulary() -> None:
    expected = {
        "OPTIMAL": "optimal", "UNCERTIFIED": "uncertified", "INFEASIBLE": "infeasible",
        "UNBOUNDED": "unbounded", "INACCURATE": "inaccurate", "MAX_ITERATIONS": "max_iterations",
        "TIME_LIMIT": "time_limit", "NUMERICAL_ERROR": "numerical_error", "SOLVER_ERROR": "solver_error",
    }
    for name, word in expected.items():
        value = getattr(lmi_status, name)
        assert value is Status(word) and value == word
    assert lmi.STATUSES == lmi_status.STATUSES and lmi.STATUSES[0] == "optimal"
    assert set(lmi_status.STATUSES) <= SOLVER_STATUSES
    assert lmi.FAILURE_STATUSES == set(lmi_status.STATUSES) - {"optimal"}
    for mapping in (lmi_status.CLARABEL_STATUS_MAP, lmi_status.CVXPY_STATUS_MAP):
        assert all(isinstance(word, Status) and word in lmi_status.STATUSES for word in mapping.values())


def test_every_qp_backend_maps_into_the_qp_words() -> None:
    assert set(STATUSES) <= SOLVER_STATUSES and all(isinstance(s, Status) for s in STATUSES)
    for name, cls in BACKENDS.items():
        assert cls.STATUS_MAP, name
        for raw, word in cls.STATUS_MAP.items():
            assert isinstance(word, Status) and word in STATUSES, (name, raw, word)
        assert cls.map_status("a code no solver has") is Status.NUMERICAL_ERROR


def _status_words_in_code() -> list[tuple[str, int, str]]:
    """The status words the code of rmpc and benchmarks names: ``Status.X`` anywhere, string
    literals given to ``StepInfo(status=...)`` (or its first argument), and in rmpc those assigned
    to ``status`` (benchmarks' ``status`` variables also hold sweep and exit states)."""
    found = []

    def literals(node: ast.AST, path: str) -> None:
        for sub in ast.walk(node):  # also the branches of a conditional expression
            if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
                found.append((path, sub.lineno, sub.value))

    for file in sorted([*ROOT.glob("rmpc/**/*.py"), *ROOT.glob("benchmarks/**/*.py")]):
        path = str(file.relative_to(ROOT))
        for node in ast.walk(ast.parse(file.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute) and getattr(node.value, "id", None) == "Status":
                found.append((path, node.lineno, node.attr))
            elif isinstance(node, ast.Call):
                func = node.func
                if (func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")) == "StepInfo":
                    for arg in [kw.value for kw in node.keywords if kw.arg == "status"] or node.args[:1]:
                        literals(arg, path)
            elif isinstance(node, ast.Assign) and path.startswith("rmpc"):
                for target in node.targets:
                    if isinstance(target, ast.Name) and target.id == "status":
                        literals(node.value, path)
                    elif isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple):
                        for name, value in zip(target.elts, node.value.elts, strict=False):
                            if isinstance(name, ast.Name) and name.id == "status":
                                literals(value, path)
    return found


def test_every_word_a_controller_reports_is_in_the_vocabulary() -> None:
    named = _status_words_in_code()
    members = set(Status.__members__)
    for path, line, word in named:
        assert word in WORDS or word in members, f"{path}:{line} names {word!r}, not a status word"
    used = {Status[w] if w in members else Status(w) for _, _, w in named}
    # the scan sees the controllers' own words: each controller word of the table is used
    controller_words = {row.status for row in STATUS_TABLE if row.source == "controller"}
    assert controller_words <= used, controller_words - used


def test_records_hold_the_plain_word() -> None:
    record = {"status": Status.OK, "counts": {Status.REUSED: 2, Status.OPTIMAL: 1}}
    assert json.dumps(record) == '{"status": "ok", "counts": {"reused": 2, "optimal": 1}}'
    assert repr(Status.INFEASIBLE) == "'infeasible'" and str(Status.INFEASIBLE) == "infeasible"
    assert f"{Status.BOUND_VIOLATION}" == "bound_violation"
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    plant = sat.linear_model(x0, 0.01)
    traj = simulate(LQR(plant, Q=np.eye(6), R=np.eye(3)), plant, x0, duration=0.03)
    assert all(type(word) is str for word in traj.status)  # the trajectory keeps plain words
    assert json.dumps(traj.status_counts()) == '{"ok": 3}'


def test_the_docs_table_is_generated_from_the_vocabulary() -> None:
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        from status_table import status_table_rst
    finally:
        sys.path.remove(str(ROOT / "docs" / "_ext"))
    rows = [line for line in status_table_rst() if line.startswith("   * - ``")]
    assert rows == [f'   * - ``"{s.value}"``' for s in Status]
    pages = "".join(p.read_text(encoding="utf-8") for p in (ROOT / "docs").glob("*.rst"))
    assert pages.count(".. status-table::") == 1
