"""A structure-exploiting primal-dual interior-point solver for small block LMI problems.

Solves ::

    minimise c'x   subject to   S_j = C_j - sum_i x_i A_ij  >= 0   (every block j)

with ``x`` in R^n and a few symmetric blocks of small order (the Kothare problems of this
toolkit: tens of variables, blocks of order <= 25). General conic solvers handle this badly:
Clarabel factors a sparse KKT system in the half-vectorised space, in which every order-``k``
block becomes a dense ``k(k+1)/2`` square. Here each Newton step is reduced to the ``n x n``
Schur complement ``H = P' P``, where the columns of ``P`` are the half-vectorised scaled
coefficients ``K A_i K'``. The blocks are small and few, so an iteration written as numpy
calls costs more in the calls' fixed overhead than in arithmetic; the work of an iteration is
therefore done in two compiled calls (:mod:`lmi.ipm.kernels`, numba: the residuals, then the
iteration itself with its factorisation, :mod:`lmi.ipm.kernels.iteration`), and this module
keeps the data, the starting points and the stopping rules.

Algorithm: infeasible-start path following with Nesterov-Todd scaling and Mehrotra's
predictor-corrector, as in Vandenberghe's CVXOPT ``coneqp`` (L. Vandenberghe, "The CVXOPT
linear and quadratic cone program solvers", 2010), without the homogeneous self-dual embedding.
An infeasible problem is recognised from the dual iterates themselves: they grow along a Farkas
ray, and the run ends ``"infeasible"`` once the ray proves that no solution of norm below
``infeasibility_radius`` exists (see :meth:`BlockLMISolver.solve`). An unbounded problem is
recognised from the primal iterates in the same way: they run out along a direction of recession,
and the run ends ``"unbounded"`` once a feasible iterate has ``c'x <= -infeasibility_radius
max(1, ||c||)``; otherwise it ends ``"insufficient_progress"``, ``"max_iterations"`` or
``"numerical_error"``, never as a wrong ``"optimal"``. The NT scaling of each block comes from
one Cholesky factor and one small symmetric eigen-decomposition (as in SDPT3).
Badly balanced blocks are weighted (``w_j S_j``, powers of two from a Ruiz-style balancing, see
:data:`lmi.ipm.blocks.BLOCK_WEIGHT_SPREAD`) and the variables equilibrated (unit Frobenius norm of
each weighted ``A_i``); every output is in the units of the data as given. ``H`` is factored by
Cholesky until it becomes ill-conditioned near the optimum, then through a QR factorisation of
``P`` (which does not square the condition number), whose orthogonal factor then solves the
Newton equations as a projection (:func:`lmi.ipm.kernels.step._newton_qr`); each Newton solve is
iteratively refined on the exact equations. The primal slack is recomputed from ``x`` and the
dual is updated as ``Z + alpha dZ``, so that both residuals decay as the steps say and do not
drift with the rounding of the scaling. Successive solves can be warm-started from an interior
iterate of the previous one.

Larger problems (``factors``): forming ``P`` costs ``size x n`` per block and ``P'P``
``size x n^2``, which grows as ``n_states^6`` for the Kothare blocks. When a block's
coefficients are given in factored form ``A_ij = D_j N_ij D_j'`` (a dictionary ``D_j`` shared by
all variables, sparse ``N_ij``; :mod:`lmi.kothare_factors`), ``H`` is formed directly as a sum
over pairs of entries (:func:`lmi.ipm.kernels.scaling_and_schur_direct`) and ``P`` is never
formed; the Newton products with ``P`` use the sparse coefficients. The QR phase still forms
``P``. See :data:`DIRECT_MIN_VARIABLES` for when this is used. When each block holds only part
of the variables (the vertex forms: a vertex's Lyapunov matrix and the shared variables), ``H``
is formed block by block on those variables (:func:`lmi.ipm.kernels.scaling_and_schur_blockwise`)
and factored as a block arrow (:func:`lmi.ipm.kernels.lapack.arrow_cholesky`), the products with
``P`` and ``G`` from the sparse coefficients (:meth:`lmi.ipm.blocks.BlockData._choose_formula`).

The solver is split along its seams: the data as the kernels read it (:mod:`lmi.ipm.blocks`,
the base class :class:`~lmi.ipm.blocks.BlockData`), phase one and its certificate
(:mod:`lmi.ipm.phase_one`), the compiled kernels (:mod:`lmi.ipm.kernels`) and, here, the method:
the starting points, the iterations, their stopping rules and the warm starts.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from lmi.infeasibility import MIN_RADIUS
from lmi.ipm import kernels as _kernels
from lmi.ipm.blocks import BlockData, BlockFactor, block_pairs
from lmi.ipm.phase_one import PhaseOneResult, run_phase_one
from lmi.threads import SingleThreadBlas
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.status import Status
from toolkit_common.validation import as_vector, check_positive, is_integer, is_real

__all__ = [
    "INFEASIBILITY_RADIUS", "OBJECTIVE_AGREEMENT", "OBJECTIVE_SCALE_LIMIT", "QR_LATE_FLOPS", "QR_SWITCH",
    "QR_SWITCH_LATE",
    "REDUCED_TOL", "SOLVER_STATUS_MAP", "STALL_WINDOW", "STEP_ACCURACY", "BlockLMISolver", "IPMResult",
]

_LOG = logging.getLogger(__name__)

#: A run that stalls but has reached relative residuals and gap below this ends as
#: ``"inaccurate"`` (Clarabel's ``AlmostSolved``).
REDUCED_TOL = 1e-6

#: An answer is "optimal" (or "inaccurate") only if its primal and dual objectives agree to
#: this fraction of the larger (at least 1), whatever the residuals and the gap say. The
#: residuals and the gap are relative to norms over all blocks, so a block whose data are
#: many orders of magnitude larger than the others' can hide the rest: measured on SDPLIB's
#: control2 with its second block multiplied by 1e50 (the block weights do not reach such a
#: span), the run ended "optimal" after 8 iterations with primal residual 5e-23, dual residual
#: 2e-10 relative to ``||G'z||``, relative gap 3e-11, at ``c'x`` = 7.1e12 (the optimum is
#: 8.3) and a dual objective of 2.5e23. At a converged answer the objectives agree to the
#: order of the residuals and the gap, far below this.
OBJECTIVE_AGREEMENT = REDUCED_TOL

#: The Newton system is solved by Cholesky of the Schur complement ``H`` until a pivot falls
#: below this fraction of ``sqrt(H_jj)`` (a scale-invariant measure of the accuracy lost), then,
#: for the rest of the solve, by a QR factorisation of the scaled coefficients ``P`` (about twice
#: the cost; it does not square ``P``'s condition number). Measured on paper P: 1e-6 gave the
#: fewest iterations; 1e-7 and below cost 2 more iterations per solve at 2 vertices.
QR_SWITCH = 1e-6

#: The switch (see :data:`QR_SWITCH`) on large problems of the direct path, where ``H`` is formed
#: from the factored coefficients and the QR phase must also form ``P``: there a QR iteration
#: costs many Cholesky iterations (the flexible satellite at 20 states, 487 variables, ``P`` of
#: 3099 / 8019 rows at 2 / 8 vertices: 77-81 ms against 9-12 ms, 220-238 against 16-18 ms), and
#: switching later saves more QR iterations than the Cholesky phase adds. Over 5 warm solves
#: there (thread time): 1e-6 took a median 447 / 1339 ms (4-5 / 5-8 QR iterations), 1e-8 240 /
#: 691 ms (1-4 / 1-3), gamma the same within 6e-9 relative; 1e-10 gave the iterations of 1e-8
#: (where the switch then comes, Cholesky breaks down outright).
QR_SWITCH_LATE = 1e-8

#: The direct path uses :data:`QR_SWITCH_LATE` when the QR of ``P`` (``2 m n^2`` operations for
#: ``m`` rows and ``n`` variables) costs at least this many: 2.1e8 for the flexible satellite at
#: 14 states, 1.5e9 at 20; paper P's problems (2.6e6-7.4e6, with or without a peak bound) keep
#: :data:`QR_SWITCH`, which gave them the fewest iterations.
QR_LATE_FLOPS = 1e8

#: A Newton step of the Cholesky phase must meet its dual equation (``||P' dz~ + r_d||``) to
#: this fraction of the larger of the current dual residual and the dual tolerance (in the units
#: of ``||r_d||``): at 1 a step of any length ``alpha <= 1`` then leaves the dual residual,
#: ``(1 - alpha) r_d + alpha e``, no larger than that. A step that misses it is not taken, and the
#: solve goes on in the QR phase from that iteration (:func:`lmi.ipm.kernels.step.newton_step`).
#: The pivot test (:data:`QR_SWITCH`) sees the factor, not the step: on Kothare's example 2 (two
#: masses, spring constant in [0.5, 10], the textbook LMIs, 15 variables) the pivots stayed above
#: it while one Cholesky step raised the dual residual from 2e-11 to 3e-6 relative at a relative
#: gap of 1e-8; the run then stalled and ended ``"inaccurate"`` (gamma 279.65208, 40
#: iterations). With the test it ends ``"optimal"`` in 37. On paper P's closed loop it sends 2
#: of 320 iterations (2 vertices) and 4 of 376 (8) to the QR phase earlier; a fraction of 0.1
#: sent 6 and 15.
STEP_ACCURACY = 1.0

#: A run stops as ``"insufficient_progress"`` when none of its measures (relative primal and
#: dual residuals, gap) has halved over this many iterations. Infeasible problems stall like
#: this. On 60 random Kothare problems (n 2-10, 1-5 vertices, 42 of them infeasible or failing) a
#: window of 15 stopped the failing runs after a median of 18 iterations (max 33) instead of 60
#: and lost none of the 18 optimal ones; a window of 10 lost one (it converged at iteration 28).
#: (That was measured with the test on the worst of the three.) The worst alone stopped runs that
#: were converging: on open-loop-unstable problems the relative gap can rise for a while as the
#: objective grows while both residuals fall by orders of magnitude; on the generic stress set's
#: ``n16-v2-generic-peak-s0`` (:mod:`dev.generic_stress`) the gap went from 0.80 to 0.42
#: relative over iterations 7-22 while the primal residual fell from 1e-2 to 4e-5, the run was
#: stopped there, and it converges in 41 iterations when any measure halving counts as progress.
#: SDPLIB's control3 without block weights stalled the same way under the worst-measure rule
#: (c'x = 220.5 at iteration 16, its relative gap near 0.5 from iteration 12 to 33 while gap and
#: objective fell together and the dual residual fell 50-fold). A stalled run whose dual iterate
#: grows along a ray goes on for an infeasibility proof (see :meth:`BlockLMISolver.solve`); if a
#: measure halves again over the window, the stall is withdrawn and the ordinary rules apply
#: again. The cost of the any-measure rule: failing runs can go on longer (measured with block
#: weights from a span of 20: the stress set's n10-v2-infeasible-s2 ran 60 iterations instead of
#: 48, a 16-state random problem 44 instead of 34).
STALL_WINDOW = 15
STALL_FACTOR = 0.5

#: An objective whose largest entry (as given) exceeds this is divided by a power of two
#: inside the iterations (:func:`objective_scale`; the minimisers are the same, every output is
#: in the units of ``c`` as given). Far above any data of the toolkit's problems, so that their
#: answers are bit for bit those of an unscaled run; below it the norms, the gap and the dual
#: iterates stay far from overflow. Measured: ``c`` with an entry of 1e200 ended in a
#: ``ZeroDivisionError`` inside the kernels before this.
OBJECTIVE_SCALE_LIMIT = 1e50

#: The default ``infeasibility_radius`` of :class:`BlockLMISolver`: a run ends ``"infeasible"``
#: when its dual iterate proves that no solution of norm below this exists (the radius
#: :mod:`lmi.infeasibility` asks of a certificate).
INFEASIBILITY_RADIUS = MIN_RADIUS
#: ... and only when the dual iterate is a ray: ``||G'z|| <= RAY_TOL ||z||`` (``G`` the
#: equilibrated coefficients, unit columns). A bounded dual optimum of a feasible problem whose
#: optimal value is large has a large radius too but ``G'z = -c``. Measured at the proof on the
#: 60 far states of :mod:`dev.far_states`: ``||G'z|| / ||z||`` of 2e-12..3e-10 (see
#: :meth:`BlockLMISolver.solve`).
RAY_TOL = 1e-6

#: The solver's own words (``IPMResult.solver_status``) mapped to the status vocabulary
#: (``IPMResult.status``). ``"insufficient_progress"``: the run stalled (see :data:`STALL_WINDOW`)
#: without an answer; like Clarabel's ``InsufficientProgress`` it is a numerical failure.
SOLVER_STATUS_MAP: dict[str, Status] = {
    "optimal": Status.OPTIMAL,
    "inaccurate": Status.INACCURATE,
    "infeasible": Status.INFEASIBLE,
    "unbounded": Status.UNBOUNDED,
    "max_iterations": Status.MAX_ITERATIONS,
    "numerical_error": Status.NUMERICAL_ERROR,
    "insufficient_progress": Status.NUMERICAL_ERROR,
}


@dataclass
class IPMResult:
    """Outcome of :meth:`BlockLMISolver.solve`.

    ``status`` is a word of the toolkit's status vocabulary (:class:`toolkit_common.status.Status`):
    ``"optimal"`` (residuals and gap within the tolerances), ``"inaccurate"`` (a stalled run that
    reached :data:`REDUCED_TOL`), ``"infeasible"`` (with a Farkas ray, below),
    ``"max_iterations"`` or ``"numerical_error"``; ``solver_status`` is the solver's own word, which
    tells a stall (``"insufficient_progress"``) from a breakdown (``"numerical_error"``, see
    :data:`SOLVER_STATUS_MAP`). ``x`` is the variable vector; ``S`` and ``Z`` are the slack and
    dual blocks (in the order the blocks were given, without padding, in the units of the data as
    given whatever the solver's block weights). With status
    ``"infeasible"``, ``Z`` is the Farkas ray (scaled to unit Frobenius norm over all blocks,
    positive definite) and ``infeasibility_radius`` the radius it proves: ``sum_j <C_j, Z_j> < 0``
    and no ``x`` with ``||x|| < infeasibility_radius`` satisfies the LMIs (see
    :meth:`BlockLMISolver.solve`). With status ``"unbounded"``, ``x`` satisfies the LMIs (to
    ``tol_feas``) with ``c'x <= -infeasibility_radius max(1, ||c||)`` (``c`` as equilibrated) and
    ``x / ||x||`` is a direction of recession (to :data:`RAY_TOL`): the objective has no finite
    lower bound;
    otherwise ``infeasibility_radius`` is NaN.
    """

    status: str
    x: np.ndarray
    S: list[np.ndarray]
    Z: list[np.ndarray]
    iterations: int
    primal_objective: float
    dual_objective: float
    primal_residual: float
    dual_residual: float
    gap: float
    solve_time: float
    infeasibility_radius: float = float("nan")
    solver_status: str = ""
    #: How many of the ``iterations`` took their step from the QR factorisation of ``P`` (the
    #: phase after the Cholesky factor of ``H`` lost the accuracy the step needs, see
    #: :data:`QR_SWITCH`, :data:`STEP_ACCURACY`); a warm start's failed run included.
    qr_iterations: int = 0
    #: The relative gap at the iteration whose step was the first from the QR factorisation (NaN
    #: without one): near the optimum the QR phase is the end game of a badly conditioned ``H``;
    #: far from it, a sign of badly scaled coordinates (:data:`lmi.backends.ipm.REBALANCE_QR_GAP`).
    qr_start_gap: float = float("nan")



class BlockLMISolver(BlockData):
    """Interior-point solver for ``min c'x, C_j - sum_i x_i A_ij >= 0``, data updatable in place.

    Parameters
    ----------
    c : (n,) ndarray
        Objective.
    blocks : sequence of (C_j, A_j)
        ``C_j`` is ``(k_j, k_j)`` symmetric, ``A_j`` is ``(n, k_j, k_j)`` with symmetric slices.
    tol_feas, tol_gap_abs, tol_gap_rel : float
        Relative primal/dual residual and absolute/relative duality gap at termination.
    max_iter : int
        Iteration limit of a cold start.
    warm_max_iter : int
        Iteration limit of a warm start (then it is retried cold).
    warm_gap, warm_feas : float
        The iterate kept for the next warm start is the last one of a successful solve with a
        relative gap in ``[warm_gap / 10, warm_gap]`` and relative residuals below
        ``warm_feas``. Measured on paper P's closed loop (2 and 8 vertices), ``1e-2``/``1e-3``
        took 8-10 iterations per solve against 16-20 cold; ``1e-1`` took 10-11, ``1e-3`` 13.
    infeasibility_radius : float
        A run ends ``"infeasible"`` when its dual iterate proves that no solution of norm below
        this exists (``inf`` switches the test off; see :meth:`solve`).
    factors : sequence of BlockFactor or None, optional
        Factored coefficients of some blocks (:mod:`lmi.kothare_factors`).
    load_kernels : bool
        Load (or compile) the kernels now, at construction (default); ``False`` leaves it to the
        first solve (:class:`lmi.backends.ipm.IPMKothare` when the C core runs its solves).

    Raises
    ------
    InvalidArgumentError
        For data of the wrong shape, non-finite or non-symmetric data, or bad settings; the
        message names the argument.

    Notes
    -----
    An instance keeps work buffers and the warm-start point between solves: use one instance
    per thread (each :class:`lmi.KothareProblem` has its own). The iterations run in compiled
    kernels (:mod:`lmi.ipm.kernels`). The first solver built in a process loads them (about
    0.3 s; after a fresh install it compiles them, 10-20 s), so that this cost falls on the
    construction and not on the first solve of a real-time loop.

    Examples
    --------
    The largest eigenvalue of ``M`` is ``min t`` subject to ``t I - M >= 0``:

    >>> import numpy as np
    >>> m = np.array([[2.0, 1.0], [1.0, 2.0]])
    >>> res = BlockLMISolver([1.0], [(-m, -np.eye(2)[None])]).solve()
    >>> res.status, round(float(res.x[0]), 6)
    ('optimal', 3.0)
    """

    def __init__(
        self,
        c: np.ndarray,
        blocks: Sequence[tuple[np.ndarray, np.ndarray]],
        *,
        tol_feas: float = 1e-8,
        tol_gap_abs: float = 1e-8,
        tol_gap_rel: float = 1e-8,
        max_iter: int = 60,
        warm_max_iter: int = 25,
        warm_gap: float = 1e-2,
        warm_feas: float = 1e-3,
        infeasibility_radius: float = INFEASIBILITY_RADIUS,
        factors: Sequence[BlockFactor | None] | None = None,
        load_kernels: bool = True,
    ) -> None:
        self.c = as_vector(c, "c")
        n = self.n = self.c.shape[0]
        if n == 0:
            raise InvalidArgumentError("c", "at least one variable (a non-empty vector)", "an empty vector")
        blocks = block_pairs(blocks)
        for name, value in (("tol_feas", tol_feas), ("tol_gap_abs", tol_gap_abs),
                            ("tol_gap_rel", tol_gap_rel), ("warm_gap", warm_gap),
                            ("warm_feas", warm_feas)):
            check_positive(value, name)
        # NaN fails too; inf switches the test off
        if not (is_real(infeasibility_radius) and infeasibility_radius > 0.0):
            raise InvalidArgumentError("infeasibility_radius", "a number > 0 (inf: no test)",
                                       repr(infeasibility_radius))
        for name, value in (("max_iter", max_iter), ("warm_max_iter", warm_max_iter)):
            if not is_integer(value) or value < 1:
                raise InvalidArgumentError(name, "an integer >= 1", repr(value))
        self.tol_feas, self.tol_gap_abs, self.tol_gap_rel = tol_feas, tol_gap_abs, tol_gap_rel
        self.max_iter = int(max_iter)
        self.warm_max_iter = int(warm_max_iter)
        self.warm_gap, self.warm_feas = warm_gap, warm_feas
        self.infeasibility_radius = float(infeasibility_radius)
        self._warm: tuple | None = None
        super().__init__(n, blocks, factors)
        self._phase_one_solver: BlockLMISolver | None = None
        self._blas = SingleThreadBlas()
        if load_kernels:
            _load_kernels()

    def qr_switch(self) -> float:
        """The pivot ratio below which the Newton system goes from Cholesky of ``H`` to the QR of
        ``P`` for the rest of a solve: :data:`QR_SWITCH_LATE` on the direct path when the QR
        costs at least :data:`QR_LATE_FLOPS`, :data:`QR_SWITCH` otherwise."""
        qr_flops = 2.0 * self._layout.size * float(self.n) ** 2
        return QR_SWITCH_LATE if self._formula != "rows" and qr_flops >= QR_LATE_FLOPS else QR_SWITCH

    def reset_warm_start(self) -> None:
        """Forget the stored warm-start point (the next warm solve starts cold)."""
        self._warm = None

    # -- the solve -----------------------------------------------------------------------
    def solve(self, warm_start: bool = False) -> IPMResult:
        """Solve with the current data.

        With ``warm_start``, start from the iterate the previous solve passed through at a
        relative gap of ``warm_gap`` (an interior, roughly centred point) instead of the
        default initial point; the residuals the new data cause are handled like any
        infeasible start. A warm start that fails is retried cold (one that ends
        ``"infeasible"`` is a proof like any other and is kept).

        Infeasibility: the dual iterates ``Z`` stay positive definite, and when the LMIs have no
        solution they grow along a Farkas ray (``sum_j <A_ij, Z_j> -> 0`` relative to ``Z``,
        ``sum_j <C_j, Z_j> < 0``). Every iterate gives the radius ``r = -sum_j <C_j, Z_j> /
        ||(sum_j <A_ij, Z_j>)_i||``: a solution ``x`` would give ``0 <= sum_j <S_j, Z_j> =
        sum_j <C_j, Z_j> - sum_i x_i sum_j <A_ij, Z_j> <= -r ||a|| + ||x|| ||a||`` (``a`` the
        vector of the ``sum_j <A_ij, Z_j>``), so none exists with ``||x|| < r``. The run ends
        ``"infeasible"`` once ``r >= infeasibility_radius``. A run that stalls while ``r`` keeps
        growing (its inverse halved over :data:`STALL_WINDOW` iterations) goes on for that proof,
        up to ``max_iter``; if it converges again meanwhile (its worst relative residual or gap
        halved over the window), the stall is withdrawn and the ordinary rules apply again.
        Without either it ends ``"insufficient_progress"`` with the iterate of the stall (or its
        ``"inaccurate"`` point), as it would have stopped without the test. A feasible problem can reach that
        radius only if all its solutions are at least that large (and only with a ray, see
        :data:`RAY_TOL`). On random open-loop-unstable Kothare problems of 2-6 states at
        10 to 1e6 times beyond the states the input can hold, and on the stress set's infeasible
        problems of 6-14 states, the proof came after 18-60 iterations (78 problems).
        """
        start = time.perf_counter()
        _load_kernels()  # if the construction did not (load_kernels=False): with its notice
        empty = self.absent_variables()
        if empty.size:
            res = self._solve_without(empty)
            res.solve_time = time.perf_counter() - start
            return res
        if self.n > self._layout.size:
            res = self._solve_reduced()
            res.solve_time = time.perf_counter() - start
            return res
        with self._blas.limit():
            self._refresh()
            res = None
            spent = spent_qr = 0
            if warm_start and self._warm is not None:
                res = self._run(self._warm, self.warm_max_iter)
                if res.status not in ("optimal", "infeasible"):
                    spent, spent_qr, res = res.iterations, res.qr_iterations, None
            if res is None:
                res = self._run(None, self.max_iter)
        res.iterations += spent
        res.qr_iterations += spent_qr
        res.solver_status = res.status
        res.status = SOLVER_STATUS_MAP[res.status]
        res.solve_time = time.perf_counter() - start
        return res

    def _solve_without(self, empty: np.ndarray) -> IPMResult:
        """Solve with the variables ``empty`` (in no block) taken out: they are free directions.

        A fresh solver (cold, plain blocks) solves for the others. Where every absent variable
        has ``c_i = 0`` it is set to 0 and the answer is that solver's. Otherwise the objective
        has no lower bound as soon as the rest is feasible: ``x_i`` of an absent variable with
        ``c_i != 0`` is moved along ``-sign(c_i)`` until ``c'x <= -infeasibility_radius max(1,
        ||c||)`` and the status is ``"unbounded"`` (an ``"infeasible"`` rest stays infeasible, its
        ray proves it for the whole problem: the absent variables add nothing to it)."""
        keep = np.setdiff1d(np.arange(self.n), empty)
        if keep.size:
            rest = BlockLMISolver(
                self.c[keep], [(c_j, a_j[keep]) for c_j, a_j in zip(self._const, self._coef, strict=True)],
                tol_feas=self.tol_feas, tol_gap_abs=self.tol_gap_abs, tol_gap_rel=self.tol_gap_rel,
                max_iter=self.max_iter, infeasibility_radius=self.infeasibility_radius).solve()
        else:
            rest = _constant_blocks(self._const)
        x = np.zeros(self.n)
        if keep.size:
            x[keep] = rest.x
        direction = -np.sign(self.c[empty])
        if np.any(direction != 0.0) and rest.status in ("optimal", "inaccurate", "unbounded"):
            radius = self.infeasibility_radius
            if not np.isfinite(radius):
                radius = INFEASIBILITY_RADIUS
            target = radius * max(1.0, float(np.linalg.norm(self.c)))
            pull = float(np.abs(self.c[empty]) @ np.abs(direction))
            x[empty] = direction * (target + max(0.0, float(self.c @ x))) / pull
            rest.status, rest.solver_status = Status.UNBOUNDED, "unbounded"
        rest.x = x
        rest.primal_objective = float(self.c @ x)
        return rest

    def _range_basis(self) -> tuple[np.ndarray, np.ndarray]:
        """``(R, N)``: bases of the directions of ``x`` that move the blocks and of those that do
        not (``sum_i d_i A_ij = 0`` for every block ``j``, ``d`` a column of ``N``), from the SVD of
        the packed coefficients with unit columns; ``x = R y`` spans every slack the LMIs can
        reach. Columns of ``N`` have unit norm."""
        lay = self._layout
        cols = np.zeros((lay.size, self.n))
        for j, coef in enumerate(self._coef):
            iu0, iu1, w = lay.triangle(j)
            cols[lay.rows(j)] = (coef[:, iu0, iu1] * w).T
        norms = np.linalg.norm(cols, axis=0)  # > 0: absent variables are taken out before
        _, sing, vt = np.linalg.svd(cols / norms, full_matrices=True)
        rank = int(np.sum(sing > max(cols.shape) * np.finfo(float).eps * sing[0]))
        basis = vt.T / norms[:, None]  # x = D V y with D = diag(1 / norms)
        null = basis[:, rank:]
        return basis[:, :rank], null / np.linalg.norm(null, axis=0)

    def _reduced_solver(self, objective: np.ndarray, basis: np.ndarray) -> BlockLMISolver:
        """A solver of the same blocks in the variables ``y`` of ``x = basis y``."""
        blocks = [(c_j, np.einsum("ik,ilm->klm", basis, a_j)) for c_j, a_j in zip(
            self._const, self._coef, strict=True)]
        return BlockLMISolver(
            objective, blocks, tol_feas=self.tol_feas, tol_gap_abs=self.tol_gap_abs,
            tol_gap_rel=self.tol_gap_rel, max_iter=self.max_iter,
            infeasibility_radius=self.infeasibility_radius)

    def _solve_reduced(self) -> IPMResult:
        """Solve a problem with more variables than its blocks have entries (``n > sum_j k_j (k_j
        + 1) / 2``): some directions ``d`` of ``x`` leave every block unchanged, and the Newton
        system of the iterations is singular along them.

        With ``x = R y + N t`` (:meth:`_range_basis`) the blocks depend on ``y`` only. If ``c`` is
        orthogonal to every such direction (``|c'd| <= 1e-9 ||c||`` for each unit column ``d`` of
        ``N``), the problem is the one in ``y``, solved as such, and ``x = R y``. Otherwise the
        objective has no lower bound as soon as the blocks are feasible: ``x`` moves along such a
        ``d`` with ``c'd < 0`` until ``c'x <= -infeasibility_radius max(1, ||c||)``, and the status
        is ``"unbounded"`` (as for a variable in no block, :meth:`_solve_without`); an
        ``"infeasible"`` answer in ``y`` keeps its ray (``sum_j <A_ij, Z_j>`` is the same
        combination of the reduced ones, and vanishes along ``N``)."""
        basis, null = self._range_basis()
        c_null = null.T @ self.c
        free = np.abs(c_null) > 1e-9 * float(np.linalg.norm(self.c))
        rest = self._reduced_solver(basis.T @ self.c, basis).solve()
        x = basis @ rest.x
        if np.any(free) and rest.status in ("optimal", "inaccurate", "unbounded"):
            radius = self.infeasibility_radius
            if not np.isfinite(radius):
                radius = INFEASIBILITY_RADIUS
            target = radius * max(1.0, float(np.linalg.norm(self.c)))
            k = int(np.argmax(np.abs(c_null)))
            step = (target + max(0.0, float(self.c @ x))) / abs(float(c_null[k]))
            x = x - np.sign(c_null[k]) * step * null[:, k]
            rest.status, rest.solver_status = Status.UNBOUNDED, "unbounded"
        rest.x = x
        rest.primal_objective = float(self.c @ x)
        return rest

    def phase_one(self) -> PhaseOneResult:
        """Decide feasibility of the current data: ``min t`` s.t. ``C_j - sum_i x_i A_ij + t I >= 0``
        (for weighted blocks, :func:`lmi.ipm.blocks.block_weights`, ``w_j (C_j - ...) + t I >= 0``:
        the sign of ``t``, which decides, is the same).

        The phase-one problem is strictly feasible by construction and started at a feasible
        point (``x = 0``, ``t = 1 + max(0, -lambda_min(C))``), so its primal iterates stay
        feasible and its dual iterates ``Z`` stay positive definite. It stops as soon as

        * an iterate has ``t < 0``: its ``x`` is strictly feasible for the original problem
          (``"feasible"``; checked by Cholesky of every ``C_j - sum_i x_i A_ij``), or
        * the dual iterate, moved onto ``sum_j <A_ij, Z_j> = 0`` (for every original ``i``) by
          the least-norm correction, is still positive semidefinite with
          ``sum_j <C_j, Z_j> <= -PHASE_ONE_MARGIN ||C|| ||Z||``: a Farkas certificate of
          infeasibility (``"infeasible"``, see :class:`PhaseOneResult`).

        Otherwise (its optimum ``t* = 0``, i.e. the data on the boundary of feasibility, or a
        failed run) the answer is ``"inconclusive"``. An interior ``Z`` is well conditioned, so
        the correction, of the size of the dual residual, leaves it positive definite once
        that residual is small; the limit of a failed run of the problem itself is a nearly
        singular ray that such a correction makes indefinite. The phase-one solver is built on
        the first call (the same blocks with one more variable of coefficient ``-I``; factored
        blocks keep their factored form when their dictionary holds the identity columns) and
        reused.
        """
        _load_kernels()
        if self.n + 1 > self._layout.size:
            return self._phase_one_reduced()
        with self._blas.limit():
            return run_phase_one(self)

    def _phase_one_reduced(self) -> PhaseOneResult:
        """Phase one when some directions of ``x`` move no block (variables in no block, or more
        variables than the blocks have entries, counting phase one's own ``t``): on the problem
        in the directions that do (:meth:`_range_basis`), whose feasible slacks are the same. If
        those directions with ``-I`` span every block's entries, a strictly feasible point is the
        least-squares solution of ``sum_i x_i A_ij = C_j - I`` (checked by Cholesky)."""
        start = time.perf_counter()
        keep = np.setdiff1d(np.arange(self.n), self.absent_variables())
        if keep.size == 0:
            answer = _constant_blocks(self._const)
            ok = answer.status == Status.OPTIMAL
            return PhaseOneResult("feasible" if ok else "infeasible", None if ok else answer.Z,
                                  np.zeros(self.n) if ok else None, np.nan, np.nan, np.nan, np.nan, 0,
                                  str(answer.status), time.perf_counter() - start)
        sub = BlockLMISolver(self.c[keep], [(c_j, a_j[keep]) for c_j, a_j in zip(
            self._const, self._coef, strict=True)], load_kernels=False)
        basis, _ = sub._range_basis()
        if basis.shape[1] + 1 <= sub._layout.size:
            res = sub._reduced_solver(np.zeros(basis.shape[1]), basis).phase_one()
            y_map = basis
        else:  # the coefficients span every entry: C - sum x_i A_i = I has a solution
            lay = sub._layout
            mat = np.zeros((lay.size, keep.size))
            rhs = np.zeros(lay.size)
            for j, (c_j, a_j) in enumerate(zip(sub._const, sub._coef, strict=True)):
                iu0, iu1, w = lay.triangle(j)
                mat[lay.rows(j)] = (a_j[:, iu0, iu1] * w).T
                rhs[lay.rows(j)] = (c_j - np.eye(c_j.shape[0]))[iu0, iu1] * w
            point = np.linalg.lstsq(mat, rhs, rcond=None)[0]
            low = min(float(np.linalg.eigvalsh(c_j - np.einsum("i,ikl->kl", point, a_j))[0])
                      for c_j, a_j in zip(sub._const, sub._coef, strict=True))
            ok = low > 0.0
            res = PhaseOneResult("feasible" if ok else "inconclusive", None, point if ok else None,
                                 np.nan, np.nan, np.nan, -low, 0, "least squares", 0.0)
            y_map = np.eye(keep.size)
        if res.x is not None:
            x = np.zeros(self.n)
            x[keep] = y_map @ res.x
            res.x = x
        res.solve_time = time.perf_counter() - start
        return res

    def _initial_point(self, cvec: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """CVXOPT's initial point: least squares, shifted into the interiors."""
        g_mat, h_vec = self._g_mat, self._h_vec
        gtg_f = cho_factor(g_mat.T @ g_mat + 1e-12 * np.eye(self.n))
        x = cho_solve(gtg_f, g_mat.T @ h_vec)
        s = self._shift_interior(self._unpack(h_vec - g_mat @ x))
        z = self._shift_interior(self._unpack(-g_mat @ cho_solve(gtg_f, cvec)))
        return x, s, z

    def _run(self, warm: tuple | None, max_iter: int, monitor: Any = None) -> IPMResult:
        """The iterations. ``monitor(x, s, z)`` (optional, phase one) is called at every iterate
        with the equilibrated ``x``; a word it returns ends the run with that status."""
        lay = self._layout
        packing = lay.arrays
        orders = lay.orders
        dscale = self._dscale
        g_mat, h_vec = self._g_mat, self._h_vec
        # an objective far beyond the data's scale (1e200) is divided by a power of two (exact):
        # the same minimisers, and no overflow in its norm, the gap or the dual iterates
        obj_scale = objective_scale(self.c)
        cvec = self.c * dscale * obj_scale
        c_norm = max(1.0, float(np.linalg.norm(cvec)))
        h_norm = max(1.0, float(np.linalg.norm(h_vec)))
        if warm is None:
            x, s, z = self._initial_point(cvec)
        else:
            x, s, z = warm[0] / dscale, warm[1], warm[2]
        # S is kept as h - G x + theta r0 (theta = prod(1 - alpha)): the primal residual then
        # decays exactly, where updating S through the scaling lets it drift up near the optimum
        # (measured: 1e-10 -> 3e-6 relative over the last iterations of some paper-P solves)
        r0 = _kernels.pack(s, *packing) + g_mat @ x - h_vec
        theta = 1.0
        kk, lam, pt_mat, no_pt, h_mat, h_work, r_fac, qr_h, qr_tau, gram_block, h_block = self._workspace()
        sp = self._sparse
        # the blockwise formula's products with G come from the sparse coefficients (G "not
        # formed": no rows), the others' from G itself
        g_kern = np.zeros((0, self.n)) if self._formula == "blockwise" else g_mat
        s_chol = np.zeros_like(s)
        status = "max_iterations"
        pres = dres = gap = np.inf
        it = 0
        use_qr = False
        qr_steps = 0
        qr_start_gap = np.nan
        qr_switch = self.qr_switch()
        no_qr = (np.zeros((0, 0)), np.zeros(0))  # no Householder factors (the Cholesky phase)
        best: tuple | None = None
        warm_next: tuple | None = None
        merits: list[tuple[float, float, float]] = []
        ray_merits: list[float] = []
        radius = np.nan
        stall_point: tuple | None = None  # the iterate where the run stalled, while a ray grows
        ray_test = bool(np.isfinite(self.infeasibility_radius))  # inf: the test is off
        if not _kernels.cholesky_blocks(s, orders, s_chol):
            max_iter, status = -1, "numerical_error"
        debug = _LOG.isEnabledFor(logging.DEBUG)
        for it in range(max_iter + 1):
            rd, rp, gap, pcost, dcost, n_rp, n_gx, n_sp, n_rd, n_gtz = _kernels.residuals(
                s, z, x, g_kern, h_vec, cvec, *packing, *sp)
            pres = n_rp / max(h_norm, n_gx, n_sp)
            dres = n_rd / max(c_norm, n_gtz)
            rel_gap = gap / max(abs(pcost), abs(dcost), 1e-300)
            # the objectives must agree (see OBJECTIVE_AGREEMENT); both measures are invariant to
            # the variable and block scaling
            agree = abs(pcost - dcost) <= OBJECTIVE_AGREEMENT * max(1.0, abs(pcost), abs(dcost))
            if debug:
                _LOG.debug("%3d %+.9e %+.9e pres %.1e dres %.1e gap %.1e", it, pcost, dcost, pres,
                           dres, gap)
            if agree and pres <= self.tol_feas and dres <= self.tol_feas and (
                gap <= self.tol_gap_abs or rel_gap <= self.tol_gap_rel
            ) and _kernels.blocks_within(s, x, rp, g_kern, h_vec, self.tol_feas, *packing, *sp):
                status = "optimal"
                break
            if (stall_point is None and agree and max(pres, dres) <= REDUCED_TOL
                    and min(gap, rel_gap) <= REDUCED_TOL
                    and _kernels.blocks_within(s, x, rp, g_kern, h_vec, REDUCED_TOL, *packing, *sp)):
                best = (x, s, z, pres, dres, gap)
            if monitor is not None and (word := monitor(x, s, z)) is not None:
                status, best = word, None
                break
            # the dual iterate as a Farkas ray: sum_j <A_ij, Z_j> = (G'z)_i / dscale_i
            gtz = rd - cvec
            radius = dcost / max(float(np.linalg.norm(gtz / dscale)), 1e-300) if dcost > 0.0 else 0.0
            if ray_test and radius >= self.infeasibility_radius and n_gtz <= RAY_TOL * float(np.linalg.norm(
                    _kernels.pack(z, *packing))):
                status, best = "infeasible", None
                break
            # the primal iterate as a ray: far out, feasible and along a direction of recession
            if ray_test and pres <= self.tol_feas and -pcost >= self.infeasibility_radius * c_norm and (
                    self._recession_direction(x)):
                status, best = "unbounded", None
                break
            merits.append((pres, dres, min(gap, rel_gap)))
            ray_merits.append(1.0 / radius if radius > 0.0 else np.inf)
            ray_grows = ray_test and it >= STALL_WINDOW and (
                ray_merits[-1] <= STALL_FACTOR * ray_merits[-1 - STALL_WINDOW])
            # progress: any of the three measures halved over the window (see STALL_WINDOW)
            halved = it >= STALL_WINDOW and any(now <= STALL_FACTOR * then for now, then in zip(
                merits[-1], merits[-1 - STALL_WINDOW], strict=True))
            stalled = it >= STALL_WINDOW and not halved
            if stall_point is None:
                if stalled:
                    if not ray_grows:
                        status = "insufficient_progress"
                        break
                    # stalled, but the dual iterate grows along a ray: go on for a proof (up to
                    # max_iter, while the radius keeps growing)
                    stall_point = (x, s, z, pres, dres, gap)
            elif halved:
                # converging again (a measure halved over the window): not a stall after all,
                # back to the ordinary rules (control3 before its block weights, see STALL_WINDOW)
                stall_point = None
            elif not ray_grows:
                break
            if stall_point is None and (0.1 * self.warm_gap <= rel_gap <= self.warm_gap
                                        and max(pres, dres) <= self.warm_feas):
                warm_next = (x * dscale, s, z)
            if it == max_iter:
                break
            s_new, z_new, chol_new = np.zeros_like(s), np.zeros_like(z), np.zeros_like(s)
            mu, ref_scale = gap / self.degree, max(c_norm, n_gtz)
            err_limit = STEP_ACCURACY * max(n_rd, self.tol_feas * ref_scale)
            # one compiled call: the scaling, H or P, its factor and the step (kernels.iteration)
            if self._formula == "blockwise":  # H block by block, P formed in the QR phase only
                out = _kernels.blockwise_iteration(
                    s_chol, z, *packing, *sp, self._blockvars[0], *self._arrow_local,
                    *self._arrow, gram_block, h_block, kk, lam,
                    pt_mat, no_pt, h_mat, h_work, r_fac, qr_h, qr_tau, *no_qr, use_qr, x, theta, r0, rd, rp,
                    g_kern, h_vec, mu, ref_scale, qr_switch, s_new, z_new, chol_new, err_limit)
            elif self._direct:  # H from the factored coefficients, P formed in the QR phase only
                out = _kernels.grouped_iteration(
                    s_chol, z, *packing, *sp, *self._fact, *self._groups, kk, lam, pt_mat, no_pt, h_mat,
                    h_work, r_fac, qr_h, qr_tau, *no_qr, use_qr, x, theta, r0, rd, rp, g_mat, h_vec, mu,
                    ref_scale, qr_switch, s_new, z_new, chol_new, err_limit)
            else:
                out = _kernels.rows_iteration(
                    s_chol, z, *packing, *sp, kk, lam, pt_mat, h_mat, h_work, r_fac, qr_h, qr_tau, *no_qr,
                    use_qr, x, theta, r0, rd, rp, g_mat, h_vec, mu, ref_scale, qr_switch, s_new, z_new,
                    chol_new, err_limit)
            code, x_new, theta, a_aff, sigma, alpha, use_qr = out
            if use_qr and qr_steps == 0:
                qr_start_gap = rel_gap
            qr_steps += int(use_qr)
            if debug:
                _LOG.debug("    sigma %.2e alpha_aff %.3f alpha %.3f qr %s", sigma, a_aff, alpha, use_qr)
            if code != 0:
                status = "numerical_error"
                break
            x, s, z, s_chol = x_new, s_new, z_new, chol_new
        if stall_point is not None and status not in ("optimal", "infeasible"):
            # no proof came: the run ends as it would have at the stall, with that iterate
            status = "insufficient_progress"
            x, s, z, pres, dres, gap = stall_point
        if status == "optimal" and warm_next is not None:
            self._warm = warm_next
        if status != "optimal" and best is not None:
            status = "inaccurate"
            x, s, z, pres, dres, gap = best
        # the blocks in the original units: S_j = (w_j S_j) / w_j, Z_j = w_j (Z_j / w_j), exact
        # (powers of two); a ray is normalised over the original blocks
        bw = self.block_weights
        s_out = [s[j, :k, :k] / bw[j] for j, k in enumerate(self.block_orders)]
        zp = _kernels.pack(z, *packing)
        z_orig = z * bw[:, None, None] / obj_scale
        z_scale = 1.0
        if status == "infeasible":
            z_scale = 1.0 / float(np.linalg.norm(_kernels.pack(z_orig, *packing)))
        z_out = [z_orig[j, :k, :k] * z_scale for j, k in enumerate(self.block_orders)]
        return IPMResult(
            status, x * dscale, s_out, z_out, it, float(cvec @ x) / obj_scale, -float(h_vec @ zp) / obj_scale,
            pres, dres, gap / obj_scale, 0.0, radius if status == "infeasible" else np.nan,
            qr_iterations=qr_steps, qr_start_gap=qr_start_gap,
        )

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles (Dask workers) leave the work arrays behind (each makes its own)."""
        state = dict(self.__dict__)
        state.pop("_work", None)
        return state

    def _workspace(self) -> tuple[np.ndarray, ...]:
        """The iterations' work arrays, made once per problem size and reused by every solve
        (every entry a kernel reads is written first at each iteration): the NT scalings ``K``
        and ``lambda``, ``P'`` (``n x size``), ``P`` not formed (``n x 0``), ``H``, the
        factorisation's work array, its factor ``R``, the Householder factors of ``P`` and the
        blockwise formula's Gram workspace and ``P_j'P_j`` (flat, the largest block's sizes). Fresh
        arrays of ``n x size`` cost page faults at their first writes in every solve (measured on
        paper P: about 0.1 ms of a 4 ms warm solve)."""
        n, size, nb, kmax = self.n, self._layout.size, len(self.block_orders), self._kmax
        bv_off, orders = self._blockvars[0], self._layout.orders
        own = np.diff(bv_off)
        sizes = orders * (orders + 1) // 2
        block_size = int(np.max(2 * own * sizes + sizes * sizes, initial=0))  # M, U', U of _block_gram
        block_h = int(np.max(own * own, initial=0))
        work = getattr(self, "_work", None)
        if (work is None or work[2].shape != (n, size) or work[0].shape != (nb, kmax, kmax)
                or work[9].shape[0] < block_size or work[10].shape[0] < block_h):
            work = (np.zeros((nb, kmax, kmax)), np.zeros((nb, kmax)), np.zeros((n, size)), np.zeros((n, 0)),
                    np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, size)), np.zeros(n),
                    np.zeros(block_size), np.zeros(block_h))
            self._work = work
        return work

    def _recession_direction(self, x: np.ndarray) -> bool:
        """Whether ``d = x / ||x||`` (equilibrated) is a direction of recession to :data:`RAY_TOL`:
        ``sum_i d_i A_ij <= RAY_TOL ||sum_i d_i A_ij|| I`` for every block ``j`` (then ``C_j - sum_i
        (x_i + t d_i) A_ij`` stays positive semidefinite, up to that tolerance, for every ``t >= 0``)."""
        gd = self._g_mat @ (x / max(float(np.linalg.norm(x)), 1e-300))
        scale = float(np.linalg.norm(gd))
        blocks = self._unpack(gd)
        return scale > 0.0 and all(
            float(np.linalg.eigvalsh(blocks[j, :k, :k])[-1]) <= RAY_TOL * scale
            for j, k in enumerate(self.block_orders))

    def _unpack(self, vec: np.ndarray) -> np.ndarray:
        return _kernels.unpack(vec, *self._layout.arrays, self._kmax)

    def _shift_interior(self, mats: np.ndarray) -> np.ndarray:
        """``mats + t I`` (every block), ``t = 1 + max(0, -lambda_min)``."""
        low = min(float(np.linalg.eigvalsh(mats[j, :k, :k])[0]) for j, k in enumerate(self.block_orders))
        shift = 1.0 + max(0.0, -low)
        for j, k in enumerate(self.block_orders):
            mats[j, :k, :k] += shift * np.eye(k)
        return mats


# -- helpers -------------------------------------------------------------------------------
def objective_scale(cvec: np.ndarray) -> float:
    """1, or the power of two that brings the largest ``|c_i|`` (as given) into ``[0.5, 1]`` when it
    exceeds :data:`OBJECTIVE_SCALE_LIMIT`. The objective as given, not as equilibrated: a block far
    out of scale makes the equilibrated ``c`` large by itself, and the solver's tests of such runs
    (:data:`OBJECTIVE_AGREEMENT`, with its floor of 1) were measured on that ``c`` unscaled."""
    big = float(np.max(np.abs(cvec), initial=0.0))
    if big <= OBJECTIVE_SCALE_LIMIT:
        return 1.0
    return float(np.ldexp(1.0, -int(np.ceil(np.log2(big)))))


#: Set once a solver in this process has run the kernels (see :func:`_load_kernels`).
_KERNELS_LOADED = threading.Event()


def _load_kernels() -> None:
    """Load (or, after an install, compile) the kernels once per process, at construction.

    numba loads a cached kernel on its first call with given argument types: measured, the
    first solve of a process took 294 ms instead of 3 ms. A one-variable problem solved here
    makes every kernel run once with the argument types of real solves. The flag is set first,
    so the solver built here does not recurse.
    """
    if _KERNELS_LOADED.is_set():
        return
    _KERNELS_LOADED.set()
    with _kernels.compile_notice():  # a line on stderr when they compile (lmi.ipm.kernels.notice)
        BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])]).solve()


def _constant_blocks(consts: list[np.ndarray]) -> IPMResult:
    """The answer when no variable appears in any block: ``"optimal"`` (``x`` anything, here
    empty) if every ``C_j >= 0``, else ``"infeasible"`` with ``Z`` the eigenvector of the most
    negative eigenvalue (``<C_j, Z_j> < 0``, and there are no ``A_ij`` to cancel it)."""
    lows = [np.linalg.eigh(0.5 * (c_j + c_j.T)) for c_j in consts]
    worst = int(np.argmin([w[0] for w, _ in lows]))
    z = [np.zeros_like(c_j) for c_j in consts]
    s = [c_j.copy() for c_j in consts]
    empty = np.zeros(0)
    if lows[worst][0][0] >= 0.0:
        return IPMResult(Status.OPTIMAL, empty, s, z, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                         solver_status="optimal")
    vec = lows[worst][1][:, 0]
    z[worst] = np.outer(vec, vec)
    return IPMResult(Status.INFEASIBLE, empty, s, z, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, float("inf"),
                     solver_status="infeasible")


