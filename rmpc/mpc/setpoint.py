"""Steady-state targets of a polytope: ``(x_s, u_s)`` with ``C_r x_s = r`` on every vertex.

A set-point ``r`` on chosen outputs ``y_r = C_r x`` is held with a constant input only at a
state ``x_s`` with ``x_s = A_j x_s + B_j u_s`` on every vertex ``j`` (the plant may be any member
of the polytope). :func:`steady_target` solves the stacked equations

    [A_j - I, B_j] [x_s; u_s] = 0   (every j),     C_r x_s = r

in the least-squares sense (the smallest ``(x_s, u_s)`` where several hold) and refuses a
reference the equations do not hold for, naming the vertex that cannot share the steady state.
With an input disturbance ``d`` (``x+ = A_j x + B_j (u + d)``) the target input is ``u_s - d``
on every vertex at once, so the disturbance only shifts ``u_s`` (offset-free control,
:class:`rmpc.RMPC` with ``offset_free=True``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError

__all__ = ["SteadyTarget", "steady_target"]


@dataclass(frozen=True)
class SteadyTarget:
    """A steady state ``x_s`` and input ``u_s`` shared by every vertex, for ``C_r x_s = r``."""

    x: np.ndarray
    u: np.ndarray
    outputs: np.ndarray
    reference: np.ndarray


def _solve(lhs: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, bool]:
    """The least-squares solution of ``lhs z = rhs`` and whether it solves it (to rounding)."""
    sol, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    scale = max(1.0, float(np.abs(rhs).max(initial=0.0)), float(np.abs(sol).max(initial=0.0)))
    tol = 1e-9 * scale * max(1.0, float(np.abs(lhs).max()))
    return sol, float(np.abs(lhs @ sol - rhs).max(initial=0.0)) <= tol


def steady_target(A: np.ndarray, B: np.ndarray, reference: ArrayLike, outputs: ArrayLike) -> SteadyTarget:
    """The steady-state target of ``reference`` on ``outputs`` (``C_r``) over the vertices ``(A, B)``.

    Raises
    ------
    InvalidArgumentError
        Naming ``outputs`` for a matrix of the wrong shape, ``reference`` for a wrong length,
        non-finite values, or a reference that no steady state common to every vertex meets
        (with the vertex that cannot share it and the residual).
    """
    n, m = A.shape[1], B.shape[2]
    c_r = np.atleast_2d(np.asarray(outputs, dtype=float))
    if c_r.ndim != 2 or c_r.shape[1] != n or not np.all(np.isfinite(c_r)):
        raise InvalidArgumentError("outputs", f"a finite p x {n} matrix C_r (y_r = C_r x)",
                                   f"shape {c_r.shape}")
    r = np.atleast_1d(np.asarray(reference, dtype=float)).reshape(-1)
    if r.shape != (c_r.shape[0],) or not np.all(np.isfinite(r)):
        raise InvalidArgumentError("reference", f"{c_r.shape[0]} finite values (one per row of outputs)",
                                   repr(np.asarray(reference).tolist()))
    rows = [np.hstack([a - np.eye(n), b]) for a, b in zip(A, B, strict=True)]
    out_row = np.hstack([c_r, np.zeros((c_r.shape[0], m))])
    alone = []
    for j, row in enumerate(rows):  # each vertex on its own first: a reference it cannot meet
        x_j, ok = _solve(np.vstack([row, out_row]), np.concatenate([np.zeros(n), r]))
        if not ok:
            raise InvalidArgumentError(
                "reference", "a reference every vertex can hold (C_r x_s = r with x_s = A_j x_s + B_j u_s)",
                f"vertex {j} has no such steady state",
            )
        alone.append(x_j)
    sol, ok = _solve(np.vstack([*rows, out_row]), np.concatenate([np.zeros(n * len(rows)), r]))
    if not ok:
        each = "; ".join(
            f"vertex {j}: x_s = {np.round(v[:n], 6).tolist()}, u_s = {np.round(v[n:], 6).tolist()}"
            for j, v in enumerate(alone)
        )
        raise InvalidArgumentError(
            "reference", "a steady state common to every vertex (x_s = A_j x_s + B_j u_s for all j)",
            f"each vertex holds it at its own ({each}); a smaller polytope, or an uncertainty that keeps "
            "the steady state (an inertia, not a friction), has a common one",
        )
    x_s, u_s = sol[:n], sol[n:]
    return SteadyTarget(x_s, u_s, c_r, r)
