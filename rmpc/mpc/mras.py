"""The pieces of a model reference adaptive system (MRAS): the estimate's integrator and filters.

:class:`ParameterIntegrator` integrates an adaptation rate by the discrete integrator
``Ts / (1 - z^-1)`` (forward Euler) with a projection onto ``|theta_i| <= bound_i``;
:class:`SensitivityFilter` produces sensitivity derivatives ``de/dtheta`` from measured
signals. The rules of :mod:`rmpc.mpc.adaptation` are built on them, and so is the tests'
reproduction of Astrom & Wittenmark's example 5.2 (*Adaptive Control*, 2nd ed.).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_matrix, as_optional_limits, as_vector, check_positive, check_real

__all__ = ["ParameterIntegrator", "SensitivityFilter"]


class ParameterIntegrator:
    """``theta(k+1) = Proj[theta(k) + Ts rate(k)]``: an adaptation law's discrete integrator.

    Parameters
    ----------
    n_params : int
        Number of parameters.
    dt : float
        Sample time ``Ts`` of the integrator ``Ts / (1 - z^-1)`` (s).
    bound : float or array_like, optional
        Projection: after each step ``|theta_i| <= bound_i`` is enforced by clipping
        (``None``: no bound).
    theta0 : array_like, optional
        Initial parameters (default zero); :meth:`reset` returns to them.

    Examples
    --------
    >>> from rmpc.mpc.mras import ParameterIntegrator
    >>> theta = ParameterIntegrator(2, dt=0.1, bound=1.0)
    >>> theta.step([2.0, -20.0]).tolist()
    [0.2, -1.0]
    """

    def __init__(
        self,
        n_params: int,
        dt: float,
        *,
        bound: ArrayLike | None = None,
        theta0: ArrayLike | None = None,
    ) -> None:
        if isinstance(n_params, bool) or not isinstance(n_params, int | np.integer) or n_params < 1:
            raise InvalidArgumentError("n_params", "a positive integer", repr(n_params))
        self.n_params = int(n_params)
        self.dt = check_positive(dt, "dt")
        n_p = self.n_params
        self.theta0 = np.zeros(n_p) if theta0 is None else as_vector(theta0, "theta0", n_p)
        self.bound = as_optional_limits(bound, "bound", self.n_params, per="parameter")
        if self.bound is not None and np.any(np.abs(self.theta0) > self.bound):
            raise InvalidArgumentError(
                "theta0", f"|theta0_i| <= bound_i = {self.bound.tolist()}", repr(self.theta0.tolist())
            )
        self._theta = self.theta0.copy()

    @property
    def theta(self) -> np.ndarray:
        """The current parameters (a copy)."""
        return self._theta.copy()

    def reset(self) -> None:
        """Return to ``theta0``."""
        self._theta = self.theta0.copy()

    def step(self, rate: ArrayLike) -> np.ndarray:
        """One step, ``theta(k+1) = Proj[theta(k) + Ts rate]``; returns ``theta(k+1)`` (a copy)."""
        self._integrate(as_vector(rate, "rate", self.n_params))
        return self._theta.copy()

    def _integrate(self, rate: np.ndarray) -> None:
        """:meth:`step` without the argument check (hot loops that built a valid rate)."""
        theta = self._theta + self.dt * rate
        if self.bound is not None:
            theta = np.clip(theta, -self.bound, self.bound)
        self._theta = theta

    def __repr__(self) -> str:
        return f"ParameterIntegrator(n_params={self.n_params}, dt={self.dt:g})"


class SensitivityFilter:
    """A discrete linear filter that produces sensitivity derivatives ``de/dtheta``.

    ``s(k+1) = A s(k) + B v(k)``, output ``w(k) = C s(k) + D v(k)``. The input ``v`` may be a
    vector ``(r,)`` or a matrix ``(r, columns)`` whose columns are filtered independently (one
    column per parameter), and ``A`` may be replaced at each step (a time-varying filter, as
    for a closed loop whose gain changes).

    Parameters
    ----------
    a : (n, n) array_like
    b : (n, r) array_like
    c : (p, n) array_like, optional
        Default: the identity (the output is the state).
    d : (p, r) array_like, optional
        Default: zero (the filter is strictly proper: the output at ``k`` depends on inputs
        up to ``k - 1`` only).
    columns : int, optional
        Number of columns of ``v`` (``None``: ``v`` is a vector).

    Examples
    --------
    ``am / (p + am)`` with ``am = 2`` sampled at 0.01 s (zero-order hold), unit DC gain:

    >>> from rmpc.mpc.mras import SensitivityFilter
    >>> filt = SensitivityFilter.first_order(pole=2.0, dt=0.01)
    >>> for _ in range(1000):
    ...     filt.advance([1.0])
    >>> round(float(filt.output()[0]), 6)
    1.0
    """

    def __init__(
        self,
        a: ArrayLike,
        b: ArrayLike,
        c: ArrayLike | None = None,
        d: ArrayLike | None = None,
        *,
        columns: int | None = None,
    ) -> None:
        self.a = as_matrix(a, "a")
        n = self.a.shape[0]
        self.a = as_matrix(self.a, "a", (n, n))
        self.b = as_matrix(b, "b", (n, None))
        r = self.b.shape[1]
        self.c = np.eye(n) if c is None else as_matrix(c, "c", (None, n))
        p = self.c.shape[0]
        self.d = np.zeros((p, r)) if d is None else as_matrix(d, "d", (p, r))
        if columns is not None and (
            isinstance(columns, bool) or not isinstance(columns, int | np.integer) or columns < 1
        ):
            raise InvalidArgumentError("columns", "None or a positive integer", repr(columns))
        self.columns = None if columns is None else int(columns)
        self._shape = (n,) if self.columns is None else (n, self.columns)
        self._state = np.zeros(self._shape)

    @classmethod
    def first_order(cls, pole: float, dt: float, gain: float = 1.0) -> SensitivityFilter:
        """``gain * pole / (p + pole)`` discretised with a zero-order hold at ``dt``."""
        pole = check_positive(pole, "pole")
        dt = check_positive(dt, "dt")
        gain = check_real(gain, "gain")
        decay = float(np.exp(-pole * dt))
        return cls([[decay]], [[gain * (1.0 - decay)]])

    @property
    def state(self) -> np.ndarray:
        """The filter state ``s(k)`` (a copy)."""
        return self._state.copy()

    def reset(self) -> None:
        """Zero the state."""
        self._state = np.zeros(self._shape)

    def _input(self, v: ArrayLike) -> np.ndarray:
        r = self.b.shape[1]
        if self.columns is None:
            return as_vector(v, "v", r)
        return as_matrix(v, "v", (r, self.columns))

    def output(self, v: ArrayLike | None = None) -> np.ndarray:
        """``C s(k) + D v(k)`` (``v`` may be left out when ``D = 0``)."""
        out = self.c @ self._state
        if v is not None:
            out = out + self.d @ self._input(v)
        elif np.any(self.d != 0.0):
            raise InvalidArgumentError("v", "the input v(k) (the filter has a direct term D)", "None")
        return out

    def advance(self, v: ArrayLike, a: ArrayLike | None = None) -> None:
        """``s(k+1) = A s(k) + B v(k)``; ``a`` replaces ``A`` for this step only."""
        n = self.a.shape[0]
        a_k = self.a if a is None else as_matrix(a, "a", (n, n))
        self._state = a_k @ self._state + self.b @ self._input(v)
