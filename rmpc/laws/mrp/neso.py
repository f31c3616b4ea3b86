"""The reduced-order nonlinear extended state observer (NESO) of paper M, with Han's ``fal``.

J. Han, "From PID to active disturbance rejection control", IEEE Trans. Industrial Electronics
56(3), 2009 (the form is **likely**: paper M's equations were lost).
It estimates the lumped unknown acceleration ``d``
of the rate equation ``w' = f2(w) + J0^-1 Tc + d`` (reduced order, **certain**: the disturbance
does not enter the kinematics)::

    f2(w) = -J0^-1 (w x J0 w),      e = what - w
    what' = f2(w) + J0^-1 Tc + dhat - beta1 * fal(e, alpha1, delta)
    dhat' = Proj_B( -beta2 * fal(e, alpha2, delta) ),      Tdhat = J0 dhat
    fal(e, alpha, delta) = |e|^alpha sign(e)  if |e| > delta,   e / delta^(1 - alpha)  otherwise

(``*`` and ``fal`` act per component). ``delta > 0``, ``0 < alpha <= 1`` and positive gains are
**certain**; ``alpha = 1`` is a linear extended (Luenberger) observer.

Toolkit choices (**assumed**):

- gains from a bandwidth ``w_o`` (:meth:`NESO.from_bandwidth`): the linear observer with a
  double pole at ``-w_o`` inside ``|e| <= delta``, ``beta1 = 2 w_o delta^(1 - alpha1)``,
  ``beta2 = w_o^2 delta^(1 - alpha2)`` (lower gain outside). Defaults ``w_o = 10`` rad/s,
  ``alpha1 = 0.5``, ``alpha2 = 0.25``, ``delta = 0.01`` rad/s: ``beta1 = 2.0``,
  ``beta2 = 3.1623``;
- projection on the box ``|dhat_i| <= B`` (``B = 0.05`` rad/s^2): the rate of a component at
  its bound is zeroed when it points outward, and the state is clipped after each step;
- ``what(0) = w(0)``, ``dhat(0) = 0``.

For a constant ``d``, ``J = J0`` and ``e`` in the linear zone,
``dhat(t) = d [1 - (1 + w_o t) exp(-w_o t)]``: within 1 % of ``d`` from ``t = 6.6384 / w_o``.
``Tdhat = J0 dhat`` equals the true torque only when ``J = J0``; with a model error it also
absorbs the inertia mismatch (a lumped disturbance).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.vectors import cross3
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_inertia, as_positive_values, as_vector, check_positive

__all__ = ["NESO", "fal"]


def _exponent(value: Any, name: str) -> float:
    alpha = check_positive(value, name)
    if alpha > 1.0:
        raise InvalidArgumentError(name, "an exponent in (0, 1]", repr(alpha))
    return alpha


def fal(e: ArrayLike, alpha: float, delta: float) -> np.ndarray:
    """Han's ``fal``: ``|e|^alpha sign(e)`` for ``|e| > delta``, ``e / delta^(1 - alpha)`` inside.

    Continuous at ``|e| = delta``, odd, and the identity for ``alpha = 1``.

    Parameters
    ----------
    e : array_like
        Error, any shape (per component).
    alpha : float
        Exponent in ``(0, 1]``.
    delta : float
        Width of the linear zone, > 0.

    Examples
    --------
    >>> from rmpc.laws.mrp.neso import fal
    >>> fal([0.005, 0.04, -0.04], alpha=0.5, delta=0.01).round(4).tolist()
    [0.05, 0.2, -0.2]
    """
    alpha = _exponent(alpha, "alpha")
    delta = check_positive(delta, "delta")
    return _fal(np.asarray(e, dtype=float), alpha, delta)


def _fal(e: np.ndarray, alpha: float, delta: float) -> np.ndarray:
    abs_e = np.abs(e)
    return np.where(abs_e > delta, np.sign(e) * abs_e**alpha, e / delta ** (1.0 - alpha))


class NESO:
    """Nonlinear extended state observer of the rate equation, with a box projection.

    A pure object: the observer state ``z = [what, dhat]`` is held by its user (a controller,
    or a test integrating it with ``solve_ivp``); :meth:`derivative` is its right-hand side.

    Parameters
    ----------
    inertia : array_like
        The model inertia ``J0`` (three principal values or a ``3 x 3`` SPD matrix, kg m^2).
    gain1, gain2 : float or (3,) array_like
        ``beta1`` and ``beta2`` (> 0). :meth:`from_bandwidth` chooses them from ``w_o``.
    alpha1, alpha2 : float
        ``fal`` exponents in ``(0, 1]``.
    delta : float
        Linear-zone width of ``fal`` (rad/s), > 0.
    bound : float or (3,) array_like
        ``B``: the box ``|dhat_i| <= B_i`` (rad/s^2), > 0.

    Examples
    --------
    >>> from rmpc import NESO
    >>> neso = NESO.from_bandwidth([3.0, 3.0, 2.0])
    >>> neso.gain1.round(4).tolist(), neso.gain2.round(4).tolist()
    ([2.0, 2.0, 2.0], [3.1623, 3.1623, 3.1623])
    >>> NESO.linear([3.0, 3.0, 2.0], bandwidth=10.0).gain2.tolist()   # alpha = 1: w_o^2
    [100.0, 100.0, 100.0]
    """

    n_states = 6

    def __init__(
        self,
        inertia: ArrayLike,
        gain1: ArrayLike,
        gain2: ArrayLike,
        *,
        alpha1: float = 0.5,
        alpha2: float = 0.25,
        delta: float = 0.01,
        bound: ArrayLike = 0.05,
    ) -> None:
        self._inertia = as_inertia(inertia)
        self._inertia_inv = np.linalg.inv(self._inertia)
        self.gain1 = as_positive_values(gain1, "gain1", 3, per="axis")
        self.gain2 = as_positive_values(gain2, "gain2", 3, per="axis")
        self.alpha1 = _exponent(alpha1, "alpha1")
        self.alpha2 = _exponent(alpha2, "alpha2")
        self.delta = check_positive(delta, "delta")
        self.bound = as_positive_values(bound, "bound", 3, per="axis")
        self.bandwidth: float | None = None
        for arr in (self._inertia, self._inertia_inv, self.gain1, self.gain2, self.bound):
            arr.setflags(write=False)

    @classmethod
    def from_bandwidth(
        cls,
        inertia: ArrayLike,
        bandwidth: float = 10.0,
        *,
        alpha1: float = 0.5,
        alpha2: float = 0.25,
        delta: float = 0.01,
        bound: Any = 0.05,
    ) -> NESO:
        """Gains matching the linear observer with a double pole at ``-bandwidth`` for ``|e| <= delta``.

        ``beta1 = 2 w_o delta^(1 - alpha1)``, ``beta2 = w_o^2 delta^(1 - alpha2)`` (**assumed**
        rule; defaults **assumed**: paper M's values were lost).
        """
        w_o = check_positive(bandwidth, "bandwidth")
        a1, a2 = _exponent(alpha1, "alpha1"), _exponent(alpha2, "alpha2")
        d = check_positive(delta, "delta")
        obs = cls(
            inertia, 2.0 * w_o * d ** (1.0 - a1), w_o**2 * d ** (1.0 - a2),
            alpha1=a1, alpha2=a2, delta=d, bound=bound,
        )
        obs.bandwidth = w_o
        return obs

    @classmethod
    def linear(cls, inertia: ArrayLike, bandwidth: float = 10.0, *, bound: Any = 0.05) -> NESO:
        """The linear extended state observer (``alpha1 = alpha2 = 1``), poles at ``-bandwidth``."""
        return cls.from_bandwidth(inertia, bandwidth, alpha1=1.0, alpha2=1.0, delta=1.0, bound=bound)

    @property
    def inertia(self) -> np.ndarray:
        """The model inertia ``J0`` (read-only)."""
        return self._inertia

    def __repr__(self) -> str:
        return (
            f"NESO(bandwidth={self.bandwidth!r}, gain1={self.gain1.tolist()}, "
            f"gain2={self.gain2.tolist()}, alpha1={self.alpha1!r}, alpha2={self.alpha2!r}, "
            f"delta={self.delta!r}, bound={self.bound.tolist()})"
        )

    def settings(self) -> dict[str, Any]:
        """The observer's parameters, for reports."""
        return {
            "estimator": "NESO" if (self.alpha1, self.alpha2) != (1.0, 1.0) else "linear ESO",
            "bandwidth": self.bandwidth,
            "gain1": self.gain1.tolist(),
            "gain2": self.gain2.tolist(),
            "alpha1": self.alpha1,
            "alpha2": self.alpha2,
            "delta": self.delta,
            "bound": self.bound.tolist(),
        }

    def initial_state(self, w: ArrayLike) -> np.ndarray:
        """``[w(0), 0]``."""
        return np.concatenate((as_vector(w, "w", 3), np.zeros(3)))

    def derivative(self, z: np.ndarray, w: np.ndarray, torque: np.ndarray) -> np.ndarray:
        """``z'`` for the observer state ``z = [what, dhat]``, measured rate ``w`` and applied
        control torque ``torque`` (pure, unchecked)."""
        what, dhat = z[:3], z[3:6]
        e = what - w
        f2 = -self._inertia_inv @ cross3(w, self._inertia @ w)
        what_dot = f2 + self._inertia_inv @ torque + dhat - self.gain1 * _fal(e, self.alpha1, self.delta)
        dhat_dot = -self.gain2 * _fal(e, self.alpha2, self.delta)
        outward = ((dhat >= self.bound) & (dhat_dot > 0.0)) | ((dhat <= -self.bound) & (dhat_dot < 0.0))
        return np.concatenate((what_dot, np.where(outward, 0.0, dhat_dot)))

    def project(self, z: np.ndarray) -> np.ndarray:
        """Clip ``dhat`` to the box (after a discrete step)."""
        return np.concatenate((z[:3], np.clip(z[3:6], -self.bound, self.bound)))

    def torque_estimate(self, z: np.ndarray) -> np.ndarray:
        """``Tdhat = J0 dhat`` (N m)."""
        return self._inertia @ z[3:6]

    def advance(self, z: ArrayLike, w: ArrayLike, torque: ArrayLike, dt: float) -> np.ndarray:
        """One RK4 step of length ``dt`` with ``w`` and ``torque`` held, then the projection."""
        z = as_vector(z, "z", 6)
        w = as_vector(w, "w", 3)
        torque = as_vector(torque, "torque", 3)
        h = check_positive(dt, "dt")
        k1 = self.derivative(z, w, torque)
        k2 = self.derivative(z + 0.5 * h * k1, w, torque)
        k3 = self.derivative(z + 0.5 * h * k2, w, torque)
        k4 = self.derivative(z + h * k3, w, torque)
        return self.project(z + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
