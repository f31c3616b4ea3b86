""":meth:`lmi.offline.NestedKothareProblem.solve` with ``outer``: the nesting LMI
``Q_outer - Q >= 0`` holds for the outer ellipsoid as given, also when it binds.

Kothare (1996), example 1: the ellipsoid designed at ``[0.05, 0]``, shrunk to 0.3 of itself
(still containing ``[0.025, 0]``), is smaller than the ellipsoid designed freely at ``[0.025, 0]``
(measured margin -0.66). Nested in it, the design pays with a larger ``gamma`` (0.00218 against
0.00189 measured) and stays inside it (measured margin +6e-8)."""

from __future__ import annotations

import dataclasses

import numpy as np

from lmi.offline import NestedKothareProblem, nesting_margin

A = [[[1, 0.1], [0, 1 - 0.1 * a]] for a in (0.1, 10.0)]
B = [[[0.0], [0.1 * 0.787]]] * 2
X_INNER = np.array([0.025, 0.0])


def test_a_binding_nesting_constraint_keeps_the_inner_ellipsoid_inside_the_outer_one() -> None:
    prob = NestedKothareProblem(A, B, Q=np.diag([1.0, 0.0]), R=[[2e-5]], dt=0.1,
                                input_constraint="peak", u_max=2.0)
    designed = prob.solve([0.05, 0.0])
    assert designed.ok
    outer = dataclasses.replace(designed, Q=0.3 * designed.Q)
    assert X_INNER @ np.linalg.solve(outer.Q, X_INNER) < 1.0  # the inner state is inside it
    free = prob.solve(X_INNER)
    assert free.ok and nesting_margin(outer.Q, free.Q) < -0.1  # the constraint must bind
    nested = prob.solve(X_INNER, outer=outer)
    assert nested.ok, nested.status
    assert nested.nesting_margin >= -prob.certificate_tol
    assert nested.nesting_margin == nesting_margin(outer.Q, nested.Q)
    assert nested.gamma > free.gamma
