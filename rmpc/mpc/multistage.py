"""Multi-stage (scenario-tree) MPC over the vertices of a polytopic model.

Lucia, Finkler & Engell, "Multi-stage nonlinear model predictive control applied to a
semi-batch polymerization reactor under uncertainty", Journal of Process Control 23(9), 2013:
the uncertainty is represented by a tree of its discrete realisations, here the vertices
``(A_j, B_j)`` of a :class:`~models.PolytopicModel`. In the first ``robust_horizon`` stages every
node branches into one child per vertex; then each branch keeps its vertex up to the horizon
(:mod:`rmpc.mpc.scenario_tree`). Every node has its own input, shared by all the scenarios
through it (non-anticipativity), so the plan is a causal policy that reacts to the vertex
realised, not one open-loop sequence for all. The cost is the expected cost over equally
likely scenarios::

    min  sum_nodes p(node) (x'Q x + u'R u)  +  sum_leaves p(leaf) x_N' P_leaf x_N
    s.t. x_child = A_j x_parent + B_j u_parent   (j the edge's vertex; x at the root = the measured x)
         |u_i| <= u_max_i at every input node,   H x <= h at every predicted state node

with ``p`` the share of scenarios through a node. The QP is sparse (inputs and states of every
node are variables, the dynamics equality rows); it is built once, and at each step only the
right-hand side of the first stage's rows (``A_j x``) changes: an update of two vectors, then a
solve through the QP layer :mod:`rmpc.qp` that reuses the back-end's factorisation (Clarabel by
default, chosen on measurement: docs/multistage.rst). The state rows are held
:data:`STATE_MARGIN` inside their bounds, against the solvers' accuracy.

Terminal ingredient: a terminal *cost*, no terminal set. By default (``terminal="vertex"``) the
leaf of a branch that keeps vertex ``j`` is weighted by ``P_j``, the Riccati solution of vertex
``j``: the unconstrained infinite-horizon cost of that branch's own plant, which is what the
tree assumes after the robust horizon. ``"nominal"`` uses the nominal model's Riccati solution
for every leaf; a matrix may be given instead (for example the ``Q^-1``-scaled matrix of
Kothare's robust ellipsoid, whose quadratic form bounds the worst-case cost over the polytope).
Kothare's invariant ellipsoid as a terminal *set* is a quadratic constraint, not a QP, and is not
offered.

What it guarantees, and what not
--------------------------------
* A step whose QP is solved (``"optimal"``) applies an input within the input bounds (exact box
  constraints; a solver excess above 1e-6 of the bound is reported as ``"bound_violation"``).
* With ``robust_horizon >= 1`` the tree holds every vertex successor ``A_j x + B_j u`` of the
  applied input inside the state polytope; the true successor of any plant in the polytope is a
  convex combination of those, so **the next state satisfies the state constraints**, whatever
  plant of the polytope acts (``last.extra["next_state_margin"]`` is the largest ``H x_j - h``
  over the vertices, <= 0 up to the solver's tolerance).
* **Not guaranteed: recursive feasibility** with state constraints. The branches assume a
  constant vertex after the robust horizon, and there is no robust invariant terminal set, so a
  QP solved at one sample may be infeasible at the next one under a switching plant. (With
  ``robust_horizon = horizon`` and a terminal set that is robust control invariant it would be:
  the feasible set of the QP is convex and contains every vertex successor; that set is not
  computed here.) Without state constraints the QP is always feasible.
* An unsolved QP is a status (``"infeasible"``, ``"max_iterations"``, ...), never a silent
  number: the step then applies the previous plan's input for the realised plant where it can,
  else the nominal LQR gain clipped to the input bounds, and
  sets ``last.fallback``.
* Stability is not proven: the terminal cost is a Lyapunov function of each branch's LQR only
  where that LQR does not saturate.

Input bounds are per component (``|u_i| <= u_max_i``, ``input_constraint="peak"``). The
Euclidean bound ``||u||_2 <= u_max`` of Kothare's form is a second-order cone constraint, not a
QP: it is refused with a message.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import ArrayLike
from scipy.optimize import nnls

from models import PolytopicModel
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode, plant_design
from rmpc.io.saveable import Saveable
from rmpc.mpc.scenario_tree import MAX_VARIABLES, ScenarioTree, check_tree_size, tree_size
from rmpc.qp import QP, QPBackend, make_backend
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import (
    as_matrix,
    as_optional_limits,
    as_vector,
    check_choice,
    check_count,
    check_pd,
    check_psd,
)

__all__ = ["MAX_DENSE_VARIABLES", "STATE_MARGIN", "MultiStageMPC", "riccati"]

#: The largest tree a dense QP back-end (ProxQP, Clarabel's stacking, cvxpy) is handed: its
#: matrices are then dense, ``8 n^2`` bytes for ``H`` alone (3000 variables: 72 MB). Larger trees
#: need ``backend="osqp"`` (sparse).
MAX_DENSE_VARIABLES = 3000

#: Accepted excess of the solver's input over its bound (relative), before it is clipped to it.
_BOUND_TOL = 1e-6

#: The state polytope of the QP is ``H x <= h - STATE_MARGIN * max(1, |h|)``: the solvers meet
#: their constraints to about 1e-8 (OSQP's and ProxQP's tolerances), and without the margin a
#: predicted state on its bound came out 1e-8 beyond it (measured with OSQP on paper P's
#: satellite with a rate bound of 0.3 rad/s: 11 of 1500 samples).
STATE_MARGIN = 1e-6

#: The previous plan's inputs are used after a failed solve when the measured state is this
#: close (relative, ``max(1, ||x||)``) to a convex combination of the plan's first-stage states.
_PLAN_TOL = 1e-6

_TERMINALS = ("vertex", "nominal")

#: The back-ends that take the QP's matrices sparse.
_SPARSE_BACKENDS = ("osqp", "clarabel")


def riccati(
    a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray, name: str
) -> tuple[np.ndarray, np.ndarray]:
    """The discrete Riccati solution ``P`` and the LQR gain ``K`` (``u = -K x``) of ``(a, b)``.

    Raises :class:`~toolkit_common.errors.InvalidArgumentError` naming ``name`` when the pair is
    not stabilisable with ``(Q, A)`` detectable.

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.mpc.multistage import riccati
    >>> p, k = riccati(np.eye(1), np.eye(1), np.eye(1), np.eye(1), "plant")
    >>> round(float(p[0, 0]), 6), round(float(k[0, 0]), 6)
    (1.618034, 0.618034)
    """
    try:
        p = sla.solve_discrete_are(a, b, q, r)
    except (ValueError, np.linalg.LinAlgError) as err:
        raise InvalidArgumentError(
            name, "a stabilisable (A, B) with detectable (Q, A)", f"the Riccati equation failed: {err}"
        ) from None
    p = 0.5 * (p + p.T)
    k = np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)
    return p, k


def _simplex_weights(points: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The weights ``l >= 0``, ``sum l = 1`` whose combination of the columns of ``points`` is
    nearest ``x`` (non-negative least squares with the sum as a heavily weighted row)."""
    scale = 1e3 * max(1.0, float(np.abs(points).max()))
    mat = np.vstack((points, np.full((1, points.shape[1]), scale)))
    weights, _ = nnls(mat, np.concatenate((x, [scale])))
    return weights / max(weights.sum(), 1e-300)


def _polytope(value: Any, name: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(value, tuple | list) or len(value) != 2:
        raise ArgumentTypeError(name, "a pair (H, h) describing H x <= h", type(value).__name__)
    h_mat = as_matrix(value[0], f"{name} H", (None, n))
    h_vec = as_vector(value[1], f"{name} h", h_mat.shape[0])
    if np.any(h_vec < 0):
        i = int(np.argmin(h_vec))
        raise InvalidArgumentError(
            f"{name} h", "h >= 0 (a polytope containing the origin, the point the controller regulates to)",
            f"h[{i}] = {h_vec[i]:.6g}",
        )
    if np.any(np.all(h_mat == 0, axis=1)):
        raise InvalidArgumentError(f"{name} H", "rows that are not all zero", "an all-zero row")
    return h_mat, h_vec


class MultiStageMPC(Saveable):
    """Multi-stage (scenario-tree) MPC over the vertices of a polytopic model, solved as one QP.

    Parameters
    ----------
    plant : PolytopicModel
        The tree branches over its vertices; the fallback gain is its nominal model's LQR.
    Q : (n, n) array_like
        State weight, symmetric positive semidefinite.
    R : (m, m) array_like
        Input weight, symmetric positive definite.
    horizon : int
        Prediction horizon ``N`` in samples (default 10).
    robust_horizon : int
        Stages that branch, ``1 <= robust_horizon <= horizon`` (default 1).
    u_max : float, (m,) array_like or None
        ``|u_i| <= u_max_i`` at every input node; ``None`` for no bound.
    input_constraint : {"peak"}
        ``"peak"`` (per component). ``"ellipsoid"`` (``||u||_2 <= u_max``) is refused: it is not
        a QP constraint.
    state_constraints : (H, h) pair, optional
        ``H x <= h`` at every predicted state (stages 1 to ``N``); ``h >= 0`` (the origin inside).
    output_matrix, y_max : array_like, optional
        Output bounds ``|C x| <= y_max`` (as :class:`~rmpc.RMPC` takes them), added to the state
        polytope as the rows ``[C; -C] x <= [y_max; y_max]``.
    terminal : {"vertex", "nominal"} or (n, n) array_like
        The terminal cost (see the module docstring; default ``"vertex"``).
    backend : {"clarabel", "osqp", "proxqp", "cvxpy"} or QPBackend
        The QP back-end (default ``"clarabel"``: sparse, interior point, every QP of the measured
        trees solved; ProxQP was faster on the smallest tree, OSQP failed on many: see
        docs/multistage.rst). Clarabel and OSQP take the matrices sparse; the others take trees of
        at most :data:`MAX_DENSE_VARIABLES` variables.
    solver_options : mapping, optional
        The back-end's settings, passed to :func:`rmpc.qp.make_backend`.
    max_variables : int
        The largest tree accepted, in QP variables (default
        :data:`~rmpc.mpc.scenario_tree.MAX_VARIABLES`); a larger one is refused, naming
        ``robust_horizon`` with the estimate of the tree's size.

    Attributes
    ----------
    name : str
        ``"MultiStageMPC"``.
    tree : ScenarioTree
        The tree's nodes.
    size : dict
        The tree's and the QP's size (:func:`~rmpc.mpc.scenario_tree.tree_size`).
    last : StepInfo or None
        The last step: the back-end's status (or ``"bound_violation"``), ``solve_time``,
        ``iterations``, ``fallback``, ``extra`` (``objective``, ``backend``, ``raw_status``,
        ``step_time``, ``next_state_margin``, ``fallback_kind``: ``None``, ``"previous_plan"``
        or ``"lqr"``).

    Examples
    --------
    >>> import numpy as np
    >>> from models import PolytopicModel
    >>> from rmpc import MultiStageMPC
    >>> A = np.array([[1.0, 1.0], [0.0, 1.0]])
    >>> plant = PolytopicModel([(A, [[0.5], [1.0]]), (A, [[0.4], [0.8]])], dt=1.0)
    >>> ms = MultiStageMPC(plant, Q=np.eye(2), R=np.eye(1), horizon=5, u_max=1.0,
    ...                    state_constraints=(np.vstack((np.eye(2), -np.eye(2))), [10, 10, 10, 10]))
    >>> u = ms.step([2.0, 1.0])
    >>> ms.last.status, bool(abs(u[0]) <= 1.0), ms.size["scenarios"], ms.size["variables"]
    ('optimal', True, 2, 29)
    """

    name = "MultiStageMPC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: PolytopicModel,
        Q: ArrayLike,
        R: ArrayLike,
        horizon: int = 10,
        robust_horizon: int = 1,
        u_max: ArrayLike | None = None,
        input_constraint: str = "peak",
        *,
        state_constraints: tuple[ArrayLike, ArrayLike] | None = None,
        output_matrix: ArrayLike | None = None,
        y_max: ArrayLike | None = None,
        terminal: str | ArrayLike = "vertex",
        backend: str | QPBackend = "clarabel",
        solver_options: Mapping[str, Any] | None = None,
        max_variables: int = MAX_VARIABLES,
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            raise ArgumentTypeError("plant", "a models.PolytopicModel", type(plant).__name__)
        n, m, nv = plant.n_states, plant.n_inputs, plant.n_vertices
        self.plant, self.dt = plant, plant.dt
        self.Q = check_psd(as_matrix(Q, "Q", (n, n)), "Q")
        self.R = check_pd(as_matrix(R, "R", (m, m)), "R")
        self.horizon = check_count(horizon, "horizon")
        self.robust_horizon = check_count(robust_horizon, "robust_horizon")
        if self.robust_horizon > self.horizon:
            raise InvalidArgumentError(
                "robust_horizon", f"an integer in [1, horizon = {self.horizon}]", repr(robust_horizon)
            )
        self.max_variables = check_count(max_variables, "max_variables")
        if input_constraint == "ellipsoid":
            raise InvalidArgumentError(
                "input_constraint",
                "'peak' (|u_i| <= u_max_i): the Euclidean bound ||u||_2 <= u_max is a second-order cone "
                "constraint, which a QP cannot hold (pass 'peak', or an inner polytope of the ball "
                "through RMPC's forms)", repr(input_constraint),
            )
        check_choice(input_constraint, "input_constraint", ("peak",))
        self.input_constraint = "peak"
        self.u_max = as_optional_limits(u_max, "u_max", m, per="input")
        self.state_constraints = None if state_constraints is None else _polytope(
            state_constraints, "state_constraints", n)
        if (output_matrix is None) != (y_max is None):
            raise InvalidArgumentError(
                "output_matrix, y_max", "both or neither",
                f"output_matrix {'given' if output_matrix is not None else 'None'}, "
                f"y_max {'given' if y_max is not None else 'None'}",
            )
        self.output_matrix = None if output_matrix is None else as_matrix(
            output_matrix, "output_matrix", (None, n))
        self.y_max = None if self.output_matrix is None else as_optional_limits(
            y_max, "y_max", self.output_matrix.shape[0], per="output")
        rows = self._state_rows()
        self.size = tree_size(nv, self.horizon, self.robust_horizon, n_states=n, n_inputs=m,
                              state_rows=rows[0].shape[0])
        check_tree_size(self.size, self.max_variables, nv, self.horizon, self.robust_horizon)
        self.tree = ScenarioTree(nv, self.horizon, self.robust_horizon)
        self.backend = self._make_backend(backend, solver_options)
        self._n, self._m = n, m
        self._vertices = [plant.vertex(j) for j in range(nv)]
        _, self.K_nominal = riccati(*plant.nominal, self.Q, self.R, "plant (nominal model)")
        self.terminal, self._terminal_p = self._terminal(terminal)
        self._h_rows, self._h_vec = rows
        self._build()
        self.reset()

    # -- construction --------------------------------------------------------------------
    def _state_rows(self) -> tuple[np.ndarray, np.ndarray]:
        n = self.plant.n_states
        mats, vecs = [np.zeros((0, n))], [np.zeros(0)]
        if self.state_constraints is not None:
            mats.append(self.state_constraints[0])
            vecs.append(self.state_constraints[1])
        if self.output_matrix is not None:
            assert self.y_max is not None
            mats += [self.output_matrix, -self.output_matrix]
            vecs += [self.y_max, self.y_max]
        return np.vstack(mats), np.concatenate(vecs)

    def _make_backend(self, backend: str | QPBackend, options: Mapping[str, Any] | None) -> QPBackend:
        if options is not None and not isinstance(options, Mapping):
            raise ArgumentTypeError("solver_options", "a mapping of setting names", type(options).__name__)
        if isinstance(backend, QPBackend):
            if options:
                raise InvalidArgumentError(
                    "solver_options", "None when backend is a QPBackend instance", repr(dict(options)))
            made = backend
        elif isinstance(backend, str):
            made = make_backend(backend, argument="backend", **dict(options or {}))
        else:
            raise ArgumentTypeError(
                "backend", "a back-end name or a rmpc.qp.QPBackend", type(backend).__name__)
        if made.name not in _SPARSE_BACKENDS and self.size["variables"] > MAX_DENSE_VARIABLES:
            raise InvalidArgumentError(
                "backend",
                f"'osqp' or 'clarabel' (sparse) for a tree of more than MAX_DENSE_VARIABLES = "
                f"{MAX_DENSE_VARIABLES} variables (the other back-ends hold the QP's matrices dense)",
                f"{made.name!r} with {self.size['variables']} variables",
            )
        return made

    def _terminal(self, terminal: Any) -> tuple[str | np.ndarray, list[np.ndarray]]:
        nv, n = self.plant.n_vertices, self.plant.n_states
        if isinstance(terminal, str):
            check_choice(terminal, "terminal", _TERMINALS)
            if terminal == "nominal":
                p, _ = riccati(*self.plant.nominal, self.Q, self.R, "plant (nominal model)")
                return terminal, [p] * nv
            return terminal, [riccati(a, b, self.Q, self.R, f"plant (vertex {j})")[0]
                              for j, (a, b) in enumerate(self._vertices)]
        p = check_psd(as_matrix(terminal, "terminal", (n, n)), "terminal")
        return p, [p] * nv

    def _build(self) -> None:
        """The QP's matrices (sparse) and its constant vectors, built once."""
        n, m, tree = self._n, self._m, self.tree
        counts = tree.nodes_per_stage
        probs = tree.probabilities()
        n_u = m * sum(counts[:-1])
        u_off = np.concatenate(([0], np.cumsum(counts[:-1]))) * m      # first input variable of stage k
        x_off = n_u + np.concatenate(([0], np.cumsum(counts[1:]))) * n  # first state variable of stage k+1
        n_var = self.size["variables"]
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        eye_r, eye_c = np.nonzero(np.eye(n))
        ab = [(sp.coo_matrix(a), sp.coo_matrix(b)) for a, b in self._vertices]
        for k in range(tree.horizon):
            parent, child, vertex = tree.transitions(k)
            for p_i, c_i, v in zip(parent.tolist(), child.tolist(), vertex.tolist(), strict=True):
                row0 = x_off[k] + n * c_i - n_u  # equality rows are numbered as the state variables
                rows.append(row0 + eye_r)
                cols.append(x_off[k] + n * c_i + eye_c)
                vals.append(np.ones(n))
                a, b = ab[v]
                if k > 0:
                    rows.append(row0 + a.row)
                    cols.append(x_off[k - 1] + n * p_i + a.col)
                    vals.append(-a.data)
                rows.append(row0 + b.row)
                cols.append(u_off[k] + m * p_i + b.col)
                vals.append(-b.data)
        n_eq = self.size["equality_rows"]
        eq = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(n_eq, n_var))
        state_nodes = self.size["state_nodes"]
        blocks = [eq]
        if self._h_rows.shape[0]:
            ineq = sp.kron(sp.identity(state_nodes), sp.csr_matrix(self._h_rows))
            blocks.append(sp.hstack([sp.csc_matrix((ineq.shape[0], n_u)), ineq]))
        self._C = sp.csc_matrix(sp.vstack(blocks))
        # the Hessian: 2 x (node probability) x weight, so that 1/2 z'Hz is the expected cost
        diag: list[Any] = []
        for k in range(tree.horizon):
            diag += [2.0 * probs[k] * self.R] * counts[k]
        for k in range(1, tree.horizon + 1):
            if k < tree.horizon:
                diag += [2.0 * probs[k] * self.Q] * counts[k]
            else:
                nv = self.plant.n_vertices
                diag += [2.0 * probs[k] * self._terminal_p[i % nv] for i in range(counts[k])]
        self._H = sp.csc_matrix(sp.block_diag(diag, format="csc"))
        self._l = np.concatenate((np.zeros(n_eq), np.full(self._C.shape[0] - n_eq, -np.inf)))
        tightened = self._h_vec - STATE_MARGIN * np.maximum(1.0, np.abs(self._h_vec))
        self._u = np.concatenate((np.zeros(n_eq), np.tile(tightened, state_nodes)))
        # the first stage's states and the inputs of their nodes, for the previous-plan fallback
        nv = self.plant.n_vertices
        self._stage1_x = slice(n_u, n_u + n * nv)
        self._stage1_u = slice(m, m + m * nv)
        bound = np.full(n_u, np.inf) if self.u_max is None else np.tile(self.u_max, n_u // m)
        self._lb = np.concatenate((-bound, np.full(n_var - n_u, -np.inf)))
        self._ub = np.concatenate((bound, np.full(n_var - n_u, np.inf)))
        self._first_a = np.vstack([a for a, _ in self._vertices])  # rows of A_j x, stage 1's right-hand side
        self._dense = self.backend.name not in _SPARSE_BACKENDS

    def qp_at(self, x: ArrayLike) -> QP:
        """The QP the controller solves at state ``x`` (for tests and reports; sparse matrices)."""
        x = as_vector(x, "x", self._n)
        lo, up = self._rhs(x)
        return QP(H=self._H, g=np.zeros(self._H.shape[0]), C=self._C, l=lo, u=up, lb=self._lb, ub=self._ub)

    def status_at(self, x: ArrayLike) -> Status:
        """Solve the tree at ``x`` and return the back-end's status, without a step.

        ``last`` and the plan of the fallback are kept; for a region of attraction (the states
        where the status is ``"optimal"``). A back-end with a warm start starts its next solve
        from this one.

        Examples
        --------
        >>> import numpy as np
        >>> from models import PolytopicModel
        >>> from rmpc import MultiStageMPC
        >>> A = np.array([[1.0, 1.0], [0.0, 1.0]])
        >>> plant = PolytopicModel([(A, [[0.5], [1.0]]), (A, [[0.4], [0.8]])], dt=1.0)
        >>> box = (np.vstack((np.eye(2), -np.eye(2))), [10, 2, 10, 2])
        >>> ms = MultiStageMPC(plant, np.eye(2), np.eye(1), horizon=5, u_max=0.5, state_constraints=box)
        >>> ms.status_at([0.0, 1.0]), ms.status_at([9.5, 2.0]), ms.last is None
        ('optimal', 'infeasible', True)
        """
        x = as_vector(x, "x", self._n)
        return self._solve(x).status

    def _solve(self, x: np.ndarray) -> Any:
        """The back-end's answer at ``x`` (set up on the first call, vectors updated after)."""
        lo, up = self._rhs(x)
        if not self._setup_done:
            h, c = (self._H.toarray(), self._C.toarray()) if self._dense else (self._H, self._C)
            self.backend.setup(QP(H=h, g=np.zeros(h.shape[0]), C=c, l=lo, u=up, lb=self._lb, ub=self._ub))
            self._setup_done = True
        else:
            self.backend.update(l=lo, u=up)
        return self.backend.solve()

    def _rhs(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lo, up = self._l.copy(), self._u.copy()
        first = self._first_a @ x
        lo[: first.size] = first
        up[: first.size] = first
        return lo, up

    # -- the step(x) protocol ---------------------------------------------------------------
    def reset(self) -> None:
        """Forget the last step and plan (the back-end keeps its factorisation and warm start)."""
        self.last: StepInfo | None = None
        self._plan: np.ndarray | None = None

    def _fallback(self, x: np.ndarray) -> tuple[np.ndarray, str]:
        """The input after a failed solve, and which one it is.

        ``"previous_plan"``: when the last solved plan's first-stage states ``x_j`` contain the
        measured ``x`` as a convex combination ``sum l_j x_j`` (the plant acted as a member of
        the polytope), the same combination of those nodes' inputs, which satisfies the input
        bounds; with ``robust_horizon >= 2`` the next state is then a convex combination of
        the plan's second-stage states, so it satisfies the state constraints too. Otherwise
        ``"lqr"``: the nominal LQR gain clipped to the input bounds (no state guarantee). The
        plan is used once: a second failure in a row takes the LQR input.
        """
        plan, self._plan = self._plan, None
        if plan is not None and self.tree.horizon > 1:
            nv, n, m = self.plant.n_vertices, self._n, self._m
            states = plan[self._stage1_x].reshape(nv, n).T
            weights = _simplex_weights(states, x)
            if np.linalg.norm(states @ weights - x) <= _PLAN_TOL * max(1.0, float(np.linalg.norm(x))):
                u = plan[self._stage1_u].reshape(nv, m).T @ weights
                if self.u_max is not None:
                    u = np.clip(u, -self.u_max, self.u_max)  # round-off only: a convex combination
                return u, "previous_plan"
        u = -self.K_nominal @ x
        if self.u_max is not None:
            u = np.clip(u, -self.u_max, self.u_max)
        return u, "lqr"

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return the root input of the tree solved at the measured state ``x``."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        x = as_vector(x, "x", self._n)
        res = self._solve(x)
        status, fallback = res.status, False
        m = self._m
        if res.status == Status.OPTIMAL:
            u = res.x[:m].copy()
            if self.u_max is not None:
                excess = np.max(np.abs(u) - self.u_max - _BOUND_TOL * self.u_max)
                if excess > 0:
                    status, fallback = Status.BOUND_VIOLATION, True
                else:
                    u = np.clip(u, -self.u_max, self.u_max)
        else:
            fallback = True
        kind = None
        if fallback:
            u, kind = self._fallback(x)
        else:
            self._plan = res.x.copy()
        margin = None
        if self._h_rows.shape[0]:
            succ = np.array([a @ x + b @ u for a, b in self._vertices])
            margin = float(np.max(succ @ self._h_rows.T - self._h_vec))
        self.last = StepInfo(
            status=status, solve_time=res.solve_time, iterations=res.iterations, fallback=fallback,
            extra={"objective": res.objective, "backend": self.backend.name, "raw_status": res.raw_status,
                   "step_time": time.perf_counter() - start, "next_state_margin": margin,
                   "fallback_kind": kind},
        )
        return u

    _setup_done = False

    # -- save and load ------------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The plant, weights, horizons, bounds, terminal cost and the QP back-end by name."""
        from rmpc.qp.factory import backend_design

        saved_backend = backend_design(self.backend)
        sc = self.state_constraints
        terminal = self.terminal
        return {"plant": plant_design(self.plant), **encode({
            "Q": self.Q, "R": self.R, "horizon": self.horizon, "robust_horizon": self.robust_horizon,
            "u_max": self.u_max, "input_constraint": self.input_constraint,
            "state_H": None if sc is None else sc[0], "state_h": None if sc is None else sc[1],
            "output_matrix": self.output_matrix, "y_max": self.y_max,
            "terminal": terminal if isinstance(terminal, str) else "matrix",
            "terminal_matrix": None if isinstance(terminal, str) else terminal,
            **saved_backend,
            "max_variables": self.max_variables,
        }, "MultiStageMPC design")}

    @classmethod
    def _from_design(cls, design: Design) -> MultiStageMPC:
        state_h, state_v = design.optional_array("state_H", 2), design.optional_array("state_h", 1)
        terminal: str | np.ndarray = design.text("terminal")
        matrix = design.optional_array("terminal_matrix", 2)
        if terminal == "matrix":
            if matrix is None:
                raise InvalidArgumentError(
                    "design terminal_matrix", "a matrix with terminal 'matrix'", "None")
            terminal = matrix
        return cls(
            design.plant(), Q=design.array("Q", 2), R=design.array("R", 2), horizon=design.integer("horizon"),
            robust_horizon=design.integer("robust_horizon"), u_max=design.optional_array("u_max", 1),
            input_constraint=design.text("input_constraint"),
            state_constraints=None if state_h is None else (state_h, state_v),
            output_matrix=design.optional_array("output_matrix", 2), y_max=design.optional_array("y_max", 1),
            terminal=terminal, backend=design.text("backend"),
            solver_options=design.mapping("solver_options"),
            max_variables=design.integer("max_variables"),
        )

    def settings(self) -> dict[str, Any]:
        """Every parameter of the controller and the tree's size, for reports."""
        return {
            "horizon": self.horizon, "robust_horizon": self.robust_horizon,
            "u_max": None if self.u_max is None else self.u_max.tolist(),
            "input_constraint": self.input_constraint, "state_rows": int(self._h_rows.shape[0]),
            "terminal": self.terminal if isinstance(self.terminal, str) else "matrix",
            "backend": self.backend.name, "dt": self.dt, **self.size,
        }

    def __repr__(self) -> str:
        return (f"MultiStageMPC(horizon={self.horizon}, robust_horizon={self.robust_horizon}, "
                f"scenarios={self.size['scenarios']}, backend={self.backend.name!r})")
