"""The QP families of ``rmpc bench methods``: multi-stage and tube MPC beside the LMI forms.

The LMI forms answer ``solve(x)`` with a bound ``gamma`` and a certificate; the QP families
(:class:`rmpc.MultiStageMPC`, :class:`rmpc.TubeMPC`) answer with a QP's status. :class:`QPMethod`
gives them the ``solve(x)`` the suite's region search and its solve at ``x0`` call: the status of
the QP at ``x`` (``"optimal"`` where it is solved), no ``gamma``. :func:`qp_method` builds the
controller of a method on a problem, or says why it does not apply.

What each family assumes (the report says it next to the numbers): the LMI forms and the
multi-stage tree take the polytope of plants (``x+ = A_j x + B_j u``, any ``j`` at every sample
for the vertex-pair forms and the tree); the tube takes one plant with an additive disturbance
``w`` in a polytope ``W`` (``x+ = A x + B u + w``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType, SimpleNamespace
from typing import Any

import numpy as np

from benchmarks.suites.methods_problems import MethodsProblem

__all__ = ["QP_METHODS", "QPAnswer", "QPMethod", "qp_method", "state_box"]

#: The QP families' methods (name -> what it is).
QP_METHODS: Mapping[str, str] = MappingProxyType({
    "tube": "Mayne, Seron & Rakovic 2005: the rigid tube around a nominal plan (one plant, additive W)",
    "tube_tightening": "Chisci, Rossiter & Zappa 2001: constraints tightened along the horizon (one plant, "
                       "additive W)",
    "multistage": "Lucia, Finkler & Engell 2013: a scenario tree over the vertices, robust horizon 1, "
                  "one QP (Clarabel)",
})

#: The tube's prediction horizon in the suite (samples; Mayne, Seron & Rakovic's example).
TUBE_HORIZON = 9

#: The multi-stage tree's prediction horizon in the suite (samples).
MULTISTAGE_HORIZON = 10


@dataclass(frozen=True)
class QPAnswer:
    """What :meth:`QPMethod.solve` returns: the QP's status at ``x`` (no cost bound)."""

    status: str
    gamma: None = None
    iterations: int | None = None
    slack: None = None

    @property
    def certificate(self) -> Any:
        """``ok`` where the QP was solved (``"optimal"``): the region search's test."""
        return SimpleNamespace(ok=self.status == "optimal")


class QPMethod:
    """A QP family's controller with the ``solve(x)`` of the suite (its QP's status at ``x``).

    ``step``, ``reset`` and ``last`` are the controller's own.
    """

    def __init__(self, ctrl: Any) -> None:
        self.ctrl = ctrl

    def solve(self, x: np.ndarray) -> QPAnswer:
        """The status of the controller's QP at ``x`` (``status_at``, or a step from a reset)."""
        if hasattr(self.ctrl, "status_at"):
            return QPAnswer(str(self.ctrl.status_at(x)))
        self.ctrl.reset()
        self.ctrl.step(x)
        status = str(self.ctrl.last.status)
        self.ctrl.reset()
        return QPAnswer(status)

    def step(self, x: np.ndarray) -> np.ndarray:
        """The controller's step."""
        return self.ctrl.step(x)

    def reset(self) -> None:
        """The controller's reset."""
        self.ctrl.reset()

    @property
    def last(self) -> Any:
        """The controller's last step."""
        return self.ctrl.last


def state_box(problem: MethodsProblem) -> tuple[np.ndarray, np.ndarray] | None:
    """The problem's output bounds ``|C x| <= y_max`` as ``H x <= h`` (``None`` without)."""
    if problem.output_matrix is None or problem.y_max is None:
        return None
    c = np.asarray(problem.output_matrix, dtype=float)
    y = np.asarray(problem.y_max, dtype=float)
    return np.vstack((c, -c)), np.concatenate((y, y))


def qp_method(
    problem: MethodsProblem, method: str
) -> tuple[QPMethod | None, str | None, bool, dict[str, Any]]:
    """The controller of QP ``method`` on ``problem``.

    Returns
    -------
    ctrl : QPMethod or None
        ``None`` where the method does not apply.
    skip_reason : str or None
        Why it does not apply.
    comparable : bool
        Whether it solves the problem's own bounds (a QP takes ``|u_l| <= u_max``; a problem that
        bounds ``||u||_2`` runs it with the peak bound, as the auxiliary saturation).
    options : dict
        The controller's settings, for the record.
    """
    from rmpc import MultiStageMPC, TubeMPC

    comparable = problem.input_constraint == "peak" or problem.plant.n_inputs == 1
    if method in ("tube", "tube_tightening"):
        if problem.w_box is None or problem.plant.n_vertices != 1:
            return None, ("tube MPC takes one plant with an additive disturbance set W; this problem "
                          "is a polytope of plants" + ("" if problem.w_box is not None else " without W")
                          ), True, {}
        kind = "rigid" if method == "tube" else "tightening"
        if kind == "rigid" and problem.w_matrix is not None and (
                np.linalg.matrix_rank(problem.w_matrix) < problem.n_states):
            return None, ("the rigid tube's cross-section needs a full-dimensional E W (Rakovic et "
                          "al.'s A^s W in alpha W); this disturbance enters through "
                          f"{np.linalg.matrix_rank(problem.w_matrix)} of {problem.n_states} state "
                          "directions: the tightening (tube_tightening) runs here"), True, {}
        box = state_box(problem)
        ctrl = TubeMPC(problem.true_plant, problem.Q, problem.R, horizon=TUBE_HORIZON, kind=kind,
                       u_max=float(problem.u_max), state_constraints=box, w_max=problem.w_box,
                       E=problem.w_matrix)
        options = {"kind": kind, "horizon": TUBE_HORIZON, "u_max": float(problem.u_max),
                   "w_max": problem.w_box.tolist(), "backend": "clarabel"}
        if box is not None:
            options["state_constraints"] = "|C x| <= y_max"
        if problem.w_matrix is not None:
            options["E"] = "the nominal B (a torque disturbance)"
        return QPMethod(ctrl), None, comparable, options
    if method == "multistage":
        options = {"horizon": MULTISTAGE_HORIZON, "robust_horizon": 1, "u_max": float(problem.u_max),
                   "input_constraint": "peak", "backend": "clarabel"}
        box = state_box(problem)
        ctrl = MultiStageMPC(problem.plant, problem.Q, problem.R, horizon=MULTISTAGE_HORIZON,
                             robust_horizon=1, u_max=float(problem.u_max), state_constraints=box)
        if box is not None:
            options["state_constraints"] = "|C x| <= y_max"
        return QPMethod(ctrl), None, comparable, options
    raise KeyError(method)
