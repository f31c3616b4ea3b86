"""The controller protocol every controller of the toolkit follows, and its per-step info."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["Controller", "StepInfo"]


@dataclass(frozen=True)
class StepInfo:
    """What a controller reports about one call of ``step``.

    Attributes
    ----------
    status : str
        ``"optimal"`` or a failure word (``"infeasible"``, ``"numerical_error"``,
        ``"max_iterations"``, ...); ``"reused"`` when a previous certified answer was kept.
    solve_time : float
        Time spent in the optimiser during this step (s); 0 for a fixed gain.
    gamma : float or None
        The cost bound of robust MPC, where the controller has one.
    iterations : int or None
        Solver iterations, where reported.
    fallback : bool
        Whether the applied control came from a fallback (an older gain) after a failure.
    extra : dict
        Controller-specific details.
    """

    status: str
    solve_time: float = 0.0
    gamma: float | None = None
    iterations: int | None = None
    fallback: bool = False
    extra: dict[str, Any] = field(default_factory=dict)


@runtime_checkable
class Controller(Protocol):
    """The ``step(x)`` protocol.

    A controller is built once, ``reset()`` before a run, and called once per sample with the
    measured state; it returns the control to apply now. After each call ``last`` describes
    that step (at least ``status`` and ``solve_time``; see :class:`StepInfo`).
    """

    last: Any

    def step(self, x: np.ndarray) -> np.ndarray:  # pragma: no cover - protocol
        """Return the control to apply for the measured state ``x``."""
        ...

    def reset(self) -> None:  # pragma: no cover - protocol
        """Forget all internal state (memory, adaptation, last solution)."""
        ...
