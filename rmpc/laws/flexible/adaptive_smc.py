"""Adaptive sliding-mode attitude control (paper S's adaptive SMC baseline).

Source: paper S (Fathi and Bolandi's survey of flexible satellites, in Persian) prints the adaptive
part (**certain**), added to an
SMC equivalent control::

    u_ad = -(s / ||s||) (b0h + p1h Phi1)   if ||s|| >= s_b,   else -(s / s_b) (b0h + p1h Phi1)
    Phi1 = 1 + ||w||^2,   b0h' = n0 (||s|| - e0 b0h),   p1h' = n1 (||s|| Phi1 - e1 p1h)

Paper S prints the surface ``s = x + c x'``; the toolkit uses ``s = w + lambda q_v``. The
equivalent control is the CSMC law of
:mod:`rmpc.laws.flexible.csmc` without its switching term (gyroscopic and modal-reaction cancellation,
``-lambda J_mb q_v'``, ``-K_s s``); the adaptive term replaces the constant switching gain.
Defaults (all **assumed**; paper S gives no gains): ``lambda = 0.1 1/s``, ``K_s = 20 N m s`` (as
CSMC's), ``s_b = 0.01 rad/s``, ``n0 = n1 = 10``, ``e0 = e1 = 0.1``, ``b0h(0) = 0.1 N m``,
``p1h(0) = 0``. The gains advance by forward Euler each sample and stay non-negative.
"""

from __future__ import annotations

import time
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from models import FlexibleSatellite
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms, gain_matrix
from toolkit_common.validation import check_positive

__all__ = ["AdaptiveSMC"]


class AdaptiveSMC:
    """SMC equivalent control plus paper S's adaptive switching gain; record name "ASMC".

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model.
    dt : float
        Sample time (s).
    q_ref : (4,) array_like, optional
        Target attitude (default the identity).
    lam : float
        Surface slope (1/s).
    K_s : float, (3,) or (3, 3) array_like
        Proportional gain of the equivalent control (N m s).
    s_b : float
        Boundary-layer radius (rad/s).
    n0, e0, n1, e1 : float
        Adaptation rates and leakages.
    b0_init, p1_init : float
        Initial adaptive gains (N m, N m s^2).
    flex_feedforward : bool
        Cancel the modal reaction with the measured ``eta, eta'``.

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from models.attitude.quaternion import quat_from_axis_angle
    >>> from rmpc.laws.flexible.adaptive_smc import AdaptiveSMC
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> ctrl = AdaptiveSMC(sat)
    >>> u = ctrl.step(sat.state(quat_from_axis_angle([0, 0, 1], 0.2)))  # -K_s s - b0h s/s_b
    >>> round(float(u[2]), 6), ctrl.name
    (-0.2995, 'ASMC')
    """

    name = "ASMC"
    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        q_ref: ArrayLike | None = None,
        lam: float = 0.1,
        K_s: ArrayLike = 20.0,
        s_b: float = 0.01,
        n0: float = 10.0,
        e0: float = 0.1,
        n1: float = 10.0,
        e1: float = 0.1,
        b0_init: float = 0.1,
        p1_init: float = 0.0,
        flex_feedforward: bool = True,
    ) -> None:
        self.terms = FlexibleTerms(plant, q_ref, flex_feedforward)
        self.dt = check_positive(dt, "dt")
        self.lam = check_positive(lam, "lam")
        self.K_s = gain_matrix(K_s, "K_s")
        self.s_b = check_positive(s_b, "s_b")
        self.n0 = check_positive(n0, "n0", allow_zero=True)
        self.e0 = check_positive(e0, "e0", allow_zero=True)
        self.n1 = check_positive(n1, "n1", allow_zero=True)
        self.e1 = check_positive(e1, "e1", allow_zero=True)
        self.b0_init = check_positive(b0_init, "b0_init", allow_zero=True)
        self.p1_init = check_positive(p1_init, "p1_init", allow_zero=True)
        self.last: StepInfo | None = None
        self.reset()

    def reset(self) -> None:
        """Adaptive gains back to their initial values."""
        self._b0 = self.b0_init
        self._p1 = self.p1_init
        self.last = None

    def law(
        self,
        x: ArrayLike,
        b0: float,
        p1: float,
        v: ArrayLike | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The continuous-time law, a pure function: ``(u, s)`` at ``x`` for gains ``b0, p1``.

        ``v`` is this sample's PZT command (its reaction on the hub is cancelled; ``None``: 0).
        """
        q, w, eta, eta_dot = self.terms.split(x)
        err = self.terms.error(q, w)
        s = w + self.lam * err.qv
        u_eq = self.terms.sliding_torque(
            w, eta, eta_dot, self.terms.pzt(v), s, self.lam * err.qv_dot, self.K_s, 0.0, 1.0, "tanh"
        )
        norm = float(np.linalg.norm(s))
        gain = b0 + p1 * (1.0 + float(w @ w))
        u_ad = -(s / max(norm, self.s_b)) * gain
        return u_eq + u_ad, s

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``[u; v]`` for the measured state (``v = inputs.pzt``, this sample's PZT command, or 0)."""
        start = time.perf_counter()
        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        u, s = self.law(x, self._b0, self._p1, pzt)
        _, w, _, _ = self.terms.split(x)
        norm = float(np.linalg.norm(s))
        extra = {"sigma": s, "b0": self._b0, "p1": self._p1}
        self._b0 = max(0.0, self._b0 + self.dt * self.n0 * (norm - self.e0 * self._b0))
        self._p1 = max(0.0, self._p1 + self.dt * self.n1 * (norm * (1.0 + float(w @ w)) - self.e1 * self._p1))
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra=extra)
        return self.terms.command(u, pzt)

    def __repr__(self) -> str:
        return f"AdaptiveSMC(lam={self.lam:g}, s_b={self.s_b:g}, dt={self.dt:g})"
