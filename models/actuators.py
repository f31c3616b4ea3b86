"""Actuator layers: paper P's reaction-wheel model and a torque limiter (saturation block)."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import (
    as_positive_values,
    as_vector,
    check_choice,
    check_count,
    check_positive,
    check_real,
)

__all__ = ["MAX_AXES", "ReactionWheelActuator", "TorqueLimiter"]

MAX_AXES = 1_000
"""Default bound on ``ReactionWheelActuator(n_axes=...)``: a spacecraft has 3 to 6 wheels, and the
states are allocated at once (``n_axes = 10**9`` ended in a MemoryError);
``ReactionWheelActuator(..., max_axes=N)`` lifts it."""


def _gain(value: Any, name: str, which: str) -> float:
    out = check_real(value, name)
    if not out > 0.0:
        expected = f"an {which} gain > 0 (a DC gain c b / (1 - a) > 0: the torque follows the command)"
        raise InvalidArgumentError(name, expected, repr(out))
    return out


class ReactionWheelActuator:
    """Paper P's reaction-wheel actuator, one first-order discrete system per axis.

    ``xa(k+1) = a xa(k) + b ua(k)``, ``ya(k) = c xa(k)`` with the values printed in paper P
    (**certain**): ``a = 0.86``, ``b = 0.0093``, ``c = 14.28``; DC gain
    ``c b / (1 - a) ~= 0.949``. Paper P states no sample time for it; it is run at the
    controller's sample time.

    Each axis is a first-order lag sampled at ``dt``: ``a = exp(-dt / tau)`` lies in ``[0, 1)``
    (``a = 0``: a lag much shorter than the sample, the torque follows one sample late), and the
    wheel turns the way it is commanded: ``b > 0`` and ``c > 0``, so the DC gain is positive. A
    pole ``a < 0`` (a sign flip every sample, which no sampled lag gives), ``|a| >= 1`` (no
    decay) and a zero or negative gain are refused.

    Parameters
    ----------
    n_axes : int
        Number of independent axes (3 for the satellite), at most ``max_axes``.
    a : float
        Pole, ``0 <= a < 1``.
    b, c : float
        Input gain and output gain, both ``> 0``.
    max_axes : int
        The largest ``n_axes`` accepted (default :data:`~models.actuators.MAX_AXES`, 1000); a
        larger ``n_axes`` is refused with an error naming this limit. Pass a larger value to lift it.

    Examples
    --------
    >>> from models import ReactionWheelActuator
    >>> act = ReactionWheelActuator()
    >>> round(act.dc_gain, 4)
    0.9486
    """

    def __init__(
        self,
        n_axes: int = 3,
        a: float = 0.86,
        b: float = 0.0093,
        c: float = 14.28,
        *,
        max_axes: int = MAX_AXES,
    ) -> None:
        limit = check_count(max_axes, "max_axes")
        n_axes = check_count(n_axes, "n_axes", limit=limit, limit_name="max_axes", unit=" axes")
        self.a = check_real(a, "a")
        if not 0.0 <= self.a < 1.0:
            expected = "a decaying first-order pole, 0 <= a < 1 (a = exp(-dt / tau))"
            raise InvalidArgumentError("a", expected, repr(self.a))
        self.b = _gain(b, "b", "input")
        self.c = _gain(c, "c", "output")
        self.n_axes = int(n_axes)
        self._state = np.zeros(n_axes)

    @property
    def dc_gain(self) -> float:
        """Steady-state gain from command to torque, ``c b / (1 - a)``."""
        return self.c * self.b / (1.0 - self.a)

    @property
    def state(self) -> np.ndarray:
        """Copy of the internal wheel states ``xa``."""
        return self._state.copy()

    def reset(self) -> None:
        """Zero the wheel states."""
        self._state = np.zeros(self.n_axes)

    def output(self) -> np.ndarray:
        """The torque delivered during the current sample, ``c xa(k)``."""
        return self.c * self._state

    def step(self, command: ArrayLike) -> np.ndarray:
        """Return the torque of this sample and advance the wheel states with ``command``."""
        ua = as_vector(command, "command", self.n_axes)
        torque = self.output()
        self._state = self.a * self._state + self.b * ua
        return torque


class TorqueLimiter:
    """A saturation block that clips commanded torques.

    Parameters
    ----------
    u_max : float or array_like
        Limit (N m); a scalar or one value per axis, all > 0.
    kind : {"box", "norm"}
        ``"box"`` clips each axis to ``[-u_max_i, u_max_i]`` (paper P's limiter);
        ``"norm"`` scales the vector down to ``||u||_2 <= u_max`` (scalar ``u_max`` only).

    Examples
    --------
    >>> from models import TorqueLimiter
    >>> TorqueLimiter(1.0)([2.0, -0.5, -3.0]).tolist()
    [1.0, -0.5, -1.0]
    """

    def __init__(self, u_max: ArrayLike, kind: Literal["box", "norm"] = "box") -> None:
        self.kind = check_choice(kind, "kind", ("box", "norm"))
        if np.ndim(u_max) == 0:
            self.u_max: float | np.ndarray = check_positive(u_max, "u_max")
        else:
            if kind == "norm":
                raise InvalidArgumentError("u_max", "a scalar for kind='norm'", repr(u_max))
            self.u_max = as_positive_values(u_max, "u_max", None, per="axis", what="limits")

    def __call__(self, u: ArrayLike) -> np.ndarray:
        """Return the clipped torque."""
        u = as_vector(u, "u")
        if self.kind == "box":
            return np.clip(u, -self.u_max, self.u_max)
        norm = float(np.linalg.norm(u))
        limit = float(self.u_max)
        return u if norm <= limit else u * (limit / norm)

    def is_saturated(self, u: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``u`` reaches or exceeds the limit."""
        u = as_vector(u, "u")
        if self.kind == "box":
            return bool(np.any(np.abs(u) >= np.asarray(self.u_max) * (1 - tol)))
        return bool(np.linalg.norm(u) >= float(self.u_max) * (1 - tol))
