"""A structure-exploiting primal-dual interior-point solver for small block LMI problems.

Solves ::

    minimise c'x   subject to   S_j = C_j - sum_i x_i A_ij  >= 0   (every block j)

with ``x`` in R^n and a few symmetric blocks of small order (the Kothare problems of this
toolkit: tens of variables, blocks of order <= 25). General conic solvers handle this badly:
Clarabel factors a sparse KKT system in the half-vectorised space, in which every order-``k``
block becomes a dense ``k(k+1)/2`` square. Here each Newton step is reduced to the ``n x n``
Schur complement ``H = P' P``, where the columns of ``P`` are the half-vectorised scaled
coefficients ``K A_i K'``; the blocks are stacked into arrays of equal order (smaller blocks
padded with a constant identity, which leaves the feasible set unchanged) so that each
operation is one batched numpy call per stack rather than one call per block, and the large
work arrays are allocated once.

Algorithm: infeasible-start path following with Nesterov-Todd scaling and Mehrotra's
predictor-corrector, as in Vandenberghe's CVXOPT ``coneqp`` (L. Vandenberghe, "The CVXOPT
linear and quadratic cone program solvers", 2010), without the homogeneous self-dual embedding:
an infeasible or unbounded problem ends as ``"insufficient_progress"``, ``"max_iterations"`` or
``"numerical_error"``, never as a wrong ``"optimal"``. The NT scaling of each block comes from
one Cholesky factor and one small symmetric eigen-decomposition (``_nt_scaling``, as in SDPT3).
Variables are equilibrated (unit Frobenius norm of each ``A_i``). ``H`` is factored by Cholesky until it
becomes ill-conditioned near the optimum, then through a QR factorisation of ``P`` (which does
not square the condition number); each Newton solve is iteratively refined on the exact
equations. Successive solves can be warm-started from an interior iterate of the previous one.
"""

from __future__ import annotations

import itertools
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.linalg.lapack import dpotrf, dpotrs

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["REDUCED_TOL", "STALL_WINDOW", "BlockLMISolver", "IPMResult"]

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

#: Cost model of the default stacking (see ``_default_levels``).
STACK_OVERHEAD_US = 90.0
BLOCK_FLOP_US = 0.02

#: At most this many steps of iterative refinement per Newton solve (each stops early once
#: the residual of ``P' dz = -r_d`` stops shrinking).
REFINE_STEPS = 3


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


class _Stack:
    """Blocks padded to one order ``k``: ``C`` is ``(c, k, k)``, ``A`` is ``(c, n, k, k)``.

    Also caches the coefficients with the variable scaling ``D`` applied, in the two layouts
    the iterations use: ``left`` ``(c, k, n k)`` for the congruences and ``packed``
    ``(L c, n)`` (half-vectorised rows, ordered (entry, block)) for the residuals.
    """

    def __init__(self, members: list[int], order: int, n: int) -> None:
        self.members = members
        self.order = order
        self.count = len(members)
        self.c_mat = np.zeros((self.count, order, order))
        self.a_mat = np.zeros((self.count, n, order, order))
        self.iu0, self.iu1 = np.triu_indices(order)
        self.w = np.where(self.iu0 == self.iu1, 1.0, np.sqrt(2.0))
        self.left = np.zeros((self.count, order, n * order))
        self.packed = np.zeros((self.iu0.shape[0] * self.count, n))
        self.dirty: set[int] = set(range(self.count))
        # work buffers of the congruences, allocated once: large temporaries allocated per
        # iteration come from fresh pages (mmap) and cost more than the products themselves
        self.buf_left = np.empty((self.count, order, n * order))
        self.buf_right = np.empty((self.count, order * n, order))
        # flat positions of the packed entries (entry, block, variable) in buf_right
        l_idx, b_idx, i_idx = np.meshgrid(
            np.arange(self.iu0.shape[0]), np.arange(self.count), np.arange(n), indexing="ij"
        )
        self.take_index = np.ravel_multi_index(
            (b_idx, self.iu0[l_idx], i_idx, self.iu1[l_idx]), (self.count, order, n, order)
        ).reshape(-1, n)
        self.take_weight = np.repeat(self.w, self.count)[:, None]

    def set_block(self, pos: int, const: np.ndarray, coef: np.ndarray | None) -> None:
        size = const.shape[0]
        self.c_mat[pos] = 0.0
        self.c_mat[pos, :size, :size] = const
        self.c_mat[pos, size:, size:] = np.eye(self.order - size)  # padding: constant identity
        if coef is not None:
            self.a_mat[pos] = 0.0
            self.a_mat[pos, :, :size, :size] = coef
            self.dirty.add(pos)

    def refresh(self, dscale: np.ndarray) -> None:
        """Bring the scaled caches of the changed blocks up to date."""
        n, k = self.a_mat.shape[1], self.order
        rows = self.packed.reshape(-1, self.count, n)
        for pos in self.dirty:
            scaled = self.a_mat[pos] * dscale[:, None, None]  # (n, k, k)
            self.left[pos] = scaled.transpose(1, 0, 2).reshape(k, n * k)
            rows[:, pos, :] = (scaled[:, self.iu0, self.iu1] * self.w).T
        self.dirty.clear()


def _sym(mats: np.ndarray) -> np.ndarray:
    return 0.5 * (mats + np.swapaxes(mats, -1, -2))


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
    stack_orders : sequence of int, optional
        The orders blocks are padded to (each block goes into the smallest listed order that
        holds it). Default: chosen by a cost model (``_default_levels``); for paper P's
        problem, orders 12 and 15.

    Raises
    ------
    InvalidArgumentError
        For data of the wrong shape, non-finite or non-symmetric data, or bad settings; the
        message names the argument.

    Notes
    -----
    An instance keeps work buffers and the warm-start point between solves: use one instance
    per thread (each :class:`lmi.KothareProblem` has its own).

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
        stack_orders: Sequence[int] | None = None,
    ) -> None:
        self.c = as_vector(c, "c")
        n = self.c.shape[0]
        self.n = n
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
        self._g_mat: np.ndarray | None = None  # all stacks' packed coefficients, stacked
        checked = [_check_block(j, const, coef, n) for j, (const, coef) in enumerate(blocks)]
        orders = [const.shape[0] for const, _ in checked]
        self.block_orders = orders
        if stack_orders is None:
            levels = _default_levels(orders)
        else:
            levels = sorted({int(k) for k in stack_orders})
            if not levels or max(orders) > levels[-1]:
                raise InvalidArgumentError(
                    "stack_orders", f"orders holding every block (largest {max(orders)})",
                    repr(list(stack_orders)),
                )
        self._where: list[tuple[int, int]] = []  # block -> (stack, position)
        members: dict[int, list[int]] = {}
        for j, k in enumerate(orders):
            level = next(lv for lv in levels if lv >= k)
            members.setdefault(level, []).append(j)
        self._stacks = [_Stack(members[lv], lv, n) for lv in sorted(members)]
        self._where = [(0, 0)] * len(orders)
        for si, st in enumerate(self._stacks):
            for pos, j in enumerate(st.members):
                self._where[j] = (si, pos)
        self.degree = sum(st.count * st.order for st in self._stacks)
        sizes = [st.packed.shape[0] for st in self._stacks]
        bounds = np.cumsum([0, *sizes])
        self._p_rows = [slice(int(lo), int(hi)) for lo, hi in itertools.pairwise(bounds)]
        self._p_buf = np.empty((int(bounds[-1]), n))
        self._build_pack_maps()
        for j, (const, coef) in enumerate(checked):
            self.set_block(j, const, coef)

    @property
    def stack_shapes(self) -> list[tuple[int, int]]:
        """``(count, order)`` of each stack."""
        return [(st.count, st.order) for st in self._stacks]

    def reset_warm_start(self) -> None:
        """Forget the stored warm-start point (the next warm solve starts cold)."""
        self._warm = None

    def set_block(self, j: int, const: np.ndarray, coef: np.ndarray | None = None) -> None:
        """Replace block ``j``'s constant (and coefficients, if given)."""
        if isinstance(j, bool) or not (isinstance(j, int | np.integer) and 0 <= j < len(self.block_orders)):
            raise InvalidArgumentError("j", f"a block index in [0, {len(self.block_orders)})", repr(j))
        const_c, coef_c = _check_block(int(j), const, coef, self.n, self.block_orders[j])
        si, pos = self._where[j]
        self._stacks[si].set_block(pos, const_c, coef_c)

    # -- the solve -----------------------------------------------------------------------
    def solve(self, warm_start: bool = False) -> IPMResult:
        """Solve with the current data.

        With ``warm_start``, start from the iterate the previous solve passed through at a
        relative gap of ``warm_gap`` (an interior, roughly centred point) instead of the
        default initial point; the residuals the new data cause are handled like any
        infeasible start. A warm start that fails is retried cold.
        """
        start = time.perf_counter()
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

    def _run(self, warm: tuple | None, max_iter: int) -> IPMResult:
        stacks = self._stacks
        n = self.n
        # equilibrate the variables once, x = D x~ with unit-norm scaled coefficients (later
        # coefficient updates, e.g. a bound scaling, keep D)
        if self._dscale is None:
            norms = np.sqrt(sum(np.einsum("cikl,cikl->i", st.a_mat, st.a_mat) for st in stacks))
            self._dscale = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
            for st in stacks:
                st.dirty.update(range(st.count))
        dscale = self._dscale
        if any(st.dirty for st in stacks) or self._g_mat is None:
            for st in stacks:
                if st.dirty:
                    st.refresh(dscale)
            self._g_mat = np.vstack([st.packed for st in stacks])
        g_mat = self._g_mat
        cvec = self.c * dscale
        p_buf = self._p_buf
        p_rows = self._p_rows
        h_vec = self._pack([st.c_mat for st in stacks])
        c_norm = max(1.0, float(np.linalg.norm(cvec)))
        h_norm = max(1.0, float(np.linalg.norm(h_vec)))

        if warm is None:  # CVXOPT's initial point: least squares, shifted into the interiors
            gtg_f = cho_factor(g_mat.T @ g_mat + 1e-12 * np.eye(n))
            x = cho_solve(gtg_f, g_mat.T @ h_vec)
            s = _shift_interior(self._unpack(h_vec - g_mat @ x))
            z = _shift_interior(self._unpack(-g_mat @ cho_solve(gtg_f, cvec)))
        else:
            x, s, z = warm[0] / dscale, warm[1], warm[2]
        # S is kept as h - G x + theta r0 (theta = prod(1 - alpha)): the primal residual then
        # decays exactly, where updating S through the scaling lets it drift up near the optimum
        # (measured: 1e-10 -> 3e-6 relative over the last iterations of some paper-P solves)
        r0 = self._pack(s) + g_mat @ x - h_vec
        theta = 1.0
        status = "max_iterations"
        pres = dres = gap = np.inf
        it = 0
        use_qr = False
        best: tuple | None = None
        warm_next: tuple | None = None
        merits: list[float] = []
        s_chol: list[np.ndarray] | None = None  # Cholesky factors of s, when already known
        debug = _LOG.isEnabledFor(logging.DEBUG)
        for it in range(max_iter + 1):
            sp, zp = self._pack([np.stack([a, b]) for a, b in zip(s, z, strict=True)])
            gx = g_mat @ x
            gtz = g_mat.T @ zp
            rd = gtz + cvec
            rp = gx + sp - h_vec
            gap = float(sp @ zp)
            pcost, dcost = float(cvec @ x), -float(h_vec @ zp)
            pres = float(np.linalg.norm(rp)) / max(h_norm, float(np.linalg.norm(gx)),
                                                  float(np.linalg.norm(sp)))
            dres = float(np.linalg.norm(rd)) / max(c_norm, float(np.linalg.norm(gtz)))
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
            merits.append(max(pres, dres, min(gap, rel_gap)))
            if it >= STALL_WINDOW and merits[-1] > STALL_FACTOR * merits[-1 - STALL_WINDOW]:
                status = "insufficient_progress"
                break
            if (0.1 * self.warm_gap <= rel_gap <= self.warm_gap
                    and max(pres, dres) <= self.warm_feas):
                warm_next = (x * dscale, s, z)
            if it == max_iter:
                break
            try:
                if s_chol is None:
                    s_chol = [np.linalg.cholesky(a) for a in s]
                scal = [_nt_scaling(ls, b) for ls, b in zip(s_chol, z, strict=True)]
                for (kk, _r, _l), st, rows in zip(scal, stacks, p_rows, strict=True):
                    _congruence_packed(kk, st, p_buf[rows])
                r_fac, use_qr = _factor(p_buf, use_qr)
            except (np.linalg.LinAlgError, ValueError):
                status = "numerical_error"
                break
            lams = [lam for _k, _r, lam in scal]
            mu = gap / self.degree
            ref_scale = max(c_norm, float(np.linalg.norm(gtz)))
            rpt = self._pack([kk @ r @ np.swapaxes(kk, -1, -2) for (kk, _r, _l), r in
                              zip(scal, self._unpack(rp), strict=True)])

            def newton(u: np.ndarray, rd=rd, rpt=rpt, r_fac=r_fac, ref=ref_scale):
                return _newton(p_buf, r_fac, rd, rpt, u, ref)

            # predictor: u = lambda^{o-1}(-lambda o lambda) = -diag(lambda)
            _dx, dsa, dza = newton(-self._pack([_diag(lam) for lam in lams]))
            d_aff = self._unpack(np.stack([dsa, dza]))  # per stack (2, c, k, k)
            a_aff = min(1.0, _max_step(lams, d_aff))
            sigma = (1.0 - a_aff) ** 3
            # corrector
            u_cor = []
            for lam, dd in zip(lams, d_aff, strict=True):
                rc = -_sym(dd[0] @ dd[1])
                idx = np.arange(lam.shape[-1])
                rc[..., idx, idx] += sigma * mu - lam * lam
                u_cor.append(rc * (2.0 / (lam[..., :, None] + lam[..., None, :])))
            dx, dst, dzt = newton(self._pack(u_cor))
            d_cor = self._unpack(np.stack([dst, dzt]))
            alpha = min(1.0, 0.99 * _max_step(lams, d_cor))
            if debug:
                _LOG.debug("    sigma %.2e alpha_aff %.3f alpha %.3f qr %s", sigma, a_aff, alpha, use_qr)
            if not np.isfinite(alpha) or alpha <= 1e-12:
                status = "numerical_error"
                break
            step = self._take_step(x, dx, scal, d_cor, alpha, theta, r0, g_mat, h_vec)
            if step is None:
                status = "numerical_error"
                break
            x, s, z, theta, s_chol = step
        if status == "optimal" and warm_next is not None:
            self._warm = warm_next
        if status != "optimal" and best is not None:
            status = "inaccurate"
            x, s, z, pres, dres, gap = best
        s_out: list[np.ndarray] = []
        z_out: list[np.ndarray] = []
        for j, k in enumerate(self.block_orders):
            si, pos = self._where[j]
            s_out.append(s[si][pos, :k, :k].copy())
            z_out.append(z[si][pos, :k, :k].copy())
        zp = self._pack(z)
        return IPMResult(
            status, x * dscale, s_out, z_out, it, float(cvec @ x), -float(h_vec @ zp), pres, dres,
            gap, 0.0,
        )

    def _take_step(
        self, x: np.ndarray, dx: np.ndarray, scal: list, d_cor: list[np.ndarray], alpha: float,
        theta: float, r0: np.ndarray, g_mat: np.ndarray, h_vec: np.ndarray,
    ) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray], float, list[np.ndarray]] | None:
        """``x + a dx``, ``S = h - G x + theta r0`` (and its Cholesky factors), ``Z`` from the
        scaled update.

        If rounding leaves the recomputed ``S`` not positive definite, the step is shortened
        (at most five times by 0.8); ``None`` if that does not help.
        """
        for _ in range(6):
            x_new = x + alpha * dx
            theta_new = theta * (1.0 - alpha)
            s_new = [_sym(m) for m in self._unpack(h_vec - g_mat @ x_new + theta_new * r0)]
            try:
                s_chol = [np.linalg.cholesky(m) for m in s_new]  # reused by the next scaling
            except np.linalg.LinAlgError:
                alpha *= 0.8
                continue
            z_new = []
            for (kk, _rr, lam), dd in zip(scal, d_cor, strict=True):
                lz_ = _diag(lam) + alpha * dd[1]
                z_new.append(_sym(np.swapaxes(kk, -1, -2) @ lz_ @ kk))
            return x_new, s_new, z_new, theta_new, s_chol
        return None

    def _pack(self, mats: list[np.ndarray]) -> np.ndarray:
        """Scaled half-vectorisation of the stacks ``(..., c, k, k)``, entries ordered (entry, block)."""
        lead = mats[0].shape[:-3]
        flat = np.concatenate([m.reshape(*lead, -1) for m in mats], axis=-1)
        return np.take(flat, self._pack_index, axis=-1) * self._pack_weight

    def _unpack(self, vec: np.ndarray) -> list[np.ndarray]:
        """Inverse of :meth:`_pack` for ``(..., total)`` -> per stack ``(..., c, k, k)`` (views)."""
        lead = vec.shape[:-1]
        full = np.take(vec, self._unpack_index, axis=-1) * self._unpack_weight
        return [full[..., sl].reshape(*lead, st.count, st.order, st.order)
                for sl, st in zip(self._full_slices, self._stacks, strict=True)]

    def _build_pack_maps(self) -> None:
        """Index maps between the packed vector and the stacks' full entries, all stacks at once."""
        pack_index, pack_weight, unpack_index, unpack_weight = [], [], [], []
        self._full_slices = []
        full_offset = packed_offset = 0
        for st in self._stacks:
            c, k = st.count, st.order
            n_entries = st.iu0.shape[0]
            # packed position (l, b) <- full position (b, iu0[l], iu1[l])
            l_idx, b_idx = np.meshgrid(np.arange(n_entries), np.arange(c), indexing="ij")
            pack_index.append(full_offset + np.ravel_multi_index((b_idx, st.iu0[l_idx], st.iu1[l_idx]),
                                                                 (c, k, k)).ravel())
            pack_weight.append(np.repeat(st.w, c))
            # full position (b, p, q) <- packed position of (min(p, q), max(p, q)), block b
            entry = np.zeros((k, k), dtype=int)
            entry[st.iu0, st.iu1] = np.arange(n_entries)
            entry[st.iu1, st.iu0] = np.arange(n_entries)
            weight = np.where(np.eye(k, dtype=bool), 1.0, 1.0 / np.sqrt(2.0))
            b_full = np.arange(c)[:, None, None]
            unpack_index.append((packed_offset + entry[None] * c + b_full).ravel())
            unpack_weight.append(np.broadcast_to(weight, (c, k, k)).ravel())
            self._full_slices.append(slice(full_offset, full_offset + c * k * k))
            full_offset += c * k * k
            packed_offset += n_entries * c
        self._pack_index = np.concatenate(pack_index)
        self._pack_weight = np.concatenate(pack_weight)
        self._unpack_index = np.concatenate(unpack_index)
        self._unpack_weight = np.concatenate(unpack_weight)


# -- helpers -------------------------------------------------------------------------------
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


def _default_levels(orders: list[int]) -> list[int]:
    """Stack orders minimising a cost model of one iteration.

    Each stack costs a fixed overhead (about 15 numpy calls, ~90 us here) and each block of
    padded order ``k`` about ``0.02 k^3`` us (measured on the 2-core test machine with paper P's
    problem: one stack of order 15 for 11 blocks took 1.6 ms per iteration, stacks of order
    12 and 15 took 1.3 ms, four stacks of orders 7, 9, 12, 15 took 1.4 ms). Every split of the
    sorted distinct orders into consecutive groups is tried (there are at most a handful).
    """
    distinct = sorted(set(orders))
    best_cost, best = np.inf, distinct
    for mask in range(2 ** (len(distinct) - 1)):
        levels = [k for i, k in enumerate(distinct[:-1]) if mask >> i & 1] + [distinct[-1]]
        cost = STACK_OVERHEAD_US * len(levels) + BLOCK_FLOP_US * sum(
            next(lv for lv in levels if lv >= k) ** 3 for k in orders
        )
        if cost < best_cost:
            best_cost, best = cost, levels
    return best


def _diag(lam: np.ndarray) -> np.ndarray:
    out = np.zeros((*lam.shape, lam.shape[-1]))
    idx = np.arange(lam.shape[-1])
    out[..., idx, idx] = lam
    return out


def _shift_interior(mats: list[np.ndarray]) -> list[np.ndarray]:
    low = min(float(np.min(np.linalg.eigvalsh(m))) for m in mats)
    shift = 1.0 + max(0.0, -low)
    return [m + shift * np.eye(m.shape[-1]) for m in mats]


def _nt_scaling(ls: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(K, R, lambda)`` per block of a stack: ``K S K' = R' Z R = diag(lambda)``, ``K = R^-1``.

    As in SDPT3: ``S = L L'``, ``L' Z L = Q diag(d) Q'``, ``R = L Q diag(d)^-1/4``,
    ``lambda = sqrt(d)`` and ``K = diag(lambda)^-1 R' Z`` (no inverse). Near the central path
    ``L' Z L`` is close to ``mu I``, so its eigen-decomposition is well conditioned even when
    ``S`` and ``Z`` are not. ``ls`` is the Cholesky factor ``L`` of ``S``.
    """
    d, qv = np.linalg.eigh(np.swapaxes(ls, -1, -2) @ z @ ls)
    if np.any(d <= 0.0):
        raise np.linalg.LinAlgError("lost positive definiteness")
    lam = np.sqrt(d)
    rr = (ls @ qv) / np.sqrt(lam)[..., None, :]
    kk = (np.swapaxes(rr, -1, -2) @ z) / lam[..., :, None]
    return kk, rr, lam


def _congruence_packed(kk: np.ndarray, st: _Stack, out: np.ndarray) -> None:
    """Packed ``K_b A_bi K_b'`` for every block ``b`` and variable ``i`` into ``out`` ``(L c, n)``.

    The stack's coefficients are held as ``(c, k, n k)`` (``left[b, p, i k + q] = A_bi[p, q]``),
    so both products are single matrix products per block, into preallocated buffers.
    """
    c, k = st.count, st.order
    np.matmul(kk, st.left, out=st.buf_left)  # (K A_i)[p, q] at [b, p, i k + q]
    np.matmul(st.buf_left.reshape(c, -1, k), np.swapaxes(kk, -1, -2), out=st.buf_right)
    np.take(st.buf_right, st.take_index, out=out)
    out *= st.take_weight


def _factor(p_mat: np.ndarray, use_qr: bool) -> tuple[np.ndarray, bool]:
    """Upper factor ``R`` with ``R'R = P'P``; switches to QR for good once Cholesky degrades.

    ``H = P'P`` squares ``P``'s condition number, which grows like ``1/mu`` near the optimum;
    once a relative pivot of the Cholesky factor falls below :data:`QR_SWITCH` (or Cholesky
    fails), ``P`` itself is factored.
    """
    r_fac = None
    if not use_qr:
        hmat = p_mat.T @ p_mat
        r_fac, info = dpotrf(hmat, lower=0, clean=1)
        # the pivots relative to sqrt(H_jj) (invariant to the scaling of the variables): how
        # much of each column is new, i.e. the loss of accuracy of the Cholesky factor
        rel = np.abs(np.diag(r_fac)) / np.sqrt(np.maximum(np.diag(hmat), 1e-300))
        if info != 0 or float(np.min(rel)) < QR_SWITCH:
            use_qr, r_fac = True, None
    if r_fac is None:
        r_fac = np.linalg.qr(p_mat, mode="r")
    diag = np.abs(np.diag(r_fac))
    if not np.all(np.isfinite(r_fac)) or float(np.min(diag)) == 0.0:
        raise np.linalg.LinAlgError("singular Schur complement")
    return r_fac, use_qr


def _newton(
    p_mat: np.ndarray, r_fac: np.ndarray, rd: np.ndarray, rpt: np.ndarray, u: np.ndarray,
    ref_scale: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scaled Newton step ``(dx, ds~, dz~)`` for the complementarity right-hand side ``u``.

    Solves ``P'P dx = -r_d - P'(u + r~_p)``, ``dz~ = P dx + u + r~_p``, ``ds~ = u - dz~``, then
    refines on the exact equation ``P' dz~ = -r_d`` while its residual shrinks.
    """
    v = u + rpt
    dx = dpotrs(r_fac, -rd - p_mat.T @ v, lower=0)[0]
    dzt = p_mat @ dx + v
    err = p_mat.T @ dzt + rd
    err_norm = float(np.linalg.norm(err))
    for _ in range(REFINE_STEPS):
        if err_norm <= 1e-14 * ref_scale:
            break
        ddx = dpotrs(r_fac, -err, lower=0)[0]
        dzt_new = dzt + p_mat @ ddx
        err_new = p_mat.T @ dzt_new + rd
        new_norm = float(np.linalg.norm(err_new))
        if new_norm >= err_norm:
            break
        dx, dzt, err, err_norm = dx + ddx, dzt_new, err_new, new_norm
    return dx, u - dzt, dzt


def _max_step(lams: list[np.ndarray], dirs: list[np.ndarray]) -> float:
    """Largest ``a`` with ``diag(lambda) + a d >= 0`` for both ``d`` in ``dirs`` (per stack
    ``(2, c, k, k)``), every block."""
    alpha = np.inf
    for lam, dd in zip(lams, dirs, strict=True):
        isq = 1.0 / np.sqrt(lam)
        scaled = dd * (isq[..., :, None] * isq[..., None, :])
        t = float(np.min(np.linalg.eigvalsh(scaled.reshape(-1, *scaled.shape[-2:]))))
        if t < 0:
            alpha = min(alpha, -1.0 / t)
    return alpha
