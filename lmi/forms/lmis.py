"""The LMIs of every robust MPC form, written once against a :class:`~lmi.forms.program.Program`.

The statements are those of the page "The field's robust MPC forms" of the docs (the notation:
``T_i = Q`` and ``G = Q`` for the common Lyapunov function, ``T_i = G + G' - Q_i`` for the vertex
forms; ``Y_s = D_s Y + (I - D_s) Z`` with the auxiliary saturation). :func:`declare` lays out the
variables of a form, :func:`write` adds its blocks. The same code gives the solver's data
(symbolic program), the constants at a new state and the certificate (numeric programs).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from lmi.affine import AffineMatrix
from lmi.forms.options import FormOptions
from lmi.forms.program import Layout, Program
from lmi.forms.soft import bound_slack, limit_slacks, soft_slacks

__all__ = ["FormData", "declare", "delta_congruence", "lyapunov_count", "objective", "pairs", "write"]


@dataclass(frozen=True)
class FormData:
    """The numbers one solve's LMIs are written with (in the solver's coordinates).

    ``x`` is the state, ``u_max``/``y_max`` the bounds (``(1,)`` ellipsoid or ``(m,)`` peak;
    empty without), ``w_max`` the disturbance bound and ``lam`` its contraction factor (``1.0``
    without a disturbance), all at the scale of ``x``.
    """

    A: np.ndarray  # (N, n, n)
    B: np.ndarray  # (N, n, m)
    A0: np.ndarray | None  # nominal model, cost="nominal"
    B0: np.ndarray | None
    Q1h: np.ndarray  # (p, n)
    Rh: np.ndarray  # (m, m)
    input_constraint: str | None
    C_out: np.ndarray | None
    E: np.ndarray | None
    x: np.ndarray
    u_max: np.ndarray
    y_max: np.ndarray
    w_max: float
    lam: float
    dt: float = 1.0
    q_outer: np.ndarray | None = None  # the off-line design's previous ellipsoid (common Q only)
    u_limit: np.ndarray | None = None  # soft limits (soft["u_limit"], 0 where none), at the scale of x
    y_limit: np.ndarray | None = None

    @property
    def n(self) -> int:
        return self.A.shape[1]

    @property
    def m(self) -> int:
        return self.B.shape[2]

    @property
    def n_vertices(self) -> int:
        return self.A.shape[0]


def pairs(opts: FormOptions, n_vertices: int, n_inputs: int = 1) -> list[tuple[int, int]]:
    """The ``(i, j)`` pairs of the cost and invariance LMIs: plant ``i`` now, ``Q_j`` next (with
    ``lyapunov="saturation_dependent"``: every vertex ``i`` and every sign pattern's ``Q_j`` of the
    ``2^m``, ``m = n_inputs``)."""
    if opts.saturation_dependent:
        return list(itertools.product(range(n_vertices), range(2**n_inputs)))
    if opts.lyapunov == "common":
        return [(i, 0) for i in range(n_vertices)]
    if opts.lyapunov == "vertex":
        return [(i, i) for i in range(n_vertices)]
    return list(itertools.product(range(n_vertices), repeat=2))


def _lyapunov_names(opts: FormOptions, n_vertices: int, n_inputs: int) -> list[str]:
    count = lyapunov_count(opts, n_vertices, n_inputs)
    return ["Q"] if opts.lyapunov == "common" else [f"Q{j}" for j in range(count)]


def lyapunov_count(opts: FormOptions, n_vertices: int, n_inputs: int) -> int:
    """How many Lyapunov matrices the form has: 1, one per vertex, or one per sign pattern (``2^m``)."""
    if opts.lyapunov == "common":
        return 1
    return 2**n_inputs if opts.saturation_dependent else n_vertices


def declare(opts: FormOptions, fd: FormData) -> Layout:
    """The variables of the form: ``gamma``, the ``Q``/``Q_j``, ``G``, ``Y``, ``Z``, ``u0``,
    ``s0``, ``s_u``, ``s_y``."""
    n, m = fd.n, fd.m
    lay = Layout()
    lay.full("gamma", 1, 1)
    for name in _lyapunov_names(opts, fd.n_vertices, m):
        lay.symmetric(name, n)
    if opts.vertex_lyapunov:
        lay.full("G", n, n)
    lay.full("Y", m, n)
    if opts.saturation == "auxiliary":
        lay.full("Z", m, n)
    if shares_cost(opts, fd.n_vertices, m):
        for k in range(len(_signs(opts, m))):
            lay.symmetric(f"W{k}", n)
    if opts.unsaturated_weight is not None:
        lay.full("gamma_s", 1, 1)
    if opts.free_moves:
        lay.full("u0", m, 1)
        lay.full("s0", 1, 1)
    for slack in soft_slacks(opts.soft):
        lay.full(slack.name, 1, 1)
    return lay


def shares_cost(opts: FormOptions, n_vertices: int, n_inputs: int = 1) -> bool:
    """Whether the cost LMIs share their ``Q1``/``R`` part through a variable ``W`` (more than one
    cost LMI per input sign): ``[[dt W, G' Q1h', Y_s' Rh'], [Q1h G, gamma I, 0], [Rh Y_s, 0, gamma
    I]] >= 0`` once, and ``[[T_i - dt W, M'], [M, Q_j]] >= 0`` per pair: by a Schur complement the
    same set of ``(G, Q_j, Y, gamma)`` (the best ``W`` is ``(G' Q1 G + Y_s' R Y_s) / (dt gamma)``),
    with each pair's block of order ``2n`` instead of ``2n + p + m`` (as Kothare's "delta_shared").
    With the nominal cost and the vertex Lyapunov forms (Ding et al.) the pairs' blocks hold the
    nominal model ``M = A_0 G + B_0 Y_s``; the nominal cost with one ``Q`` stays one block, and
    with the saturation-dependent function (Zhang et al.) one block per pattern pair."""
    several = len(pairs(opts, n_vertices, n_inputs)) > 1
    ding = opts.vertex_lyapunov and not opts.saturation_dependent
    return several and (opts.cost == "worst_case" or ding)


def objective(opts: FormOptions, lay: Layout) -> np.ndarray:
    """``c`` of ``min c'z``: ``gamma`` (+ ``s0``) (+ ``beta gamma_s``) + the soft constraints'
    penalties."""
    c = np.zeros(lay.size)
    c[lay.index("gamma")] = 1.0
    if "s0" in lay:
        c[lay.index("s0")] = 1.0
    if "gamma_s" in lay:  # Huang et al.'s gamma + beta gamma_s
        c[lay.index("gamma_s")] = float(opts.unsaturated_weight or 0.0)
    for slack in soft_slacks(opts.soft):
        c[lay.index(slack.name)] = slack.weight
    return c


def _signs(opts: FormOptions, m: int) -> list[np.ndarray | None]:
    if opts.saturation != "auxiliary":
        return [None]
    return [np.array(bits, dtype=float) for bits in itertools.product((1.0, 0.0), repeat=m)]


def write(prog: Program, opts: FormOptions, fd: FormData) -> Program:
    """Add every block of the form to ``prog`` (names say which LMI and which vertex)."""
    m, nv = fd.m, fd.n_vertices
    lyap = [prog.var(name) for name in _lyapunov_names(opts, nv, m)]
    common = opts.lyapunov == "common"
    g_var = lyap[0] if common else prog.var("G")

    def top(i: int) -> AffineMatrix:  # T_i
        return lyap[0] if common else g_var + g_var.T - lyap[i]

    def q_next(j: int) -> AffineMatrix:
        return lyap[0] if common else lyap[j]

    y_var = prog.var("Y")
    z_var = prog.var("Z") if opts.saturation == "auxiliary" else None

    def y_sign(sign: np.ndarray | None) -> AffineMatrix:
        if sign is None:
            return y_var
        assert z_var is not None
        return y_var.lmul(np.diag(sign)) + z_var.lmul(np.diag(1.0 - sign))

    gamma_all = prog.var("gamma")
    # Huang et al.: the unsaturated sign pattern (D_s = I, the first) bounded by gamma_s <= gamma
    gamma_s = prog.var("gamma_s") if opts.unsaturated_weight is not None else gamma_all
    if opts.unsaturated_weight is not None:
        # diag(gamma - gamma_s, gamma) >= 0: gamma_s <= gamma, with gamma as the block's own scale (a
        # 1 x 1 block's relative margin would be its sign alone)
        prog.add("unsaturated_bound", prog.bmat([[gamma_all - gamma_s, None], [None, gamma_all]]))
    signs = _signs(opts, m)
    q1h, rh = fd.Q1h, fd.Rh
    p = q1h.shape[0]

    def cost_block(a: np.ndarray, b: np.ndarray, t: AffineMatrix, qn: AffineMatrix,
                   ys: AffineMatrix, gamma: AffineMatrix) -> AffineMatrix:
        mid = g_var.lmul(a) + ys.lmul(b)
        u_eye = prog.times(gamma, np.eye(m))
        if p == 0:  # Q1 = 0: no state cost rows
            return prog.bmat([[t, mid.T, ys.T.rmul(rh.T)], [mid, qn, None], [ys.lmul(rh), None, u_eye]])
        g_eye = prog.times(gamma, np.eye(p))
        return prog.bmat([
            [t, mid.T, g_var.T.rmul(q1h.T), ys.T.rmul(rh.T)],
            [mid, qn, None, None],
            [g_var.lmul(q1h), None, g_eye, None],
            [ys.lmul(rh), None, None, u_eye],
        ])

    def invariance_block(a: np.ndarray, b: np.ndarray, t: AffineMatrix, qn: AffineMatrix,
                         ys: AffineMatrix) -> AffineMatrix:
        mid = g_var.lmul(a) + ys.lmul(b)
        if fd.E is None or fd.w_max == 0.0:
            return prog.bmat([[t, mid.T], [mid, qn]])
        q = fd.E.shape[1]
        we = prog.const(fd.w_max * fd.E)
        return prog.bmat([
            [t * fd.lam, None, mid.T],
            [None, prog.eye(q, 1.0 - fd.lam), we.T],
            [mid, we, qn],
        ])

    n = fd.n

    def delta(extra: int, rest_scale: float) -> np.ndarray:
        """``L`` of the delta congruence (see :func:`delta_congruence`)."""
        return delta_congruence(n, extra, fd.dt, rest_scale)

    cost_delta = delta(p + m, math.sqrt(fd.dt))
    pair_delta = delta(0, 1.0)  # one matrix for every [[T_i, M'], [M, Q_j]] block (read, never written)
    vertex_pairs = pairs(opts, nv, m)
    disturbed = fd.E is not None and fd.w_max > 0.0
    shared = shares_cost(opts, nv, m)
    root = math.sqrt(fd.dt)
    for k, sign in enumerate(signs):
        tag = "" if sign is None else f"_s{k}"
        ys = y_sign(sign)
        gamma = gamma_s if k == 0 else gamma_all

        def now(i: int, k: int = k) -> int:  # the index of T: the vertex, or the sign pattern
            return k if opts.saturation_dependent else i

        if shared and prog.wants(f"cost_shared{tag}"):
            w_dt = prog.var(f"W{k}") * fd.dt
            cost_rows = [g_var.T.rmul(q1h.T), ys.T.rmul(rh.T)] if p else [ys.T.rmul(rh.T)]
            gam_blocks = ([prog.times(gamma, np.eye(p))] if p else []) + [prog.times(gamma, np.eye(m))]
            size = len(cost_rows)
            rows: list[list[AffineMatrix | None]] = [[w_dt, *cost_rows]]
            for r, (row, gam_eye) in enumerate(zip(cost_rows, gam_blocks, strict=True)):
                rows.append([row.T] + [gam_eye if c == r else None for c in range(size)])
            extra = (p if p else 0) + m
            scale = np.diag(np.concatenate([np.full(n, 1.0 / root), np.full(extra, root)]))
            prog.add(f"cost_shared{tag}", prog.bmat(rows), congruence=scale)
        if shared:
            w_dt = prog.var(f"W{k}") * fd.dt
            nominal = opts.cost == "nominal"  # Ding et al.: the nominal model with T_i and Q_j
            for i, j in vertex_pairs:
                name = f"cost_nominal_{i}_{j}{tag}" if nominal else f"cost_{i}_{j}{tag}"
                if not prog.wants(name):
                    continue
                a, b = (fd.A0, fd.B0) if nominal else (fd.A[i], fd.B[i])
                assert a is not None and b is not None
                mid = g_var.lmul(a) + ys.lmul(b)
                block = prog.bmat([[top(now(i)) - w_dt, mid.T], [mid, q_next(j)]])
                prog.add(name, block, congruence=pair_delta)
        elif opts.cost == "worst_case":
            for i, j in vertex_pairs:
                if prog.wants(f"cost_{i}_{j}{tag}"):
                    prog.add(f"cost_{i}_{j}{tag}", cost_block(fd.A[i], fd.B[i], top(now(i)), q_next(j), ys,
                                                              gamma), congruence=cost_delta)
        elif opts.saturation_dependent:  # the nominal cost from T_k to every Q_j
            assert fd.A0 is not None and fd.B0 is not None
            for j in range(len(lyap)):
                if prog.wants(f"cost_nominal_{j}{tag}"):
                    prog.add(f"cost_nominal_{j}{tag}", cost_block(fd.A0, fd.B0, top(k), q_next(j), ys, gamma),
                             congruence=cost_delta)
        elif not opts.vertex_lyapunov:
            if prog.wants(f"cost_nominal{tag}"):
                assert fd.A0 is not None and fd.B0 is not None
                prog.add(f"cost_nominal{tag}", cost_block(fd.A0, fd.B0, lyap[0], lyap[0], ys, gamma),
                         congruence=cost_delta)
        else:  # the nominal cost with one vertex Lyapunov matrix: one pair, (0, 0)
            assert fd.A0 is not None and fd.B0 is not None
            for i, j in vertex_pairs:
                if prog.wants(f"cost_nominal_{i}_{j}{tag}"):
                    prog.add(f"cost_nominal_{i}_{j}{tag}",
                             cost_block(fd.A0, fd.B0, top(i), q_next(j), ys, gamma), congruence=cost_delta)
        if disturbed or opts.cost == "nominal":
            for i, j in vertex_pairs:
                if not prog.wants(f"invariance_{i}_{j}{tag}"):
                    continue
                block = invariance_block(fd.A[i], fd.B[i], top(now(i)), q_next(j), ys)
                prog.add(f"invariance_{i}_{j}{tag}", block, congruence=None if disturbed else pair_delta)
    if fd.q_outer is not None:  # Wan & Kothare's nesting, Q_outer - Q >= 0
        prog.add("nesting", prog.const(fd.q_outer) - lyap[0])
    _state_blocks(prog, opts, fd, lyap, vertex_pairs)
    _bound_blocks(prog, opts, fd, top, y_sign, signs, lyap)
    _soft_limit_blocks(prog, opts, fd, top, y_sign, signs, lyap)
    return prog


def delta_congruence(n: int, extra: int, dt: float, rest_scale: float) -> np.ndarray:
    """``L`` with ``L [r1; r2; r3] = [(r1 - r2) / sqrt(dt); r2; rest_scale r3]`` (block rows of
    sizes ``n``, ``n``, ``extra``).

    On a cost or invariance block ``[[T_i, M'], [M, Q_j], ...]`` with ``M = A_i G + B_i Y`` and
    ``A_i = I + O(dt)`` it gives the top-left block ``(T_i - M - M' + Q_j) / dt``, which for
    ``T_i = G + G' - Q_i`` is ``(Q_j - Q_i) / dt - (H_i + H_i')`` with ``H_i = ((A_i - I) G + B_i
    Y) / dt``: the differences of order ``dt`` that the printed block holds between entries of
    order one become entries of order one (Kothare's "delta" form; with ``rest_scale =
    sqrt(dt)`` the cost rows' ``gamma I`` become ``dt gamma I``). A congruence: the same LMI.
    """
    size = 2 * n + extra
    lmat = np.zeros((size, size))
    root = math.sqrt(dt)
    lmat[:n, :n] = np.eye(n) / root
    lmat[:n, n : 2 * n] = -np.eye(n) / root
    lmat[n : 2 * n, n : 2 * n] = np.eye(n)
    lmat[2 * n :, 2 * n :] = rest_scale * np.eye(extra)
    return lmat


def _with_slacks(prog: Program, opts: FormOptions, block: AffineMatrix) -> AffineMatrix:
    """``block`` with the soft constraints' slacks (``s_u, s_y``, or one per softened component,
    :func:`lmi.forms.soft.soft_slacks`) ``>= 0`` appended on its diagonal.

    A slack is zero at the optimum wherever the hard bound holds; on a ``1 x 1`` block of its
    own, the solver's block-wise residual test (relative to the block's size, then about zero)
    could never pass, so the slacks share the state block, whose size is one.
    """
    slacks = [prog.var(slack.name) for slack in soft_slacks(opts.soft)]
    if not slacks:
        return block
    rows: list[list[AffineMatrix | None]] = [[block] + [None] * len(slacks)]
    for k, slack in enumerate(slacks):
        rows.append([None] * (k + 1) + [slack] + [None] * (len(slacks) - k - 1))
    rows[0][1] = prog.zeros(block.shape[0], 1)
    for k in range(1, len(slacks)):
        rows[k][0] = prog.zeros(1, block.shape[1])
    rows[-1][0] = prog.zeros(1, block.shape[1])
    return prog.bmat(rows)


def _soft_square(prog: Program, bound: float, name: str | None) -> AffineMatrix:
    """``bound^2 (+ s_name)`` as a ``1 x 1`` affine matrix (``name`` ``None``: a hard bound)."""
    square = prog.const(bound**2)
    return square + prog.var(name) if name is not None and name in prog.layout else square


def _state_blocks(prog: Program, opts: FormOptions, fd: FormData, lyap: list[AffineMatrix],
                  vertex_pairs: list[tuple[int, int]]) -> None:
    one = prog.const(1.0)
    if not opts.free_moves:
        xc = prog.const(fd.x[:, None])
        for j, q in enumerate(lyap):
            block = prog.bmat([[one, xc.T], [xc, q]])
            prog.add(f"state_{j}", _with_slacks(prog, opts, block) if j == 0 else block)
        return
    u0 = prog.var("u0")
    # every vertex's prediction x(k+1) = A_i x + B_i u0 inside the ellipsoid of Q_j
    models = [
        (f"{i}_{j}", fd.A[i], fd.B[i], lyap[0] if len(lyap) == 1 else lyap[j]) for i, j in vertex_pairs
    ]
    if opts.cost == "nominal":
        assert fd.A0 is not None and fd.B0 is not None
        models.append(("nominal", fd.A0, fd.B0, lyap[0]))
    for tag, a, b, q in models:
        pred = u0.lmul(b) + prog.const((a @ fd.x)[:, None])
        prog.add(f"prediction_{tag}", prog.bmat([[one, pred.T], [pred, q]]))
    stage = float(fd.x @ fd.Q1h.T @ fd.Q1h @ fd.x)
    s0 = prog.var("s0") - prog.const(stage)
    stage_block = prog.bmat([[s0, u0.T.rmul(fd.Rh.T)], [u0.lmul(fd.Rh), prog.eye(fd.m)]])
    prog.add("stage_cost", _with_slacks(prog, opts, stage_block))


def _bound_blocks(prog: Program, opts: FormOptions, fd: FormData, top, y_sign, signs,
                  lyap: list[AffineMatrix]) -> None:
    m = fd.m
    kind = fd.input_constraint
    bounded = prog.var("Z") if opts.saturation == "auxiliary" else prog.var("Y")
    for j in range(len(lyap)):
        t = top(j)
        if kind == "ellipsoid":
            square = _soft_square(prog, float(fd.u_max[0]), bound_slack(opts.soft, "u", None))
            prog.add(f"input_{j}", prog.bmat([[prog.times(square, np.eye(m)), bounded],
                                               [bounded.T, t]]))
        elif kind == "peak":
            for ell in range(m):
                row = bounded.lmul(np.eye(m)[ell : ell + 1])
                square = _soft_square(prog, float(fd.u_max[ell]), bound_slack(opts.soft, "u", ell))
                prog.add(f"input_{ell}_{j}", prog.bmat([[square, row], [row.T, t]]))
    if opts.free_moves and kind is not None:
        u0 = prog.var("u0")
        if kind == "ellipsoid":
            square = _soft_square(prog, float(fd.u_max[0]), bound_slack(opts.soft, "u", None))
            prog.add("input_u0", prog.bmat([[square, u0.T], [u0, prog.eye(m)]]))
        else:
            for ell in range(m):
                comp = u0.lmul(np.eye(m)[ell : ell + 1])
                square = _soft_square(prog, float(fd.u_max[ell]), bound_slack(opts.soft, "u", ell))
                prog.add(f"input_u0_{ell}", prog.bmat([[square, comp], [comp, prog.const(1.0)]]))
    if fd.C_out is None:
        return
    g_var = lyap[0] if opts.lyapunov == "common" else prog.var("G")
    for r, c_row in enumerate(fd.C_out):
        square_bound = float(fd.y_max[r])
        for i in range(fd.n_vertices):
            for k, sign in enumerate(signs):
                tag = "" if sign is None else f"_s{k}"
                ys = y_sign(sign)
                out = (g_var.lmul(fd.A[i]) + ys.lmul(fd.B[i])).lmul(c_row[None, :])
                square = _soft_square(prog, square_bound, bound_slack(opts.soft, "y", r))
                t_out = top(k) if opts.saturation_dependent else top(i)  # T of the sign pattern itself
                prog.add(f"output_{r}_{i}{tag}", prog.bmat([[square, out], [out.T, t_out]]))
            if opts.free_moves:
                u0 = prog.var("u0")
                pred = (u0.lmul(fd.B[i]) + prog.const((fd.A[i] @ fd.x)[:, None])).lmul(c_row[None, :])
                square = _soft_square(prog, square_bound, bound_slack(opts.soft, "y", r))
                prog.add(f"output_{r}_{i}_u0", prog.bmat([[square, pred], [pred.T, prog.const(1.0)]]))


def _soft_limit_blocks(prog: Program, opts: FormOptions, fd: FormData, top, y_sign, signs,
                       lyap: list[AffineMatrix]) -> None:
    """The soft limits (``soft["u_limit"]``, ``soft["y_limit"]``) after Oravec & Bakošová, one
    block per softened component ``k`` (as the peak bounds): ``[[l_k^2 + s_k, y_k], [y_k', T_j]]
    >= 0`` for every ``j`` (``y_k`` the row ``k`` of ``Y``, the law's own gain, also with the
    auxiliary saturation, as MUP's ``sdp_cao_soft_con.m``) and, with output bounds,
    ``[[l_r^2 + s_r, c_r (A_i G + B_i Y_s)], [., T_i]] >= 0`` for every vertex ``i`` (and
    ``D_s``); with a free move, the same on ``u0`` and on every vertex's ``c_r x(k+1)``."""
    one = prog.const(1.0)
    for slack in limit_slacks(opts.soft, "u"):
        assert fd.u_limit is not None
        k = slack.component
        assert k is not None
        square = _soft_square(prog, float(fd.u_limit[k]), slack.name)
        row = prog.var("Y").lmul(np.eye(fd.m)[k : k + 1])
        for j in range(len(lyap)):
            prog.add(f"soft_limit_u{k}_{j}", prog.bmat([[square, row], [row.T, top(j)]]))
        if opts.free_moves:
            comp = prog.var("u0").lmul(np.eye(fd.m)[k : k + 1])
            prog.add(f"soft_limit_u{k}_u0", prog.bmat([[square, comp], [comp.T, one]]))
    if fd.C_out is None:
        return
    g_var = lyap[0] if opts.lyapunov == "common" else prog.var("G")
    for slack in limit_slacks(opts.soft, "y"):
        assert fd.y_limit is not None
        r = slack.component
        assert r is not None
        square = _soft_square(prog, float(fd.y_limit[r]), slack.name)
        c_row = fd.C_out[r][None, :]
        for i in range(fd.n_vertices):
            for k, sign in enumerate(signs):
                tag = "" if sign is None else f"_s{k}"
                out = (g_var.lmul(fd.A[i]) + y_sign(sign).lmul(fd.B[i])).lmul(c_row)
                prog.add(f"soft_limit_y{r}_{i}{tag}", prog.bmat([[square, out], [out.T, top(i)]]))
            if opts.free_moves:
                pred = (prog.var("u0").lmul(fd.B[i]) + prog.const((fd.A[i] @ fd.x)[:, None])).lmul(c_row)
                prog.add(f"soft_limit_y{r}_{i}_u0", prog.bmat([[square, pred], [pred.T, one]]))
