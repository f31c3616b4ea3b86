"""Farkas certificates of infeasibility, checked without trusting the solver that found them.

A conic problem ``find z with s = b - A z in K`` (``K`` a product of PSD cones, in Clarabel's
scaled half-vectorised form, and non-negative orthants) has no solution if there is a ``y`` in
the dual cone ``K* = K`` with ``A'y = 0`` and ``b'y < 0``: a solution would give
``0 <= <s, y> = b'y - z'A'y = b'y < 0``. Computed in floating point ``A'y`` is only small, so
:func:`check_farkas` proves a slightly weaker, explicit statement:

* it makes ``y`` exactly a member of ``K`` by adding ``delta I`` to each PSD block (``delta``
  the block's most negative eigenvalue, by ``numpy.linalg.eigvalsh``; zero when it is positive
  semidefinite) and clipping the orthant parts at zero,
* and with that ``y+`` every ``z`` with ``||z||_2 < radius = -b'y+ / ||A'y+||_2`` would give
  ``0 <= <s, y+> <= b'y+ + ||z|| ||A'y+|| < 0``: **no solution of norm below** ``radius``.

This is how Clarabel's own ``PrimalInfeasible`` is defined (``||A'y|| <= eps |b'y|``); a
certificate is accepted when the radius exceeds :data:`MIN_RADIUS` (of the variables of the
problem as it was solved: for :class:`lmi.KothareProblem` the normalised state ``x / ||x||``
in the balanced coordinates of :mod:`lmi.scaling`, where a solution has ``gamma``, ``Q`` and
``Y`` of order one to a few thousand).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from lmi.affine import smat_matrix, svec_indices
from toolkit_common.errors import InvalidArgumentError

__all__ = ["MIN_RADIUS", "PSD_TOL", "InfeasibilityCertificate", "check_farkas"]

#: A certificate proves infeasibility for the toolkit when no solution of norm below this exists.
MIN_RADIUS = 1e8
#: ... and its blocks are positive semidefinite up to rounding: smallest eigenvalue at least
#: minus this times the block's largest (a block far from the cone is not a certificate, even if
#: the shifted one would still be; phase one's blocks are positive definite by construction).
PSD_TOL = 1e-12


@dataclass(frozen=True)
class InfeasibilityCertificate:
    """A checked Farkas certificate (see the module docstring).

    Attributes
    ----------
    y : ndarray
        The multipliers, one entry per row of ``A`` (the dual cone's half-vectorised blocks).
    objective : float
        ``b'y+`` (negative for a proof), ``y+`` the multipliers moved into the cone.
    objective_margin : float
        ``-b'y+ / (||b|| ||y+||)``, the relative size of the contradiction.
    residual : float
        ``||A'y+|| / (||A|| ||y+||)`` (``||A||`` the Frobenius norm).
    min_eigenvalue : float
        The smallest eigenvalue of the multiplier blocks relative to the block's largest
        (``>= 0`` when ``y`` was in the cone before the shift).
    radius : float
        No solution with ``||z||_2 < radius`` exists.
    min_radius : float
        The radius a proof needs.
    """

    y: np.ndarray = field(repr=False)
    objective: float
    objective_margin: float
    residual: float
    min_eigenvalue: float
    radius: float
    min_radius: float

    @property
    def ok(self) -> bool:
        """``objective < 0``, ``radius >= min_radius`` and ``min_eigenvalue >= -PSD_TOL``: the
        problem has no solution of norm below ``min_radius``."""
        return bool(np.isfinite(self.objective) and self.objective < 0.0 and self.radius >= self.min_radius
                    and self.min_eigenvalue >= -PSD_TOL)


def check_farkas(
    a_mat: object, b: np.ndarray, cones: Sequence[tuple[str, int]], y: np.ndarray,
    min_radius: float = MIN_RADIUS,
) -> InfeasibilityCertificate:
    """Check that ``y`` proves ``b - A z in K`` has no solution of norm below ``min_radius``.

    Parameters
    ----------
    a_mat : (rows, n) ndarray or scipy sparse matrix
        ``A`` of the problem, rows in the order of ``cones``.
    b : (rows,) ndarray
    cones : sequence of (kind, size)
        ``("psd", k)`` for a PSD block of order ``k`` (``k(k+1)/2`` rows, upper triangle column
        by column, off-diagonal entries scaled by ``sqrt(2)``, as :func:`lmi.affine.svec_matrix`)
        or ``("nonneg", d)`` for ``d`` non-negative rows.
    y : (rows,) ndarray
        The candidate multipliers.
    min_radius : float
        See :data:`MIN_RADIUS`.

    Returns
    -------
    InfeasibilityCertificate
        With its margins; ``ok`` says whether it proves infeasibility.
    """
    y = np.asarray(y, dtype=float).ravel()
    b = np.asarray(b, dtype=float).ravel()
    shifted = y.copy()
    worst = np.inf
    row = 0
    for kind, size in cones:
        if kind == "psd":
            count = size * (size + 1) // 2
            block = smat_matrix(y[row:row + count], size)
            lam = np.linalg.eigvalsh(block)
            worst = min(worst, float(lam[0] / max(float(np.max(np.abs(lam))), np.finfo(float).tiny)))
            if lam[0] < 0.0:  # y+ = y + delta svec(I): delta on the diagonal entries
                rows, cols = svec_indices(size)
                shifted[row + np.flatnonzero(rows == cols)] += -float(lam[0])
        elif kind == "nonneg":
            count = size
            part = y[row:row + count]
            scale = max(float(np.max(np.abs(part), initial=0.0)), np.finfo(float).tiny)
            worst = min(worst, float(np.min(part, initial=np.inf)) / scale)
            shifted[row:row + count] = np.maximum(part, 0.0)
        else:
            raise InvalidArgumentError("cones", "('psd', k) or ('nonneg', d) entries", repr((kind, size)))
        row += count
    if row != y.size or row != b.size:
        raise InvalidArgumentError("y", f"{row} entries (the rows the cones cover), as b",
                                   f"{y.size} (b: {b.size})")
    at_y = np.asarray(a_mat.T @ shifted).ravel()  # type: ignore[attr-defined]
    a_norm = float(np.sqrt((a_mat.multiply(a_mat)).sum())) if hasattr(a_mat, "multiply") else float(
        np.linalg.norm(np.asarray(a_mat)))
    y_norm = float(np.linalg.norm(shifted))
    objective = float(b @ shifted)
    res_norm = float(np.linalg.norm(at_y))
    radius = -objective / res_norm if objective < 0.0 and res_norm > 0.0 else (
        np.inf if objective < 0.0 else 0.0)
    tiny = np.finfo(float).tiny
    return InfeasibilityCertificate(
        y=y, objective=objective,
        objective_margin=-objective / max(float(np.linalg.norm(b)) * y_norm, tiny),
        residual=res_norm / max(a_norm * y_norm, tiny), min_eigenvalue=worst, radius=float(radius),
        min_radius=float(min_radius),
    )

