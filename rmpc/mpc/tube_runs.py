"""Seeded closed-loop runs of a tube controller on ``x+ = A x + B u + w``: violations, cost, times.

What a benchmark needs of tube MPC without the benchmark harness: the double integrator of the
tube literature (:func:`double_integrator`), initial states drawn from a box and kept where the
controller's first QP is feasible (:func:`feasible_initial_states`; the kept share estimates the
region of attraction within the box), and seeded disturbance sequences run in closed loop with
every constraint violation counted (:func:`disturbance_runs`).

Examples
--------
>>> import numpy as np
>>> from rmpc import TubeMPC
>>> from rmpc.mpc.tube_runs import disturbance_runs, double_integrator
>>> problem = double_integrator()
>>> tube = TubeMPC((problem["A"], problem["B"]), **problem["controller"])
>>> runs = disturbance_runs(tube, [[-5.0, -2.0]], steps=20, rng=np.random.default_rng(0))
>>> runs.violations, runs.failed_steps
(0, 0)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import ArgumentTypeError
from toolkit_common.status import Status

__all__ = ["RunSummary", "disturbance_runs", "double_integrator", "feasible_initial_states"]

#: A constraint counts as violated when a row exceeds its bound by more than this (relative to
#: the bound, at least absolute): the QP back-ends' tolerances are 1e-8 to 1e-10.
VIOLATION_TOL = 1e-6


def double_integrator() -> dict[str, Any]:
    """The double integrator of the tube literature: ``A = [[1, 1], [0, 1]]``, ``B = [[0.5], [1]]``,
    ``|u| <= 1``, ``|x_i| <= 10``, ``W = {|w_i| <= 0.1}``, ``Q = I``, ``R = 0.01``, ``N = 9``.

    The weights and horizon are those of the example of Mayne, Seron and Rakovic (2005); the state
    bound is the box ``|x_i| <= 10`` of the toolkit's benchmark.
    """
    return {
        "A": np.array([[1.0, 1.0], [0.0, 1.0]]), "B": np.array([[0.5], [1.0]]),
        "controller": {"Q": np.eye(2), "R": 0.01, "horizon": 9, "u_max": 1.0, "x_max": [10.0, 10.0],
                       "w_max": [0.1, 0.1]},
    }


@dataclass
class RunSummary:
    """What :func:`disturbance_runs` measured.

    Attributes
    ----------
    runs, steps : int
        Sequences run and steps per sequence.
    violations : int
        Samples (over all runs) at which a state or input row exceeded its bound by more than
        :data:`VIOLATION_TOL`; the state is checked at every sample including the last.
    max_excess : float
        The largest excess of any row over its bound (negative: every row held with margin).
    failed_steps : int
        Steps whose status was not ``"optimal"`` (a fallback was applied).
    cost : list of float
        Per run, ``sum x'Qx + u'Ru`` over the steps.
    solve_times : ndarray
        Every step's QP solve time (s).
    step_times : ndarray
        Every step's wall time in ``step`` (s).
    statuses : dict
        Count per status word.
    """

    runs: int
    steps: int
    violations: int = 0
    max_excess: float = -np.inf
    failed_steps: int = 0
    cost: list[float] = field(default_factory=list)
    solve_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    step_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    statuses: dict[str, int] = field(default_factory=dict)


def _disturbance(vertices: np.ndarray, steps: int, mode: str, rng: np.random.Generator) -> np.ndarray:
    if mode == "vertices":      # a random vertex of W at every step (the worst cases are vertices)
        return vertices[rng.integers(len(vertices), size=steps)]
    if mode == "constant":      # one vertex held throughout (a constant worst-case push)
        return np.repeat(vertices[rng.integers(len(vertices))][None], steps, axis=0)
    weights = rng.dirichlet(np.ones(len(vertices)), size=steps)     # points of W
    return weights @ vertices


def disturbance_runs(
    controller: Any,
    initial_states: ArrayLike,
    steps: int = 50,
    rng: np.random.Generator | None = None,
    modes: tuple[str, ...] = ("vertices", "uniform", "constant"),
) -> RunSummary:
    """Run ``controller`` (a :class:`~rmpc.TubeMPC`) from each initial state over a seeded sequence.

    The plant is the controller's own ``x+ = A x + B u + w``; run ``r`` draws its disturbance by
    ``modes[r % len(modes)]``: a random vertex of ``W`` per step, points of ``W`` (random convex
    combinations of its vertices), or one vertex held. The controller is ``reset()`` before
    each run.
    """
    if not isinstance(rng, np.random.Generator):
        raise ArgumentTypeError("rng", "a numpy.random.Generator (seeded)", type(rng).__name__)
    x0s = np.atleast_2d(np.asarray(initial_states, dtype=float))
    A, B, W = controller.A, controller.B, controller.W      # x+ = A x + B u + E w, w in W
    (Hx, hx, _), (Hu, hu, _) = controller.X, controller.U
    tol_x, tol_u = VIOLATION_TOL * np.maximum(1.0, np.abs(hx)), VIOLATION_TOL * np.maximum(1.0, np.abs(hu))
    out = RunSummary(runs=len(x0s), steps=steps)
    solve, wall = [], []
    for r, x0 in enumerate(x0s):
        controller.reset()
        w = _disturbance(W.vertices, steps, modes[r % len(modes)], rng)
        x, cost = x0.copy(), 0.0
        for k in range(steps):
            u = controller.step(x)
            info = controller.last
            solve.append(info.solve_time)
            wall.append(info.extra.get("step_time", info.solve_time))
            out.statuses[str(info.status)] = out.statuses.get(str(info.status), 0) + 1
            out.failed_steps += info.status != Status.OPTIMAL
            ex = max(np.max(Hx @ x - hx, initial=-np.inf), np.max(Hu @ u - hu, initial=-np.inf))
            out.max_excess = max(out.max_excess, float(ex))
            out.violations += bool(np.any(Hx @ x - hx > tol_x) or np.any(Hu @ u - hu > tol_u))
            cost += float(x @ controller.Q @ x + u @ controller.R @ u)
            x = A @ x + B @ u + controller.E @ w[k]
        ex = np.max(Hx @ x - hx, initial=-np.inf)
        out.max_excess = max(out.max_excess, float(ex))
        out.violations += bool(np.any(Hx @ x - hx > tol_x))
        out.cost.append(cost)
    out.solve_times, out.step_times = np.array(solve), np.array(wall)
    return out


def feasible_initial_states(
    controller: Any, upper: ArrayLike, count: int, rng: np.random.Generator, max_draws: int = 100_000
) -> tuple[np.ndarray, float]:
    """``count`` states drawn uniformly from ``|x_i| <= upper_i`` where the controller's QP is
    feasible, and the share of draws kept (an estimate of the region of attraction's share of the
    box). The controller is ``reset()`` afterwards."""
    if not isinstance(rng, np.random.Generator):
        raise ArgumentTypeError("rng", "a numpy.random.Generator (seeded)", type(rng).__name__)
    up = np.asarray(upper, dtype=float)
    kept, draws = [], 0
    while len(kept) < count and draws < max_draws:
        x = rng.uniform(-up, up)
        draws += 1
        controller.reset()
        controller.step(x)
        if controller.last.status == Status.OPTIMAL:
            kept.append(x)
    controller.reset()
    return np.array(kept), len(kept) / max(draws, 1)
