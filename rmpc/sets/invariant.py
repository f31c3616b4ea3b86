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
* :func:`mrpi_support_bound`: an upper bound of the minimal RPI set's support within
  ``epsilon`` of it, from the partial sums and an invariant Lyapunov ellipsoid
  (:class:`LyapunovEllipsoid`); no set is built, and the disturbance set may be flat (``E W``
  with ``E`` of rank below ``n``).
* :func:`admissible_set`: the largest set of states whose autonomous trajectory ``z+ = A z``
  keeps ``G A^j z <= g_j`` for every ``j >= 0`` (E. G. Gilbert and K. T. Tan, "Linear systems
  with state and control constraints: the theory and application of maximal output admissible
  sets", IEEE Transactions on Automatic Control 36(9), 1991), with a constant or a growing
  right-hand side ``g_j``, by LPs only.

The LPs are scipy's HiGHS; the sets' representations come from :mod:`rmpc.sets.polytope`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.optimize import linprog

from rmpc.sets.polytope import Polytope, minkowski_vertices
from toolkit_common.errors import InvalidArgumentError, SolverError

__all__ = [
    "LyapunovEllipsoid",
    "MRPIApproximation",
    "admissible_set",
    "mrpi_outer",
    "mrpi_parameters",
    "mrpi_support_bound",
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


def _check_stable(A: np.ndarray, epsilon: float) -> None:
    """Refuse ``epsilon <= 0`` and an ``A = A + B K`` that is not Schur stable (named ``K``)."""
    if not epsilon > 0 or not np.isfinite(epsilon):
        raise InvalidArgumentError("epsilon", "a finite number > 0", repr(epsilon))
    rho = schur_radius(A)
    if rho >= 1.0:
        raise InvalidArgumentError("K", "a gain with A + B K Schur stable (spectral radius < 1)",
                                   f"spectral radius {rho:.6g}")


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
    _check_stable(A, epsilon)
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


def reachable_tightening(A: np.ndarray, W: Polytope, rows: np.ndarray, steps: int,
                         E: np.ndarray | None = None) -> np.ndarray:
    """``t[i, r] = h_{F_i}(rows[r]) = sum_{j<i} h_W((A^j)' rows[r])`` for ``i = 0 .. steps``.

    ``F_i = W + A W + ... + A^(i-1) W`` is the set the error ``x - z`` of a plant under ``u = K x +
    c`` reaches in ``i`` steps from ``x = z``; the constraint ``rows z_i <= b - t[i]`` on the
    nominal prediction keeps the plant's ``rows x_i <= b``. With ``E`` the disturbance is ``E d``,
    ``d`` in ``W`` (``h_{E W}(c) = h_W(E' c)``; ``E W`` may be flat, as a torque entering through
    the input matrix).
    """
    out = np.zeros((steps + 1, rows.shape[0]))
    mapped = rows.copy()              # rows A^j
    for i in range(1, steps + 1):
        out[i] = out[i - 1] + W.support(mapped if E is None else mapped @ E)
        mapped = mapped @ A
    return out


@dataclass(frozen=True)
class LyapunovEllipsoid:
    """``{z : ||L' z|| <= radius}`` with ``L L' = P``, ``A' P A - P = -I``: invariant under ``z+ =
    A z`` (``||L' A z|| <= rate ||L' z||``, ``rate < 1``)."""

    L: np.ndarray
    rate: float

    @classmethod
    def of(cls, A: np.ndarray) -> LyapunovEllipsoid:
        """The ellipsoid's shape for a Schur stable ``A``."""
        P = sla.solve_discrete_lyapunov(A.T, np.eye(A.shape[0]))
        L = np.linalg.cholesky(0.5 * (P + P.T))
        rate = float(np.linalg.norm(L.T @ A @ np.linalg.inv(L.T), 2))
        return cls(L, rate)

    def norms(self, rows: np.ndarray) -> np.ndarray:
        """``||L^-1 c||`` per row ``c``: the support of the unit-radius ellipsoid."""
        return np.linalg.norm(sla.solve_triangular(self.L, rows.T, lower=True), axis=0)

    def largest_inside(self, rows: np.ndarray, rhs: np.ndarray) -> float:
        """The largest radius with the ellipsoid inside ``{rows z <= rhs}`` (``rhs > 0``)."""
        return float(np.min(rhs / self.norms(rows)))


def mrpi_support_bound(A: np.ndarray, W: Polytope, rows: np.ndarray, epsilon: float = 1e-3,
                       E: np.ndarray | None = None, s_max: int = 5000) -> tuple[np.ndarray, int]:
    """An upper bound of the minimal RPI set's support ``h_{F_inf}(rows)`` of ``x+ = A x + E w``,
    ``w in W``, within ``epsilon`` of it, without any set built.

    ``F_inf = F_s + A^s F_inf`` and ``F_inf`` lies in the ellipsoid ``{||L' e|| <= r}`` of
    :class:`LyapunovEllipsoid` with ``r = max_w ||L' E w|| / (1 - rate)`` (robustly invariant: ``rate
    r + max_w ||L' E w|| = r``), so ``h_{F_inf}(c) <= h_{F_s}(c) + r ||L^-1 (A^s)' c||``; ``s`` is the
    first with the second term ``<= epsilon`` on every row. Unlike Rakovic et al.'s ``A^s W in
    alpha W`` (:func:`mrpi_parameters`), this needs no full-dimensional ``W``: a torque entering
    through the input matrix is a flat set in the state space.

    Returns
    -------
    bound : (len(rows),) ndarray
        ``h_{F_s}(rows) + r ||L^-1 (A^s)' rows||``, with ``h_{F_s} <= h_{F_inf} <= bound <= h_{F_s} +
        epsilon``.
    s : int
        The number of terms.

    Raises
    ------
    InvalidArgumentError
        ``A`` not Schur stable (named ``K``), ``epsilon <= 0`` or not reached within ``s_max``.
    """
    _check_stable(A, epsilon)
    shape = LyapunovEllipsoid.of(A)
    w_vertices = W.vertices if E is None else W.vertices @ E.T
    radius = float(np.max(np.linalg.norm(w_vertices @ shape.L, axis=1))) / (1.0 - shape.rate)
    sums = np.zeros(rows.shape[0])
    mapped = rows.copy()              # rows A^s
    for s in range(s_max + 1):
        rest = radius * shape.norms(mapped)
        if rest.max() <= epsilon:
            return sums + rest, s
        sums += W.support(mapped if E is None else mapped @ E)
        mapped = mapped @ A
    raise InvalidArgumentError("epsilon", f"an accuracy reached within s_max = {s_max} terms",
                               f"epsilon = {epsilon:g}")


#: Steps between two bounding boxes of the admissible set under construction (``2 n`` LPs each).
BOX_REFRESH = 8


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


def _bounding_box(H: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(lower, upper)`` of ``{H z <= h}`` per coordinate (``inf`` where unbounded)."""
    eye = np.eye(H.shape[1])
    upper = np.array([_lp_max(e, H, h) for e in eye])
    lower = -np.array([_lp_max(-e, H, h) for e in eye])
    return lower, upper


def admissible_set(
    A: np.ndarray,
    G: np.ndarray,
    g: Callable[[int], np.ndarray],
    *,
    g_limit: np.ndarray | None = None,
    max_steps: int = 2000,
    tol: float = 1e-9,
    name: str = "terminal set",
) -> Polytope:
    """The states ``z`` with ``G A^j z <= g(j)`` for all ``j >= 0``, as a polytope.

    Built by LPs only (HiGHS): the rows of step ``j`` that the set so far does not imply are
    added; at the end the rows are made irredundant and unit-norm, and boundedness is checked.
    No vertex is enumerated (in six dimensions with hundreds of rows that is what was slow).

    Parameters
    ----------
    A : (n, n) ndarray
        Schur stable.
    G : (p, n) ndarray
        Constraint rows.
    g : callable
        ``g(j)``, the right-hand side at step ``j`` (every entry > 0).
    g_limit : (p,) ndarray, optional
        For a ``g(j)`` that changes with ``j``: a bound ``0 < g_limit <= g(j)`` for every ``j``.
        The construction stops at the first ``J`` with ``A^(J+1) S_J`` inside the largest
        invariant Lyapunov ellipsoid of ``A`` (:class:`LyapunovEllipsoid`) in ``{G z <= g_limit}``
        (the ellipsoid's states keep every later constraint); the test bounds ``S_J`` by its box.
        Without it, ``g`` must be constant and the stop is Gilbert and Tan's (the rows of step
        ``J + 1`` are redundant).
    max_steps : int
        The largest ``J`` tried.

    Raises
    ------
    InvalidArgumentError
        Naming ``name`` when the set is empty or unbounded or the construction does not stop.
    """
    n = A.shape[0]
    H_acc, h_acc = G.copy(), np.asarray(g(0), dtype=float).copy()
    if not np.all(h_acc > 0):
        raise InvalidArgumentError(name, "constraints with the origin strictly inside (every g_i > 0)",
                                   f"min g_i = {float(h_acc.min()):.6g}")
    tail = None
    if g_limit is not None:
        limit = np.asarray(g_limit, dtype=float)
        if not np.all(limit > 0):
            raise InvalidArgumentError(name, "a limit of the right-hand sides with every entry > 0",
                                       f"min = {float(limit.min()):.6g}")
        shape = LyapunovEllipsoid.of(A)
        tail = (shape, shape.largest_inside(G, limit))
    box: tuple[np.ndarray, np.ndarray] | None = None
    box_step = -1
    mapped = G.copy()
    power = np.eye(n)
    for j in range(1, max_steps + 1):
        power = A @ power
        if box is None or j - box_step >= BOX_REFRESH:   # S_J shrinks: an older box holds it
            box, box_step = _bounding_box(H_acc, h_acc), j
        if tail is not None and _in_ellipsoid(power, tail, box):
            return _finished(H_acc, h_acc, tol, name)
        mapped = mapped @ A
        rhs = np.asarray(g(j), dtype=float)
        # a row the box already keeps is redundant without an LP (most rows, late on)
        keep = _box_max(mapped, box) > rhs
        if keep.any():
            keep[keep] = ~_redundant(H_acc, h_acc, mapped[keep], rhs[keep], tol)
        if tail is None and not keep.any():
            return _finished(H_acc, h_acc, tol, name)
        H_acc = np.vstack([H_acc, mapped[keep]])
        h_acc = np.concatenate([h_acc, rhs[keep]])
    raise InvalidArgumentError(name, f"a set determined within max_steps = {max_steps} steps",
                               "a construction that did not stop")


def _box_max(rows: np.ndarray, box: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """``max rows z`` over the box (``inf`` where the box is unbounded along a used coordinate)."""
    with np.errstate(invalid="ignore"):
        ends = np.maximum(rows * box[0], rows * box[1])
    ends = np.where(rows == 0.0, 0.0, ends)
    return ends.sum(axis=1)


def _in_ellipsoid(power: np.ndarray, tail: tuple[LyapunovEllipsoid, float],
                  box: tuple[np.ndarray, np.ndarray]) -> bool:
    """Whether ``power`` maps the box (of the set so far, or of an earlier, larger one) into the
    ellipsoid ``tail``: ``||L' M z|| <= ||L' M c|| + sum_i r_i ||L' M e_i||`` on the box."""
    if not np.all(np.isfinite(box[0])) or not np.all(np.isfinite(box[1])):
        return False
    shape, radius = tail
    mapped = shape.L.T @ power
    centre, half = 0.5 * (box[0] + box[1]), 0.5 * (box[1] - box[0])
    reach = np.linalg.norm(mapped @ centre) + np.linalg.norm(mapped, axis=0) @ half
    return bool(reach <= radius)


def _finished(H: np.ndarray, h: np.ndarray, tol: float, name: str) -> Polytope:
    """The irredundant, unit-norm rows of ``{H z <= h}``, checked bounded."""
    scale = np.linalg.norm(H, axis=1)
    live = scale > 0
    H, h = H[live] / scale[live, None], h[live] / scale[live]
    keep = np.ones(h.size, dtype=bool)
    for i in range(h.size):
        keep[i] = False
        if not _redundant(H[keep], h[keep], H[i:i + 1], h[i:i + 1], tol)[0]:
            keep[i] = True
    H, h = H[keep], h[keep]
    lower, upper = _bounding_box(H, h)
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        raise InvalidArgumentError(
            name, "a bounded set (the constraints must see every state under the gain)",
            f"an unbounded set (coordinates {np.flatnonzero(~np.isfinite(upper - lower)).tolist()})",
        )
    return Polytope.from_irredundant(H, h, name)
