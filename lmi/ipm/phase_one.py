"""Phase one of the block LMI solver: a feasible point, or a checked proof of infeasibility.

:func:`run_phase_one` is :meth:`lmi.ipm.BlockLMISolver.phase_one` (which documents the method):
it solves ``min t`` s.t. ``w_j (C_j - sum_i x_i A_ij) + t I >= 0`` (``w_j`` the solver's block
weights, :func:`lmi.ipm.blocks.block_weights`; 1 unless the blocks are badly balanced) with an
auxiliary solver of the same blocks and one more variable (:func:`phase_one_solver`), watching
every iterate (:class:`PhaseOneCheck`) for a strictly feasible ``x`` or a dual point that, moved
onto ``sum_j <A_ij, Z_j> = 0`` (:func:`dual_correction`), is a Farkas certificate of
infeasibility (:class:`PhaseOneResult`). It reads the solver's packed data
(:class:`lmi.ipm.blocks.BlockData`) directly and builds the auxiliary solver from the solver's
own class (``type(slv)``): it imports no solver, the solver imports it (the solver is typed
``Any`` where more than its data is used). The auxiliary solver takes the solver's weights,
so its iterates are in the weighted units of that packed data (its ``t`` has the coefficient
``-I`` there: with ``-I`` in the original blocks, phase one of SDPLIB's control3 and control4
took 5 and 6 iterations instead of 3 and 2); the certificate is returned, and its margins are
measured, in the original blocks (``Z_j = w_j Z~_j``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from lmi.ipm import kernels as _kernels
from lmi.ipm.blocks import BlockData, BlockFactor

__all__ = [
    "PHASE_ONE_MARGIN", "PHASE_ONE_MAX_ITER", "PHASE_ONE_RESIDUAL", "PHASE_ONE_TOL", "PhaseOneCheck",
    "PhaseOneResult", "dual_correction", "phase_one_solver", "run_phase_one", "with_identity",
]

#: Phase one (:meth:`BlockLMISolver.phase_one`) accepts a corrected dual point ``Z`` as a proof of
#: infeasibility only if ``sum_j <C_j, Z_j> <= -PHASE_ONE_MARGIN ||C|| ||Z||`` (Frobenius norms
#: over all blocks): a margin far above the rounding of the correction onto ``A'Z = 0``.
PHASE_ONE_MARGIN = 1e-7
#: ... and tries the correction only when the dual residual ``||G'z||`` is below this fraction of
#: ``||z||`` (before, it fails; see :func:`dual_correction`).
PHASE_ONE_RESIDUAL = 1e-8
#: Phase one's iteration limit and tolerances: it runs until a proof is found or it stalls
#: (its own optimality test, at these tolerances, practically never ends it first). On the
#: stress set's infeasible problems the proof came after 45-60 iterations: the phase-one
#: problem of an infeasible Kothare problem converges slowly (the gap shrinks by about 0.7 per
#: iteration), and the correction onto ``A'Z = 0`` succeeds only near its end.
PHASE_ONE_MAX_ITER = 100
PHASE_ONE_TOL = 1e-13


@dataclass
class PhaseOneResult:
    """Outcome of :meth:`lmi.ipm.BlockLMISolver.phase_one`.

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


def run_phase_one(slv: Any) -> PhaseOneResult:
    """Phase one on the current data of ``slv``, a :class:`lmi.ipm.BlockLMISolver` (see
    :meth:`lmi.ipm.BlockLMISolver.phase_one`)."""
    start = time.perf_counter()
    slv._refresh()
    aux = phase_one_solver(slv)
    aux._refresh()
    n, kmax = slv.n, slv._kmax
    orders = slv.block_orders
    weights = slv.block_weights
    low = min(float(np.linalg.eigvalsh(c * w)[0]) for c, w in zip(slv._const, weights, strict=True))
    t0 = 1.0 + max(0.0, -low)
    s0 = np.zeros((len(orders), kmax, kmax))
    z0 = np.zeros_like(s0)
    for j, k in enumerate(orders):
        s0[j, :k, :k] = slv._const[j] * weights[j] + t0 * np.eye(k)
        z0[j, :k, :k] = np.eye(k) / slv.degree
    x0 = np.zeros(n + 1)
    x0[n] = t0
    check = PhaseOneCheck(slv, aux._dscale)
    res = aux._run((x0, s0, z0), PHASE_ONE_MAX_ITER, check)
    found = check.found
    status = res.status if res.status in ("feasible", "infeasible") else "inconclusive"
    if status == "inconclusive" and res.status in ("optimal", "inaccurate"):
        # the last chance: the final dual point (at t* = 0 it cannot prove anything)
        zfin = np.zeros_like(z0)
        for j, k in enumerate(orders):
            zfin[j, :k, :k] = res.Z[j] / weights[j]  # back to the weighted units
        if check(res.x / aux._dscale, None, zfin) == "infeasible":
            status, found = "infeasible", check.found
    return PhaseOneResult(
        status, found.get("Z"), found.get("x"), found.get("objective", np.nan),
        found.get("residual", np.nan), found.get("min_eigenvalue", np.nan),
        float(found.get("t", res.x[n] if res.x.size > n else np.nan)), res.iterations,
        res.status, time.perf_counter() - start,
    )


def phase_one_solver(slv: Any) -> Any:
    """The phase-one solver of ``slv``, a :class:`lmi.ipm.BlockLMISolver` (built once, a solver of
    the same class), its blocks brought up to date with those of ``slv``."""
    n = slv.n
    aux = slv._phase_one_solver
    fresh = aux is None
    blocks, factors = [], []
    for j, k in enumerate(slv.block_orders):
        if fresh or not np.array_equal(aux._coef[j][:n], slv._coef[j]):
            # t's coefficient -I / w_j: -I in the weighted blocks w_j S_j the kernels see
            unit = 1.0 / slv.block_weights[j]
            coef = np.concatenate([slv._coef[j], -unit * np.eye(k)[None]])
            factor = with_identity(slv._factor_raw[j], n, k, unit)
            if fresh:
                blocks.append((slv._const[j], coef))
                factors.append(factor)
            else:
                aux.set_block(j, slv._const[j], coef, factor)
        elif not fresh:
            aux.set_block(j, slv._const[j])
    if fresh:
        cvec = np.zeros(n + 1)
        cvec[n] = 1.0
        aux = slv._phase_one_solver = type(slv)(
            cvec, blocks, tol_feas=PHASE_ONE_TOL, tol_gap_abs=PHASE_ONE_TOL,
            tol_gap_rel=PHASE_ONE_TOL, max_iter=PHASE_ONE_MAX_ITER, infeasibility_radius=np.inf,
            factors=factors)
        # the weights of slv (fixed before its first refresh): the iterates of aux are then in
        # the units of slv's packed data, which PhaseOneCheck reads
        aux.block_weights = slv.block_weights.copy()
    return aux


class PhaseOneCheck:
    """Phase one's monitor: is the iterate a strictly feasible point or does its dual point,
    corrected onto ``A'Z = 0``, prove infeasibility? (see :meth:`lmi.ipm.BlockLMISolver.phase_one`).
    What it found is left in ``found``."""

    def __init__(self, solver: BlockData, aux_scale: np.ndarray) -> None:
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
        blocks = dual_correction(slv, z)
        if blocks is None:
            return None
        zc = np.zeros_like(z)
        for j, k in enumerate(slv.block_orders):
            zc[j, :k, :k] = blocks[j]
        # the certificate in the original blocks (weights are powers of two: exact)
        weights = slv.block_weights
        blocks = [zj * wj for zj, wj in zip(blocks, weights, strict=True)]
        h_orig = np.concatenate([h[lay.rows(j)] / weights[j] for j in range(len(blocks))])
        zp = _kernels.pack(zc * weights[:, None, None], *packing)
        z_norm = float(np.linalg.norm(zp))
        objective = float(h_orig @ zp)
        if not (z_norm > 0.0 and objective <= -PHASE_ONE_MARGIN * float(np.linalg.norm(h_orig)) * z_norm):
            return None
        worst = np.inf
        for zj in blocks:
            lam = np.linalg.eigvalsh(zj)
            worst = min(worst, float(lam[0] / max(float(np.max(np.abs(lam))), 1e-300)))
        if not worst >= 0.0:
            return None
        # |sum_j <A_ij, Z_j>| relative to ||A_i|| ||Z|| (Frobenius norms over all blocks)
        a_z = sum(np.einsum("ikl,kl->i", a, zj) for a, zj in zip(slv._coef, blocks, strict=True))
        a_norm = np.sqrt(sum(np.einsum("ikl,ikl->i", a, a) for a in slv._coef))
        residual = float(np.max(np.abs(a_z) / np.where(a_norm > 0.0, a_norm, 1.0), initial=0.0)) / z_norm
        self.found = {"Z": blocks, "objective": objective, "residual": residual,
                      "min_eigenvalue": worst, "t": t}
        return "infeasible"


def dual_correction(slv: BlockData, z: np.ndarray) -> list[np.ndarray] | None:
    """``Z`` (positive definite blocks, padded) moved onto ``sum_j <A_ij, Z_j> = 0`` by the
    correction of least norm in ``Z``'s own metric: with ``Z_j = L_j L_j'``, ``Z_j + dZ_j =
    L_j (I + F_j) L_j'`` with ``||F||_F`` least, i.e. ``F`` the least-norm solution of
    ``sum_j <L_j' A_ij L_j, F_j> = -sum_j <A_ij, Z_j>``. The result is positive semidefinite
    exactly when every ``I + F_j`` is (checked); a correction of least Frobenius norm in ``Z``'s
    coordinates instead falls mostly on the directions where ``Z`` is small and made it
    indefinite (measured). ``Z`` and the result are in the solver's weighted units (``Z_j / w_j``;
    the correction ``F`` is the same in either). ``None`` when it is not positive definite or
    ``I + F`` is not."""
    factors, cols = [], []
    for j, k in enumerate(slv.block_orders):
        try:
            low = np.linalg.cholesky(z[j, :k, :k])
        except np.linalg.LinAlgError:
            return None
        factors.append(low)
        scaled = low.T @ (slv._coef[j] * (slv._dscale * slv.block_weights[j])[:, None, None]) @ low
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


def with_identity(raw: BlockFactor | None, n: int, k: int, scale: float = 1.0) -> BlockFactor | None:
    """Block ``j``'s factored coefficients with one more variable (index ``n``) of coefficient
    ``-scale I``, or ``None`` if the dictionary lacks an identity column for some row."""
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
            np.concatenate([q, idx]), np.concatenate([val, -scale * np.ones(k)]))
