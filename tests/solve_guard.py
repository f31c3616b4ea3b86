"""A guard for tests that claim a step solves nothing: every SDP solve entry point raises.

Used instead of a wall-clock bound: "the lookup is fast" stands for "the lookup solves no
optimisation problem", which can be asserted exactly; the time itself is measured in the
benchmarks (``python -m benchmarks.timing.offline``).
"""

from __future__ import annotations

from typing import Any

import cvxpy
import pytest

from lmi import KothareProblem
from lmi.offline import NestedKothareProblem


def forbid_solves(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Make the toolkit's SDP solves and cvxpy's raise; return the list of attempts (to assert empty).

    Patched: :meth:`lmi.KothareProblem.solve` (every back-end), the off-line design's
    :meth:`lmi.offline.NestedKothareProblem.solve` and :meth:`cvxpy.Problem.solve`. The list
    records an attempt even when the caller catches the error.
    """
    attempts: list[str] = []

    def refuse(name: str) -> Any:
        def solve(*args: Any, **kwargs: Any) -> None:
            attempts.append(name)
            raise AssertionError(f"{name} called where nothing should be solved")

        return solve

    for owner, name in ((KothareProblem, "KothareProblem"), (NestedKothareProblem, "NestedKothareProblem"),
                        (cvxpy.Problem, "cvxpy.Problem")):
        monkeypatch.setattr(owner, "solve", refuse(f"{name}.solve"))
    return attempts
