"""The paper suite reports paper P's values that no physical satellite has (computed, not typed in)."""

from __future__ import annotations

import numpy as np

from benchmarks.suites.paper import inconsistencies
from models import PAPER_P_INERTIA


def test_paper_p_inertia_breaks_the_triangle_inequality_and_the_report_says_by_how_much():
    lines = "\n".join(inconsistencies(np.diag(PAPER_P_INERTIA)))
    j1, j2, j3 = sorted(PAPER_P_INERTIA)
    assert j3 > j1 + j2  # the fact the section reports: 4.2953 > 1.2928 + 1.2928
    assert f"{j3 - (j1 + j2):.4f} kg m^2" in lines
    assert "1.2928, 1.2928, 4.2953" in lines


def test_a_physical_inertia_has_no_inconsistency():
    lines = inconsistencies(np.diag([1.0, 1.0, 1.9]))
    assert "- None found in the values this suite uses." in lines
    assert not any("triangle" in line for line in lines)


def test_a_rotated_inertia_is_judged_by_its_principal_moments():
    """A full matrix with the same principal moments gets the same verdict (eigenvalues, not the diagonal)."""
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, np.cos(0.7), -np.sin(0.7)], [0.0, np.sin(0.7), np.cos(0.7)]]
    )
    full = rot @ np.diag(PAPER_P_INERTIA) @ rot.T
    assert inconsistencies(full) == inconsistencies(np.diag(PAPER_P_INERTIA))
