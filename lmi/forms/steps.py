"""The forms with steps: later prediction steps with gains of their own (``horizon > 1``).

Two methods of the field, stated on the page "The field's robust MPC forms" of the docs:

- Shi, Su & Chu ("An improved model predictive control for uncertain systems with input
  constraints", Journal of the Franklin Institute 350, 2013): ``horizon=N`` steps, step ``t``
  with its own ``G_t``, ``Y_t`` (and ``Z_t``) and Lyapunov matrices ``Q_t`` (or ``Q_t^j``), chained
  from step to step; the last step's ellipsoid is invariant under its own gain (the terminal
  ellipsoid). Any Lyapunov form, with or without the auxiliary saturation.
- Li, Shi, Sun & Wang ("An improved constrained robust model predictive control algorithm for
  linear systems with polytopic uncertainty", Proc. IEEE/ASME AIM 2008): ``horizon=2,
  step_gains="vertex"``, one Lyapunov matrix ``X``, a first gain ``Y`` and one second-step gain
  ``Y_v`` per first-step vertex ``v``, both acting on the state at ``k`` (``u(k+1) = Y_v X^-1
  x(k)``), the cost bound over the two steps for every vertex pair ``(v, w)``.

:func:`declare_form` and :func:`write_form` give every form's variables and blocks: the forms
without steps are those of :mod:`lmi.forms.lmis`. The first step's variables keep the names of
the forms without steps (``Q``/``Q<j>``, ``G``, ``Y``, ``Z``), so that the answer (``F = Y G^-1``,
the first step's law) is read back the same way; a later step's carry ``@<t>`` (``Y@2``, ``Q0@2``)
and Li's second-step gains ``@v<v>`` (``Y@v0``).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from lmi.affine import AffineMatrix
from lmi.forms.lmis import FormData, declare, delta_congruence, pairs, write
from lmi.forms.options import FormOptions
from lmi.forms.program import Layout, Program

__all__ = ["declare_form", "step_name", "write_form"]


def step_name(name: str, t: int) -> str:
    """The name of variable ``name`` of step ``t`` (1-based; step 1's is ``name`` itself)."""
    return name if t == 1 else f"{name}@{t}"


def _lyapunov_names(opts: FormOptions, n_vertices: int, t: int) -> list[str]:
    names = ["Q"] if opts.lyapunov == "common" else [f"Q{j}" for j in range(n_vertices)]
    return [step_name(name, t) for name in names]


def _signs(opts: FormOptions, m: int) -> list[np.ndarray | None]:
    """``None`` without saturation; else the diagonals of the ``2^m`` matrices ``D_s`` (in the
    order of :func:`lmi.forms.lmis.write`)."""
    if opts.saturation != "auxiliary":
        return [None]
    return [np.array(bits, dtype=float) for bits in itertools.product((1.0, 0.0), repeat=m)]


def declare_form(opts: FormOptions, fd: FormData) -> Layout:
    """The variables of any form: :func:`lmi.forms.lmis.declare` without steps."""
    if not opts.has_steps:
        return declare(opts, fd)
    n, m = fd.n, fd.m
    lay = Layout()
    lay.full("gamma", 1, 1)
    if opts.step_gains == "vertex":  # Li et al.: X, Y, Y_v
        lay.symmetric("Q", n)
        lay.full("Y", m, n)
        for v in range(fd.n_vertices):
            lay.full(f"Y@v{v}", m, n)
        return lay
    for t in range(1, opts.horizon + 1):
        for name in _lyapunov_names(opts, fd.n_vertices, t):
            lay.symmetric(name, n)
        if opts.vertex_lyapunov:
            lay.full(step_name("G", t), n, n)
        lay.full(step_name("Y", t), m, n)
        if opts.saturation == "auxiliary":
            lay.full(step_name("Z", t), m, n)
    return lay


def write_form(prog: Program, opts: FormOptions, fd: FormData) -> Program:
    """Add every block of any form to ``prog``: :func:`lmi.forms.lmis.write` without steps."""
    if not opts.has_steps:
        return write(prog, opts, fd)
    if opts.step_gains == "vertex":
        return _write_two_steps(prog, fd)
    return _write_chain(prog, opts, fd)


def _state(prog: Program, fd: FormData, q: AffineMatrix, name: str) -> None:
    xc = prog.const(fd.x[:, None])
    if prog.wants(name):
        prog.add(name, prog.bmat([[prog.const(1.0), xc.T], [xc, q]]))


def _input(prog: Program, fd: FormData, gain: AffineMatrix, t_mat: AffineMatrix, tag: str) -> None:
    """``gain`` (its rows ``y_l``) bounded inside the ellipsoid ``t_mat``: ellipsoid ``[[u_max^2 I,
    Y], [Y', T]] >= 0`` or peak ``[[u_max,l^2, y_l], [y_l', T]] >= 0``."""
    m = fd.m
    if fd.input_constraint == "ellipsoid":
        square = prog.eye(m, float(fd.u_max[0]) ** 2)
        prog.add(f"input_{tag}", prog.bmat([[square, gain], [gain.T, t_mat]]))
    elif fd.input_constraint == "peak":
        for ell in range(m):
            row = gain.lmul(np.eye(m)[ell : ell + 1])
            square = prog.const(float(fd.u_max[ell]) ** 2)
            prog.add(f"input_{ell}_{tag}", prog.bmat([[square, row], [row.T, t_mat]]))


def _output(prog: Program, fd: FormData, image: AffineMatrix, t_mat: AffineMatrix, tag: str) -> None:
    """``|c_r x+| <= y_max,r`` for a predicted state ``x+ = image G^-1 x`` with ``x`` in the
    ellipsoid of ``t_mat``: ``[[y_max,r^2, c_r image], [., T]] >= 0`` for every output row ``r``."""
    if fd.C_out is None:
        return
    for r, c_row in enumerate(fd.C_out):
        out = image.lmul(c_row[None, :])
        prog.add(f"output_{r}_{tag}", prog.bmat([[prog.const(float(fd.y_max[r]) ** 2), out], [out.T, t_mat]]))


def _cost_rows(prog: Program, fd: FormData, states: list[AffineMatrix],
               inputs: list[AffineMatrix]) -> tuple[list[AffineMatrix], list[AffineMatrix]]:
    """The weighted rows ``Q1^(1/2) S`` and ``R^(1/2) U`` of the cost blocks, with their ``gamma I``."""
    gamma = prog.var("gamma")
    p = fd.Q1h.shape[0]
    rows: list[AffineMatrix] = []
    diag: list[AffineMatrix] = []
    for s_mat, u_mat in zip(states, inputs, strict=True):
        if p:
            rows.append(s_mat.lmul(fd.Q1h))
            diag.append(prog.times(gamma, np.eye(p)))
        rows.append(u_mat.lmul(fd.Rh))
        diag.append(prog.times(gamma, np.eye(fd.m)))
    return rows, diag


def _cost_block(prog: Program, top: AffineMatrix, image: AffineMatrix, nxt: AffineMatrix,
                rows: list[AffineMatrix], diag: list[AffineMatrix]) -> AffineMatrix:
    """``[[T, M', R_1', ..., R_k'], [M, Q_next, 0, ...], [R_1, 0, gamma I, ...], ...]``."""
    k = len(rows)
    table: list[list[AffineMatrix | None]] = [[top, image.T, *[r.T for r in rows]], [image, nxt] + [None] * k]
    for a, (row, block) in enumerate(zip(rows, diag, strict=True)):
        table.append([row, None] + [block if b == a else None for b in range(k)])
    return prog.bmat(table)


def _write_chain(prog: Program, opts: FormOptions, fd: FormData) -> Program:
    """Shi et al.'s ``N`` steps: for step ``t`` and every pair ``(i, j)`` (and sign ``D_s``), the
    cost block with ``T_t,i``, ``A_i G_t + B_i Y_t,s`` and ``Q_(t+1),j`` (``Q_N,j`` at the last
    step); ``x`` in every ``Q_1,j``; the bounds of every step inside its own ``T_t,j``."""
    nv, horizon = fd.n_vertices, opts.horizon
    common = opts.lyapunov == "common"
    lyap = {t: [prog.var(name) for name in _lyapunov_names(opts, nv, t)] for t in range(1, horizon + 1)}
    p = fd.Q1h.shape[0]
    cost_delta = delta_congruence(fd.n, p + fd.m, fd.dt, math.sqrt(fd.dt))
    signs = _signs(opts, fd.m)
    for t in range(1, horizon + 1):
        g_var = lyap[t][0] if common else prog.var(step_name("G", t))
        y_var = prog.var(step_name("Y", t))
        z_var = prog.var(step_name("Z", t)) if opts.saturation == "auxiliary" else None

        def top(i: int, t: int = t, g_var: AffineMatrix = g_var) -> AffineMatrix:
            return lyap[t][0] if common else g_var + g_var.T - lyap[t][i]

        nxt = lyap[min(t + 1, horizon)]
        for k, sign in enumerate(signs):
            tag = "" if sign is None else f"_s{k}"
            if sign is None:
                ys = y_var
            else:
                assert z_var is not None
                ys = y_var.lmul(np.diag(sign)) + z_var.lmul(np.diag(1.0 - sign))
            wanted = [(i, j) for i, j in pairs(opts, nv) if prog.wants(f"cost_{i}_{j}{tag}_t{t}")]
            rows, diag = _cost_rows(prog, fd, [g_var], [ys]) if wanted else ([], [])
            for i, j in wanted:
                image = g_var.lmul(fd.A[i]) + ys.lmul(fd.B[i])
                block = _cost_block(prog, top(i), image, nxt[0 if common else j], rows, diag)
                prog.add(f"cost_{i}_{j}{tag}_t{t}", block, congruence=cost_delta)
            for i in range(nv):
                _output(prog, fd, g_var.lmul(fd.A[i]) + ys.lmul(fd.B[i]), top(i), f"{i}{tag}_t{t}")
        bounded = z_var if z_var is not None else y_var
        for j in range(len(lyap[t])):
            _input(prog, fd, bounded, top(j), f"{j}_t{t}")
    for j, q in enumerate(lyap[1]):
        _state(prog, fd, q, f"state_{j}")
    return prog


def _write_two_steps(prog: Program, fd: FormData) -> Program:
    """Li et al.'s two steps: ``X1_v = A_v X + B_v Y``, ``X2_vw = A_w X1_v + B_w Y_v``; for every
    pair ``(v, w)`` the cost block ``[[X, X2_vw', (Q1^(1/2) X)', (R^(1/2) Y)', (Q1^(1/2) X1_v)',
    (R^(1/2) Y_v)'], [X2_vw, X, 0, ...], [..., gamma I, ...], ...] >= 0``; ``x`` in ``X``; ``Y`` and
    every ``Y_v`` inside the input bound; ``C X1_v`` and ``C X2_vw`` inside the output bound."""
    nv = fd.n_vertices
    x_var, y_var = prog.var("Q"), prog.var("Y")
    p = fd.Q1h.shape[0]
    cost_delta = delta_congruence(fd.n, 2 * (p + fd.m), fd.dt, math.sqrt(fd.dt))
    for v in range(nv):
        y_v = prog.var(f"Y@v{v}")
        first = x_var.lmul(fd.A[v]) + y_var.lmul(fd.B[v])
        wanted = any(prog.wants(f"cost_{v}_{w}") for w in range(nv))
        rows, diag = _cost_rows(prog, fd, [x_var, first], [y_var, y_v]) if wanted else ([], [])
        for w in range(nv):
            second = first.lmul(fd.A[w]) + y_v.lmul(fd.B[w])
            if prog.wants(f"cost_{v}_{w}"):
                prog.add(f"cost_{v}_{w}", _cost_block(prog, x_var, second, x_var, rows, diag),
                         congruence=cost_delta)
            _output(prog, fd, second, x_var, f"{v}_{w}")
        _output(prog, fd, first, x_var, f"{v}")
        _input(prog, fd, y_v, x_var, f"v{v}")
    _input(prog, fd, y_var, x_var, "0")
    _state(prog, fd, x_var, "state_0")
    return prog
