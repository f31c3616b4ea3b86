"""An independent cvxpy construction of the robust MPC forms (a test helper, not production code).

Written from the statements of the papers and the LMIs of ``docs/rmpc_forms.rst``, with cvxpy
variables built directly from the raw vertex matrices (nothing from :mod:`lmi` or :mod:`rmpc`):

- Kothare, Balakrishnan & Morari, "Robust constrained model predictive control using linear
  matrix inequalities", Automatica 32(10), 1996 (``lyapunov="common"``).
- Cuzzola, Geromel & Morari, "An improved approach for constrained robust model predictive
  control", Automatica 38(7), 2002, and Mao, "Robust stabilization of uncertain time-varying
  discrete systems and comments on 'an improved approach for constrained robust model predictive
  control'", Automatica 39(6), 2003 (``"vertex"``, ``"vertex_pairs"``: one ``Q_j`` per vertex and
  a slack ``G``, the Lyapunov matrix ``Q_j^-1`` and ``F = Y G^-1``).
- Wan & Kothare, "Efficient robust constrained model predictive control with a time varying
  terminal constraint set", Systems & Control Letters 48, 2003 (``cost="nominal"``).
- Cao & Lin, "Min-max MPC algorithm for LPV systems subject to input saturation", IEE
  Proceedings - Control Theory and Applications 152(3), 2005 (``saturation="auxiliary"``).
- Oravec & Bakošová's soft-constrained robust MPC, 2016 (``soft``).

:func:`reference_gamma` returns the status, the bound and the variables, together with every LMI
evaluated at the returned point (``variables["lmis"]``) and the smallest eigenvalue of each,
relative to its norm (``variables["residual"]``, the worst over all LMIs): a test trusts the
reference's gamma only where that residual says Clarabel's answer satisfies its own LMIs.
"""

from __future__ import annotations

import itertools
from typing import Any

import cvxpy as cp
import numpy as np
import scipy.optimize


def _psd_sqrt(M: np.ndarray) -> np.ndarray:
    w, V = np.linalg.eigh((M + M.T) / 2)
    return (V * np.sqrt(np.clip(w, 0.0, None))) @ V.T


def _symmetrised(M: Any) -> np.ndarray:
    M = np.asarray(M, float)
    return (M + M.T) / 2


def _r(expr: Any, shape: tuple[int, int]) -> Any:
    return cp.reshape(expr, shape, order="C")


def _sym(M: Any) -> Any:
    """Symmetric part of a block expression that is symmetric by construction (for cvxpy)."""
    return (M + M.T) / 2


def relative_min_eig(M: np.ndarray) -> float:
    """Smallest eigenvalue of the symmetric part of ``M`` over ``max(1, ||M||_2)``."""
    S = (M + M.T) / 2
    return float(np.linalg.eigvalsh(S)[0] / max(1.0, np.linalg.norm(S, 2)))


def reference_gamma(
    A_list: list[np.ndarray],
    B_list: list[np.ndarray],
    Q1: np.ndarray,
    R: np.ndarray,
    x: np.ndarray,
    *,
    u_max: float | np.ndarray,
    input_constraint: str = "peak",
    lyapunov: str = "common",
    cost: str = "worst_case",
    nominal: tuple[np.ndarray, np.ndarray] | None = None,
    free_moves: int = 0,
    saturation: str | None = None,
    soft: dict[str, float] | None = None,
    disturbance: tuple | None = None,
    output_matrix: np.ndarray | None = None,
    y_max: float | np.ndarray | None = None,
    solver: str = "CLARABEL",
    solver_options: dict[str, Any] | None = None,
    level: float | None = None,
    at: dict[str, Any] | None = None,
) -> tuple[str, float, dict[str, Any]]:
    """Solve one robust MPC form in cvxpy from raw matrices.

    Parameters
    ----------
    A_list, B_list : list of ndarray
        The vertices ``(A_i, B_i)``.
    Q1, R : ndarray
        State and input weights.
    x : ndarray
        The measured state.
    u_max : float or ndarray
        Input bound (per input for ``"peak"``).
    input_constraint : {"peak", "ellipsoid"}
    lyapunov : {"common", "vertex", "vertex_pairs"}
    cost : {"worst_case", "nominal"}
    nominal : (A0, B0), optional
        The nominal model (needed with ``cost="nominal"``).
    free_moves : {0, 1}
    saturation : {None, "auxiliary"}
    soft : dict, optional
        ``{"u": w_u, "y": w_y}`` (either key may be absent).
    disturbance : tuple, optional
        ``(E, w_max)`` or ``(E, w_max, lam)``; without ``lam`` the contraction factor is searched
        (bounded scalar minimisation of gamma over ``(0, 1)``).
    output_matrix, y_max : ndarray, optional
        Output bound ``|c_r x(k+1)| <= y_max,r``.
    solver : str
        A cvxpy solver name.
    solver_options : dict, optional
        Passed to ``problem.solve``.
    level : float, optional
        Instead of minimising the objective, keep it ``<= level`` and maximise the smallest
        eigenvalue ``margin`` of every LMI (used by :func:`reference_upper`).
    at : dict, optional
        Do not solve: evaluate every LMI at these values (``gamma`` (the whole bound), ``Y``,
        ``Q`` or ``G`` and ``Q_vertices``, ``Z``, ``u0``, ``slack``) and return status
        ``"evaluated"`` with ``lmis``, ``residual`` and ``abs_min_eig``.

    Returns
    -------
    status : str
        cvxpy's status.
    gamma : float
        The bound on the cost (``s0 + gamma`` with a free move), ``nan`` when not solved.
    variables : dict
        ``F``, ``Y``, ``G``, ``Q`` (list of ``Q_j``), ``Z``, ``H``, ``u0``, ``slack``, ``lam``,
        ``objective``, ``lmis`` (each LMI at the solution), ``residual`` (the worst relative
        smallest eigenvalue over them), ``abs_min_eig`` (the worst absolute one) and ``margin``
        (with ``level``).
    """
    if disturbance is not None and len(disturbance) == 2 and float(disturbance[1]) > 0.0 and at is None:
        E, w_max = disturbance

        def at(lam: float) -> tuple[str, float, dict[str, Any]]:
            return reference_gamma(
                A_list, B_list, Q1, R, x, u_max=u_max, input_constraint=input_constraint,
                lyapunov=lyapunov, cost=cost, nominal=nominal, free_moves=free_moves,
                saturation=saturation, soft=soft, disturbance=(E, w_max, lam),
                output_matrix=output_matrix, y_max=y_max, solver=solver, solver_options=solver_options,
            )

        def objective(lam: float) -> float:
            status, _, var = at(lam)
            return var["objective"] if status == "optimal" else 1e12

        # a coarse grid first (gamma(lam) is not known to be unimodal), then a local refinement
        grid = np.linspace(0.02, 0.98, 25)
        values = [objective(lam) for lam in grid]
        k = int(np.argmin(values))
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        res = scipy.optimize.minimize_scalar(objective, bounds=(lo, hi), method="bounded",
                                             options={"xatol": 1e-5})
        best = float(res.x) if res.fun <= values[k] else float(grid[k])
        return at(best)

    A_list = [np.atleast_2d(np.asarray(a, float)) for a in A_list]
    B_list = [np.asarray(b, float).reshape(A_list[0].shape[0], -1) for b in B_list]
    n, m = B_list[0].shape
    N = len(A_list)
    x = np.asarray(x, float).reshape(n)
    Q1h = _psd_sqrt(np.atleast_2d(np.asarray(Q1, float)))
    Rh = _psd_sqrt(np.atleast_2d(np.asarray(R, float)))
    umax = np.broadcast_to(np.asarray(u_max, float), (m,)).copy()
    soft = dict(soft or {})

    gamma = cp.Variable(name="gamma")
    Y = cp.Variable((m, n), name="Y")
    if lyapunov == "common":
        Qc = cp.Variable((n, n), symmetric=True, name="Q")
        G = Qc
        Qs = [Qc]
        T = [Qc] * N
        pairs = [(i, 0) for i in range(N)]
    else:
        G = cp.Variable((n, n), name="G")
        Qs = [cp.Variable((n, n), symmetric=True, name=f"Q{j}") for j in range(N)]
        T = [G + G.T - Qj for Qj in Qs]
        if lyapunov == "vertex":
            pairs = [(i, i) for i in range(N)]
        elif lyapunov == "vertex_pairs":
            pairs = [(i, j) for i in range(N) for j in range(N)]
        else:
            raise ValueError(lyapunov)

    Z = None
    if saturation == "auxiliary":
        Z = cp.Variable((m, n), name="Z")
        Ys = []
        for bits in itertools.product((0.0, 1.0), repeat=m):
            D = np.diag(bits)
            Ys.append(D @ Y + (np.eye(m) - D) @ Z)
    elif saturation is None:
        Ys = [Y]
    else:
        raise ValueError(saturation)

    s_u = cp.Variable(nonneg=True, name="s_u") if "u" in soft else None
    s_y = cp.Variable(nonneg=True, name="s_y") if "y" in soft else None

    lmis: list[Any] = []

    def cost_lmi(A: np.ndarray, B: np.ndarray, Ti: Any, Qj: Any, Yk: Any) -> Any:
        AGBY = A @ G + B @ Yk
        return cp.bmat([
            [Ti, AGBY.T, G.T @ Q1h, Yk.T @ Rh],
            [AGBY, Qj, np.zeros((n, n)), np.zeros((n, m))],
            [Q1h @ G, np.zeros((n, n)), gamma * np.eye(n), np.zeros((n, m))],
            [Rh @ Yk, np.zeros((m, n)), np.zeros((m, n)), gamma * np.eye(m)],
        ])

    if cost == "worst_case":
        for i, j in pairs:
            for Yk in Ys:
                lmis.append(cost_lmi(A_list[i], B_list[i], T[i], Qs[j], Yk))
    elif cost == "nominal":
        if lyapunov != "common" or nominal is None:
            raise ValueError("nominal cost needs the common form and a nominal model")
        A0, B0 = (np.asarray(nominal[0], float), np.asarray(nominal[1], float).reshape(n, m))
        for Yk in Ys:
            lmis.append(cost_lmi(A0, B0, T[0], Qs[0], Yk))
            for i in range(N):
                AQBY = A_list[i] @ G + B_list[i] @ Yk
                lmis.append(cp.bmat([[Qs[0], AQBY.T], [AQBY, Qs[0]]]))
    else:
        raise ValueError(cost)

    objective = gamma
    u0 = None
    if free_moves == 0:
        for Qj in Qs:
            lmis.append(cp.bmat([[np.ones((1, 1)), x[None, :]], [x[:, None], Qj]]))
    elif free_moves == 1:
        u0 = cp.Variable(m, name="u0")
        s0 = cp.Variable(name="s0")
        lmis.append(cp.bmat([
            [_r(s0 - float(x @ Q1 @ x), (1, 1)), _r(Rh @ u0, (1, m))],
            [_r(Rh @ u0, (m, 1)), np.eye(m)],
        ]))
        objective = objective + s0
        for i, j in pairs:
            xp = _r(A_list[i] @ x + B_list[i] @ u0, (n, 1))
            lmis.append(cp.bmat([[np.ones((1, 1)), xp.T], [xp, Qs[j]]]))
        # the bound on u0
        if input_constraint == "ellipsoid":
            top = float(umax[0] ** 2) + (s_u if s_u is not None else 0.0)
            lmis.append(cp.bmat([[_r(top, (1, 1)), _r(u0, (1, m))],
                                 [_r(u0, (m, 1)), np.eye(m)]]))
        else:
            for k in range(m):
                top = float(umax[k] ** 2) + (s_u if s_u is not None else 0.0)
                lmis.append(cp.bmat([[_r(top, (1, 1)), _r(u0[k], (1, 1))],
                                     [_r(u0[k], (1, 1)), np.ones((1, 1))]]))
    else:
        raise ValueError(free_moves)

    # the bounds on the feedback law's input (Z with saturation), for every Lyapunov matrix
    Yb = Z if Z is not None else Y
    for Tj in T[: len(Qs)]:
        if input_constraint == "ellipsoid":
            top = float(umax[0] ** 2) * np.eye(m) + (s_u * np.eye(m) if s_u is not None else 0.0)
            lmis.append(cp.bmat([[top, Yb], [Yb.T, Tj]]))
        elif input_constraint == "peak":
            for k in range(m):
                top = float(umax[k] ** 2) + (s_u if s_u is not None else 0.0)
                yl = _r(Yb[k, :], (1, n))
                lmis.append(cp.bmat([[_r(top, (1, 1)), yl], [yl.T, Tj]]))
        else:
            raise ValueError(input_constraint)

    E = w_max = lam = None
    if disturbance is not None:
        E = np.asarray(disturbance[0], float).reshape(n, -1)
        w_max = float(disturbance[1])
        lam = float(disturbance[2]) if len(disturbance) > 2 else 1.0
        if at is not None and at.get("lam") is not None:
            lam = float(at["lam"])

    if output_matrix is not None:
        C = np.atleast_2d(np.asarray(output_matrix, float))
        p = C.shape[0]
        ymax = np.broadcast_to(np.asarray(y_max, float), (p,)).copy()
        if E is not None and w_max:
            ymax = ymax - np.linalg.norm(C @ E, axis=1) * w_max
        for r in range(p):
            top = float(ymax[r] ** 2) + (s_y if s_y is not None else 0.0)
            for i in range(N):
                for Yk in Ys:
                    row = _r(C[r] @ (A_list[i] @ G + B_list[i] @ Yk), (1, n))
                    lmis.append(cp.bmat([[_r(top, (1, 1)), row], [row.T, T[i]]]))
                if free_moves == 1:
                    yp = _r(C[r] @ (A_list[i] @ x + B_list[i] @ u0), (1, 1))
                    lmis.append(cp.bmat([[_r(top, (1, 1)), yp], [yp, np.ones((1, 1))]]))

    if E is not None and w_max > 0.0:
        q = E.shape[1]
        inv_pairs = pairs if cost == "worst_case" else [(i, 0) for i in range(N)]
        for i, j in inv_pairs:
            for Yk in Ys:
                AGBY = A_list[i] @ G + B_list[i] @ Yk
                lmis.append(cp.bmat([
                    [lam * T[i], np.zeros((n, q)), AGBY.T],
                    [np.zeros((q, n)), (1.0 - lam) * np.eye(q), w_max * E.T],
                    [AGBY, w_max * E, Qs[j]],
                ]))

    if s_u is not None:
        objective = objective + float(soft["u"]) * s_u
    if s_y is not None:
        objective = objective + float(soft["y"]) * s_y

    if at is not None:
        # evaluate every LMI at given values (a numpy check of another solver's answer)
        gamma.value = float(at["gamma"])
        Y.value = np.asarray(at["Y"], float).reshape(m, n)
        if lyapunov == "common":
            Qs[0].value = _symmetrised(at["Q"])
        else:
            G.value = np.asarray(at["G"], float)
            for Qj, val in zip(Qs, at["Q_vertices"], strict=True):
                Qj.value = _symmetrised(val)
        if Z is not None:
            Z.value = np.asarray(at["Z"], float).reshape(m, n)
        if u0 is not None:
            u0.value = np.asarray(at["u0"], float).reshape(m)
            s0.value = float(x @ Q1 @ x + u0.value @ R @ u0.value)
            gamma.value = float(at["gamma"]) - float(s0.value)
        for key, var in (("u", s_u), ("y", s_y)):
            if var is not None:
                var.value = max(0.0, float(at["slack"][key]))
        values = [np.asarray(M.value) for M in lmis]
        return "evaluated", float(at["gamma"]), {
            "lmis": values, "residual": min(relative_min_eig(M) for M in values),
            "abs_min_eig": min(float(np.linalg.eigvalsh((M + M.T) / 2)[0]) for M in values),
        }

    margin = None
    if level is None:
        problem = cp.Problem(cp.Minimize(objective), [_sym(M) >> 0 for M in lmis])
    else:
        margin = cp.Variable(name="margin")
        problem = cp.Problem(
            cp.Maximize(margin),
            [_sym(M) - margin * np.eye(M.shape[0]) >> 0 for M in lmis] + [objective <= level, margin <= 1.0],
        )
    try:
        problem.solve(solver=solver, **(solver_options or {}))
        status = problem.status
    except cp.error.SolverError as exc:  # pragma: no cover - reported, not raised
        status = f"solver_error: {exc}"
    if status not in ("optimal", "optimal_inaccurate"):
        return status, float("nan"), {"objective": float("nan"), "residual": -np.inf}

    Gv = np.asarray(G.value)
    F = np.asarray(Y.value) @ np.linalg.inv(Gv)
    values = [np.asarray(M.value) for M in lmis]
    total = float(gamma.value) + (float(s0.value) if free_moves == 1 else 0.0)
    variables = {
        "F": F,
        "Y": np.asarray(Y.value),
        "G": Gv,
        "Q": [np.asarray(Qj.value) for Qj in Qs],
        "Z": None if Z is None else np.asarray(Z.value),
        "H": None if Z is None else np.asarray(Z.value) @ np.linalg.inv(Gv),
        "u0": None if u0 is None else np.asarray(u0.value),
        "gamma_feedback": float(gamma.value),
        "slack": {k: float(v.value) for k, v in (("u", s_u), ("y", s_y)) if v is not None},
        "lam": lam,
        "objective": float(objective.value),
        "margin": None if margin is None else float(margin.value),
        "abs_min_eig": min(float(np.linalg.eigvalsh((M + M.T) / 2)[0]) for M in values),
        "lmis": values,
        "residual": min(relative_min_eig(M) for M in values),
    }
    return status, total, variables


def reference_upper(*args: Any, rtol: float = 1e-7, max_steps: int = 40, **kwargs: Any) -> float:
    """The smallest level found at which the form has a strictly feasible point, checked in numpy.

    Bisection between Clarabel's minimum (not trusted: its point may violate the LMIs slightly)
    and a level at which the maximal-margin problem returns a point where every LMI has a
    positive smallest eigenvalue and the objective is below the level: the optimum is ``<=`` the
    returned value whatever the solver's accuracy. Arguments as :func:`reference_gamma` (with
    ``lam`` given for a disturbance).
    """
    status, g0, _ = reference_gamma(*args, **kwargs)
    if not np.isfinite(g0):
        raise RuntimeError(f"reference not solved: {status}")

    def certified(level: float) -> bool:
        status, _, var = reference_gamma(*args, level=level, **kwargs)
        ok = status in ("optimal", "optimal_inaccurate")
        return ok and var["abs_min_eig"] > 0.0 and var["objective"] <= level

    lo, hi = g0, g0
    for k in range(30):
        if certified(hi):
            break
        lo = hi
        hi = g0 + max(abs(g0), 1e-12) * 1e-6 * 2.0**k
    else:
        raise RuntimeError("no certified level")
    for _ in range(max_steps):
        if hi - lo <= rtol * abs(hi):
            break
        mid = 0.5 * (lo + hi)
        if certified(mid):
            hi = mid
        else:
            lo = mid
    return hi


def solution_values(sol: Any) -> dict[str, Any]:
    """The variables of an :class:`lmi.LMISolution` in the form ``reference_gamma(at=...)`` takes."""
    G = sol.G if sol.G is not None else sol.Q
    return {
        "gamma": sol.gamma, "Y": sol.Y, "Q": sol.Q, "G": sol.G, "Q_vertices": sol.Q_vertices,
        "Z": None if sol.H is None else sol.H @ G, "u0": sol.u0, "slack": sol.slack, "lam": sol.lam,
        "gamma_s": getattr(sol, "gamma_s", None),
    }


def realised_cost(
    A_seq: list[np.ndarray], B_seq: list[np.ndarray], Q1: np.ndarray, R: np.ndarray, x0: np.ndarray,
    law: Any,
) -> tuple[float, float, np.ndarray]:
    """Closed-loop cost ``sum x' Q1 x + u' R u`` along a given plant sequence, the largest ``|u|``
    (componentwise) and the final state; ``law(x, k)`` returns the input."""
    x = np.asarray(x0, float)
    total = 0.0
    u_peak = 0.0
    for k, (A, B) in enumerate(zip(A_seq, B_seq, strict=True)):
        u = np.atleast_1d(law(x, k))
        total += float(x @ Q1 @ x + u @ R @ u)
        u_peak = max(u_peak, float(np.max(np.abs(u))))
        x = A @ x + B @ u
    return total, u_peak, x



# -- the forms with steps, from MUP's sdp_li.m / sdp_shi.m (Oravec & Bakosova's toolbox) -----------

def reference_steps(
    A_list: list[np.ndarray],
    B_list: list[np.ndarray],
    Q1: np.ndarray,
    R: np.ndarray,
    x: np.ndarray,
    *,
    u_max: float | np.ndarray,
    method: str,
    horizon: int = 2,
    lyapunov: str = "vertex_pairs",
    saturation: str | None = None,
    output_matrix: np.ndarray | None = None,
    y_max: float | np.ndarray | None = None,
    at: dict[str, Any] | None = None,
) -> tuple[str, float, dict[str, Any]]:
    """Li et al.'s two-step form (``method="li"``) or Shi et al.'s N steps (``"shi"``) in cvxpy,
    written after MUP's ``sdp_li.m`` and ``sdp_shi.m`` with MUP's own variables, with the changes
    the docs' page states: the objective ``gamma`` alone (MUP adds ``trace(X)``), per-component
    peak input bounds, output bounds ``|c_r x|`` at every step and every vertex (pair), and for
    Shi the last step's ellipsoid as the terminal one (``Q_(N+1) = Q_N``).

    MUP's variables: Li: ``X``, ``Y``, ``Yp[v]``; Shi: per step ``X[t]`` (not symmetric),
    ``Y[t]``, ``Z[t]`` (the law's inputs ``Y - E_j Z`` over the diagonal 0/1 matrices ``E_j``, the
    bound on ``Y - Z``) and ``Q[t][v]`` (a list of one matrix with ``lyapunov="common"``, where
    ``X[t] = Q[t][0]`` is symmetric). ``at`` evaluates every LMI at given values of these names
    (and ``gamma``) instead of solving. Returns as :func:`reference_gamma`.
    """
    A_list = [np.atleast_2d(np.asarray(a, float)) for a in A_list]
    B_list = [np.asarray(b, float).reshape(A_list[0].shape[0], -1) for b in B_list]
    n, m = B_list[0].shape
    nv = len(A_list)
    x = np.asarray(x, float).reshape(n)
    Wx = _psd_sqrt(np.atleast_2d(np.asarray(Q1, float)))
    Wu = _psd_sqrt(np.atleast_2d(np.asarray(R, float)))
    umax = np.broadcast_to(np.asarray(u_max, float), (m,)).copy()
    C = None if output_matrix is None else np.atleast_2d(np.asarray(output_matrix, float))
    ymax = None if C is None else np.broadcast_to(np.asarray(y_max, float), (C.shape[0],)).copy()
    Zx, Zxu, Zux = np.zeros((n, n)), np.zeros((n, m)), np.zeros((m, n))
    g = cp.Variable(name="gamma")
    lmis: list[Any] = []
    named: dict[str, Any] = {"gamma": g}

    def peak(gain: Any, t_mat: Any) -> None:
        for k in range(m):
            row = _r(gain[k, :], (1, n))
            lmis.append(cp.bmat([[np.full((1, 1), umax[k] ** 2), row], [row.T, t_mat]]))

    def outputs(image: Any, t_mat: Any) -> None:
        if C is None:
            return
        for r in range(C.shape[0]):
            row = _r(C[r] @ image, (1, n))
            lmis.append(cp.bmat([[np.full((1, 1), ymax[r] ** 2), row], [row.T, t_mat]]))

    if method == "li":
        X = cp.Variable((n, n), symmetric=True, name="X")
        Y = cp.Variable((m, n), name="Y")
        Yp = [cp.Variable((m, n), name=f"Yp{v}") for v in range(nv)]
        named.update({"X": X, "Y": Y, **{f"Yp{v}": Yp[v] for v in range(nv)}})
        for v in range(nv):
            x1 = A_list[v] @ X + B_list[v] @ Y
            for vp in range(nv):
                x2 = A_list[vp] @ x1 + B_list[vp] @ Yp[v]
                lmis.append(cp.bmat([
                    [X, x2.T, (Wx @ X).T, (Wu @ Y).T, (Wx @ x1).T, (Wu @ Yp[v]).T],
                    [x2, X, Zx, Zxu, Zx, Zxu],
                    [Wx @ X, Zx, g * np.eye(n), Zxu, Zx, Zxu],
                    [Wu @ Y, Zux, Zux, g * np.eye(m), Zux, np.zeros((m, m))],
                    [Wx @ x1, Zx, Zx, Zxu, g * np.eye(n), Zxu],
                    [Wu @ Yp[v], Zux, Zux, np.zeros((m, m)), Zux, g * np.eye(m)],
                ]))
                outputs(x2, X)
            outputs(x1, X)
            peak(Yp[v], X)
        peak(Y, X)
        lmis.append(cp.bmat([[np.ones((1, 1)), x[None, :]], [x[:, None], X]]))
    elif method == "shi":
        common = lyapunov == "common"
        nq = 1 if common else nv
        if lyapunov == "vertex_pairs" or common:
            pairs = [(v, vp) for v in range(nv) for vp in range(nv)]
        else:
            pairs = [(v, v) for v in range(nv)]
        Q = [[cp.Variable((n, n), symmetric=True, name=f"Q{t}_{v}") for v in range(nq)]
             for t in range(horizon)]
        X = [Q[t][0] if common else cp.Variable((n, n), name=f"X{t}") for t in range(horizon)]
        Y = [cp.Variable((m, n), name=f"Y{t}") for t in range(horizon)]
        # without saturation the law is Y itself and the bound is on Y: Z = 0, E = {0}
        aux = saturation == "auxiliary"
        Z = [cp.Variable((m, n), name=f"Z{t}") if aux else np.zeros((m, n)) for t in range(horizon)]
        for t in range(horizon):
            named.update({f"Y{t}": Y[t], **{f"Q{t}_{v}": Q[t][v] for v in range(nq)}})
            if aux:
                named[f"Z{t}"] = Z[t]
            if not common:
                named[f"X{t}"] = X[t]
        E = [np.diag(bits) for bits in itertools.product((0.0, 1.0), repeat=m)] if aux else [np.zeros((m, m))]

        def top(t: int, v: int) -> Any:
            return Q[t][0] if common else X[t] + X[t].T - Q[t][v]

        for t in range(horizon):
            nxt = Q[min(t + 1, horizon - 1)]  # the terminal ellipsoid: Q_(N+1) = Q_N
            for Ej in E:
                law = Y[t] - Ej @ Z[t]
                for v, vp in pairs:
                    image = A_list[v] @ X[t] + B_list[v] @ law
                    lmis.append(cp.bmat([
                        [top(t, v), image.T, (Wx @ X[t]).T, (Wu @ law).T],
                        [image, nxt[0 if common else vp], Zx, Zxu],
                        [Wx @ X[t], Zx, g * np.eye(n), Zxu],
                        [Wu @ law, Zux, Zux, g * np.eye(m)],
                    ]))
                for v in range(nv):
                    outputs(A_list[v] @ X[t] + B_list[v] @ law, top(t, v))
            for v in range(nq):
                peak(Y[t] - Z[t], top(t, v))
        for v in range(nq):
            lmis.append(cp.bmat([[np.ones((1, 1)), x[None, :]], [x[:, None], Q[0][v]]]))
    else:
        raise ValueError(method)

    if at is not None:
        for name, var in named.items():
            val = np.asarray(at[name], float).reshape(var.shape)
            var.value = _symmetrised(val) if var.is_symmetric() else val
        values = [np.asarray(M.value, float) for M in lmis]
        return "evaluated", float(at["gamma"]), {
            "lmis": values, "residual": min(relative_min_eig(M) for M in values),
        }
    problem = cp.Problem(cp.Minimize(g), [_sym(M) >> 0 for M in lmis])
    try:
        problem.solve(solver="CLARABEL")
    except cp.error.SolverError as exc:  # Clarabel fails on Kothare's example 2: reported
        return f"solver_error: {exc}", float("nan"), {"residual": -np.inf}
    if problem.status not in ("optimal", "optimal_inaccurate"):
        return problem.status, float("nan"), {"residual": -np.inf}
    values = [np.asarray(M.value, float) for M in lmis]
    return problem.status, float(g.value), {
        "residual": min(relative_min_eig(M) for M in values),
        **{name: np.asarray(var.value) for name, var in named.items()},
    }


def steps_values(sol: Any, method: str, horizon: int, n_vertices: int) -> dict[str, Any]:
    """The variables of an :class:`lmi.LMISolution` of a form with steps in MUP's names
    (:func:`reference_steps`'s ``at``): Shi's ``Z`` is ``Y - H G`` (MUP bounds ``Y - Z``)."""
    out: dict[str, Any] = {"gamma": sol.gamma}
    if method == "li":
        out.update({"X": sol.Q, "Y": sol.Y})
        out.update({f"Yp{v}": sol.steps[f"Y@v{v}"] for v in range(n_vertices)})
        return out
    vertex = sol.G is not None

    def var(name: str, t: int) -> np.ndarray:
        return sol.steps[f"{name}@{t + 1}"] if t else {"G": sol.G, "Y": sol.Y}[name]

    for t in range(horizon):
        g_mat = var("G", t) if vertex else (sol.steps[f"Q@{t + 1}"] if t else sol.Q)
        y_mat = var("Y", t)
        out[f"Y{t}"] = y_mat
        if sol.H is not None:
            out[f"Z{t}"] = y_mat - (sol.H @ g_mat if t == 0 else sol.steps[f"Z@{t + 1}"])
        if vertex:
            out[f"X{t}"] = g_mat
            for v in range(n_vertices):
                out[f"Q{t}_{v}"] = sol.Q_vertices[v] if t == 0 else sol.steps[f"Q{v}@{t + 1}"]
        else:
            out[f"Q{t}_0"] = g_mat
    return out


def mup_reference(
    A_list: list[np.ndarray],
    B_list: list[np.ndarray],
    Q1: np.ndarray,
    R: np.ndarray,
    x: np.ndarray,
    *,
    u_max: float | np.ndarray,
    nominal: tuple[np.ndarray, np.ndarray] | None = None,
    lyapunov: str = "common",
    cost: str = "worst_case",
    saturation: str | None = None,
    output_matrix: np.ndarray | None = None,
    y_max: float | np.ndarray | None = None,
    soft_u: tuple[list[float], list[float] | None] | None = None,
    soft_y: tuple[list[float], list[float] | None] | None = None,
    at: dict[str, Any] | None = None,
    level: float | None = None,
    solver: str = "CLARABEL",
) -> tuple[str, float, dict[str, Any]]:
    """Ding et al.'s nominal cost with vertex Lyapunov matrices and Oravec & Bakošová's soft
    constraints per component, in cvxpy from raw matrices (peak input bounds, no free move, no
    disturbance).

    Written from MUP's ``sdp_ding.m`` and ``sdp_*_soft_con.m`` (Ding, Xi, Cychowski & O'Mahony,
    "Improving off-line approach to robust MPC based-on nominal performance cost", Automatica 43,
    2007; Oravec & Bakošová's soft-constrained robust MPC, 2016), with the bounds per component
    as ``docs/rmpc_forms.rst`` states them (MUP's joint ``diag(u^2)`` blocks are the same for one
    input; per component here for the outputs):

    - ``cost="nominal"`` with ``lyapunov="vertex_pairs"``: for every pair ``(v, w)`` the nominal
      cost block with ``X + X' - Q_v`` and ``Q_w`` and the invariance block of vertex ``v``
      ``[[X + X' - Q_v, (A_v X + B_v Y)'], [., Q_w]]``; ``"vertex"``: the pairs ``(v, v)``;
      ``"common"``: Wan & Kothare's ``X = Q``;
    - the state in every ``Q_v``; the hard bounds ``|u_l| <= u_max,l`` (on ``Z`` with the auxiliary
      saturation) and ``|c_r x(k+1)| <= y_max,r`` for every ``T_v`` / vertex;
    - ``soft_u = (weights, limits)``: one slack ``s_k >= 0`` per component with weight ``> 0``;
      ``limits`` ``None``: the hard bound of that component becomes ``u_max,k^2 + s_k``; else an
      extra ``[[l_k^2 + s_k, y_k], [y_k', T_v]] >= 0`` on the law's own ``Y`` (as
      ``sdp_cao_soft_con.m``); ``soft_y`` the same on the outputs (for every ``D_s`` with the
      saturation); the objective ``gamma + sum w_k s_k``.

    ``at``: evaluate every LMI at ``gamma, Y, Q or G and Q_vertices, Z, slack`` (``sol.slack``'s
    keys ``"u0"``, ``"y1"``) instead of solving; ``level``: keep the objective ``<= level`` and
    maximise the smallest eigenvalue of every LMI (``abs_min_eig`` then says whether the point is
    strictly feasible, :func:`mup_reference_upper`). Returns as :func:`reference_gamma`.
    """
    A_list = [np.asarray(a, float) for a in A_list]
    n = A_list[0].shape[0]
    B_list = [np.asarray(b, float).reshape(n, -1) for b in B_list]
    m, N = B_list[0].shape[1], len(A_list)
    x = np.asarray(x, float).reshape(n)
    Q1h, Rh = _psd_sqrt(np.atleast_2d(Q1)), _psd_sqrt(np.atleast_2d(R))
    umax = np.broadcast_to(np.asarray(u_max, float), (m,))
    gamma, Y = cp.Variable(name="gamma"), cp.Variable((m, n), name="Y")
    if lyapunov == "common":
        G = cp.Variable((n, n), symmetric=True, name="Q")
        Qs, T, pairs = [G], [G] * N, [(i, 0) for i in range(N)]
    else:
        G = cp.Variable((n, n), name="G")
        Qs = [cp.Variable((n, n), symmetric=True, name=f"Q{j}") for j in range(N)]
        T = [G + G.T - Qv for Qv in Qs]
        every = list(itertools.product(range(N), repeat=2))
        pairs = [(v, v) for v in range(N)] if lyapunov == "vertex" else every
    Z = cp.Variable((m, n), name="Z") if saturation == "auxiliary" else None
    Ys = [Y] if Z is None else [np.diag(b) @ Y + np.diag(1.0 - np.array(b)) @ Z
                                for b in itertools.product((1.0, 0.0), repeat=m)]
    slacks: dict[str, Any] = {}
    for fam, spec in (("u", soft_u), ("y", soft_y)):
        if spec is not None:
            for k, w in enumerate(spec[0]):
                if w > 0.0:
                    slacks[f"{fam}{k}"] = cp.Variable(nonneg=True, name=f"s_{fam}{k}")

    def square(bound: float, key: str, limit: bool) -> Any:
        fam = key[0]
        spec = soft_u if fam == "u" else soft_y
        softened = key in slacks and spec is not None and (spec[1] is not None) == limit
        return _r(bound**2 + (slacks[key] if softened else 0.0), (1, 1))

    lmis: list[Any] = []

    def cost_lmi(A: np.ndarray, B: np.ndarray, Tv: Any, Qw: Any, Yk: Any) -> Any:
        M = A @ G + B @ Yk
        return cp.bmat([
            [Tv, M.T, G.T @ Q1h, Yk.T @ Rh],
            [M, Qw, np.zeros((n, n)), np.zeros((n, m))],
            [Q1h @ G, np.zeros((n, n)), gamma * np.eye(n), np.zeros((n, m))],
            [Rh @ Yk, np.zeros((m, n)), np.zeros((m, n)), gamma * np.eye(m)],
        ])

    for Yk in Ys:
        if cost == "worst_case":
            lmis += [cost_lmi(A_list[v], B_list[v], T[v], Qs[w], Yk) for v, w in pairs]
        else:
            A0, B0 = np.asarray(nominal[0], float), np.asarray(nominal[1], float).reshape(n, m)
            if lyapunov == "common":
                lmis.append(cost_lmi(A0, B0, G, G, Yk))
            else:
                lmis += [cost_lmi(A0, B0, T[v], Qs[w], Yk) for v, w in pairs]
            for v, w in pairs:
                M = A_list[v] @ G + B_list[v] @ Yk
                lmis.append(cp.bmat([[T[v], M.T], [M, Qs[w]]]))
    for Qv in Qs:
        lmis.append(cp.bmat([[np.ones((1, 1)), x[None, :]], [x[:, None], Qv]]))
    Yb = Y if Z is None else Z
    for v in range(len(Qs)):
        for k in range(m):
            lmis.append(cp.bmat([[square(umax[k], f"u{k}", False), _r(Yb[k, :], (1, n))],
                                 [_r(Yb[k, :], (n, 1)), T[v]]]))
            if soft_u is not None and soft_u[1] is not None and f"u{k}" in slacks:
                lmis.append(cp.bmat([[square(soft_u[1][k], f"u{k}", True), _r(Y[k, :], (1, n))],
                                     [_r(Y[k, :], (n, 1)), T[v]]]))
    if output_matrix is not None:
        C = np.atleast_2d(np.asarray(output_matrix, float))
        ymax = np.broadcast_to(np.asarray(y_max, float), (C.shape[0],))
        for r in range(C.shape[0]):
            for v in range(N):
                for Yk in Ys:
                    row = _r(C[r] @ (A_list[v] @ G + B_list[v] @ Yk), (1, n))
                    lmis.append(cp.bmat([[square(ymax[r], f"y{r}", False), row], [row.T, T[v]]]))
                    if soft_y is not None and soft_y[1] is not None and f"y{r}" in slacks:
                        lmis.append(cp.bmat([[square(soft_y[1][r], f"y{r}", True), row], [row.T, T[v]]]))
    weights = {f"{fam}{k}": w for fam, spec in (("u", soft_u), ("y", soft_y)) if spec is not None
               for k, w in enumerate(spec[0])}
    objective = gamma + sum(weights[key] * var for key, var in slacks.items())

    if at is not None:
        gamma.value = float(at["gamma"])
        Y.value = np.asarray(at["Y"], float).reshape(m, n)
        if lyapunov == "common":
            G.value = _symmetrised(at["Q"])
        else:
            G.value = np.asarray(at["G"], float)
            for Qv, val in zip(Qs, at["Q_vertices"], strict=True):
                Qv.value = _symmetrised(val)
        if Z is not None:
            Z.value = np.asarray(at["Z"], float).reshape(m, n)
        for key, var in slacks.items():
            var.value = max(0.0, float(at["slack"][key]))
        values = [np.asarray(M.value) for M in lmis]
        return "evaluated", float(at["gamma"]), {
            "lmis": values, "residual": min(relative_min_eig(M) for M in values),
            "objective": float(objective.value),
        }
    if level is None:
        problem = cp.Problem(cp.Minimize(objective), [_sym(M) >> 0 for M in lmis])
    else:
        margin = cp.Variable(name="margin")
        problem = cp.Problem(cp.Maximize(margin), [_sym(M) - margin * np.eye(M.shape[0]) >> 0 for M in lmis]
                             + [objective <= level, margin <= 1.0])
    try:
        problem.solve(solver=solver)
        status = problem.status
    except cp.error.SolverError as exc:  # pragma: no cover - reported, not raised
        status = f"solver_error: {exc}"
    if status not in ("optimal", "optimal_inaccurate"):
        return status, float("nan"), {"objective": float("nan"), "residual": -np.inf}
    values = [np.asarray(M.value) for M in lmis]
    return status, float(gamma.value), {
        "abs_min_eig": min(float(np.linalg.eigvalsh((M + M.T) / 2)[0]) for M in values),
        "F": np.asarray(Y.value) @ np.linalg.inv(np.asarray(G.value)),
        "slack": {key: float(var.value) for key, var in slacks.items()},
        "objective": float(objective.value), "lmis": values,
        "residual": min(relative_min_eig(M) for M in values),
    }


def mup_reference_upper(*args: Any, rtol: float = 1e-6, max_steps: int = 40, **kwargs: Any) -> float:
    """The smallest objective level found at which :func:`mup_reference`'s LMIs have a strictly
    feasible point checked in numpy (bisection from Clarabel's minimum, as
    :func:`reference_upper`): the reference's optimum is ``<=`` it whatever Clarabel's accuracy."""
    status, _, var = mup_reference(*args, **kwargs)
    g0 = var["objective"]
    if not np.isfinite(g0):
        raise RuntimeError(f"reference not solved: {status}")

    def certified(level: float) -> bool:
        status, _, var = mup_reference(*args, level=level, **kwargs)
        ok = status in ("optimal", "optimal_inaccurate")
        return ok and var["abs_min_eig"] > 0.0 and var["objective"] <= level

    lo, hi = g0, g0
    for k in range(30):
        if certified(hi):
            break
        lo = hi
        hi = g0 + max(abs(g0), 1e-12) * 1e-6 * 2.0**k
    else:
        raise RuntimeError("no certified level")
    for _ in range(max_steps):
        if hi - lo <= rtol * abs(hi):
            break
        mid = 0.5 * (lo + hi)
        if certified(mid):
            hi = mid
        else:
            lo = mid
    return hi


# -- MUP's saturation methods: huang, wan_huang, mao_huang, zhang, wan_zhang ----------------------
#
# Written from MUP's rmpc_methods/sdp_<key>.m (Oravec & Bakosova's toolbox) and the papers it cites:
# Huang, Li, Lin & Xi, "An improved robust model predictive control design in the presence of
# actuator saturation", Automatica 47, 2011; Zhang, Wang & Li, "Min-max MPC for LPV systems subject
# to actuator saturation by a saturation-dependent Lyapunov function", Chinese Control Conference,
# 2013. MUP's sign patterns: u_var holds the binary numbers 0 .. 2^m - 1 (a column each, the first
# input the most significant bit), E_j = diag(u_var(:, nj + 1 - j)) and Et_j = diag(u_var(:, j)),
# so that j = 1 is the unsaturated pattern (E_1 = I). As in this module's other forms (and unlike
# MUP's code): no trace(X) in the objective, non-strict LMIs, the peak bound one input at a time.
# Zhang's form as docs/rmpc_forms.rst states it (one matrix Q_j per sign pattern, MUP's W_j and
# Q_j being one family there: see the page for why).

SATURATION_METHODS = ("huang", "wan_huang", "mao_huang", "zhang", "wan_zhang")


def _mup_sign_patterns(m: int) -> list[tuple[np.ndarray, np.ndarray]]:
    nj = 2**m
    u_var = np.array([[int(bit) for bit in np.binary_repr(k, m)] for k in range(nj)], float).T
    return [(np.diag(u_var[:, nj - 1 - j]), np.diag(u_var[:, j])) for j in range(nj)]


def reference_saturation(
    A_list: list[np.ndarray], B_list: list[np.ndarray], Q1: np.ndarray, R: np.ndarray, x: np.ndarray, *,
    method: str, u_max: float | np.ndarray, beta: float | None = None,
    nominal: tuple[np.ndarray, np.ndarray] | None = None, output_matrix: np.ndarray | None = None,
    y_max: float | np.ndarray | None = None, at: dict[str, Any] | None = None, solver: str = "CLARABEL",
) -> tuple[str, float, dict[str, Any]]:
    """One of MUP's saturation methods in cvxpy from raw matrices (peak input bound).

    ``at``: do not solve, evaluate every LMI at ``gamma``, ``gamma_s``, ``Y``, ``Z`` and ``Q``
    (common) or ``G`` and ``Q_vertices``; returns ``"evaluated"`` with ``residual`` (the worst
    relative smallest eigenvalue). Otherwise returns cvxpy's status, ``gamma`` and the variables
    with ``objective`` and ``residual`` at Clarabel's point.
    """
    if method not in SATURATION_METHODS:
        raise ValueError(method)
    A_list = [np.atleast_2d(np.asarray(a, float)) for a in A_list]
    B_list = [np.asarray(b, float).reshape(A_list[0].shape[0], -1) for b in B_list]
    n, m = B_list[0].shape
    nv = len(A_list)
    x = np.asarray(x, float).reshape(n, 1)
    Wx, Wu = _psd_sqrt(np.atleast_2d(np.asarray(Q1, float))), _psd_sqrt(np.atleast_2d(np.asarray(R, float)))
    umax = np.broadcast_to(np.asarray(u_max, float), (m,))
    patterns = _mup_sign_patterns(m)
    huang = "huang" in method
    g = cp.Variable(name="g")
    gs = cp.Variable(name="gs") if huang else g
    Y = cp.Variable((m, n), name="Y")
    Z = cp.Variable((m, n), name="Z")
    if method in ("huang", "wan_huang"):
        X = cp.Variable((n, n), symmetric=True, name="X")
        lyap = [X]
    else:  # mao_huang: a Q_v per vertex; zhang, wan_zhang: a Q_j per sign pattern
        X = cp.Variable((n, n), name="X")
        lyap = [cp.Variable((n, n), symmetric=True, name=f"Q{k}")
                for k in range(nv if method == "mao_huang" else len(patterns))]

    def top(k: int) -> Any:
        return X if len(lyap) == 1 else X + X.T - lyap[k]

    def u_of(j: int) -> Any:
        E, Et = patterns[j]
        return E @ Y + Et @ Z

    def conv(A: np.ndarray, B: np.ndarray, t: Any, nxt: Any, j: int, gamma: Any | None) -> Any:
        M = A @ X + B @ u_of(j)
        if gamma is None:  # invariance only
            return cp.bmat([[t, M.T], [M, nxt]])
        return cp.bmat([
            [t, M.T, (Wx @ X).T, (Wu @ u_of(j)).T],
            [M, nxt, np.zeros((n, n)), np.zeros((n, m))],
            [Wx @ X, np.zeros((n, n)), gamma * np.eye(n), np.zeros((n, m))],
            [Wu @ u_of(j), np.zeros((m, n)), np.zeros((m, n)), gamma * np.eye(m)],
        ])

    lmis: list[Any] = []
    bound_g = [g - gs] if huang else []  # MUP's g - gs >= ZERO
    for j in range(len(patterns)):
        gam = gs if j == 0 else g
        if method == "huang":
            lmis += [conv(A_list[v], B_list[v], X, X, j, gam) for v in range(nv)]
        elif method == "mao_huang":
            lmis += [conv(A_list[v], B_list[v], top(v), lyap[vp], j, gam)
                     for v in range(nv) for vp in range(nv)]
        elif method == "zhang":
            lmis += [conv(A_list[v], B_list[v], top(j), lyap[jp], j, gam)
                     for v in range(nv) for jp in range(len(patterns))]
        else:  # the nominal cost, invariance at every vertex
            A0, B0 = np.asarray(nominal[0], float), np.asarray(nominal[1], float).reshape(n, m)
            nexts = range(len(lyap))
            lmis += [conv(A0, B0, top(j if method == "wan_zhang" else 0), lyap[jp], j, gam) for jp in nexts]
            lmis += [conv(A_list[v], B_list[v], top(j if method == "wan_zhang" else 0), lyap[jp], j, None)
                     for v in range(nv) for jp in nexts]
    # the state in every ellipsoid; the auxiliary gain's rows inside every T
    lmis += [cp.bmat([[np.ones((1, 1)), x.T], [x, q]]) for q in lyap]
    for k in range(len(lyap)):
        for ell in range(m):
            z_row = _r(Z[ell, :], (1, n))
            lmis.append(cp.bmat([[np.full((1, 1), umax[ell] ** 2), z_row], [z_row.T, top(k)]]))
    if output_matrix is not None:
        C = np.atleast_2d(np.asarray(output_matrix, float))
        ymax = np.broadcast_to(np.asarray(y_max, float), (C.shape[0],))
        for r in range(C.shape[0]):
            for v in range(nv):
                for j in range(len(patterns)):
                    row = _r(C[r] @ (A_list[v] @ X + B_list[v] @ u_of(j)), (1, n))
                    t = top(j) if method in ("zhang", "wan_zhang") else top(v if method == "mao_huang" else 0)
                    lmis.append(cp.bmat([[np.full((1, 1), ymax[r] ** 2), row], [row.T, t]]))
    objective = g + (float(beta) * gs if huang else 0.0)
    if at is not None:
        g.value = float(at["gamma"])
        if huang:
            gs.value = float(at["gamma_s"])
        Y.value, Z.value = np.asarray(at["Y"], float), np.asarray(at["Z"], float)
        if len(lyap) == 1:
            X.value = _symmetrised(at["Q"])
        else:
            X.value = np.asarray(at["G"], float)
            for q, val in zip(lyap, at["Q_vertices"], strict=True):
                q.value = _symmetrised(val)
        values = [np.asarray(M.value) for M in lmis] + [np.array([[float(b.value)]]) for b in bound_g]
        scale = max(1.0, abs(float(at["gamma"])))
        residual = min([relative_min_eig(M) for M in values[: len(lmis)]]
                       + [float(v[0, 0]) / scale for v in values[len(lmis):]])
        return "evaluated", float(at["gamma"]), {"residual": residual}
    problem = cp.Problem(cp.Minimize(objective), [_sym(M) >> 0 for M in lmis] + [b >= 0 for b in bound_g])
    try:
        problem.solve(solver=solver)
        status = problem.status
    except cp.error.SolverError as exc:  # pragma: no cover - reported, not raised
        status = f"solver_error: {exc}"
    if status not in ("optimal", "optimal_inaccurate"):
        return status, float("nan"), {"objective": float("nan"), "residual": -np.inf}
    values = [np.asarray(M.value) for M in lmis]
    residual = min([relative_min_eig(M) for M in values]
                   + [float(b.value) / max(1.0, abs(float(g.value))) for b in bound_g])
    return status, float(g.value), {
        "gamma_s": float(gs.value), "objective": float(objective.value), "residual": residual,
        "F": np.asarray(Y.value) @ np.linalg.inv(np.asarray(X.value)),
    }
