"""Invariant sets of tube MPC: the mRPI outer approximation, tightenings, admissible sets.

* :func:`mrpi_outer`: an outer approximation ``Z = (1 - alpha)^-1 (W + A W + ... + A^(s-1) W)`` of
  the minimal robust positively invariant set ``F_inf = sum_i A^i W`` of ``x+ = A x + w``,
  ``w in W``, to an accuracy ``epsilon`` in the infinity norm: ``F_inf  in  Z  in  F_inf +
  B_inf(epsilon)``; Algorithm 1 of S. V. Rakovic, E. C. Kerrigan, K. I. Kouramas and D. Q. Mayne,
  "Invariant approximations of the minimal robust positively invariant set", IEEE Transactions
  on Automatic Control 50(3), 2005.
* :func:`reachable_tightening`: the support functions ``sum_{j<i} h_W((A^j)' c)`` of the
  disturbance's reachable sets ``F_i``, the tightening of L. Chisci, J. A. Rossiter and G. Zappa,
  "Systems with persistent disturbances: predictive control with restricted constraints",
  Automatica 37(7), 2001.
* :func:`admissible_set`: the largest set of states whose autonomous trajectory ``z+ = A z``
  keeps ``G A^j z <= g_j`` for every ``j >= 0`` (E. G. Gilbert and K. T. Tan, "Linear systems
  with state and control constraints: the theory and application of maximal output admissible
  sets", IEEE Transactions on Automatic Control 36(9), 1991), with a constant or a growing
  right-hand side ``g_j``.

The LPs are scipy's HiGHS; the sets' representations come from :mod:`rmpc.sets.polytope`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from rmpc.sets.polytope import Polytope, minkowski_vertices
from toolkit_common.errors import InvalidArgumentError, SolverError

__all__ = [
    "MRPIApproximation",
    "admissible_set",
    "mrpi_outer",
    "mrpi_parameters",
    "reachable_tightening",
    "schur_radius",
]


def schur_radius(matrix: np.ndarray) -> float:
    """The spectral radius ``max |eig(A)|`` (``< 1``: ``A`` is Schur stable)."""
    return float(np.max(np.abs(np.linalg.eigvals(matrix))))


@dataclass(frozen=True)
class MRPIApproximation:
    """The result of :func:`mrpi_outer`.

    Attributes
    ----------
    Z : Polytope
        ``(1 - alpha)^-1 F_s``, robust positively invariant for ``x+ = A x + w``.
    alpha : float
        The smallest ``alpha`` with ``A^s W in alpha W``.
    s : int
        The number of terms of the Minkowski sum.
    epsilon : float
        The requested accuracy: ``Z in F_inf + B_inf(epsilon)``.
    M : float
        ``M(s)``, the largest support of ``F_s`` along a coordinate direction.
    """

    Z: Polytope
    alpha: float
    s: int
    epsilon: float
    M: float

    @property
    def bound(self) -> float:
        """``alpha (1 - alpha)^-1 M(s)``: the proven infinity-norm distance bound, ``<= epsilon``."""
        return self.alpha / (1.0 - self.alpha) * self.M


def mrpi_parameters(A: np.ndarray, W: Polytope, epsilon: float = 1e-3, s_max: int = 200
                    ) -> tuple[float, int, float]:
    """The ``(alpha, s, M(s))`` of Rakovic et al.'s Algorithm 1: the smallest ``s`` with ``A^s W in
    alpha W`` and ``alpha <= epsilon / (epsilon + M(s))``, so that ``(1 - alpha)^-1 F_s`` is RPI and
    within ``epsilon`` of ``F_inf``. Its support function is ``(1 - alpha)^-1 sum_{i<s} h_W((A^i)'
    d)`` (:func:`reachable_tightening` at step ``s``): no set needs to be built for it.

    Raises
    ------
    InvalidArgumentError
        ``A`` not Schur stable (named ``K``), ``W`` without the origin inside, ``epsilon <= 0``
        or not reached within ``s_max`` terms.
    """
    n = A.shape[0]
    if not epsilon > 0 or not np.isfinite(epsilon):
        raise InvalidArgumentError("epsilon", "a finite number > 0", repr(epsilon))
    rho = schur_radius(A)
    if rho >= 1.0:
        raise InvalidArgumentError("K", "a gain with A + B K Schur stable (spectral radius < 1)",
                                   f"spectral radius {rho:.6g}")
    if not W.contains_origin_inside():
        raise InvalidArgumentError("W", "a disturbance set with the origin in its interior",
                                   f"min h_i = {float(W.h.min()):.6g}")
    eye = np.eye(n)
    directions = np.vstack([eye, -eye])
    power = eye                       # A^(s-1)
    sums = np.zeros(2 * n)            # sum_{i<s} h_W(+-(A^i)' e_j)
    s = 0
    while s < s_max:
        s += 1
        sums += W.support(directions @ power)
        power = A @ power             # A^s
        alpha = float(np.max(W.support(W.H @ power) / W.h))
        m_s = float(sums.max())
        if alpha < 1.0 and alpha <= epsilon / (epsilon + m_s):
            break
    if not (alpha < 1.0 and alpha <= epsilon / (epsilon + m_s)):
        raise InvalidArgumentError(
            "epsilon", f"an accuracy reached within s_max = {s_max} terms", f"epsilon = {epsilon:g}"
        )
    return alpha, s, m_s


def mrpi_outer(A: np.ndarray, W: Polytope, epsilon: float = 1e-3, s_max: int = 200,
               max_vertices: int = 5000) -> MRPIApproximation:
    """Rakovic et al.'s outer epsilon-approximation of the minimal RPI set of ``x+ = A x + w``.

    Parameters
    ----------
    A : (n, n) ndarray
        The closed-loop matrix ``A + B K``, Schur stable.
    W : Polytope
        The disturbance set, with the origin in its interior.
    epsilon : float
        The accuracy (> 0): the result lies within ``epsilon`` of ``F_inf`` in the infinity norm.
    s_max : int
        The largest number of terms tried.
    max_vertices : int
        The largest vertex count of the Minkowski sum accepted (its H-representation is built).

    Raises
    ------
    InvalidArgumentError
        ``A`` not Schur stable, ``W`` without the origin inside, ``epsilon <= 0``, no ``s <=
        s_max`` reaching ``epsilon``, or a sum with more than ``max_vertices`` vertices.

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.sets import Polytope, mrpi_outer
    >>> approx = mrpi_outer(np.array([[0.5]]), Polytope.box([1.0]), epsilon=1e-3)
    >>> approx.s, round(float(approx.Z.h[0]), 4)
    (11, 2.0)
    """
    alpha, s, m_s = mrpi_parameters(A, W, epsilon, s_max)
    power = np.eye(A.shape[0])
    vertices = W.vertices
    for term in range(1, s):
        power = A @ power
        if vertices.shape[0] * W.vertices.shape[0] > 20 * max_vertices:     # refuse before a slow hull
            raise InvalidArgumentError(
                "W", f"a Minkowski sum of at most max_vertices = {max_vertices} vertices "
                "(use kind='tightening', which needs no explicit set)",
                f"{vertices.shape[0]} vertices after {term} of {s} terms, "
                f"{vertices.shape[0] * W.vertices.shape[0]} points in the next sum",
            )
        vertices = minkowski_vertices(vertices, W.vertices @ power.T)
        if vertices.shape[0] > max_vertices:
            raise InvalidArgumentError(
                "W", f"a Minkowski sum of at most max_vertices = {max_vertices} vertices "
                "(use kind='tightening', which needs no explicit set)",
                f"{vertices.shape[0]} vertices after {term + 1} of {s} terms",
            )
    Z = Polytope.from_vertices(vertices / (1.0 - alpha), "Z")
    return MRPIApproximation(Z=Z, alpha=alpha, s=s, epsilon=float(epsilon), M=m_s)


def reachable_tightening(A: np.ndarray, W: Polytope, rows: np.ndarray, steps: int) -> np.ndarray:
    """``t[i, r] = h_{F_i}(rows[r]) = sum_{j<i} h_W((A^j)' rows[r])`` for ``i = 0 .. steps``.

    ``F_i = W + A W + ... + A^(i-1) W`` is the set the error ``x - z`` of a plant under ``u = K x +
    c`` reaches in ``i`` steps from ``x = z``; the constraint ``rows z_i <= b - t[i]`` on the
    nominal prediction keeps the plant's ``rows x_i <= b``.
    """
    out = np.zeros((steps + 1, rows.shape[0]))
    mapped = rows.copy()              # rows A^j
    for i in range(1, steps + 1):
        out[i] = out[i - 1] + W.support(mapped)
        mapped = mapped @ A
    return out


def _lp_max(objective: np.ndarray, H: np.ndarray, h: np.ndarray) -> float:
    """``max objective' z`` s.t. ``H z <= h`` (HiGHS); ``inf`` when unbounded."""
    res = linprog(-objective, A_ub=H, b_ub=h, bounds=[(None, None)] * H.shape[1], method="highs")
    if res.status == 3:
        return np.inf
    if res.status != 0:
        raise SolverError(f"admissible set: the LP failed ({res.message})")
    return float(-res.fun)


def _redundant(H: np.ndarray, h: np.ndarray, rows: np.ndarray, rhs: np.ndarray, tol: float) -> np.ndarray:
    """For each of ``rows z <= rhs``: whether ``H z <= h`` implies it."""
    return np.array([_lp_max(r, H, h) <= b + tol * max(1.0, abs(b)) for r, b in zip(rows, rhs, strict=True)])


def admissible_set(
    A: np.ndarray,
    G: np.ndarray,
    g: Callable[[int], np.ndarray],
    *,
    tail: Polytope | None = None,
    max_steps: int = 200,
    tol: float = 1e-9,
    name: str = "terminal set",
) -> Polytope:
    """The states ``z`` with ``G A^j z <= g(j)`` for all ``j >= 0``, as a polytope.

    Parameters
    ----------
    A : (n, n) ndarray
        Schur stable.
    G : (p, n) ndarray
        Constraint rows.
    g : callable
        ``g(j)``, the right-hand side at step ``j`` (every entry > 0).
    tail : Polytope, optional
        For a ``g(j)`` that changes with ``j``: a positively invariant set (``A tail in tail``)
        inside ``{G z <= g(j)}`` for every ``j``. The construction stops at the first ``J`` with
        ``A^(J+1) S_J in tail``: from there on every constraint holds. Without it, ``g`` must be
        constant and the stop is Gilbert and Tan's (the rows of step ``J + 1`` are redundant).
    max_steps : int
        The largest ``J`` tried.

    Raises
    ------
    InvalidArgumentError
        Naming ``name`` when the set is empty or the construction does not stop.
    """
    n = A.shape[0]
    H_acc, h_acc = G.copy(), np.asarray(g(0), dtype=float).copy()
    if not np.all(h_acc > 0):
        raise InvalidArgumentError(name, "constraints with the origin strictly inside (every g_i > 0)",
                                   f"min g_i = {float(h_acc.min()):.6g}")
    mapped = G.copy()
    power = np.eye(n)
    for j in range(1, max_steps + 1):
        power = A @ power
        if tail is not None:
            check_rows = tail.H @ power
            if _redundant(H_acc, h_acc, check_rows, tail.h, tol).all():
                return _reduced(H_acc, h_acc, name)
        mapped = mapped @ A
        rhs = np.asarray(g(j), dtype=float)
        keep = ~_redundant(H_acc, h_acc, mapped, rhs, tol)
        if tail is None and not keep.any():
            return _reduced(H_acc, h_acc, name)
        H_acc = np.vstack([H_acc, mapped[keep]])
        h_acc = np.concatenate([h_acc, rhs[keep]])
    raise InvalidArgumentError(name, f"a set determined within max_steps = {max_steps} steps",
                               "a construction that did not stop")


def _reduced(H: np.ndarray, h: np.ndarray, name: str) -> Polytope:
    return Polytope(H, h, name)
