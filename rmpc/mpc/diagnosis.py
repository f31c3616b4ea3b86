"""Why a robust MPC has no certified gain at a state, and what to try.

When the LMI problem of :class:`~rmpc.RMPC` gives no certified answer, the controller says so
(:class:`~rmpc.errors.NoCertifiedGainWarning`, or :class:`~rmpc.errors.SolverError` with
``on_failure="raise"``) with a diagnosis made of a few more solves at the same state, from the
least to the most constrained problem (Kothare, Balakrishnan & Morari 1996, with the soft bounds
of Oravec & Bakosova 2016's soft-constrained variants):

1. **No bounds at all.** Kothare's problem without input and output bounds is feasible at every
   state or at none (its LMIs scale with the state), so an infeasible one is a property of the
   polytope: a vertex with an unstable mode the input cannot move (the PBH test
   ``rank [A_j - lambda I, B_j] < n`` at ``|lambda| >= 1``), or no common quadratic Lyapunov
   function over the vertices.
2. **The form's own additions.** With a disturbance (or another form) the same bounds are tried
   on Kothare's plain problem: feasible there, the addition blocks (e.g. ``w_max`` too large).
3. **Soft bounds.** The bounds softened (``soft={"u": w, "y": w}``, :mod:`lmi.forms`): the
   slacks say which bound blocks and about how far it would have to move from this state.
4. Otherwise the solver failed on a problem that has a certified answer (``numerical_error``
   where a softened solve is exact): the hint says to try another back-end.

Nothing here changes the answer a controller applies; it only explains it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmi import KothareProblem
from lmi.data import KothareData
from lmi.forms import FormProblem
from models.linear import unreachable_modes
from rmpc.mpc.fallback import is_certified

__all__ = ["FailureDiagnosis", "diagnose", "uncontrollable_unstable_modes"]

#: The soft bounds' weight of the diagnosis: large against the cost bound, so a slack is paid
#: only where the hard bound cannot hold (the bound it reports is then close to the smallest).
SOFT_WEIGHT = 1e4


@dataclass(frozen=True)
class FailureDiagnosis:
    """What blocks a certified gain at one state.

    Attributes
    ----------
    status : str
        The status of the solve that failed.
    blocking : str
        ``"stabilisability"`` (no gain exists at any state), ``"common_lyapunov"``, ``"form"``
        (the form's addition, e.g. the disturbance), ``"input_bound"``, ``"output_bound"``,
        ``"input_and_output_bound"``, ``"solver"`` (a certified answer exists) or ``"unknown"``.
    reason : str
        One sentence on what blocks, with the numbers found.
    hint : str
        What to try.
    needed : dict
        The bounds a softened solve needed from this state (``"u_max"``, ``"y_max"``), where
        a bound blocks.
    """

    status: str
    blocking: str
    reason: str
    hint: str
    needed: dict[str, float] = field(default_factory=dict)

    def message(self) -> str:
        """``reason`` and ``hint`` in one text."""
        return f"{self.reason} Try: {self.hint}"


def uncontrollable_unstable_modes(
    A: np.ndarray, B: np.ndarray, tol: float = 1e-9
) -> list[tuple[int, complex]]:
    """``(vertex, eigenvalue)`` of every mode with ``|lambda| >= 1`` that ``B_j`` cannot move
    (:func:`models.linear.unreachable_modes` per vertex)."""
    return [(j, lam) for j, (a, b) in enumerate(zip(A, B, strict=True))
            for lam in unreachable_modes(a, b, only_unstable=True, tol=tol)]


def _u_max(data: KothareData) -> Any:
    """The input bound as a problem takes it (a scalar for the ellipsoid bound), or ``None``."""
    if data.input_constraint is None:
        return None
    return float(data.u_max[0]) if data.input_constraint == "ellipsoid" else data.u_max


def _unbounded(data: KothareData, z: np.ndarray, backend: str) -> Any:
    return KothareProblem(data.A, data.B, data.Q1, data.R, dt=data.dt, input_constraint=None,
                          backend=backend).solve(z)


def diagnose(data: KothareData, z: np.ndarray, status: str, *, has_addition: bool = False,
             backend: str = "ipm") -> FailureDiagnosis:
    """Explain a failed solve of the problem ``data`` at the deviation ``z``.

    Parameters
    ----------
    data : KothareData
        The failed problem's data (vertices, weights, bounds).
    z : (n,) ndarray
        The state (deviation from the reference) it failed at.
    status : str
        The failed solve's status.
    has_addition : bool
        Whether the failed problem is a form beyond Kothare's (a disturbance, another Lyapunov
        form, ...): then Kothare's plain problem with the same bounds is tried first.
    backend : str
        The back-end of the diagnosis' solves.
    """
    if not is_certified(_unbounded(data, z, backend)):
        modes = uncontrollable_unstable_modes(data.A, data.B)
        if modes:
            listed = ", ".join(
                f"vertex {j}: lambda = {lam:.4g} (|lambda| = {abs(lam):.4g})" for j, lam in modes
            )
            return FailureDiagnosis(
                status, "stabilisability",
                f"No gain exists at any state: an unstable mode the input cannot move ({listed}).",
                "check the model's B (an actuator missing?) or control only the controllable part.",
            )
        return FailureDiagnosis(
            status, "common_lyapunov",
            "No gain exists at any state even without input and output bounds: the vertices share "
            "no quadratic Lyapunov function that one feedback gain makes decrease.",
            "lyapunov='vertex' (uncertainty constant in time) or a smaller polytope.",
        )
    bounded = data.input_constraint is not None or data.C_out is not None
    if has_addition:
        plain = KothareProblem(
            data.A, data.B, data.Q1, data.R, dt=data.dt, input_constraint=data.input_constraint,
            u_max=_u_max(data), output_matrix=data.C_out,
            y_max=data.y_max if data.C_out is not None else None, backend=backend,
        ).solve(z)
        if is_certified(plain):
            return FailureDiagnosis(
                status, "form",
                "Kothare's problem with the same bounds has a certified gain here; the form's addition "
                "(the disturbance bound, the Lyapunov form) is what has none.",
                "a smaller disturbance bound w_max (or a given lam), or the default form.",
            )
    if not bounded:
        return _solver_failure(status)
    soft = {}
    if data.input_constraint is not None:
        soft["u"] = SOFT_WEIGHT
    if data.C_out is not None:
        soft["y"] = SOFT_WEIGHT
    relaxed = FormProblem(
        data.A, data.B, data.Q1, data.R, dt=data.dt, input_constraint=data.input_constraint,
        u_max=_u_max(data), output_matrix=data.C_out,
        y_max=data.y_max if data.C_out is not None else None, soft=soft, backend=backend,
    ).solve(z)
    if not is_certified(relaxed) or relaxed.slack is None:
        return FailureDiagnosis(
            status, "unknown",
            f"The solve ended {status!r}, and a solve with softened bounds found no answer either "
            f"({relaxed.status!r}).",
            "a state closer to the reference, or backend='clarabel'.",
        )
    return _bound_diagnosis(data, status, relaxed.slack)


def _bound_diagnosis(data: KothareData, status: str, slack: dict[str, float]) -> FailureDiagnosis:
    """Which bound the softened solve had to relax (its slacks, squared units)."""
    tol = 1e-6
    needed: dict[str, float] = {}
    parts = []
    s_u = slack.get("u", 0.0)
    if s_u > tol * max(1.0, float(np.max(data.u_max)) ** 2):
        big = float(np.max(data.u_max))
        needed["u_max"] = float(np.sqrt(big**2 + s_u))
        parts.append(f"the input bound u_max = {big:.4g} (a softened solve needed about "
                     f"{needed['u_max']:.4g})")
    s_y = slack.get("y", 0.0)
    if data.C_out is not None and s_y > tol * max(1.0, float(np.max(data.y_max)) ** 2):
        big = float(np.max(data.y_max))
        needed["y_max"] = float(np.sqrt(big**2 + s_y))
        parts.append(f"the output bound y_max = {big:.4g} (a softened solve needed about "
                     f"{needed['y_max']:.4g})")
    if not parts:
        return _solver_failure(status)
    blocking = ("input_and_output_bound" if len(parts) == 2
                else "input_bound" if "u_max" in needed else "output_bound")
    soft = ", ".join(f"{k!r}: weight" for k in ("u", "y") if f"{k}_max" in needed)
    return FailureDiagnosis(
        status, blocking,
        f"From this state no gain keeps {' and '.join(parts)}.",
        f"a larger bound, soft bounds (soft={{{soft}}}), or a start closer to the reference.",
        needed,
    )


def _solver_failure(status: str) -> FailureDiagnosis:
    hints = {
        "max_iterations": "more iterations (solver_options={'max_iter': ...}) or the default options.",
        "time_limit": "a longer time limit, or the default options.",
    }
    return FailureDiagnosis(
        status, "solver",
        f"The solve ended {status!r} although the problem has a certified answer here (a softened "
        "or unbounded solve found one with every bound kept).",
        hints.get(status, "backend='clarabel', or report the state: the toolkit's solver should have "
                  "answered."),
    )
