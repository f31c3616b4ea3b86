"""The second-order command filter of command-filtered backstepping, with magnitude and rate clips.

Farrell, Polycarpou, Sharma & Dong, "Command filtered backstepping", IEEE Trans. Automatic
Control 54(6), 2009; the form paper M cites
(paper M's own equations were lost, this standard form is **likely**)::

    q1' = q2
    q2' = 2 zeta wn [ S_R( wn / (2 zeta) (S_M(x0) - q1) ) - q2 ]
    x_c = q1,   x_c' = q2

``S_M`` and ``S_R`` clip each component at ``+-M`` and ``+-R`` (none by default). Without clips
the filter is ``wn^2 / (s^2 + 2 zeta wn s + wn^2)`` per component: DC gain 1 and, for
``zeta = 0.5``, ``wn = 2`` rad/s (**certain**; the unit rad/s **likely**), a 16.30 % overshoot
with its peak at 1.814 s. It supplies the commanded signal ``x_c`` *and its derivative*
``x_c'`` without differentiating anything analytically. With a rate clip and
``|q2(0)| <= R`` the output rate never exceeds ``R``.

The compensating signals ``chi`` that remove the filter's effect from the Lyapunov analysis
depend on the controller's gains and live in :class:`rmpc.CFBackstepping`.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rmpc.controller import StepInfo
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_optional_limits, as_vector, check_positive

__all__ = ["CommandFilter"]


class CommandFilter:
    """A second-order low-pass filter that outputs a command and its derivative, per component.

    Parameters
    ----------
    natural_frequency : float
        ``wn`` (rad/s), > 0. Paper M: 2 (**certain**).
    damping : float
        ``zeta``, > 0. Paper M: 0.5 (**certain**).
    magnitude_limit : float or (size,) array_like, optional
        ``M``: clip of the filter input, per component (default none).
    rate_limit : float or (size,) array_like, optional
        ``R``: clip of the output rate, per component (default none).
    size : int
        Number of components (3 for a body rate).
    dt : float
        Sample time of :meth:`step` (s), used only when the filter runs on its own; a
        controller that embeds the filter integrates :meth:`derivative` with its own step.

    Notes
    -----
    The filter state is ``q = [q1, q2]`` (``2 size`` entries). It starts at
    ``q1(0) = S_M(x0(0))``, ``q2(0) = 0`` (**assumed**): the first input sets it, so the filter
    starts at rest on its input and the output has no initial jump.

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc import CommandFilter
    >>> filt = CommandFilter(natural_frequency=2.0, damping=0.5, size=1, dt=0.01)
    >>> out = [filt.step([0.0]) for _ in range(1)] + [filt.step([1.0]) for _ in range(400)]
    >>> peak = max(float(o[0]) for o in out)
    >>> round(peak, 3)                      # 1 + exp(-pi zeta / sqrt(1 - zeta^2))
    1.163
    """

    def __init__(
        self,
        natural_frequency: float = 2.0,
        damping: float = 0.5,
        *,
        magnitude_limit: ArrayLike | None = None,
        rate_limit: ArrayLike | None = None,
        size: int = 3,
        dt: float = 0.01,
    ) -> None:
        self.natural_frequency = check_positive(natural_frequency, "natural_frequency")
        self.damping = check_positive(damping, "damping")
        if isinstance(size, bool) or not isinstance(size, int | np.integer) or size < 1:
            raise InvalidArgumentError("size", "a positive integer", repr(size))
        self.size = int(size)
        self.magnitude_limit = as_optional_limits(magnitude_limit, "magnitude_limit", self.size)
        self.rate_limit = as_optional_limits(rate_limit, "rate_limit", self.size)
        self.dt = check_positive(dt, "dt")
        self._state: np.ndarray | None = None
        self.last: StepInfo | None = None

    @property
    def n_states(self) -> int:
        """Size of the filter state ``[q1, q2]``."""
        return 2 * self.size

    def __repr__(self) -> str:
        return (
            f"CommandFilter(natural_frequency={self.natural_frequency!r}, damping={self.damping!r}, "
            f"magnitude_limit={None if self.magnitude_limit is None else self.magnitude_limit.tolist()}, "
            f"rate_limit={None if self.rate_limit is None else self.rate_limit.tolist()})"
        )

    def settings(self) -> dict[str, Any]:
        """The filter's parameters, for reports."""
        return {
            "natural_frequency": self.natural_frequency,
            "damping": self.damping,
            "magnitude_limit": None if self.magnitude_limit is None else self.magnitude_limit.tolist(),
            "rate_limit": None if self.rate_limit is None else self.rate_limit.tolist(),
        }

    # -- continuous time -----------------------------------------------------------------------
    def clip_input(self, x0: np.ndarray) -> np.ndarray:
        """``S_M(x0)``."""
        m = self.magnitude_limit
        return x0 if m is None else np.clip(x0, -m, m)

    def initial_state(self, x0: ArrayLike) -> np.ndarray:
        """``[S_M(x0), 0]``: at rest on the input."""
        x0 = as_vector(x0, "x0", self.size)
        return np.concatenate((self.clip_input(x0), np.zeros(self.size)))

    def derivative(self, q: np.ndarray, x0: np.ndarray) -> np.ndarray:
        """``q'`` for the filter state ``q = [q1, q2]`` and the input ``x0`` (pure, unchecked)."""
        k = self.size
        q1, q2 = q[:k], q[k:]
        zeta, wn = self.damping, self.natural_frequency
        rate = wn / (2.0 * zeta) * (self.clip_input(x0) - q1)
        if self.rate_limit is not None:
            rate = np.clip(rate, -self.rate_limit, self.rate_limit)
        return np.concatenate((q2, 2.0 * zeta * wn * (rate - q2)))

    # -- sampled, on its own ---------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the state; the next :meth:`step` starts the filter at rest on its input."""
        self._state = None
        self.last = None

    @property
    def output(self) -> tuple[np.ndarray, np.ndarray]:
        """``(x_c, x_c')`` now (after :meth:`step`: the values for the next sample)."""
        if self._state is None:
            raise InvalidArgumentError("state", "a filter that has been stepped once", "a reset filter")
        return self._state[: self.size].copy(), self._state[self.size :].copy()

    def step(self, x0: ArrayLike) -> np.ndarray:
        """Return ``x_c`` for this sample, then advance one RK4 step of ``dt`` with ``x0`` held.

        ``last.extra`` holds ``"rate"`` (``x_c'`` at this sample).
        """
        start = time.perf_counter()
        x0 = as_vector(x0, "x0", self.size)
        if self._state is None:
            self._state = self.initial_state(x0)
        q = self._state
        out, rate = q[: self.size].copy(), q[self.size :].copy()
        h = self.dt
        k1 = self.derivative(q, x0)
        k2 = self.derivative(q + 0.5 * h * k1, x0)
        k3 = self.derivative(q + 0.5 * h * k2, x0)
        k4 = self.derivative(q + h * k3, x0)
        self._state = q + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        self.last = StepInfo(status="ok", solve_time=time.perf_counter() - start, extra={"rate": rate})
        return out
