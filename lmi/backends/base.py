"""What every back-end of :class:`lmi.KothareProblem` is: built once, solved per state.

A back-end is built on the validated :class:`~lmi.KothareData` and solves the *normalised*
problem: :meth:`KothareBackend.solve` gets the state divided by its norm and the bounds divided
alike, and returns a :class:`RawResult` that :class:`~lmi.KothareProblem` rescales and
certifies. The back-ends (:mod:`lmi.backends.ipm`, :mod:`lmi.backends.clarabel`,
:mod:`lmi.backends.cvxpy`) are siblings under :class:`KothareBackend`; the two that share the
conic form of the LMIs hold it as a :class:`~lmi.backends.conic.KothareConic`, and the
interior-point back-end hands a failed solve to a Clarabel back-end it owns.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from lmi.data import KothareData
from lmi.infeasibility import InfeasibilityCertificate

__all__ = ["KothareBackend", "RawResult"]


@dataclass
class RawResult:
    """What a back-end returns for the normalised problem (before rescaling)."""

    status: str
    solver_status: str
    gamma: float
    Q: np.ndarray | None
    Y: np.ndarray | None
    iterations: int | None
    solve_time: float
    #: A checked proof of infeasibility (the IPM's phase one), when the status is "infeasible".
    infeasibility: InfeasibilityCertificate | None = None
    #: The back-end's own dual bound on the optimal ``gamma`` (Clarabel's dual objective), in
    #: the units of :attr:`gamma`; ``None`` where the back-end reports none.
    gamma_dual: float | None = None
    #: ``(gamma, Q, Y)`` of a strictly feasible point the IPM's phase one found on the way, in the
    #: units of :attr:`gamma`, :attr:`Q`, :attr:`Y`; :class:`lmi.KothareProblem` mixes it into an
    #: answer whose certificate fails (``None``: no such point).
    interior: tuple[float, np.ndarray, np.ndarray] | None = None


class KothareBackend(ABC):
    """A solver of the Kothare problem on fixed data: ``solve(x, u_max, y_max)`` per state.

    Attributes
    ----------
    name : str
        The back-end's name in :attr:`lmi.LMISolution.backend` (``"ipm"``, ``"clarabel"``,
        ``"cvxpy:SOLVER"``).
    data : KothareData
        The problem data the back-end solves (for the IPM, in its balanced coordinates).
    """

    name: str
    data: KothareData

    @abstractmethod
    def solve(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray) -> RawResult:
        """Solve at the normalised state ``x`` with the normalised bounds; never raises on a failure."""

    def reset(self) -> None:
        """Forget what earlier solves left behind (warm starts, adapted coordinates); default: nothing."""
        return None

    def gamma(self, objective: float) -> float:
        """``gamma`` from the solver's objective ``gamma_s`` (``dt gamma`` in the delta formulations)."""
        gamma = float(objective)
        if self.data.formulation != "standard":
            gamma /= self.data.dt
        return gamma
