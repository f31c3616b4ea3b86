"""Disturbance torque profiles ``d(t)`` for the simulator."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive, check_real

__all__ = [
    "ConstantDisturbance",
    "DisturbanceFn",
    "SineDisturbance",
    "StepDisturbance",
    "as_disturbance",
    "disturbance_at",
]

DisturbanceFn = Callable[..., np.ndarray]


@dataclass(frozen=True)
class StepDisturbance:
    """A torque that switches from zero to ``magnitude`` at ``t_start`` and stays.

    Parameters
    ----------
    magnitude : array_like, shape (m,)
        The torque after the step (N m), one value per axis.
    t_start : float
        Switching time (s), >= 0.

    Examples
    --------
    >>> from rmpc import StepDisturbance
    >>> d = StepDisturbance([0.5, 0.5, 0.5], t_start=10.0)
    >>> d(9.99).tolist(), d(10.0).tolist()
    ([0.0, 0.0, 0.0], [0.5, 0.5, 0.5])
    """

    magnitude: Any
    t_start: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "magnitude", as_vector(self.magnitude, "magnitude"))
        object.__setattr__(self, "t_start", check_positive(self.t_start, "t_start", allow_zero=True))

    def __call__(self, t: float) -> np.ndarray:
        return self.magnitude.copy() if t >= self.t_start else np.zeros_like(self.magnitude)

    def breakpoints(self) -> tuple[float, ...]:
        """Times where the profile is discontinuous (the integrator stops there)."""
        return (self.t_start,)


@dataclass(frozen=True)
class ConstantDisturbance:
    """A constant torque for all times."""

    magnitude: Any

    def __post_init__(self) -> None:
        object.__setattr__(self, "magnitude", as_vector(self.magnitude, "magnitude"))

    def __call__(self, t: float) -> np.ndarray:
        return self.magnitude.copy()

    def breakpoints(self) -> tuple[float, ...]:
        return ()


@dataclass(frozen=True)
class SineDisturbance:
    """``amplitude * sin(2 pi frequency t + phase)`` per axis."""

    amplitude: Any
    frequency: float
    phase: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude", as_vector(self.amplitude, "amplitude"))
        object.__setattr__(self, "frequency", check_positive(self.frequency, "frequency"))
        object.__setattr__(self, "phase", check_real(self.phase, "phase"))

    def __call__(self, t: float) -> np.ndarray:
        return self.amplitude * np.sin(2.0 * np.pi * self.frequency * t + self.phase)

    def breakpoints(self) -> tuple[float, ...]:
        return ()


def as_disturbance(value: Any, size: int, x0: ArrayLike | None = None) -> Callable[..., np.ndarray] | None:
    """Accept ``None``, a profile object or any callable ``d(t)`` returning ``size`` values.

    A disturbance whose attribute ``state_dependent`` is true is called as ``d(t, x)`` (the
    torque of a spinning disk inside the bus depends on the body rates, say); ``x0`` is then
    the state it is probed at.
    """
    if value is None:
        return None
    if not callable(value):
        raise ArgumentTypeError(
            "disturbance", "None or a callable d(t) such as StepDisturbance", type(value).__name__
        )
    if getattr(value, "state_dependent", False):
        probe = np.asarray(value(0.0, np.asarray(x0, dtype=float)), dtype=float)
    else:
        probe = np.asarray(value(0.0), dtype=float)
    if probe.shape != (size,):
        raise InvalidArgumentError(
            "disturbance", f"d(t) of shape ({size},)", f"shape {probe.shape}"
        )
    return value


def disturbance_at(disturbance: DisturbanceFn, t: float, x: np.ndarray) -> np.ndarray:
    """``d(t, x)`` for a state-dependent disturbance (``state_dependent = True``), else ``d(t)``.

    Raises
    ------
    InvalidArgumentError
        Naming ``disturbance`` and the time when a value is NaN or infinite (an integrator fed
        one would shrink its step without end or carry the NaN into the state).
    """
    if getattr(disturbance, "state_dependent", False):
        value = np.asarray(disturbance(t, x), dtype=float)
    else:
        value = np.asarray(disturbance(t), dtype=float)
    if not np.all(np.isfinite(value)):
        raise InvalidArgumentError("disturbance", "finite values d(t)", f"{value.tolist()} at t = {t:.9g} s")
    return value
