"""The certified gain of an online robust MPC: kept between solves, the fallback when one fails.

Robust MPC applies ``u = F z`` with the gain ``F`` of an LMI solution whose certificate holds
(:class:`lmi.LMISolution`). :class:`CertifiedGain` is the part of such a controller that decides
what to apply at a step, the same way for :class:`~rmpc.RMPC` and :class:`~rmpc.ScheduledRMPC`:

- a solve with a usable status and a holding certificate replaces the gain (its status is
  reported);
- a solve without one keeps the last certified gain (zero before the first one) and reports the
  solver's status with ``fallback=True``, or raises :class:`~toolkit_common.errors.SolverError`
  with ``on_failure="raise"``. Zero is no certified input: the first step that applies it warns
  (:class:`~toolkit_common.errors.NoCertifiedGainWarning`, once until :meth:`CertifiedGain.reset`
  or the next certified gain) with the status and a diagnosis (:mod:`rmpc.mpc.diagnosis`: which
  bound blocks and what to try), kept in the step's ``extra["diagnosis"]``; a raised failure
  carries the same diagnosis in its message;
- near the origin (``||z|| <= hold_radius``, where the problem degenerates) no solve is made and
  the last gain is applied, status ``"reused"``; so is a gain kept on purpose (RMPC's
  ``resolve_threshold``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any, Literal

import numpy as np

from lmi import LMISolution
from rmpc.controller import StepInfo
from toolkit_common.errors import NoCertifiedGainWarning, SolverError
from toolkit_common.status import Status, is_usable
from toolkit_common.validation import check_choice, check_positive

__all__ = ["CertifiedGain", "is_certified"]

#: What a controller does when a solve gives no certified gain.
ON_FAILURE = ("fallback", "raise")


def is_certified(sol: LMISolution) -> bool:
    """Whether ``sol``'s gain may be applied: a usable status and a certificate that holds."""
    return is_usable(sol.status) and sol.certificate is not None and sol.certificate.ok


class CertifiedGain:
    """The last certified gain of a robust MPC, with its invariant ellipsoid and its input bound.

    Parameters
    ----------
    owner : str
        The controller's name, for the message of a raised failure (``"RMPC"``).
    on_failure : {"fallback", "raise"}
        What :meth:`take` does with a solve that gives no certified gain.
    hold_radius : float
        Below this norm of the state (deviation) no solve is made (:meth:`near_origin`).

    Attributes
    ----------
    solution : LMISolution or None
        The last certified solution.
    bound : ndarray or None
        The input bound it was certified for.

    Examples
    --------
    >>> import numpy as np
    >>> from lmi import KothareProblem
    >>> from rmpc.mpc.fallback import CertifiedGain
    >>> prob = KothareProblem([[2.0]], [[1.0]], Q=[[1.0]], R=[[1.0]], u_max=1.0)  # unstable
    >>> kept = CertifiedGain("example")
    >>> u, info = kept.take(prob.solve([0.5]), np.array([0.5]), (1, 1))
    >>> print(info.status, info.fallback, kept.gain is not None)
    optimal False True
    >>> u, info = kept.take(prob.solve([50.0]), np.array([50.0]), (1, 1))  # too far to stabilise
    >>> print(info.status, info.fallback, info.extra["had_gain"])
    infeasible True True
    """

    def __init__(
        self, owner: str, on_failure: Literal["fallback", "raise"] = "fallback", hold_radius: float = 1e-9
    ) -> None:
        self.owner = owner
        self.on_failure = check_choice(on_failure, "on_failure", ON_FAILURE)
        self.hold_radius = check_positive(hold_radius, "hold_radius", allow_zero=True)
        self.solution: LMISolution | None = None
        self.bound: np.ndarray | None = None
        self._q_inv: np.ndarray | None = None
        self._warned = False

    def reset(self) -> None:
        """Forget the gain (and that the missing gain was warned about)."""
        self.solution = None
        self.bound = None
        self._q_inv = None
        self._warned = False

    @property
    def gain(self) -> np.ndarray | None:
        """The last certified ``F`` (a copy), or ``None``."""
        return None if self.solution is None else np.array(self.solution.F)

    @property
    def q_inv(self) -> np.ndarray | None:
        """``Q^-1`` of the last certified solution (its invariant ellipsoid ``z' Q^-1 z <= 1``)."""
        if self._q_inv is None and self.solution is not None:
            self._q_inv = np.linalg.inv(self.solution.Q)
        return self._q_inv

    def applied(self, shape: tuple[int, int]) -> np.ndarray:
        """The gain to apply: the last certified one, or zero of ``shape`` before the first."""
        if self.solution is None:
            return np.zeros(shape)
        assert self.solution.F is not None
        return self.solution.F

    def contains(self, z: np.ndarray) -> bool:
        """Whether ``z`` lies in the invariant ellipsoid of the last certified gain."""
        q_inv = self.q_inv
        return q_inv is not None and bool(z @ q_inv @ z <= 1.0 + 1e-9)

    def near_origin(self, z: np.ndarray) -> bool:
        """Whether ``||z|| <= hold_radius``: no solve, the last gain is kept (:meth:`reuse`)."""
        return float(np.linalg.norm(z)) <= self.hold_radius

    def reuse(
        self, z: np.ndarray, shape: tuple[int, int], reason: str, **extra: Any
    ) -> tuple[np.ndarray, StepInfo]:
        """``u = F z`` with the last gain and a ``"reused"`` step (``extra["reason"]``, then ``extra``)."""
        info = StepInfo(status=Status.REUSED, extra={"solution": None, "reason": reason, **extra})
        return self.applied(shape) @ z, info

    def take(
        self, sol: LMISolution, z: np.ndarray, shape: tuple[int, int], *, x: np.ndarray | None = None,
        bound: np.ndarray | None = None, extra: dict[str, Any] | None = None,
        failure_extra: dict[str, Any] | None = None,
        diagnose: Callable[[], Any] | None = None,
    ) -> tuple[np.ndarray, StepInfo]:
        """``u = F z`` after the solve ``sol`` and the step's :class:`~rmpc.StepInfo`.

        Parameters
        ----------
        sol : LMISolution
            This step's solve.
        z : (n,) ndarray
            The state the gain multiplies.
        shape : (m, n)
            The shape of the zero gain applied before any certified one.
        x : (n,) ndarray, optional
            The measured state named in a raised failure (default ``z``).
        bound : ndarray, optional
            The input bound ``sol`` was solved with (kept with a certified gain).
        extra, failure_extra : dict, optional
            Added to ``extra`` after ``"solution"``: ``extra`` for a certified solve,
            ``failure_extra`` (then ``"had_gain"``) for a fallback.
        diagnose : callable, optional
            Called (with no argument) when ``sol`` is not certified and the failure is raised or
            zero is applied: returns the :class:`~rmpc.mpc.diagnosis.FailureDiagnosis` that the
            message and ``extra["diagnosis"]`` carry.

        Raises
        ------
        SolverError
            With ``on_failure="raise"``, when ``sol`` is not certified.

        Warns
        -----
        NoCertifiedGainWarning
            When zero is applied for want of any certified gain (once until :meth:`reset` or
            the next certified gain).
        """
        if is_certified(sol):
            assert sol.F is not None and sol.Q is not None
            self.solution, self.bound, self._q_inv = sol, bound, None
            self._warned = False
            info = StepInfo(
                status=sol.status, solve_time=sol.solve_time, gamma=sol.gamma, iterations=sol.iterations,
                extra={"solution": sol, **(extra or {})},
            )
            return sol.F @ z, info
        where = z if x is None else x
        if self.on_failure == "raise":
            why = "" if diagnose is None else " " + diagnose().message()
            raise SolverError(
                f"{self.owner}.step: the LMI solve at x = {where.tolist()} returned status {sol.status!r} "
                f"(solver: {sol.solver_status!r}) and on_failure='raise'.{why}"
            )
        details = {"solution": sol, **(failure_extra or {}), "had_gain": self.solution is not None}
        if self.solution is None and not self._warned:
            self._warned = True
            diagnosis = None if diagnose is None else diagnose()
            details["diagnosis"] = diagnosis
            why = "" if diagnosis is None else " " + diagnosis.message()
            warnings.warn(
                f"{self.owner}.step: no certified gain at x = {where.tolist()} (status {sol.status!r}); "
                f"applying u = 0, which no certificate stands behind, until a solve certifies a gain "
                f"(on_failure='raise' stops instead).{why}",
                NoCertifiedGainWarning, stacklevel=3,
            )
        info = StepInfo(
            status=sol.status, solve_time=sol.solve_time, gamma=None, iterations=sol.iterations,
            fallback=True, extra=details,
        )
        return self.applied(shape) @ z, info
