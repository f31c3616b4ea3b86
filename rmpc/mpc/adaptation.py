"""The adaptation rules of model reference adaptive systems (MRAS), in discrete time.

A model reference adaptive system compares the plant output ``y`` with the output ``ym`` of a
reference model and adjusts a parameter vector ``theta`` so that the error ``e = y - ym``
becomes small. The MIT rule (Astrom & Wittenmark, *Adaptive Control*, 2nd ed., section 5.2)
descends the gradient of ``J(theta) = e' e / 2``::

    dtheta/dt = -gamma (de/dtheta)' e                              (plain MIT rule)
    dtheta/dt = -gamma (de/dtheta)' e / (alpha + |de/dtheta|^2)    (normalised MIT rule)

``de/dtheta`` (the *sensitivity derivative*) is produced by filters driven by measured signals
(:class:`SensitivityFilter`). The time derivative is integrated by the discrete integrator
``Ts / (1 - z^-1)`` (forward Euler)::

    theta(k+1) = theta(k) - gamma Ts (de/dtheta)(k)' e(k) [/ (alpha + |de/dtheta|^2)]

The plain rule's speed scales with the square of the signal levels, so a large command or a
soft loop can make it unstable; the normalised rule divides that scale out and its speed is
set by ``gamma`` alone (Astrom & Wittenmark, chapter 5).

The tests reproduce Astrom & Wittenmark's example 5.2 (adaptation of a feedforward gain and a
feedback gain for a first-order plant) with :class:`MITRule` and :class:`SensitivityFilter`.
:class:`LyapunovRule` is the Lyapunov redesign of the same system. :class:`rmpc.CRMPC` uses these
pieces around robust MPC.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_positive, check_real

__all__ = [
    "LyapunovRule",
    "MITRule",
    "SensitivityFilter",
]

class MITRule:
    """Gradient (MIT-rule) adaptation of a parameter vector through a discrete integrator.

    Parameters
    ----------
    n_params : int
        Number of adjustable parameters.
    gain : float
        Adaptation gain ``gamma`` (>= 0; 0 freezes the parameters). Its unit is that of
        ``theta`` per second per unit of ``(de/dtheta)' e`` for the plain rule and
        1/s for the normalised rule.
    dt : float
        Sample time ``Ts`` of the integrator ``Ts / (1 - z^-1)`` (s).
    normalized : bool
        Divide the gradient by ``alpha + ||de/dtheta||_F^2`` (the normalised MIT rule).
    alpha : float
        Regularisation ``alpha > 0`` of the normalised rule; ignored by the plain rule.
    theta0 : array_like, optional
        Initial parameters (default zero); :meth:`reset` returns to them.
    bound : float or array_like, optional
        Projection: after each update ``|theta_i| <= bound_i`` is enforced by clipping
        (``None``: no bound).

    Examples
    --------
    One parameter, ``e = theta - 3`` (so ``de/dtheta = 1``): the rule drives ``theta`` to 3.

    >>> import numpy as np
    >>> from rmpc.mpc.adaptation import MITRule
    >>> rule = MITRule(1, gain=5.0, dt=0.01)
    >>> for _ in range(2000):
    ...     theta = rule.update(rule.theta - 3.0, np.ones((1, 1)))
    >>> round(float(theta[0]), 6)
    3.0
    """

    def __init__(
        self,
        n_params: int,
        gain: float,
        dt: float,
        *,
        normalized: bool = False,
        alpha: float = 1.0,
        theta0: Any = None,
        bound: Any = None,
    ) -> None:
        if isinstance(n_params, bool) or not isinstance(n_params, int | np.integer) or n_params < 1:
            raise InvalidArgumentError("n_params", "a positive integer", repr(n_params))
        self.n_params = int(n_params)
        self.gain = check_positive(gain, "gain", allow_zero=True)
        self.dt = check_positive(dt, "dt")
        if not isinstance(normalized, bool | np.bool_):
            found = f"{type(normalized).__name__} {normalized!r}"
            raise ArgumentTypeError("normalized", "True or False", found)
        self.normalized = bool(normalized)
        self.alpha = check_positive(alpha, "alpha")
        n_p = self.n_params
        self.theta0 = np.zeros(n_p) if theta0 is None else as_vector(theta0, "theta0", n_p)
        self.bound = _bound(bound, "bound", self.n_params)
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

    def rate(self, error: Any, sensitivity: Any) -> np.ndarray:
        """``dtheta/dt`` of the (plain or normalised) MIT rule for this error and sensitivity.

        Parameters
        ----------
        error : array_like, shape (p,)
            The model-following error ``e = y - ym``.
        sensitivity : array_like, shape (p, n_params)
            ``de/dtheta``, column ``i`` the sensitivity of ``e`` to ``theta_i``.
        """
        e = as_vector(error, "error")
        sens = as_matrix(sensitivity, "sensitivity", (e.shape[0], self.n_params))
        grad = sens.T @ e
        if self.normalized:
            grad = grad / (self.alpha + float(np.sum(sens * sens)))
        return -self.gain * grad

    def update(self, error: Any, sensitivity: Any) -> np.ndarray:
        """One step of the integrator, ``theta(k+1) = theta(k) + Ts * rate``; returns ``theta(k+1)``."""
        self._integrate(self.rate(error, sensitivity))
        return self._theta.copy()

    def _gradient_step(self, e: np.ndarray, sens: np.ndarray) -> None:
        """:meth:`update` without the argument checks (hot loops that built valid arrays)."""
        grad = sens.T @ e
        if self.normalized:
            grad = grad / (self.alpha + float(np.sum(sens * sens)))
        self._integrate(-self.gain * grad)

    def _integrate(self, rate: np.ndarray) -> None:
        theta = self._theta + self.dt * rate
        if self.bound is not None:
            theta = np.clip(theta, -self.bound, self.bound)
        self._theta = theta

    def __repr__(self) -> str:
        kind = "normalised" if self.normalized else "plain"
        return f"MITRule(n_params={self.n_params}, gain={self.gain:g}, dt={self.dt:g}, {kind})"


#: Relative eigenvalue below which ``B' P B`` counts as singular (inputs that B maps onto each other).
RANK_TOL = 1e-10


class LyapunovRule:
    """Lyapunov-based adaptation of an input-disturbance estimate (MRAS with a stability proof).

    For a plant ``z' = A z + B_t (u + d)`` whose input matrix is ``B_t = c B`` with an unknown
    ``c > 0`` (an inertia scale), the control ``u = F z - theta``, the reference model
    ``zm' = (A + B F) zm`` and the error ``e = z - zm``, the law::

        dtheta/dt = Gamma B' P e,    Gamma = g (B' P B)^-1

    with ``P > 0`` a common Lyapunov matrix of the closed loops ``A + c B F`` over the
    uncertainty set, makes ``V = e' P e + c (d - theta)' Gamma^-1 (d - theta)`` non-increasing
    for a constant ``d`` (``V' = e' ((A + cBF)' P + P (A + cBF)) e`` plus a term in ``zm``,
    which decays): ``e`` and ``theta`` stay bounded and, with ``zm -> 0``, ``theta -> d``
    (Astrom & Wittenmark, *Adaptive Control*, 2nd ed., section 5.3, the Lyapunov redesign of the
    MIT rule; the argument needs only the sign of ``c``). The normalisation by
    ``B' P B`` gives ``g`` the unit 1/s^2 whatever the scale of ``P`` and ``B``: ``sqrt(g)`` is
    of the order of the estimator's bandwidth in rad/s.

    In discrete time (sample ``Ts``) the law is integrated by forward Euler, with the
    delta-operator input matrix ``B_delta = B_d / Ts`` of the sampled model (which tends to
    ``B`` as ``Ts -> 0``)::

        theta(k) = Proj[ theta(k-1) + Ts g (B_delta' P B_delta)^-1 B_delta' P e(k) ]

    and the projection clips ``|theta_i| <= bound_i``. With more inputs than ``B`` has rank
    (four reaction wheels for three axes), ``B' P B`` is singular and its pseudo-inverse is used:
    the rate is the minimum-norm one, in the range of ``B'``; a combination of inputs that ``B``
    maps to zero cannot be estimated and is not moved.

    Parameters
    ----------
    n_params : int
        Number of parameters (inputs).
    gain : float
        ``g`` (1/s^2, >= 0; 0 freezes the estimate).
    dt : float
        Sample time ``Ts`` (s).
    bound : float or array_like, optional
        Projection bound per parameter (``None``: none).
    theta0 : array_like, optional
        Initial estimate (default zero).

    Examples
    --------
    One input, ``B = [0, 1]'`` (a double integrator), ``P = I``, an error purely in the rate:
    the estimate moves by ``Ts g e_rate`` per step.

    >>> import numpy as np
    >>> from rmpc.mpc.adaptation import LyapunovRule
    >>> rule = LyapunovRule(1, gain=100.0, dt=0.01)
    >>> rule.update(np.array([0.0, 0.5]), np.array([[0.0], [1.0]]), np.eye(2)).tolist()
    [0.5]
    """

    def __init__(
        self, n_params: int, gain: float, dt: float, *, bound: Any = None, theta0: Any = None
    ) -> None:
        if isinstance(n_params, bool) or not isinstance(n_params, int | np.integer) or n_params < 1:
            raise InvalidArgumentError("n_params", "a positive integer", repr(n_params))
        self.n_params = int(n_params)
        self.gain = check_positive(gain, "gain", allow_zero=True)
        self.dt = check_positive(dt, "dt")
        n_p = self.n_params
        self.theta0 = np.zeros(n_p) if theta0 is None else as_vector(theta0, "theta0", n_p)
        self.bound = _bound(bound, "bound", self.n_params)
        if self.bound is not None and np.any(np.abs(self.theta0) > self.bound):
            raise InvalidArgumentError(
                "theta0", f"|theta0_i| <= bound_i = {self.bound.tolist()}", repr(self.theta0.tolist())
            )
        self._theta = self.theta0.copy()

    @property
    def theta(self) -> np.ndarray:
        """The current estimate (a copy)."""
        return self._theta.copy()

    def reset(self) -> None:
        """Return to ``theta0``."""
        self._theta = self.theta0.copy()

    def rate(self, error: Any, b_delta: Any, p_mat: Any) -> np.ndarray:
        """``dtheta/dt = g (B' P B)^-1 B' P e`` for the error, input matrix and Lyapunov matrix.

        Parameters
        ----------
        error : (n,) array_like
            ``e = z - zm``.
        b_delta : (n, n_params) array_like
            The input matrix ``B`` (continuous time, or ``B_d / Ts`` of the sampled model).
        p_mat : (n, n) array_like
            The Lyapunov matrix ``P`` (symmetric positive definite).
        """
        e = as_vector(error, "error")
        b = as_matrix(b_delta, "b_delta", (e.shape[0], self.n_params))
        p = as_matrix(p_mat, "p_mat", (e.shape[0], e.shape[0]))
        return self._rate(e, b, p)

    def _rate(self, e: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
        pb = p @ b
        gram = b.T @ pb
        eig = np.linalg.eigvalsh(gram)
        if eig[0] > RANK_TOL * eig[-1]:
            return self.gain * np.linalg.solve(gram, pb.T @ e)
        # More inputs than B has rank (e.g. four wheels for three axes): the minimum-norm rate,
        # in the range of B'; components of theta that B maps to zero are left where they are.
        return self.gain * (np.linalg.pinv(gram, rcond=RANK_TOL, hermitian=True) @ (pb.T @ e))

    def update(self, error: Any, b_delta: Any, p_mat: Any) -> np.ndarray:
        """One forward-Euler step of the law, projected; returns the new estimate."""
        theta = self._theta + self.dt * self.rate(error, b_delta, p_mat)
        if self.bound is not None:
            theta = np.clip(theta, -self.bound, self.bound)
        self._theta = theta
        return self._theta.copy()

    def __repr__(self) -> str:
        return f"LyapunovRule(n_params={self.n_params}, gain={self.gain:g}, dt={self.dt:g})"


def _bound(value: Any, name: str, size: int) -> np.ndarray | None:
    """``None`` or positive bounds, one per parameter (a scalar is broadcast)."""
    if value is None:
        return None
    if np.ndim(value) == 0:
        arr = np.full(size, check_real(value, name))
    else:
        arr = as_vector(value, name, size)
    if np.any(arr <= 0.0):
        raise InvalidArgumentError(name, "positive bounds (or None)", repr(arr.tolist()))
    return arr


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

    >>> from rmpc.mpc.adaptation import SensitivityFilter
    >>> filt = SensitivityFilter.first_order(pole=2.0, dt=0.01)
    >>> for _ in range(1000):
    ...     filt.advance([1.0])
    >>> round(float(filt.output()[0]), 6)
    1.0
    """

    def __init__(self, a: Any, b: Any, c: Any = None, d: Any = None, *, columns: int | None = None) -> None:
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

    def _input(self, v: Any) -> np.ndarray:
        r = self.b.shape[1]
        if self.columns is None:
            return as_vector(v, "v", r)
        return as_matrix(v, "v", (r, self.columns))

    def output(self, v: Any = None) -> np.ndarray:
        """``C s(k) + D v(k)`` (``v`` may be left out when ``D = 0``)."""
        out = self.c @ self._state
        if v is not None:
            out = out + self.d @ self._input(v)
        elif np.any(self.d != 0.0):
            raise InvalidArgumentError("v", "the input v(k) (the filter has a direct term D)", "None")
        return out

    def advance(self, v: Any, a: Any = None) -> None:
        """``s(k+1) = A s(k) + B v(k)``; ``a`` replaces ``A`` for this step only."""
        n = self.a.shape[0]
        a_k = self.a if a is None else as_matrix(a, "a", (n, n))
        self._state = a_k @ self._state + self.b @ self._input(v)
