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
therefore done by three compiled kernels (:mod:`lmi.ipm_kernels`, numba) and one LAPACK
factorisation, and this module keeps the data, the starting points and the stopping rules.

Algorithm: infeasible-start path following with Nesterov-Todd scaling and Mehrotra's
predictor-corrector, as in Vandenberghe's CVXOPT ``coneqp`` (L. Vandenberghe, "The CVXOPT
linear and quadratic cone program solvers", 2010), without the homogeneous self-dual embedding:
an infeasible or unbounded problem ends as ``"insufficient_progress"``, ``"max_iterations"`` or
``"numerical_error"``, never as a wrong ``"optimal"``. The NT scaling of each block comes from
one Cholesky factor and one small symmetric eigen-decomposition (as in SDPT3).
Variables are equilibrated (unit Frobenius norm of each ``A_i``). ``H`` is factored by Cholesky until it
becomes ill-conditioned near the optimum, then through a QR factorisation of ``P`` (which does
not square the condition number); each Newton solve is iteratively refined on the exact
equations. Successive solves can be warm-started from an interior iterate of the previous one.

Larger problems (``factors``): forming ``P`` costs ``size x n`` per block and ``P'P``
``size x n^2``, which grows as ``n_states^6`` for the Kothare blocks. When a block's
coefficients are given in factored form ``A_ij = D_j N_ij D_j'`` (a dictionary ``D_j`` shared by
all variables, sparse ``N_ij``; :mod:`lmi.kothare_factors`), ``H`` is formed directly as a sum
over pairs of entries (:func:`lmi.ipm_kernels.scaling_and_schur_direct`) and ``P`` is never
formed; the Newton products with ``P`` use the sparse coefficients. The QR phase still forms
``P``. See :data:`DIRECT_MIN_VARIABLES` for when this is used.
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
from scipy.linalg.lapack import dpotrf

from lmi import ipm_kernels as _kernels
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = [
    "DIRECT_MIN_VARIABLES", "PHASE_ONE_MARGIN", "REDUCED_TOL", "STALL_WINDOW", "BlockFactor",
    "BlockLMISolver", "IPMResult", "PhaseOneResult",
]

#: A block's coefficients in factored form ``A_ij = D N_ij D'``: ``(D, var, p, q, value)``, the
#: dictionary ``D`` (``k x d``) and the entries ``N_ij[p, q] = N_ij[q, p] = value`` (``i = var``,
#: ``p <= q``; entries that repeat a position add up).
BlockFactor = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]

_LOG = logging.getLogger(__name__)

#: A run that stalls but has reached relative residuals and gap below this ends as
#: ``"inaccurate"`` (Clarabel's ``AlmostSolved``).
REDUCED_TOL = 1e-6

#: The Newton system is solved by Cholesky of the Schur complement ``H`` until a pivot falls
#: below this fraction of ``sqrt(H_jj)`` (a scale-invariant measure of the accuracy lost), then,
#: for the rest of the solve, by a QR factorisation of the scaled coefficients ``P`` (about twice
#: the cost; it does not square ``P``'s condition number). Measured on paper P: 1e-6 gave the
#: fewest iterations; 1e-7 and below cost 2 more iterations per solve at 2 vertices.
QR_SWITCH = 1e-6

#: A run stops as ``"insufficient_progress"`` when its worst measure (relative residuals and
#: gap) has not halved over this many iterations. Infeasible problems stall like this. On 60
#: random Kothare problems (n 2-10, 1-5 vertices, 42 of them infeasible or failing) a window of
#: 15 stopped the failing runs after a median of 18 iterations (max 33) instead of 60 and lost
#: none of the 18 optimal ones; a window of 10 lost one (it converged at iteration 28).
STALL_WINDOW = 15
STALL_FACTOR = 0.5

#: ``H`` is formed from the factored coefficients (:func:`lmi.ipm_kernels.scaling_and_schur_direct`)
#: only for more variables than this, and when the operation count says it is cheaper. Below,
#: the Schur complement is a small part of an iteration: on paper P (61 variables with its
#: ellipsoid input bound) both ways measured the same median per solve (3.2-3.3 ms at 2
#: vertices, 7.3-7.7 ms at 8), and the rows path keeps paper P's records bit-identical (the
#: direct sum rounds differently; with a peak bound paper P has 67 variables and takes the
#: direct path). On the 14-state flexible satellite (259 variables, 2 vertices) the direct form
#: took the warm median from 876 ms to 21 ms (load ~7).
DIRECT_MIN_VARIABLES = 64

#: Phase one (:meth:`BlockLMISolver.phase_one`) accepts a corrected dual point ``Z`` as a proof of
#: infeasibility only if ``sum_j <C_j, Z_j> <= -PHASE_ONE_MARGIN ||C|| ||Z||`` (Frobenius norms
#: over all blocks): a margin far above the rounding of the correction onto ``A'Z = 0``.
PHASE_ONE_MARGIN = 1e-7
#: ... and tries the correction only when the dual residual ``||G'z||`` is below this fraction of
#: ``||z||`` (before, it fails; see :func:`_dual_correction`).
PHASE_ONE_RESIDUAL = 1e-8
#: Phase one's iteration limit and tolerances: it runs until a proof is found or it stalls
#: (its own optimality test, at these tolerances, practically never ends it first). On the
#: stress set's infeasible problems the proof came after 45-60 iterations: the phase-one
#: problem of an infeasible Kothare problem converges slowly (the gap shrinks by about 0.7 per
#: iteration), and the correction onto ``A'Z = 0`` succeeds only near its end.
PHASE_ONE_MAX_ITER = 100
PHASE_ONE_TOL = 1e-13


@dataclass
class IPMResult:
    """Outcome of :meth:`BlockLMISolver.solve`.

    ``x`` is the variable vector; ``S`` and ``Z`` are the slack and dual blocks (in the order
    the blocks were given, without padding).
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


@dataclass
class PhaseOneResult:
    """Outcome of :meth:`BlockLMISolver.phase_one`.

    ``status`` is ``"infeasible"`` (``Z`` proves it, see below), ``"feasible"`` (``x`` is a
    point with every ``C_j - sum_i x_i A_ij`` positive definite, checked by Cholesky) or
    ``"inconclusive"`` (phase one ended, ``run_status``, without either).

    For ``"infeasible"``, ``Z`` holds positive semidefinite blocks (smallest eigenvalues in
    ``min_eigenvalue``, relative to each block's largest) with ``sum_j <A_ij, Z_j> = 0`` for
    every ``i`` to rounding (``residual``, the largest ``|sum_j <A_ij, Z_j>|`` over
    ``||A_i|| ||Z||``) and ``objective = sum_j <C_j, Z_j> < 0``: a feasible ``x`` would give
    ``0 <= sum_j <S_j, Z_j> = objective - sum_i x_i sum_j <A_ij, Z_j>``, impossible unless
    ``||x||`` is at least about ``|objective| / (residual ||A|| ||Z||)``.
    """

    status: str
    Z: list[np.ndarray] | None
    x: np.ndarray | None
    objective: float
    residual: float
    min_eigenvalue: float
    t: float
    iterations: int
    run_status: str
    solve_time: float


class BlockLMISolver:
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

    Raises
    ------
    InvalidArgumentError
        For data of the wrong shape, non-finite or non-symmetric data, or bad settings; the
        message names the argument.

    Notes
    -----
    An instance keeps work buffers and the warm-start point between solves: use one instance
    per thread (each :class:`lmi.KothareProblem` has its own). The iterations run in compiled
    kernels (:mod:`lmi.ipm_kernels`). The first solver built in a process loads them (about
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
        factors: Sequence[BlockFactor | None] | None = None,
    ) -> None:
        self.c = as_vector(c, "c")
        n = self.n = self.c.shape[0]
        if len(blocks) == 0:
            raise InvalidArgumentError("blocks", "at least one (C_j, A_j) pair", "none")
        for name, value in (("tol_feas", tol_feas), ("tol_gap_abs", tol_gap_abs),
                            ("tol_gap_rel", tol_gap_rel), ("warm_gap", warm_gap),
                            ("warm_feas", warm_feas)):
            check_positive(value, name)
        for name, value in (("max_iter", max_iter), ("warm_max_iter", warm_max_iter)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InvalidArgumentError(name, "an integer >= 1", repr(value))
        self.tol_feas, self.tol_gap_abs, self.tol_gap_rel = tol_feas, tol_gap_abs, tol_gap_rel
        self.max_iter = max_iter
        self.warm_max_iter = warm_max_iter
        self.warm_gap, self.warm_feas = warm_gap, warm_feas
        self._warm: tuple | None = None
        self._dscale: np.ndarray | None = None
        checked = [_check_block(j, const, coef, n) for j, (const, coef) in enumerate(blocks)]
        orders = [const.shape[0] for const, _ in checked]
        self.block_orders = orders
        self.degree = sum(orders)
        self._layout = _PackedLayout(orders)
        lay = self._layout
        self._kmax = max(orders)
        self._coef: list[np.ndarray] = [np.zeros((n, k, k)) for k in orders]
        self._dirty: set[int] = set()
        self._h_vec = np.zeros(lay.size)
        self._g_mat = np.zeros((lay.size, n))  # packed scaled coefficients
        self._sparse: tuple[np.ndarray, ...] = ()  # non-zero scaled coefficients (kernels' sp_*)
        self._sparse_parts: list[tuple[np.ndarray, ...]] = [() for _ in orders]
        # factored coefficients A_ij = D_j N_ij D_j' (kernels' dict_*, fe_*; see
        # scaling_and_schur_direct); None: D_j = I and N_ij = A_ij
        if factors is not None and len(factors) != len(checked):
            raise InvalidArgumentError("factors", f"one entry (or None) per block, {len(checked)}",
                                       f"{len(factors)} entries")
        self._factor_raw: list[BlockFactor | None] = [None] * len(checked)
        self._fact_parts: list[tuple[np.ndarray, ...]] = [() for _ in orders]
        self._fact: tuple[np.ndarray, ...] = ()
        self._groups: tuple[np.ndarray, np.ndarray] = (np.zeros(1, dtype=np.int64),
                                                       np.zeros(0, dtype=np.int64))
        self._direct = False
        self._const: list[np.ndarray] = [const for const, _ in checked]
        self._phase_one_solver: BlockLMISolver | None = None
        for j, (const, coef) in enumerate(checked):
            self._set_checked(j, const, coef)
            if factors is not None and factors[j] is not None:
                self._factor_raw[j] = _check_factor(j, factors[j], coef, n)
        _load_kernels()

    def reset_warm_start(self) -> None:
        """Forget the stored warm-start point (the next warm solve starts cold)."""
        self._warm = None

    def set_block(self, j: int, const: np.ndarray, coef: np.ndarray | None = None,
                  factor: BlockFactor | None = None) -> None:
        """Replace block ``j``'s constant (and coefficients, if given, with their factored form
        ``factor`` or none)."""
        if isinstance(j, bool) or not (isinstance(j, int | np.integer) and 0 <= j < len(self.block_orders)):
            raise InvalidArgumentError("j", f"a block index in [0, {len(self.block_orders)})", repr(j))
        if factor is not None and coef is None:
            raise InvalidArgumentError("factor", "None unless coef is given", "a factor without coef")
        const_c, coef_c = _check_block(int(j), const, coef, self.n, self.block_orders[j])
        checked_factor = None if factor is None else _check_factor(int(j), factor, coef_c, self.n)
        self._set_checked(int(j), const_c, coef_c)
        if coef_c is not None:
            if (checked_factor is None) != (self._factor_raw[int(j)] is None) or checked_factor is not None:
                self._dirty.add(int(j))
                self._fact_parts[int(j)] = ()
            self._factor_raw[int(j)] = checked_factor

    def _set_checked(self, j: int, const: np.ndarray, coef: np.ndarray | None) -> None:
        rows = self._layout.rows(j)
        iu0, iu1, w = self._layout.triangle(j)
        self._h_vec[rows] = const[iu0, iu1] * w
        self._const[j] = const.copy()
        if coef is not None and not np.array_equal(coef, self._coef[j]):
            self._coef[j] = coef.copy()
            self._dirty.add(j)

    def _refresh(self) -> None:
        """Variable scaling (once) and the scaled coefficients of the changed blocks."""
        if self._dscale is None:
            # equilibrate the variables once, x = D x~ with unit-norm scaled coefficients
            # (later coefficient updates, e.g. a bound scaling, keep D)
            norms = np.sqrt(sum(np.einsum("ikl,ikl->i", a, a) for a in self._coef))
            self._dscale = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
            self._dirty = set(range(len(self.block_orders)))
        if not self._dirty:
            return
        rebuild = not self._sparse
        for j in sorted(self._dirty):
            scaled = self._coef[j] * self._dscale[:, None, None]  # (n, k, k)
            iu0, iu1, w = self._layout.triangle(j)
            upper = scaled[:, iu0, iu1]  # (n, entries), entries in packed order
            self._g_mat[self._layout.rows(j)] = (upper * w).T
            pattern = upper != 0.0
            old = self._sparse_parts[j]
            if (old and np.array_equal(pattern, old[0]) and self._fact_parts[j]
                    and self._factor_raw[j] is None):  # same non-zeros (e.g. a bound scaling)
                lo, hi = self._sparse[0][j], self._sparse[0][j + 1]
                self._sparse[3][lo:hi] = upper[pattern]
                flo, fhi = self._fact[2][j], self._fact[2][j + 1]
                self._fact[6][flo:fhi] = upper[pattern] * _entry_weight(old[4][old[2]], old[5][old[2]])
                continue
            var, entry = np.nonzero(pattern)  # ordered (variable, entry), as upper[pattern]
            pair_entries, pair_of = np.unique(entry, return_inverse=True)
            self._sparse_parts[j] = (pattern, var, pair_of, upper[pattern], iu0[pair_entries],
                                     iu1[pair_entries])
            self._fact_parts[j] = self._factored_part(j)
            rebuild = True
        self._dirty.clear()
        if rebuild:
            self._sparse = _concatenate_sparse(self._sparse_parts)
            self._fact = _concatenate_factors(self._fact_parts, self._kmax)
            self._groups = _factor_groups(self._fact_parts, self._factor_raw)
            self._direct = self._direct_is_cheaper()

    def _factored_part(self, j: int) -> tuple[np.ndarray, ...]:
        """``(D, var, p, q, value)`` of block ``j`` with the variable scaling and the weights of
        :func:`lmi.ipm_kernels.scaling_and_schur_direct`, sorted by variable."""
        raw = self._factor_raw[j]
        if raw is None:  # D = I: the sparse upper-triangle entries
            _, var, pair_of, val, prow, pcol = self._sparse_parts[j]
            p, q = prow[pair_of], pcol[pair_of]
            dmat = np.eye(self.block_orders[j])
        else:
            dmat, var, p, q, val = raw
            val = val * self._dscale[var]
            order = np.argsort(var, kind="stable")
            var, p, q, val = var[order], p[order], q[order], val[order]
        return dmat, var, p, q, val * _entry_weight(p, q)

    def _direct_is_cheaper(self) -> bool:
        """Whether forming ``H`` from the factored coefficients costs fewer operations than
        forming ``P`` and ``P'P``."""
        n = self.n
        direct, rows = 0.0, 0.0
        for j, k in enumerate(self.block_orders):
            dmat, var = self._fact_parts[j][0], self._fact_parts[j][1]
            d = dmat.shape[1]
            size = k * (k + 1) // 2
            direct += 2.0 * var.shape[0] ** 2 + k * k * d + k * d * d
            rows += self._sparse_parts[j][1].shape[0] * size + size * n * n
        return n > DIRECT_MIN_VARIABLES and direct < rows

    # -- the solve -----------------------------------------------------------------------
    def solve(self, warm_start: bool = False) -> IPMResult:
        """Solve with the current data.

        With ``warm_start``, start from the iterate the previous solve passed through at a
        relative gap of ``warm_gap`` (an interior, roughly centred point) instead of the
        default initial point; the residuals the new data cause are handled like any
        infeasible start. A warm start that fails is retried cold.
        """
        start = time.perf_counter()
        self._refresh()
        res = None
        spent = 0
        if warm_start and self._warm is not None:
            res = self._run(self._warm, self.warm_max_iter)
            if res.status != "optimal":
                spent, res = res.iterations, None
        if res is None:
            res = self._run(None, self.max_iter)
        res.iterations += spent
        res.solve_time = time.perf_counter() - start
        return res

    def phase_one(self) -> PhaseOneResult:
        """Decide feasibility of the current data: ``min t`` s.t. ``C_j - sum_i x_i A_ij + t I >= 0``.

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
        start = time.perf_counter()
        self._refresh()
        aux = self._phase_one_data()
        aux._refresh()
        n, kmax = self.n, self._kmax
        orders = self.block_orders
        low = min(float(np.linalg.eigvalsh(c)[0]) for c in self._const)
        t0 = 1.0 + max(0.0, -low)
        s0 = np.zeros((len(orders), kmax, kmax))
        z0 = np.zeros_like(s0)
        for j, k in enumerate(orders):
            s0[j, :k, :k] = self._const[j] + t0 * np.eye(k)
            z0[j, :k, :k] = np.eye(k) / self.degree
        x0 = np.zeros(n + 1)
        x0[n] = t0
        check = _PhaseOneCheck(self, aux._dscale)
        res = aux._run((x0, s0, z0), PHASE_ONE_MAX_ITER, check)
        found = check.found
        status = res.status if res.status in ("feasible", "infeasible") else "inconclusive"
        if status == "inconclusive" and res.status in ("optimal", "inaccurate"):
            # the last chance: the final dual point (at t* = 0 it cannot prove anything)
            zfin = np.zeros_like(z0)
            for j, k in enumerate(orders):
                zfin[j, :k, :k] = res.Z[j]
            if check(res.x / aux._dscale, None, zfin) == "infeasible":
                status, found = "infeasible", check.found
        return PhaseOneResult(
            status, found.get("Z"), found.get("x"), found.get("objective", np.nan),
            found.get("residual", np.nan), found.get("min_eigenvalue", np.nan),
            float(found.get("t", res.x[n] if res.x.size > n else np.nan)), res.iterations,
            res.status, time.perf_counter() - start,
        )

    def _phase_one_data(self) -> BlockLMISolver:
        """The phase-one solver (built once), its blocks brought up to date with this one's."""
        n = self.n
        aux = self._phase_one_solver
        fresh = aux is None
        blocks, factors = [], []
        for j, k in enumerate(self.block_orders):
            if fresh or not np.array_equal(aux._coef[j][:n], self._coef[j]):
                coef = np.concatenate([self._coef[j], -np.eye(k)[None]])
                factor = _with_identity(self._factor_raw[j], n, k)
                if fresh:
                    blocks.append((self._const[j], coef))
                    factors.append(factor)
                else:
                    aux.set_block(j, self._const[j], coef, factor)
            elif not fresh:
                aux.set_block(j, self._const[j])
        if fresh:
            cvec = np.zeros(n + 1)
            cvec[n] = 1.0
            aux = self._phase_one_solver = BlockLMISolver(
                cvec, blocks, tol_feas=PHASE_ONE_TOL, tol_gap_abs=PHASE_ONE_TOL,
                tol_gap_rel=PHASE_ONE_TOL, max_iter=PHASE_ONE_MAX_ITER, factors=factors)
        return aux

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
        n = self.n
        lay = self._layout
        packing = lay.arrays
        orders = lay.orders
        dscale = self._dscale
        g_mat, h_vec = self._g_mat, self._h_vec
        cvec = self.c * dscale
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
        kmax = self._kmax
        kk = np.zeros((len(orders), kmax, kmax))
        lam = np.zeros((len(orders), kmax))
        pt_mat = np.zeros((n, lay.size))  # P', P = the scaled coefficients, packed
        no_pt = np.zeros((n, 0))  # P not formed: the kernels use the sparse coefficients
        h_mat = np.zeros((n, n))
        sp = self._sparse
        s_chol = np.zeros_like(s)
        status = "max_iterations"
        pres = dres = gap = np.inf
        it = 0
        use_qr = False
        best: tuple | None = None
        warm_next: tuple | None = None
        merits: list[float] = []
        if not _kernels.cholesky_blocks(s, orders, s_chol):
            max_iter, status = -1, "numerical_error"
        debug = _LOG.isEnabledFor(logging.DEBUG)
        for it in range(max_iter + 1):
            rd, rp, gap, pcost, dcost, n_rp, n_gx, n_sp, n_rd, n_gtz = _kernels.residuals(
                s, z, x, g_mat, h_vec, cvec, *packing)
            pres = n_rp / max(h_norm, n_gx, n_sp)
            dres = n_rd / max(c_norm, n_gtz)
            rel_gap = gap / max(abs(pcost), abs(dcost), 1e-300)
            if debug:
                _LOG.debug("%3d %+.9e %+.9e pres %.1e dres %.1e gap %.1e", it, pcost, dcost, pres,
                           dres, gap)
            if pres <= self.tol_feas and dres <= self.tol_feas and (
                gap <= self.tol_gap_abs or rel_gap <= self.tol_gap_rel
            ):
                status = "optimal"
                break
            if max(pres, dres) <= REDUCED_TOL and min(gap, rel_gap) <= REDUCED_TOL:
                best = (x, s, z, pres, dres, gap)
            if monitor is not None and (word := monitor(x, s, z)) is not None:
                status, best = word, None
                break
            merits.append(max(pres, dres, min(gap, rel_gap)))
            if it >= STALL_WINDOW and merits[-1] > STALL_FACTOR * merits[-1 - STALL_WINDOW]:
                status = "insufficient_progress"
                break
            if (0.1 * self.warm_gap <= rel_gap <= self.warm_gap
                    and max(pres, dres) <= self.warm_feas):
                warm_next = (x * dscale, s, z)
            if it == max_iter:
                break
            pt_use = pt_mat
            if self._direct and not use_qr:  # H from the factored coefficients, P not formed
                if not _kernels.scaling_and_schur_grouped(s_chol, z, orders, *self._fact,
                                                          *self._groups, kk, lam, h_mat):
                    status = "numerical_error"
                    break
                r_fac, use_qr = _cholesky(h_mat)
                pt_use = no_pt
            if not self._direct or use_qr:
                if not _kernels.scaling_and_schur_rows(s_chol, z, *packing, *self._sparse, kk, lam,
                                                       pt_mat):
                    status = "numerical_error"
                    break
                try:
                    r_fac, use_qr = _factor(pt_mat, use_qr)
                except (np.linalg.LinAlgError, ValueError):
                    status = "numerical_error"
                    break
                pt_use = pt_mat
            s_new, z_new, chol_new = np.zeros_like(s), np.zeros_like(z), np.zeros_like(s)
            code, x_new, theta, a_aff, sigma, alpha = _kernels.newton_step(
                pt_use, r_fac, kk, lam, x, theta, r0, rd, rp, g_mat, h_vec, gap / self.degree,
                max(c_norm, n_gtz), *packing, *sp, s_new, z_new, chol_new)
            if debug:
                _LOG.debug("    sigma %.2e alpha_aff %.3f alpha %.3f qr %s", sigma, a_aff, alpha, use_qr)
            if code != 0:
                status = "numerical_error"
                break
            x, s, z, s_chol = x_new, s_new, z_new, chol_new
        if status == "optimal" and warm_next is not None:
            self._warm = warm_next
        if status != "optimal" and best is not None:
            status = "inaccurate"
            x, s, z, pres, dres, gap = best
        s_out = [s[j, :k, :k].copy() for j, k in enumerate(self.block_orders)]
        z_out = [z[j, :k, :k].copy() for j, k in enumerate(self.block_orders)]
        zp = _kernels.pack(z, *packing)
        return IPMResult(
            status, x * dscale, s_out, z_out, it, float(cvec @ x), -float(h_vec @ zp), pres, dres,
            gap, 0.0,
        )

    def _unpack(self, vec: np.ndarray) -> np.ndarray:
        return _kernels.unpack(vec, *self._layout.arrays, self._kmax)

    def _shift_interior(self, mats: np.ndarray) -> np.ndarray:
        """``mats + t I`` (every block), ``t = 1 + max(0, -lambda_min)``."""
        low = min(float(np.linalg.eigvalsh(mats[j, :k, :k])[0]) for j, k in enumerate(self.block_orders))
        shift = 1.0 + max(0.0, -low)
        for j, k in enumerate(self.block_orders):
            mats[j, :k, :k] += shift * np.eye(k)
        return mats


class _PackedLayout:
    """Where each block's upper triangle sits in a packed vector (see :mod:`lmi.ipm_kernels`)."""

    def __init__(self, orders: list[int]) -> None:
        self.orders = np.asarray(orders, dtype=np.int64)
        sizes = [k * (k + 1) // 2 for k in orders]
        self.offsets = np.cumsum([0, *sizes]).astype(np.int64)
        self.size = int(self.offsets[-1])
        self._triangles = []
        for k in orders:
            iu0, iu1 = np.triu_indices(k)
            self._triangles.append((iu0, iu1, np.where(iu0 == iu1, 1.0, np.sqrt(2.0))))
        self.ent_row = np.concatenate([t[0] for t in self._triangles]).astype(np.int64)
        self.ent_col = np.concatenate([t[1] for t in self._triangles]).astype(np.int64)
        self.ent_w = np.concatenate([t[2] for t in self._triangles])
        #: the arguments every kernel takes, in order
        self.arrays = (self.orders, self.offsets, self.ent_row, self.ent_col, self.ent_w)

    def rows(self, j: int) -> slice:
        return slice(int(self.offsets[j]), int(self.offsets[j + 1]))

    def triangle(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Row and column indices of block ``j``'s upper triangle, and the packing weights."""
        return self._triangles[j]


# -- helpers -------------------------------------------------------------------------------
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
    BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])]).solve()


class _PhaseOneCheck:
    """Phase one's monitor: is the iterate a strictly feasible point or does its dual point,
    corrected onto ``A'Z = 0``, prove infeasibility? (see :meth:`BlockLMISolver.phase_one`).
    What it found is left in ``found``."""

    def __init__(self, solver: BlockLMISolver, aux_scale: np.ndarray) -> None:
        self.solver = solver
        self.aux_scale = aux_scale
        self.found: dict[str, Any] = {}

    def __call__(self, x: np.ndarray, s: np.ndarray | None, z: np.ndarray) -> str | None:
        slv = self.solver
        n, lay = slv.n, slv._layout
        packing = lay.arrays
        t = float(x[n] * self.aux_scale[n])
        if t < 0.0:
            xo = x[:n] * self.aux_scale[:n]
            slack = _kernels.unpack(slv._h_vec - slv._g_mat @ (xo / slv._dscale), *packing, slv._kmax)
            chol = np.zeros_like(slack)
            if _kernels.cholesky_blocks(slack, lay.orders, chol):
                self.found = {"x": xo, "t": t}
                return "feasible"
        h = slv._h_vec
        zp = _kernels.pack(z, *packing)
        if float(h @ zp) >= 0.0:  # -<C, Z> <= 0 before the correction: not yet
            return None
        # the correction succeeds only once the dual residual is small compared with Z's
        # smallest eigenvalues, i.e. near the end of phase one (measured on the stress set:
        # residuals 1e-11..1e-10 of unit-trace Z); it costs a least-squares solve
        if float(np.linalg.norm(slv._g_mat.T @ zp)) > PHASE_ONE_RESIDUAL * float(np.linalg.norm(zp)):
            return None
        blocks = _dual_correction(slv, z)
        if blocks is None:
            return None
        zc = np.zeros_like(z)
        for j, k in enumerate(slv.block_orders):
            zc[j, :k, :k] = blocks[j]
        zp = _kernels.pack(zc, *packing)
        z_norm = float(np.linalg.norm(zp))
        objective = float(h @ zp)
        if not (z_norm > 0.0 and objective <= -PHASE_ONE_MARGIN * float(np.linalg.norm(h)) * z_norm):
            return None
        worst = np.inf
        for zj in blocks:
            lam = np.linalg.eigvalsh(zj)
            worst = min(worst, float(lam[0] / max(float(np.max(np.abs(lam))), 1e-300)))
        if not worst >= 0.0:
            return None
        # |sum_j <A_ij, Z_j>| relative to ||A_i|| ||Z|| (the equilibrated columns have unit norm)
        residual = float(np.max(np.abs(slv._g_mat.T @ zp), initial=0.0)) / z_norm
        self.found = {"Z": blocks, "objective": objective, "residual": residual,
                      "min_eigenvalue": worst, "t": t}
        return "infeasible"


def _dual_correction(slv: BlockLMISolver, z: np.ndarray) -> list[np.ndarray] | None:
    """``Z`` (positive definite blocks, padded) moved onto ``sum_j <A_ij, Z_j> = 0`` by the
    correction of least norm in ``Z``'s own metric: with ``Z_j = L_j L_j'``, ``Z_j + dZ_j =
    L_j (I + F_j) L_j'`` with ``||F||_F`` least, i.e. ``F`` the least-norm solution of
    ``sum_j <L_j' A_ij L_j, F_j> = -sum_j <A_ij, Z_j>``. The result is positive semidefinite
    exactly when every ``I + F_j`` is (checked); a correction of least Frobenius norm in ``Z``'s
    coordinates instead falls mostly on the directions where ``Z`` is small and made it
    indefinite (measured). ``None`` when it is not positive definite or ``I + F`` is not."""
    factors, cols = [], []
    for j, k in enumerate(slv.block_orders):
        try:
            low = np.linalg.cholesky(z[j, :k, :k])
        except np.linalg.LinAlgError:
            return None
        factors.append(low)
        scaled = low.T @ (slv._coef[j] * slv._dscale[:, None, None]) @ low  # (n, k, k)
        iu0, iu1, w = slv._layout.triangle(j)
        cols.append(scaled[:, iu0, iu1] * w)
    p_t = np.concatenate(cols, axis=1)  # (n, size): row i = packed L'A_i L
    resid = slv._g_mat.T @ _kernels.pack(z, *slv._layout.arrays)
    f_vec = np.linalg.lstsq(p_t, -resid, rcond=None)[0]
    out = []
    for j, k in enumerate(slv.block_orders):
        rows = slv._layout.rows(j)
        iu0, iu1, w = slv._layout.triangle(j)
        f_mat = np.zeros((k, k))
        f_mat[iu0, iu1] = f_vec[rows] / w
        f_mat[iu1, iu0] = f_vec[rows] / w
        inner = np.eye(k) + f_mat
        if not float(np.linalg.eigvalsh(inner)[0]) >= 0.0:
            return None
        out.append(factors[j] @ inner @ factors[j].T)
    return out


def _with_identity(raw: BlockFactor | None, n: int, k: int) -> BlockFactor | None:
    """Block ``j``'s factored coefficients with one more variable (index ``n``) of coefficient
    ``-I``, or ``None`` if the dictionary lacks an identity column for some row."""
    if raw is None:
        return None
    dmat, var, p, q, val = raw
    unit = (np.count_nonzero(dmat, axis=0) == 1) & (np.max(dmat, axis=0) == 1.0)
    row_of = np.argmax(np.abs(dmat), axis=0)
    cols = []
    for r in range(k):
        hit = np.flatnonzero(unit & (row_of == r))
        if hit.size == 0:
            return None
        cols.append(int(hit[0]))
    idx = np.asarray(cols, dtype=np.int64)
    return (dmat, np.concatenate([var, np.full(k, n, dtype=np.int64)]), np.concatenate([p, idx]),
            np.concatenate([q, idx]), np.concatenate([val, -np.ones(k)]))


def _entry_weight(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``sqrt(2) h`` with ``h = 1`` off the diagonal (``p != q``) and ``1/2`` on it."""
    return np.where(p == q, 0.5, 1.0) * np.sqrt(2.0)


def _concatenate_factors(parts: list[tuple[np.ndarray, ...]], kmax: int) -> tuple[np.ndarray, ...]:
    """The kernels' ``dict_mat, dict_dims, fe_off, fe_var, fe_p, fe_q, fe_val``."""
    dims = np.array([part[0].shape[1] for part in parts], dtype=np.int64)
    dict_mat = np.zeros((len(parts), kmax, int(dims.max())))
    for j, part in enumerate(parts):
        dict_mat[j, : part[0].shape[0], : dims[j]] = part[0]
    offsets = np.cumsum([0, *(part[1].shape[0] for part in parts)]).astype(np.int64)
    return (
        dict_mat, dims, offsets,
        np.concatenate([part[1] for part in parts]).astype(np.int64),
        np.concatenate([part[2] for part in parts]).astype(np.int64),
        np.concatenate([part[3] for part in parts]).astype(np.int64),
        np.concatenate([part[4] for part in parts]).astype(float),
    )


def _factor_groups(parts: list[tuple[np.ndarray, ...]],
                   raw: list[BlockFactor | None]) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's ``grp_off, grp_blk`` (:func:`lmi.ipm_kernels.scaling_and_schur_grouped`):
    blocks given in factored form whose order, dictionary width and entries are equal form one
    group (a Kothare problem's vertex blocks); every other block is a group of its own. Groups
    are ordered by their first block. Blocks without a given factor are never grouped: their
    entry values change in place with the bound scalings (see ``_refresh``)."""
    groups: list[list[int]] = []
    for j, part in enumerate(parts):
        for grp in groups:
            head = parts[grp[0]]
            if (raw[j] is not None and raw[grp[0]] is not None and part[0].shape == head[0].shape
                    and all(np.array_equal(a, b) for a, b in zip(part[1:], head[1:], strict=True))):
                grp.append(j)
                break
        else:
            groups.append([j])
    offsets = np.cumsum([0, *(len(g) for g in groups)]).astype(np.int64)
    return offsets, np.array([j for g in groups for j in g], dtype=np.int64)


def _check_factor(j: int, factor: Any, coef: np.ndarray | None, n: int) -> BlockFactor:
    """Validate a factored form ``(D, var, p, q, value)`` of block ``j``'s coefficients: it must
    reproduce them (``A_ij = D N_ij D'``) to 1e-9 relative."""
    name = f"factors[{j}]"
    if coef is None:
        raise InvalidArgumentError(name, "a factor only for a block given with coefficients", "no A")
    try:
        dmat, var, p, q, val = factor
    except (TypeError, ValueError):
        raise InvalidArgumentError(name, "a tuple (D, var, p, q, value)", repr(type(factor))) from None
    dmat = np.asarray(dmat, dtype=float)
    k = coef.shape[1]
    if dmat.ndim != 2 or dmat.shape[0] != k or dmat.shape[1] == 0 or not np.all(np.isfinite(dmat)):
        raise InvalidArgumentError(f"{name} D", f"a finite ({k}, d) matrix", f"shape {dmat.shape}")
    d = dmat.shape[1]
    var, p, q = (np.asarray(a, dtype=np.int64).ravel() for a in (var, p, q))
    val = np.asarray(val, dtype=float).ravel()
    if not (var.shape == p.shape == q.shape == val.shape):
        raise InvalidArgumentError(f"{name} entries", "var, p, q and value of equal length",
                                   f"lengths {var.size}, {p.size}, {q.size}, {val.size}")
    if np.any((var < 0) | (var >= n)) or np.any((p < 0) | (p > q) | (q >= d)) or not np.all(np.isfinite(val)):
        raise InvalidArgumentError(f"{name} entries", f"0 <= var < {n}, 0 <= p <= q < {d}, finite values",
                                   "an entry out of range")
    nmat = np.zeros((n, d, d))
    np.add.at(nmat, (var, p, q), val)
    off = p != q
    np.add.at(nmat, (var[off], q[off], p[off]), val[off])
    rebuilt = dmat @ (nmat @ dmat.T)  # matmul: an unoptimised einsum took 5.3 s of a 7.3 s build
    err = float(np.max(np.abs(rebuilt - coef), initial=0.0))
    if err > 1e-9 * max(1.0, float(np.max(np.abs(coef), initial=0.0))):
        raise InvalidArgumentError(name, "D N_i D' equal to the block's coefficients A_i",
                                   f"a largest difference of {err:.1e}")
    return dmat, var, p, q, val


def _concatenate_sparse(parts: list[tuple[np.ndarray, ...]]) -> tuple[np.ndarray, ...]:
    """The kernels' ``sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col`` from the
    per-block ``(pattern, var, pair, value, pair_row, pair_col)``."""
    entry_base = np.cumsum([0, *(part[1].shape[0] for part in parts)]).astype(np.int64)
    pair_base = np.cumsum([0, *(part[4].shape[0] for part in parts)]).astype(np.int64)
    return (
        entry_base,
        np.concatenate([part[1] for part in parts]).astype(np.int64),
        np.concatenate([part[2] + pair_base[j] for j, part in enumerate(parts)]).astype(np.int64),
        np.concatenate([part[3] for part in parts]).astype(float),
        pair_base,
        np.concatenate([part[4] for part in parts]).astype(np.int64),
        np.concatenate([part[5] for part in parts]).astype(np.int64),
    )


def _check_block(
    j: int, const: Any, coef: Any, n: int, order: int | None = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """Validate block ``j``: ``C_j`` ``(k, k)`` and ``A_j`` ``(n, k, k)``, finite and symmetric."""
    name = f"blocks[{j}]"
    c_mat = np.asarray(const, dtype=float)
    if c_mat.ndim != 2 or c_mat.shape[0] != c_mat.shape[1] or c_mat.shape[0] == 0:
        raise InvalidArgumentError(f"{name} C", "a square (k, k) matrix", f"shape {c_mat.shape}")
    k = c_mat.shape[0]
    if order is not None and k != order:
        raise InvalidArgumentError(f"{name} C", f"order {order} (the block's order)", f"order {k}")
    arrays = [("C", c_mat)]
    a_mat = None
    if coef is not None:
        a_mat = np.asarray(coef, dtype=float)
        if a_mat.shape != (n, k, k):
            raise InvalidArgumentError(f"{name} A", f"shape ({n}, {k}, {k})", f"shape {a_mat.shape}")
        arrays.append(("A", a_mat))
    for label, arr in arrays:
        if not np.all(np.isfinite(arr)):
            raise InvalidArgumentError(f"{name} {label}", "finite values", "NaN or inf")
        asym = float(np.max(np.abs(arr - np.swapaxes(arr, -1, -2)), initial=0.0))
        if asym > 1e-12 * max(1.0, float(np.max(np.abs(arr), initial=0.0))):
            raise InvalidArgumentError(f"{name} {label}", "symmetric matrices", f"asymmetry {asym:.1e}")
    return c_mat, a_mat


def _cholesky(hmat: np.ndarray) -> tuple[np.ndarray | None, bool]:
    """Upper Cholesky factor of ``H`` and ``False``, or ``(None, True)`` when a pivot relative to
    ``sqrt(H_jj)`` falls below :data:`QR_SWITCH` or Cholesky fails (then ``P`` is formed and
    factored by QR, see :func:`_factor`)."""
    r_fac, info = dpotrf(hmat, lower=0, clean=1)
    rel = np.abs(np.diag(r_fac)) / np.sqrt(np.maximum(np.diag(hmat), 1e-300))
    if info != 0 or not np.all(np.isfinite(r_fac)) or float(np.min(rel)) < QR_SWITCH:
        return None, True
    return np.ascontiguousarray(r_fac), False


def _factor(pt_mat: np.ndarray, use_qr: bool) -> tuple[np.ndarray, bool]:
    """Upper factor ``R`` with ``R'R = P'P``; switches to QR for good once Cholesky degrades.

    ``H = P'P`` squares ``P``'s condition number, which grows like ``1/mu`` near the optimum;
    once a relative pivot of the Cholesky factor falls below :data:`QR_SWITCH` (or Cholesky
    fails), ``P`` itself is factored.
    """
    r_fac = None
    if not use_qr:
        hmat = pt_mat @ pt_mat.T
        r_fac, info = dpotrf(hmat, lower=0, clean=1)
        # the pivots relative to sqrt(H_jj) (invariant to the scaling of the variables): how
        # much of each column is new, i.e. the loss of accuracy of the Cholesky factor
        rel = np.abs(np.diag(r_fac)) / np.sqrt(np.maximum(np.diag(hmat), 1e-300))
        if info != 0 or float(np.min(rel)) < QR_SWITCH:
            use_qr, r_fac = True, None
    if r_fac is None:
        r_fac = np.linalg.qr(pt_mat.T, mode="r")
    diag = np.abs(np.diag(r_fac))
    if not np.all(np.isfinite(r_fac)) or float(np.min(diag)) == 0.0:
        raise np.linalg.LinAlgError("singular Schur complement")
    return np.ascontiguousarray(r_fac), use_qr


