"""The LMI design of a robust observer for a polytope of models, with a certified error bound.

The observer runs the current (filter) form on the nominal model ``(A_0, B_0)``::

    x_bar(k) = A_0 x_hat(k-1) + B_0 u(k-1),      x_hat(k) = x_bar(k) + M (y(k) - C x_bar(k))

while the plant is any model of the polytope, ``x(k) = A x(k-1) + B u(k-1)`` with ``(A, B)`` in
the convex hull of the vertices ``(A_j, B_j)``, measured as ``y = C x + v``. The estimation error
``e = x - x_hat`` then obeys ::

    e(k) = (I - M C) A_0 e(k-1) + (I - M C) [(A - A_0) x(k-1) + (B - B_0) u(k-1)] - M v(k)

so the model mismatch enters like a disturbance proportional to the state and the input. With
per-component bounds ``|x_i| <= x_max_i``, ``|u_i| <= u_max_i``, ``|v_i| <= v_max_i`` gathered
in ``xi = D xi_n`` (``D`` the diagonal of the bounds, ``|xi_n_i| <= 1``), the ellipsoid
``{e : e' P e <= 1}`` is invariant when, for some ``alpha`` in (0, 1) and multipliers
``mu_i >= 0`` with ``sum_i mu_i <= alpha`` (the S-procedure: ``e' P e <= 1`` and every
``xi_n_i^2 <= 1`` give ``e(k)' P e(k) <= (1 - alpha) e' P e + sum_i mu_i xi_n_i^2 <= 1``), at
every vertex ``j`` ::

    [ (1 - alpha) P     0          A_0' (P - Y C)'    ]
    [ 0                 diag(mu)   G_j' (P - Y C)' ... ]   >= 0,      Y = P M
    [ (P - Y C) A_0     ...        P                  ]

with ``(P - Y C) G_j = (P - Y C) [(A_j - A_0) D_x, (B_j - B_0) D_u]`` and the noise column
``-Y D_v`` (Schur's complement of ``P``; affine in ``(P, Y, mu)`` for a fixed ``alpha``, and in
``(A_j, B_j)``, so the vertices cover the hull). The size of the bound is ``trace(P^-1)`` (the
sum of the squared semi-axes), minimised through ``Z`` with ``[[Z, I], [I, P]] >= 0``; ``alpha``
is searched over a grid and refined by golden section. Every answer is certified: the blocks
recomputed in numpy at the answer, each smallest eigenvalue relative to its largest at least
``-tol``.

The error outside the ellipsoid contracts towards it: ``e(k)' P e(k) - 1 <= (1 - alpha)^k
(e(0)' P e(0) - 1)``.

Examples
--------
A double integrator measured in position, its input gain known within +-20 %:

>>> import numpy as np
>>> A = np.array([[1.0, 0.1], [0.0, 1.0]])
>>> B = np.array([[0.005], [0.1]])
>>> vertices = [(A, 0.8 * B), (A, 1.2 * B)]
>>> design = design_robust_observer(vertices, (A, B), C=[[1.0, 0.0]], noise_bound=1e-3,
...                                 input_bound=1.0)
>>> design.status, design.certificate.ok
('optimal', True)
>>> bool(np.all(np.abs(np.linalg.eigvals(design.error_dynamics)) < 1.0))
True
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lmi.affine import svec_matrix
from lmi.certificate import Certificate
from lmi.forms.program import Layout, Program
from lmi.infeasibility import check_farkas
from lmi.ipm import BlockLMISolver
from lmi.status import INFEASIBLE, NUMERICAL_ERROR, OPTIMAL, SOLVER_ERROR
from toolkit_common.errors import InvalidArgumentError

__all__ = ["ALPHA_GRID", "ObserverDesign", "certify_observer", "design_robust_observer"]

#: The contraction parameters ``alpha`` tried first; the best is refined by golden section.
ALPHA_GRID: tuple[float, ...] = (0.02, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 0.75, 0.9)
_REFINE = 8
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class ObserverDesign:
    """The answer of :func:`design_robust_observer`.

    Attributes
    ----------
    status : str
        ``"optimal"`` (a certified gain and bound), ``"infeasible"`` (no ``alpha`` of the search
        admits one) or a failure word of the status vocabulary.
    M : ndarray or None
        The correction gain ``(n, p)``.
    P : ndarray or None
        The error ellipsoid ``{e : e' P e <= 1}``.
    alpha : float
        The contraction parameter of the answer.
    certificate : Certificate
        The blocks' relative margins recomputed at the answer.
    solver_status : str
        What the solver said (per ``alpha`` when nothing was certified).
    solve_time : float
        Seconds over the whole search.
    """

    status: str
    M: np.ndarray | None
    P: np.ndarray | None
    alpha: float
    certificate: Certificate
    solver_status: str
    solve_time: float
    nominal: tuple[np.ndarray, np.ndarray] = field(repr=False, default=(np.zeros((0, 0)), np.zeros((0, 0))))
    C: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 0)))
    mu: np.ndarray | None = field(repr=False, default=None)
    Z: np.ndarray | None = field(repr=False, default=None)

    @property
    def ok(self) -> bool:
        """A certified gain and bound."""
        return self.status == OPTIMAL and self.certificate.ok

    @property
    def error_dynamics(self) -> np.ndarray:
        """``(I - M C) A_0``, the noiseless error map on the nominal model."""
        a0 = self.nominal[0]
        return (np.eye(a0.shape[0]) - self.M @ self.C) @ a0

    @property
    def half_widths(self) -> np.ndarray:
        """The largest ``|e_i|`` on the ellipsoid: ``sqrt(diag(P^-1))``."""
        return np.sqrt(np.diag(np.linalg.inv(self.P)))


@dataclass(frozen=True)
class _Data:
    a0: np.ndarray
    b0: np.ndarray
    c: np.ndarray
    mismatch: list[np.ndarray]  # per vertex: [(A_j - A_0) D_x, (B_j - B_0) D_u] (n x channels)
    d_v: np.ndarray


def _bounds(value: Any, name: str, size: int, required: bool) -> np.ndarray | None:
    if value is None:
        if required:
            raise InvalidArgumentError(
                name, f"{size} bounds > 0 (the models of the polytope differ there, so the mismatch "
                "the observer sees grows with it)", "None")
        return None
    try:
        vec = np.broadcast_to(np.asarray(value, dtype=float), (size,)).copy()
    except (TypeError, ValueError):
        raise InvalidArgumentError(name, f"a number > 0 or {size} of them",
                                   repr(np.asarray(value, dtype=object).tolist())) from None
    if not np.all(np.isfinite(vec)) or np.any(vec <= 0.0):
        raise InvalidArgumentError(name, "finite bounds > 0", repr(vec.tolist()))
    return vec


def _data(vertices: list[tuple[np.ndarray, np.ndarray]], nominal: tuple[np.ndarray, np.ndarray],
          c: np.ndarray, noise_bound: ArrayLike, state_bound: ArrayLike | None,
          input_bound: ArrayLike | None) -> _Data:
    a0, b0 = nominal
    n, m = b0.shape
    p = c.shape[0]
    da = [np.asarray(a, float) - a0 for a, _ in vertices]
    db = [np.asarray(b, float) - b0 for _, b in vertices]
    scale_a = max(1.0, float(np.max(np.abs(a0))))
    scale_b = max(1e-300, float(np.max(np.abs(b0))))
    a_varies = any(np.max(np.abs(d)) > 1e-14 * scale_a for d in da)
    b_varies = any(np.max(np.abs(d)) > 1e-14 * scale_b for d in db)
    d_v = np.diag(_bounds(noise_bound, "noise_bound", p, required=True))
    x_max = _bounds(state_bound, "state_bound", n, required=a_varies)
    u_max = _bounds(input_bound, "input_bound", m, required=b_varies)
    mismatch = []
    for d_a, d_b in zip(da, db, strict=True):
        cols = []
        if a_varies:
            cols.append(d_a * x_max)
        if b_varies:
            cols.append(d_b * u_max)
        mismatch.append(np.hstack(cols) if cols else np.zeros((n, 0)))
    return _Data(a0, b0, c, mismatch, d_v)


def _layout(n: int, p: int, channels: int) -> Layout:
    lay = Layout()
    lay.symmetric("P", n)
    lay.full("Y", n, p)
    lay.symmetric("Z", n)
    for i in range(channels):
        lay.full(f"mu{i}", 1, 1)
    return lay


def _write(prog: Program, data: _Data, alpha: float) -> Program:
    n, p = data.a0.shape[0], data.c.shape[0]
    channels = data.mismatch[0].shape[1] + p
    pm, ym, zm = prog.var("P"), prog.var("Y"), prog.var("Z")
    mus = [prog.var(f"mu{i}") for i in range(channels)]
    mu_diag = prog.zeros(channels, channels)
    for i, mu in enumerate(mus):
        mu_diag = mu_diag + prog.times(mu, np.eye(channels)[:, [i]] @ np.eye(channels)[[i], :])
    corrected = pm - ym.rmul(data.c)  # P - Y C = P (I - M C)
    top = corrected.rmul(data.a0)
    noise = -(ym.rmul(data.d_v))
    for j, g_j in enumerate(data.mismatch):
        cols = corrected.rmul(g_j) if g_j.shape[1] else None
        bottom = noise if cols is None else prog.bmat([[cols, noise]])
        block = prog.bmat([
            [pm * (1.0 - alpha), None, top.T],
            [None, mu_diag, bottom.T],
            [top, bottom, pm],
        ])
        prog.add(f"vertex_{j}", block)
    total = prog.const(alpha)
    for mu in mus:
        total = total - mu
    prog.add("multipliers", total)
    prog.add("bound", prog.bmat([[zm, prog.eye(n)], [prog.eye(n), pm]]))
    return prog


def _observer_margins(data: _Data, alpha: float, P: np.ndarray, Y: np.ndarray, mu: np.ndarray,
                     Z: np.ndarray, tol: float = 1e-7) -> Certificate:
    """The design's blocks recomputed in numpy at an answer (a :class:`Certificate`)."""
    lay = _layout(P.shape[0], Y.shape[1], mu.size)
    values = {"P": P, "Y": Y, "Z": Z, **{f"mu{i}": np.array([[v]]) for i, v in enumerate(mu)}}
    prog = _write(Program(lay, values), data, alpha)
    margins = prog.margins()
    if not np.all(np.isfinite(P)) or np.linalg.eigvalsh(0.5 * (P + P.T))[0] <= 0.0:
        margins["P_definite"] = -np.inf
    return Certificate(margins, tol)


def _solve_at(data: _Data, alpha: float) -> tuple[str, str, dict[str, np.ndarray] | None, float]:
    """One ``alpha``: status, solver word, the variables (``None`` without an answer), time."""
    n, p = data.a0.shape[0], data.c.shape[0]
    channels = data.mismatch[0].shape[1] + p
    lay = _layout(n, p, channels)
    prog = _write(Program(lay), data, alpha)
    c = lay.vector({"Z": np.eye(n)})  # trace(Z): the svec of I picks the diagonal entries
    start = time.perf_counter()
    try:
        res = BlockLMISolver(c, prog.solver_blocks()).solve()
    except (np.linalg.LinAlgError, ValueError, FloatingPointError) as err:
        return SOLVER_ERROR, repr(err), None, time.perf_counter() - start
    elapsed = time.perf_counter() - start
    word = res.solver_status or res.status
    if res.status == INFEASIBLE:  # kept only with the Farkas ray checked on the conic data
        a_rows, b, orders = prog.conic_rows()
        ray = np.concatenate([svec_matrix(z_block) for z_block in res.Z])
        proof = check_farkas(a_rows, b, [("psd", k) for k in orders], ray)
        return (INFEASIBLE if proof.ok else NUMERICAL_ERROR), word, None, elapsed
    return res.status, word, lay.values(res.x), elapsed


def design_robust_observer(
    vertices: list[tuple[ArrayLike, ArrayLike]],
    nominal: tuple[ArrayLike, ArrayLike],
    C: ArrayLike,
    noise_bound: ArrayLike,
    state_bound: ArrayLike | None = None,
    input_bound: ArrayLike | None = None,
    alphas: tuple[float, ...] = ALPHA_GRID,
    tol: float = 1e-7,
) -> ObserverDesign:
    """The observer gain with the smallest certified error ellipsoid (see the module's text).

    Parameters
    ----------
    vertices : list of (A_j, B_j)
        The polytope's vertices.
    nominal : (A_0, B_0)
        The model the observer runs on.
    C : (p, n) array_like
        ``y = C x + v``.
    noise_bound : float or (p,) array_like
        ``|v_i| <= noise_bound_i`` (> 0).
    state_bound : float or (n,) array_like, optional
        ``|x_i| <= state_bound_i``; required when the vertices' ``A_j`` differ from ``A_0``.
    input_bound : float or (m,) array_like, optional
        ``|u_i| <= input_bound_i``; required when the ``B_j`` differ from ``B_0``.
    alphas : tuple of float
        The grid of contraction parameters in (0, 1) (then refined around the best).
    tol : float
        The certificate's tolerance on the relative margins.

    Returns
    -------
    ObserverDesign
    """
    a0, b0 = (np.atleast_2d(np.asarray(mat, dtype=float)) for mat in nominal)
    c = np.atleast_2d(np.asarray(C, dtype=float))
    if not alphas or any(not 0.0 < float(a) < 1.0 for a in alphas):
        raise InvalidArgumentError("alphas", "contraction parameters in (0, 1)", repr(alphas))
    data = _data(list(vertices), (a0, b0), c, noise_bound, state_bound, input_bound)
    tried: dict[float, tuple[str, str, dict[str, np.ndarray] | None]] = {}
    total = 0.0

    def value(alpha: float) -> float:
        nonlocal total
        status, word, values, elapsed = _solve_at(data, alpha)
        total += elapsed
        tried[alpha] = (status, word, values)
        if status != OPTIMAL or values is None:
            return math.inf
        return float(np.trace(values["Z"]))

    grid = [value(float(a)) for a in alphas]
    best = int(np.argmin(grid))
    if np.isfinite(grid[best]):
        ordered = sorted(float(a) for a in alphas)
        k = ordered.index(float(alphas[best]))
        lo = ordered[k - 1] if k > 0 else 0.5 * ordered[0]
        hi = ordered[k + 1] if k + 1 < len(ordered) else 0.5 * (1.0 + ordered[-1])
        x1, x2 = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
        f1, f2 = value(x1), value(x2)
        for _ in range(_REFINE - 2):
            if f1 < f2:
                hi, x2, f2 = x2, x1, f1
                x1 = hi - _GOLDEN * (hi - lo)
                f1 = value(x1)
            else:
                lo, x1, f1 = x1, x2, f2
                x2 = lo + _GOLDEN * (hi - lo)
                f2 = value(x2)
    channels = data.mismatch[0].shape[1] + c.shape[0]
    answers = []
    for alpha, (status, _word, values) in tried.items():
        if status != OPTIMAL or values is None:
            continue
        mu = np.array([values[f"mu{i}"][0, 0] for i in range(channels)])
        cert = _observer_margins(data, alpha, values["P"], values["Y"], mu, values["Z"], tol)
        if cert.ok:
            answers.append((float(np.trace(values["Z"])), alpha, values, cert))
    if answers:
        _, alpha, values, cert = min(answers, key=lambda item: item[0])
        p_mat = 0.5 * (values["P"] + values["P"].T)
        m_mat = np.linalg.solve(p_mat, values["Y"])
        mu = np.array([values[f"mu{i}"][0, 0] for i in range(channels)])
        return ObserverDesign(OPTIMAL, m_mat, p_mat, alpha, cert, "optimal", total, (a0, b0), c, mu,
                              0.5 * (values["Z"] + values["Z"].T))
    words = "; ".join(f"alpha {a:.3g}: {w}" for a, (_s, w, _v) in sorted(tried.items()))
    statuses = {s for s, _w, _v in tried.values()}
    status = INFEASIBLE if statuses == {INFEASIBLE} else NUMERICAL_ERROR
    return ObserverDesign(status, None, None, float("nan"), Certificate({"none": -np.inf}, tol),
                          f"no certified answer ({words})", total, (a0, b0), c)


def certify_observer(
    vertices: list[tuple[ArrayLike, ArrayLike]],
    nominal: tuple[ArrayLike, ArrayLike],
    C: ArrayLike,
    noise_bound: ArrayLike,
    state_bound: ArrayLike | None,
    input_bound: ArrayLike | None,
    alpha: float,
    P: ArrayLike,
    M: ArrayLike,
    mu: ArrayLike,
    Z: ArrayLike,
    tol: float = 1e-7,
) -> Certificate:
    """The design's blocks recomputed at a given answer (``Y = P M``): a gain and bound read back
    from a file are checked again, not trusted.

    Parameters are those of :func:`design_robust_observer` and the answer's ``alpha``, ``P``,
    ``M``, multipliers ``mu`` and trace bound ``Z``.
    """
    a0, b0 = (np.atleast_2d(np.asarray(mat, dtype=float)) for mat in nominal)
    c = np.atleast_2d(np.asarray(C, dtype=float))
    data = _data(list(vertices), (a0, b0), c, noise_bound, state_bound, input_bound)
    p_mat = np.asarray(P, dtype=float)
    mu = np.asarray(mu, dtype=float).ravel()
    if mu.size != data.mismatch[0].shape[1] + c.shape[0]:
        return Certificate({"multipliers_count": -np.inf}, tol)
    return _observer_margins(data, float(alpha), p_mat, p_mat @ np.asarray(M, dtype=float), mu,
                             np.asarray(Z, dtype=float), tol)
