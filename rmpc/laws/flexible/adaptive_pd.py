"""Adaptive-gain PD attitude control (one of paper S's surveyed baselines).

Paper S (Fathi and Bolandi's survey of flexible satellites, in Persian) lists PD with gains adapted
online among the baselines without
a law. The toolkit's law (**assumed**): ``u = -k_d w - k_p q_v`` on the error quaternion with
scalar gains that grow with the error and leak back to their initial values, kept in a box by
projection::

    k_p' = gamma_p ||q_v||^2 - sigma (k_p - k_p0),   k_d' = gamma_d ||w||^2 - sigma (k_d - k_d0)
    k_p in [k_p0, k_p_max],   k_d in [k_d0, k_d_max]

the gradient update with the sigma-modification (leakage) and projection onto a known box of
P. A. Ioannou and J. Sun, "Robust Adaptive Control", Prentice Hall, 1996 (sections 8.5.2 and
8.5.3): the leakage lets the gains come down once the error has gone, the projection keeps them
bounded whatever the error. The gains advance by forward Euler each sample, then are clipped to
the box. Defaults (**assumed**): ``k_p0 = 2 N m``, ``k_d0 = 30 N m s`` (PD's), ``k_p_max = 8 N m``,
``k_d_max = 60 N m s``, ``gamma_p = 1 N m/s``, ``gamma_d = 500 N m s^3``, ``sigma = 0.05 1/s``.
"""

from __future__ import annotations

import time
from typing import Any, ClassVar

import numpy as np

from models import FlexibleSatellite
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_positive

__all__ = ["AdaptivePD"]


class AdaptivePD:
    """``u = -k_d(t) w - k_p(t) q_v`` with gains adapted online in a box; record name "APD".

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model (only its sizes are used).
    dt : float
        Sample time (s); the gains advance by forward Euler.
    q_ref : (4,) array_like, optional
        Target attitude (default the identity).
    k_p0, k_d0 : float
        Initial and lowest gains (N m, N m s), > 0.
    k_p_max, k_d_max : float
        Highest gains, at least the initial ones.
    gamma_p, gamma_d : float
        Adaptation rates (N m/s, N m s^3), >= 0.
    sigma : float
        Leakage towards the initial gains (1/s), >= 0.

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from models.attitude.quaternion import quat_from_axis_angle
    >>> from rmpc.laws.flexible.adaptive_pd import AdaptivePD
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> apd = AdaptivePD(sat, dt=0.1)
    >>> u = apd.step(sat.state(quat_from_axis_angle([0, 0, 1], 0.2)))   # -k_p0 sin(0.1) about z
    >>> round(float(u[2]), 6), round(apd.gains[0], 6), apd.name         # k_p += dt gamma_p sin^2(0.1)
    (-0.199667, 2.000997, 'APD')
    """

    name = "APD"
    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        q_ref: Any = None,
        k_p0: float = 2.0,
        k_d0: float = 30.0,
        k_p_max: float = 8.0,
        k_d_max: float = 60.0,
        gamma_p: float = 1.0,
        gamma_d: float = 500.0,
        sigma: float = 0.05,
    ) -> None:
        self.terms = FlexibleTerms(plant, q_ref, flex_feedforward=False)
        self.dt = check_positive(dt, "dt")
        self.k_p0 = check_positive(k_p0, "k_p0")
        self.k_d0 = check_positive(k_d0, "k_d0")
        self.k_p_max = check_positive(k_p_max, "k_p_max")
        self.k_d_max = check_positive(k_d_max, "k_d_max")
        for low, high, name in ((self.k_p0, self.k_p_max, "k_p_max"), (self.k_d0, self.k_d_max, "k_d_max")):
            if high < low:
                raise InvalidArgumentError(name, f"at least the initial gain {low:g}", f"{high:g}")
        self.gamma_p = check_positive(gamma_p, "gamma_p", allow_zero=True)
        self.gamma_d = check_positive(gamma_d, "gamma_d", allow_zero=True)
        self.sigma = check_positive(sigma, "sigma", allow_zero=True)
        self.last: StepInfo | None = None
        self.reset()

    def reset(self) -> None:
        """Gains back to their initial values."""
        self._k_p = self.k_p0
        self._k_d = self.k_d0
        self.last = None

    @property
    def gains(self) -> tuple[float, float]:
        """The current ``(k_p, k_d)``."""
        return self._k_p, self._k_d

    def law(self, x: Any, k_p: float, k_d: float) -> np.ndarray:
        """The continuous-time law, a pure function: the hub torque at ``x`` for gains ``k_p, k_d``."""
        q, w, _, _ = self.terms.split(x)
        return -k_d * w - k_p * self.terms.error(q, w).qv

    def step(self, x: Any, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``[u; v]`` for the measured state (``v = inputs.pzt``, this sample's PZT command, or 0)."""
        start = time.perf_counter()
        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        q, w, _, _ = self.terms.split(x)
        qv = self.terms.error(q, w).qv
        u = -self._k_d * w - self._k_p * qv  # self.law(x, k_p, k_d) without splitting x again
        extra = {"k_p": self._k_p, "k_d": self._k_d}
        k_p = self._k_p + self.dt * (self.gamma_p * float(qv @ qv) - self.sigma * (self._k_p - self.k_p0))
        k_d = self._k_d + self.dt * (self.gamma_d * float(w @ w) - self.sigma * (self._k_d - self.k_d0))
        self._k_p = min(max(k_p, self.k_p0), self.k_p_max)
        self._k_d = min(max(k_d, self.k_d0), self.k_d_max)
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra=extra)
        return self.terms.command(u, pzt)

    def __repr__(self) -> str:
        return f"AdaptivePD(k_p={self._k_p:g}, k_d={self._k_d:g}, dt={self.dt:g})"
