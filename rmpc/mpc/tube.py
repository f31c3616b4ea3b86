"""Tube MPC for linear plants with additive bounded disturbances: rigid tube and tightening.

The plant is ``x+ = A x + B u + E w`` with ``w`` in a polytope ``W`` (origin inside; ``E = I``
unless given, e.g. the input matrix for a torque disturbance), states in
``X = {H_x x <= h_x}`` and inputs in ``U = {H_u u <= h_u}``. The input is ``u = K x + c``
around a disturbance-rejection gain ``K`` (``A_K = A + B K`` Schur stable; LQR on ``(A, B, Q,
R)`` by default), and a QP chooses the nominal prediction ``z_(i+1) = A_K z_i + B c_i``:

``kind="rigid"``
    D. Q. Mayne, M. M. Seron and S. V. Rakovic, "Robust model predictive control of constrained
    linear systems with bounded disturbances", Automatica 41(2), 2005. ``Z`` is an outer
    epsilon-approximation of the minimal RPI set of ``e+ = A_K e + w``
    (:func:`rmpc.sets.mrpi_outer`); the QP chooses the initial nominal state ``z_0`` with ``x -
    z_0 in Z`` and inputs ``v_i = K z_i + c_i``, subject to ``z_i in X - Z``, ``v_i in U - K Z``
    (Pontryagin differences) for ``i < N`` and ``z_N in X_f``; the plant gets ``u = v_0 + K (x
    - z_0)``.
``kind="tightening"``
    L. Chisci, J. A. Rossiter and G. Zappa, "Systems with persistent disturbances: predictive
    control with restricted constraints", Automatica 37(7), 2001. ``z_0 = x``; the constraints
    at step ``i`` are tightened by the reachable set ``F_i = W + A_K W + ... + A_K^(i-1) W`` of
    the error (:func:`rmpc.sets.reachable_tightening`) and ``z_N`` lies in the admissible set of
    the constraints tightened by ``F_(N+j)``, ``j >= 0``; the plant gets ``u = K x + c_0``. Only
    support functions are evaluated and only LPs solved, so ``E W`` may be flat (a torque through
    the input matrix of a six-state satellite) and the state space large.

The cost is ``sum_{i<N} z_i' Q z_i + v_i' R v_i + z_N' P z_N`` with ``P`` the Lyapunov matrix
of ``A_K`` (the Riccati solution when ``K`` is LQR's). The terminal set ``X_f`` is the maximal
admissible set of the nominal under ``K`` (:func:`rmpc.sets.admissible_set`). Both are solved as
one condensed QP through :mod:`rmpc.qp`, built once; per step only the right-hand side (and, for
the tightening, the linear term) changes, and the back-end warm-starts from the last answer.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike

from models import PolytopicModel
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode
from rmpc.io.saveable import Saveable
from rmpc.qp import QP, QPBackend, make_backend
from rmpc.sets.invariant import (
    admissible_set,
    mrpi_outer,
    mrpi_support_bound,
    reachable_tightening,
)
from rmpc.sets.polytope import Polytope
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_square_matrix, as_vector, check_choice, check_count

__all__ = ["KINDS", "MAX_HORIZON", "TubeMPC", "TubeSets"]

#: The two tube formulations.
KINDS = ("rigid", "tightening")
#: Default bound on ``horizon``: the condensed QP has ``N m`` (+ ``n``) variables and its
#: prediction matrices grow as ``N^2``; ``TubeMPC(..., max_horizon=N)`` lifts it.
MAX_HORIZON = 200
#: Accepted excess of a QP answer over its constraint rows (relative to the row's bound, at
#: least absolute): beyond it the step is a ``"bound_violation"``. The back-ends' default
#: tolerances are 1e-8 to 1e-10.
ROW_TOL = 1e-6
#: The most prediction steps beyond the horizon the tightening's terminal set may need (its
#: construction stops earlier: measured after 3 steps on the double integrator, 256 on paper P's
#: satellite holding attitude).
TERMINAL_STEPS = 2000


@dataclasses.dataclass(frozen=True)
class TubeSets:
    """What a tube design computes once: the gain, the terminal weight and the constraint sets.

    Attributes
    ----------
    K : (m, n) ndarray
        The disturbance-rejection gain (``u = K x + c``).
    P : (n, n) ndarray
        Terminal weight, ``A_K' P A_K - P = -(Q + K' R K)``.
    Z_H, Z_h : ndarray or None
        The rigid tube's cross-section ``Z = {Z_H e <= Z_h}`` (``None`` for the tightening).
    state_tightening, input_tightening : (N, p_x), (N, p_u) ndarray
        What is taken off ``h_x`` and ``h_u`` at each prediction step ``i < N``.
    terminal_H, terminal_h : ndarray
        The terminal set ``X_f = {terminal_H z <= terminal_h}``.
    alpha, s : float, int
        The mRPI approximation's parameters (rigid; NaN and 0 for the tightening).
    """

    K: np.ndarray
    P: np.ndarray
    Z_H: np.ndarray | None
    Z_h: np.ndarray | None
    state_tightening: np.ndarray
    input_tightening: np.ndarray
    terminal_H: np.ndarray
    terminal_h: np.ndarray
    alpha: float = float("nan")
    s: int = 0


def _as_constraints(value: Any, name: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(value, tuple | list) or len(value) != 2:
        raise ArgumentTypeError(name, "an (H, h) pair of the set {x : H x <= h}", type(value).__name__)
    H = as_matrix(value[0], f"{name}[0]", (None, n))
    h = as_vector(value[1], f"{name}[1]", H.shape[0])
    return H, h


def _box_rows(limits: Any, name: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    lim = np.full(n, float(limits)) if np.ndim(limits) == 0 else as_vector(limits, name, n)
    if not np.all(lim > 0) or not np.all(np.isfinite(lim)):
        raise InvalidArgumentError(name, "finite bounds > 0", repr(np.asarray(limits).tolist()))
    return np.vstack([np.eye(n), -np.eye(n)]), np.concatenate([lim, lim])


def _plant(plant: Any) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(plant, PolytopicModel):
        if plant.n_vertices != 1:
            raise InvalidArgumentError(
                "plant", "one linear model (tube MPC covers additive disturbances; for a polytope of "
                "models use RMPC or MultiStageMPC)", f"a PolytopicModel of {plant.n_vertices} vertices",
            )
        return plant.A[0].copy(), plant.B[0].copy()
    if not isinstance(plant, tuple | list) or len(plant) != 2:
        raise ArgumentTypeError("plant", "an (A, B) pair or a one-vertex models.PolytopicModel",
                                type(plant).__name__)
    A = as_matrix(plant[0], "plant[0] (A)")
    if A.shape[0] != A.shape[1]:
        raise InvalidArgumentError("plant[0] (A)", "a square matrix", f"shape {A.shape}")
    B = as_matrix(plant[1], "plant[1] (B)", (A.shape[0], None))
    return A, B


class TubeMPC(Saveable):
    """Tube MPC (rigid tube or constraint tightening) for ``x+ = A x + B u + w``, ``w in W``.

    Parameters
    ----------
    plant : (A, B) pair or PolytopicModel
        The discrete-time model (a :class:`~models.PolytopicModel` of one vertex).
    Q : float, (n,) or (n, n) array_like
        State weight, positive semidefinite.
    R : float, (m,) or (m, m) array_like
        Input weight, positive definite.
    horizon : int
        ``N``, the prediction horizon (default 9, Mayne et al.'s example).
    u_max, x_max : float or array_like, optional
        Box bounds ``|u_i| <= u_max_i``, ``|x_i| <= x_max_i``.
    w_max : float or array_like, optional
        The box ``W = {|w_i| <= w_max_i}``.
    E : (n, q) array_like, optional
        The disturbance's input matrix (``x+ = A x + B u + E w``, ``w`` in ``W`` of ``R^q``; default
        the identity). A rank below ``n`` makes ``E W`` flat: ``kind="tightening"`` takes it,
        ``kind="rigid"`` (whose cross-section ``Z`` needs Rakovic et al.'s ``A^s W in alpha W``)
        refuses it naming ``E``.
    kind : {"rigid", "tightening"}
        The formulation (see the module's description).
    state_constraints, input_constraints, disturbance_set : (H, h) pair, optional
        General polytopes ``{H x <= h}`` instead of (or on top of, for the constraints) the boxes.
        ``W`` must be bounded with the origin in its interior.
    K : (m, n) array_like, optional
        The disturbance-rejection gain, ``A + B K`` Schur stable (default: LQR on ``(A, B, Q, R)``).
    epsilon : float
        The accuracy of the rigid tube's mRPI approximation (infinity norm, default 1e-3); for
        the tightening, of the bound on the minimal RPI set's support that stops the terminal
        set's construction (:func:`rmpc.sets.mrpi_support_bound`).
    backend : {"proxqp", "osqp", "clarabel", "cvxpy"} or QPBackend
        The QP back-end (default ``"clarabel"``: on the double integrator's rigid tube, OSQP and
        ProxQP failed on feasible QPs near the edge of the feasible set (iteration limits, a
        false ``"infeasible"``), Clarabel did not; see ``docs/tube_mpc.rst``).
    solver_options : mapping, optional
        The back-end's settings (:func:`rmpc.qp.make_backend`).
    max_horizon : int
        The largest ``horizon`` accepted (:data:`MAX_HORIZON`).

    Attributes
    ----------
    name : str
        ``"TubeMPC"`` (rigid) or ``"TubeMPC-tightening"``.
    sets : TubeSets
        The gain, terminal weight and sets.
    Z : Polytope or None
        The rigid tube's cross-section.
    X, U : tuple
        The state and input constraints as ``(H, h, names)``: all rows ``H x <= h`` (boxes
        first) and the argument names they came from.
    W : Polytope
        The disturbance set (in the space of ``w``).
    E : (n, q) ndarray
        The disturbance's input matrix.
    last : StepInfo or None
        The back-end's status (``"bound_violation"`` when an answer breaks its rows), the solve
        time, ``fallback`` and ``extra`` (``z0``, ``c``, ``objective``, ``backend``, ``raw_status``).

    Raises
    ------
    InvalidArgumentError
        Naming the argument: ``W`` unbounded or without the origin inside (``w_max`` /
        ``disturbance_set``), ``K`` not stabilising, constraints that the tightening empties
        (``state_constraints`` / ``input_constraints``, or ``x_max`` / ``u_max``), wrong shapes.
    PolytopeError
        When cddlib's floating-point arithmetic gives up on a set (the rigid tube's Minkowski
        sums); the message names the set.

    Notes
    -----
    *Failures.* When the QP has no usable answer (the state lies outside the tube's feasible
    set, or the solver fails), the step applies the shifted plan of the last solved step, ``u =
    K x + c_(k)`` (Mayne's and Chisci's feasible candidate, valid while the disturbance stayed in
    ``W``; ``u = K x`` once the plan is used up), or zero when there is none;
    ``last.fallback`` is ``True`` and ``last.status`` is the back-end's word.

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc import TubeMPC
    >>> A, B = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[0.5], [1.0]])
    >>> tube = TubeMPC((A, B), Q=np.eye(2), R=0.01, horizon=9, u_max=1.0, x_max=[10, 10],
    ...                w_max=[0.1, 0.1], kind="rigid")
    >>> u = tube.step([-5.0, -2.0])
    >>> tube.last.status, bool(abs(u[0]) <= 1.0)
    ('optimal', True)
    """

    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: Any,
        Q: ArrayLike,
        R: ArrayLike,
        horizon: int = 9,
        *,
        u_max: ArrayLike | None = None,
        x_max: ArrayLike | None = None,
        w_max: ArrayLike | None = None,
        kind: str = "rigid",
        state_constraints: tuple[ArrayLike, ArrayLike] | None = None,
        input_constraints: tuple[ArrayLike, ArrayLike] | None = None,
        disturbance_set: tuple[ArrayLike, ArrayLike] | None = None,
        K: ArrayLike | None = None,
        E: ArrayLike | None = None,
        epsilon: float = 1e-3,
        backend: str | QPBackend = "clarabel",
        solver_options: Mapping[str, Any] | None = None,
        max_horizon: int = MAX_HORIZON,
    ) -> None:
        A, B = _plant(plant)
        n, m = B.shape
        self.kind = check_choice(kind, "kind", KINDS)
        limit = check_count(max_horizon, "max_horizon")
        self.N = check_count(horizon, "horizon", limit=limit, limit_name="max_horizon", unit=" samples")
        self.Q = as_square_matrix(Q, "Q", n, allow_zero=True, definite="psd")
        self.R = as_square_matrix(R, "R", m)
        self.X = self._constraints(x_max, state_constraints, "x_max", "state_constraints", n)
        self.U = self._constraints(u_max, input_constraints, "u_max", "input_constraints", m)
        if w_max is not None and disturbance_set is not None:
            raise InvalidArgumentError("disturbance_set", "None when w_max is given (one W)", "both given")
        if w_max is None and disturbance_set is None:
            raise InvalidArgumentError("w_max", "the disturbance bound (or disturbance_set)", "neither given")
        self.E = np.eye(n) if E is None else as_matrix(E, "E", (n, None))
        q = self.E.shape[1]
        if w_max is not None:
            wH, wh = _box_rows(w_max, "w_max", q)
            w_name = "w_max"
        else:
            wH, wh = _as_constraints(disturbance_set, "disturbance_set", q)
            w_name = "disturbance_set"
        W = Polytope(wH, wh, w_name)
        if not W.contains_origin_inside():
            raise InvalidArgumentError(w_name, "a disturbance set with the origin in its interior",
                                       f"min h_i = {float(W.h.min()):.6g} (the origin is not inside)")
        self.W = W
        if isinstance(epsilon, bool) or not isinstance(epsilon, int | float) or not 0 < epsilon < np.inf:
            raise InvalidArgumentError("epsilon", "a finite number > 0", repr(epsilon))
        self.epsilon = float(epsilon)
        self.A, self.B = A, B
        if K is None:
            P = sla.solve_discrete_are(A, B, self.Q, self.R)
            k = -np.linalg.solve(self.R + B.T @ P @ B, B.T @ P @ A)
        else:
            k = as_matrix(K, "K", (m, n))
        # a K with A + B K not Schur stable is refused by mrpi_parameters, naming K
        self.backend = self._backend(backend, solver_options)
        self._limit = limit
        self._assemble(self._design_sets(k))

    # -- the design ------------------------------------------------------------------------
    @staticmethod
    def _constraints(box: Any, general: Any, box_name: str, general_name: str, size: int
                     ) -> tuple[np.ndarray, np.ndarray, str]:
        rows, rhs, names = [np.zeros((0, size))], [np.zeros(0)], []
        if box is not None:
            H, h = _box_rows(box, box_name, size)
            rows.append(H)
            rhs.append(h)
            names.append(box_name)
        if general is not None:
            H, h = _as_constraints(general, general_name, size)
            rows.append(H)
            rhs.append(h)
            names.append(general_name)
        return np.vstack(rows), np.concatenate(rhs), " and ".join(names) or box_name

    @staticmethod
    def _backend(backend: Any, options: Any) -> QPBackend:
        if options is not None and not isinstance(options, Mapping):
            raise ArgumentTypeError("solver_options", "a mapping of setting names", type(options).__name__)
        if isinstance(backend, QPBackend):
            if options:
                raise InvalidArgumentError("solver_options", "None when backend is a QPBackend instance",
                                           repr(dict(options)))
            return backend
        if isinstance(backend, str):
            return make_backend(backend, argument="backend", **dict(options or {}))
        raise ArgumentTypeError("backend", "a back-end name or a rmpc.qp.QPBackend", type(backend).__name__)

    def _design_sets(self, k: np.ndarray) -> TubeSets:
        A_K = self.A + self.B @ k
        P = sla.solve_discrete_lyapunov(A_K.T, self.Q + k.T @ self.R @ k)
        P = 0.5 * (P + P.T)
        (Hx, hx, x_name), (Hu, hu, u_name) = self.X, self.U
        G = np.vstack([Hx, Hu @ k])            # rows on z of the nominal under u = K z
        gb = np.concatenate([hx, hu])
        N = self.N
        if self.kind == "rigid":
            approx = mrpi_outer(A_K, self._state_disturbance(), self.epsilon)
            Z = approx.Z
            t_x, t_u = Z.support(Hx), Z.support(Hu @ k)
            self._check_left("X - Z", x_name, hx - t_x, Hx)
            self._check_left("U - K Z", u_name, hu - t_u, Hu)
            rhs = gb - np.concatenate([t_x, t_u])
            terminal = admissible_set(A_K, G, lambda j: rhs, name="terminal set")
            return TubeSets(k, P, Z.H.copy(), Z.h.copy(), np.tile(t_x, (N, 1)), np.tile(t_u, (N, 1)),
                            terminal.H.copy(), terminal.h.copy(), approx.alpha, approx.s)
        # Chisci et al.: tightening by F_i, terminal set for F_(N+j); its construction stops once
        # the set is mapped into an ellipsoid inside the constraints tightened by a bound of the
        # minimal RPI set's support (support functions and LPs only: no set is built)
        t_all, s = mrpi_support_bound(A_K, self.W, G, self.epsilon, E=self.E)
        self._check_left("X - F_inf", x_name, hx - t_all[: len(hx)], Hx)
        self._check_left("U - K F_inf", u_name, hu - t_all[len(hx):], Hu)
        steps = N + TERMINAL_STEPS
        tight = reachable_tightening(A_K, self.W, G, steps, E=self.E)
        terminal = admissible_set(A_K, G, lambda j: gb - tight[N + j], g_limit=gb - t_all,
                                  name="terminal set", max_steps=TERMINAL_STEPS)
        return TubeSets(k, P, None, None, tight[:N, : len(hx)], tight[:N, len(hx):],
                        terminal.H.copy(), terminal.h.copy(), float("nan"), s)

    def _state_disturbance(self) -> Polytope:
        """``E W`` as a polytope of the state space (the rigid tube's Minkowski sums need one
        with the origin in its interior)."""
        n = self.A.shape[0]
        if self.E.shape == (n, n) and np.array_equal(self.E, np.eye(n)):
            return self.W
        rank = int(np.linalg.matrix_rank(self.E))
        if rank < n:
            raise InvalidArgumentError(
                "E", "for kind='rigid', a disturbance E w with the origin in the interior of E W "
                "(E of rank n; kind='tightening' takes a flat E W)",
                f"E of rank {rank} for {n} states",
            )
        return Polytope.from_vertices(self.W.vertices @ self.E.T, "E W")

    @staticmethod
    def _check_left(what: str, name: str, left: np.ndarray, rows: np.ndarray) -> None:
        if rows.shape[0] and not np.all(left > 0):
            i = int(np.argmin(left))
            raise InvalidArgumentError(
                name, f"constraints that survive the tube's tightening ({what} must contain the origin "
                "in its interior: a smaller W, a larger bound or another K)",
                f"row {i} left with {left[i]:.6g} after tightening",
            )

    # -- the QP ----------------------------------------------------------------------------
    def _assemble(self, sets: TubeSets) -> None:
        """Build the condensed QP's matrices from ``sets`` (nothing is designed here)."""
        self.sets = sets
        A, B, N = self.A, self.B, self.N
        n, m = B.shape
        k = sets.K
        A_K = A + B @ k
        rigid = self.kind == "rigid"
        self.name = "TubeMPC" if rigid else "TubeMPC-tightening"
        self.Z = Polytope(sets.Z_H, sets.Z_h, "Z") if rigid else None
        # z_i = A_K^i z0 + sum_{j<i} A_K^(i-1-j) B c_j, i = 0..N
        phi = np.zeros(((N + 1) * n, n))
        gam = np.zeros(((N + 1) * n, N * m))
        power = np.eye(n)
        for i in range(N + 1):
            phi[i * n:(i + 1) * n] = power
            power = A_K @ power
        for j in range(N):
            blk = B
            for i in range(j + 1, N + 1):
                gam[i * n:(i + 1) * n, j * m:(j + 1) * m] = blk
                blk = A_K @ blk
        sz = np.hstack([phi, gam])                                   # [z0; c] -> z_0..z_N
        sv = np.kron(np.eye(N), k) @ sz[: N * n] + np.hstack([np.zeros((N * m, n)), np.eye(N * m)])
        qbar = sla.block_diag(*([self.Q] * N + [sets.P]))
        rbar = np.kron(np.eye(N), self.R)
        hfull = 2.0 * (sz.T @ qbar @ sz + sv.T @ rbar @ sv)
        hfull = 0.5 * (hfull + hfull.T)
        (Hx, hx, _), (Hu, hu, _) = self.X, self.U
        rows, rhs = [], []
        first_state = 0 if rigid else 1                              # z_0 = x is not a decision
        for i in range(N):
            if i >= first_state and Hx.shape[0]:
                rows.append(Hx @ sz[i * n:(i + 1) * n])
                rhs.append(hx - sets.state_tightening[i])
            if Hu.shape[0]:
                rows.append(Hu @ sv[i * m:(i + 1) * m])
                rhs.append(hu - sets.input_tightening[i])
        rows.append(sets.terminal_H @ sz[N * n:])
        rhs.append(sets.terminal_h)
        cfull = np.vstack(rows)
        self._rhs = np.concatenate(rhs)
        if rigid:
            # x - z0 in Z:  -Z_H z0 <= Z_h - Z_H x
            zrows = np.hstack([-sets.Z_H, np.zeros((sets.Z_H.shape[0], N * m))])
            self._C = np.vstack([cfull, zrows])
            self._rhs = np.concatenate([self._rhs, sets.Z_h])
            self._rhs_x = np.vstack([np.zeros((cfull.shape[0], n)), -sets.Z_H])   # u(x) = rhs + rhs_x x
            self._H, self._g_x = hfull, np.zeros((n + N * m, n))
            self._cost_xx = np.zeros((n, n))
            self._nz = n + N * m
        else:
            self._C = cfull[:, n:]
            self._rhs_x = -cfull[:, :n]
            self._H = hfull[n:, n:]
            self._g_x = hfull[n:, :n]                                 # g = H_cz x
            self._cost_xx = 0.5 * hfull[:n, :n]                       # the cost's part in x alone
            self._nz = N * m
        self._row_scale = np.maximum(1.0, np.abs(self._rhs))
        self._setup_done = False
        self.reset()

    def qp_at(self, x: ArrayLike) -> QP:
        """The (validated) QP the controller solves at state ``x`` (for tests and reports)."""
        x = as_vector(x, "x", self.A.shape[0])
        return QP(H=self._H, g=self._g_x @ x, C=self._C, u=self._rhs + self._rhs_x @ x)

    # -- the step(x) protocol --------------------------------------------------------------
    def reset(self) -> None:
        """Forget the last plan (the next failure has no shifted plan to fall back on)."""
        self._plan: np.ndarray | None = None
        self._shift = 0
        self.last: StepInfo | None = None

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``u = v_0 + K (x - z_0)`` (rigid) or ``u = K x + c_0`` (tightening)."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        n, m = self.B.shape
        x = as_vector(x, "x", n)
        g, upper = self._g_x @ x, self._rhs + self._rhs_x @ x
        if not self._setup_done:
            self.backend.setup(QP(H=self._H, g=g, C=self._C, u=upper))
            self._setup_done = True
        else:
            self.backend.update(g=g, u=upper)
        res = self.backend.solve()
        status, fallback = res.status, False
        k = self.sets.K
        z0 = None
        if res.status == Status.OPTIMAL and np.all(self._C @ res.x - upper <= ROW_TOL * self._row_scale):
            if self.kind == "rigid":
                z0, c = res.x[:n], res.x[n:]
            else:
                z0, c = x, res.x
            u = k @ x + c[:m]        # v_0 + K (x - z_0) = K z_0 + c_0 + K (x - z_0)
            self._plan, self._shift = c.reshape(self.N, m), 0
        else:
            if res.status == Status.OPTIMAL:
                status = Status.BOUND_VIOLATION
            fallback = True
            u = self._fallback(x)
        self.last = StepInfo(
            status=status, solve_time=res.solve_time, iterations=res.iterations, fallback=fallback,
            extra={"z0": z0, "objective": res.objective, "backend": self.backend.name,
                   "raw_status": res.raw_status, "step_time": time.perf_counter() - start},
        )
        return u

    def _fallback(self, x: np.ndarray) -> np.ndarray:
        if self._plan is None:
            return np.zeros(self.B.shape[1])
        self._shift += 1
        c = self._plan[self._shift] if self._shift < self.N else np.zeros(self.B.shape[1])
        return self.sets.K @ x + c

    # -- save and load ---------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The model, weights, constraint and disturbance sets, options and the computed sets
        (gain, terminal weight, tube cross-section, tightenings, terminal set), so that loading
        designs nothing."""
        from rmpc.qp.factory import backend_design

        saved_backend = backend_design(self.backend)
        sets = {f.name: getattr(self.sets, f.name) for f in dataclasses.fields(self.sets)}
        return encode({
            "A": self.A, "B": self.B, "Q": self.Q, "R": self.R, "horizon": self.N, "kind": self.kind,
            "state_constraints": [self.X[0], self.X[1], self.X[2]],
            "input_constraints": [self.U[0], self.U[1], self.U[2]],
            "disturbance_set": [self.W.H, self.W.h, self.W.name], "E": self.E, "epsilon": self.epsilon,
            **saved_backend,
            "max_horizon": self._limit, "sets": sets,
        }, "TubeMPC design")

    @classmethod
    def _from_design(cls, design: Design) -> TubeMPC:
        """The saved sets as they were (no mRPI set, tightening or terminal set computed again)."""
        ctrl = cls.__new__(cls)
        ctrl.A, ctrl.B = design.array("A", 2), design.array("B", 2)
        n, m = ctrl.B.shape
        ctrl.Q = as_square_matrix(design.array("Q", 2), "design.Q", n, allow_zero=True, definite="psd")
        ctrl.R = as_square_matrix(design.array("R", 2), "design.R", m)
        ctrl.kind = check_choice(design.text("kind"), "design.kind", KINDS)
        ctrl._limit = design.integer("max_horizon")
        ctrl.N = check_count(design.integer("horizon"), "design.horizon", limit=ctrl._limit)
        ctrl.epsilon = design.number("epsilon")

        def triple(name: str, size: int) -> tuple[np.ndarray, np.ndarray, str]:
            raw = design.value(name)
            if not isinstance(raw, list) or len(raw) != 3 or not isinstance(raw[2], str):
                raise InvalidArgumentError(f"design.{name}", "[H, h, name]", repr(raw)[:80])
            part = Design({"H": raw[0], "h": raw[1]}, f"design.{name}")
            H = np.array(part.array("H"), dtype=float).reshape(-1, size)
            return H, part.array("h", 1), raw[2]

        ctrl.X, ctrl.U = triple("state_constraints", n), triple("input_constraints", m)
        saved_e = design.optional_array("E", 2)
        ctrl.E = np.eye(n) if saved_e is None else as_matrix(saved_e, "design.E", (n, None))
        wH, wh, wname = triple("disturbance_set", ctrl.E.shape[1])
        ctrl.W = Polytope(wH, wh, wname)
        ctrl.backend = cls._backend(design.text("backend"), design.mapping("solver_options"))
        part = design.part("sets")
        opt = part.optional_array
        sets = TubeSets(
            K=as_matrix(part.array("K", 2), "design.sets.K", (m, n)), P=part.array("P", 2),
            Z_H=opt("Z_H", 2), Z_h=opt("Z_h", 1),
            state_tightening=part.array("state_tightening").reshape(ctrl.N, -1),
            input_tightening=part.array("input_tightening").reshape(ctrl.N, -1),
            terminal_H=part.array("terminal_H", 2), terminal_h=part.array("terminal_h", 1),
            alpha=part.number("alpha"), s=part.integer("s"),
        )
        part.finish()
        ctrl._assemble(sets)
        return ctrl

    def settings(self) -> dict[str, Any]:
        """Every parameter of the controller, for reports."""
        return {
            "kind": self.kind, "horizon": self.N, "Q": self.Q.tolist(), "R": self.R.tolist(),
            "K": self.sets.K.tolist(), "epsilon": self.epsilon, "alpha": self.sets.alpha, "s": self.sets.s,
            "terminal_facets": int(self.sets.terminal_h.size),
            "Z_facets": None if self.sets.Z_h is None else int(self.sets.Z_h.size),
            "backend": self.backend.name, "qp_variables": self._nz, "qp_rows": int(self._C.shape[0]),
        }

    def __repr__(self) -> str:
        return f"TubeMPC(kind={self.kind!r}, horizon={self.N}, backend={self.backend.name!r})"
