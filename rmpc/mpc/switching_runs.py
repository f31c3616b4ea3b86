"""Seeded closed-loop runs on a switching polytopic plant, with the bound violations counted.

:func:`switching_runs` runs a controller on ``x(k+1) = A_j(k) x(k) + B_j(k) u(k)``, the vertex
``j(k)`` drawn at every sample from a seeded generator, and counts the samples whose applied
input breaks the input bound or whose next state breaks the state polytope. It is what
``rmpc bench methods`` calls for the ``violations`` of its records and what
``dev/multistage_timing.py`` measures :class:`~rmpc.MultiStageMPC` with; it takes any
controller of the ``step(x)`` protocol.

Examples
--------
>>> import numpy as np
>>> from models import PolytopicModel
>>> from rmpc import LQR
>>> from rmpc.mpc.switching_runs import switching_runs
>>> A = np.array([[1.0, 1.0], [0.0, 1.0]])
>>> plant = PolytopicModel([(A, [[0.5], [1.0]]), (A, [[0.4], [0.8]])], dt=1.0)
>>> out = switching_runs(LQR(plant, np.eye(2), np.eye(1)), plant, [1.0, 0.0], steps=20, runs=3,
...                      seed=0, u_max=0.05)
>>> out["samples"], out["input_violations"] > 0
(60, True)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_optional_limits, as_vector, check_count

__all__ = ["VIOLATION_TOL", "switching_runs"]

#: A bound counts as broken above ``bound + VIOLATION_TOL * max(1, |bound|)`` (round-off only).
VIOLATION_TOL = 1e-9


def _percentile(values: Sequence[float], q: float) -> float | None:
    return float(np.percentile(values, q)) if len(values) else None


def switching_runs(
    ctrl: Any,
    plant: Any,
    x0: ArrayLike,
    *,
    steps: int,
    runs: int,
    seed: int,
    u_max: ArrayLike | None = None,
    state_constraints: tuple[ArrayLike, ArrayLike] | None = None,
    Q: ArrayLike | None = None,
    R: ArrayLike | None = None,
    w_max: ArrayLike | None = None,
    E: ArrayLike | None = None,
) -> dict[str, Any]:
    """Run ``ctrl`` ``runs`` times for ``steps`` samples on seeded switching vertices of ``plant``.

    Parameters
    ----------
    ctrl : Controller
        Any controller of the ``step(x)`` protocol; ``reset()`` before each run.
    plant : PolytopicModel
        The vertices drawn from (uniformly, one per sample).
    x0 : (n,) array_like
        The start state of every run.
    steps, runs : int
        Samples per run and runs.
    seed : int
        Seed of the generator of the vertex sequences (run ``r`` uses the ``r``-th sequence).
    u_max : float or (m,) array_like, optional
        The input bound checked: ``|u_i| <= u_max_i``.
    state_constraints : (H, h) pair, optional
        The state polytope ``H x <= h`` checked at every state after the start.
    Q, R : array_like, optional
        Weights of the closed-loop cost ``sum x'Qx + u'Ru`` (default identities).
    w_max : (q,) array_like, optional
        An additive disturbance ``x+ = A_j x + B_j u + E d`` with ``d`` a vertex of the box
        ``|d_i| <= w_max_i`` drawn at every sample (after the vertex sequence of the run, from the
        same generator); ``None`` (the default) for none.
    E : (n, q) array_like, optional
        How the disturbance enters (default: the identity, ``q = n``; a torque disturbance on a
        satellite: the input matrix).

    Returns
    -------
    dict
        ``samples``, ``violations`` (samples with any broken bound), ``input_violations``,
        ``state_violations``, ``max_input_excess`` and ``max_state_excess`` (largest excess over a
        bound, <= 0 when none is broken), ``cost`` (mean over the runs), ``final_norm`` (largest
        ``||x||`` at the end of a run), ``solve_time_p50``, ``solve_time_p95`` (s, from
        ``ctrl.last.solve_time``), ``status_counts`` and ``fallbacks``.
    """
    n, m = plant.n_states, plant.n_inputs
    x_start = as_vector(x0, "x0", n)
    steps = check_count(steps, "steps")
    runs = check_count(runs, "runs")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise ArgumentTypeError("seed", "an integer", type(seed).__name__)
    bound = as_optional_limits(u_max, "u_max", m, per="input")
    if state_constraints is None:
        h_mat, h_vec = np.zeros((0, n)), np.zeros(0)
    else:
        h_mat = as_matrix(state_constraints[0], "state_constraints H", (None, n))
        h_vec = as_vector(state_constraints[1], "state_constraints h", h_mat.shape[0])
    q = np.eye(n) if Q is None else as_matrix(Q, "Q", (n, n))
    r = np.eye(m) if R is None else as_matrix(R, "R", (m, m))
    e_mat = np.eye(n) if E is None else as_matrix(E, "E", (n, None))
    w_box = None if w_max is None else as_vector(w_max, "w_max", e_mat.shape[1])
    if w_box is not None and not np.all(w_box >= 0.0):
        raise InvalidArgumentError("w_max", "bounds >= 0", repr(w_box.tolist()))
    vertices = [plant.vertex(j) for j in range(plant.n_vertices)]
    rng = np.random.default_rng(seed)
    out: dict[str, Any] = {"samples": steps * runs, "violations": 0, "input_violations": 0,
                           "state_violations": 0, "max_input_excess": -np.inf, "max_state_excess": -np.inf,
                           "status_counts": {}, "fallbacks": 0}
    times: list[float] = []
    costs, finals = [], []
    for _ in range(runs):
        sequence = rng.integers(0, len(vertices), size=steps)
        pushes = (np.zeros((steps, n)) if w_box is None
                  else (w_box * rng.choice((-1.0, 1.0), size=(steps, w_box.size))) @ e_mat.T)
        ctrl.reset()
        x, cost = x_start.copy(), 0.0
        for j, w in zip(sequence, pushes, strict=True):
            u = np.asarray(ctrl.step(x), dtype=float)
            info = ctrl.last
            if info is not None:
                times.append(float(info.solve_time))
                key = str(info.status)
                out["status_counts"][key] = out["status_counts"].get(key, 0) + 1
                out["fallbacks"] += bool(info.fallback)
            cost += float(x @ q @ x + u @ r @ u)
            a, b = vertices[int(j)]
            x = a @ x + b @ u + w
            broken = False
            if bound is not None:
                over = np.abs(u) - bound
                out["max_input_excess"] = max(out["max_input_excess"], float(np.max(over)))
                if np.any(over > VIOLATION_TOL * np.maximum(1.0, bound)):
                    out["input_violations"] += 1
                    broken = True
            if h_vec.size:
                over = h_mat @ x - h_vec
                out["max_state_excess"] = max(out["max_state_excess"], float(np.max(over)))
                if np.any(over > VIOLATION_TOL * np.maximum(1.0, np.abs(h_vec))):
                    out["state_violations"] += 1
                    broken = True
            out["violations"] += broken
        costs.append(cost)
        finals.append(float(np.linalg.norm(x)))
    out["cost"] = float(np.mean(costs))
    out["final_norm"] = float(max(finals))
    out["solve_time_p50"] = _percentile(times, 50)
    out["solve_time_p95"] = _percentile(times, 95)
    for key in ("max_input_excess", "max_state_excess"):
        if not np.isfinite(out[key]):
            out[key] = None
    return out
