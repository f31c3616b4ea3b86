"""Classical sliding-mode attitude control (CSMC) of a flexible satellite, paper V's baseline.

Source: paper V's 2x2 study compares its MTSMC with a "classical SMC" whose equation it does not
print; the toolkit (**assumed**) takes the MTSMC law of
:mod:`rmpc.laws.flexible.mtsmc` with a fixed slope ``lambda``, a constant switching gain and no integral::

    sigma = w + lambda q_v
    u = w x (J w + delta' eta') - delta' M^-1 (C eta' + K eta - Gamma_a v)
        - lambda J_mb q_v' - K_s sigma - W_0 switch(sigma)

``switch="sign"`` (default; the classical discontinuous law, which chatters at the sample rate)
or ``"tanh"`` (``tanh(sigma/eps)``, boundary-layer SMC, also paper S's baseline). A slew from rest
starts off the surface, ``sigma(0) = lambda q_v(0)``: CSMC has a reaching phase. Defaults equal
MTSMC's (``lambda = alpha_f = 0.1 1/s``, ``K_s = 20 N m s``, ``W_0 = 1 N m``, ``eps = 0.01 rad/s``;
all **assumed**). The torque is not saturated here (the plant's limiter clips it).
"""

from __future__ import annotations

import time
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from models import FlexibleSatellite
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms, SwitchKind, check_switch, gain_matrix
from toolkit_common.validation import check_positive

__all__ = ["CSMC"]


class CSMC:
    """Sliding-mode attitude control on the fixed surface ``sigma = w + lambda q_v``.

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model (nominal parameters).
    dt : float
        Sample time (s).
    q_ref : (4,) array_like, optional
        Target attitude (unit quaternion, at rest); default the identity.
    lam : float
        Surface slope ``lambda`` (1/s).
    K_s : float, (3,) or (3, 3) array_like
        Proportional reaching gain (N m s).
    W_0 : float
        Switching gain (N m).
    switch : {"sign", "tanh"}
        Switching function.
    eps : float
        Boundary-layer width for ``"tanh"`` (rad/s).
    flex_feedforward : bool
        Cancel the modal reaction with the measured ``eta, eta'``.

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from models.attitude.quaternion import quat_from_axis_angle
    >>> from rmpc import CSMC
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> ctrl = CSMC(sat, switch="tanh")
    >>> x0 = sat.state(quat_from_axis_angle([0, 0, 1], 0.5))
    >>> u = ctrl.step(x0)     # [u (3); v (4)]: -K_s sigma - W_0 tanh(sigma/eps) at rest
    >>> [round(float(val), 4) for val in u[:3]], round(float(ctrl.last.extra["sigma"][2]), 4)
    ([0.0, 0.0, -1.4807], 0.0247)
    """

    name = "CSMC"
    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        q_ref: ArrayLike | None = None,
        lam: float = 0.1,
        K_s: ArrayLike = 20.0,
        W_0: float = 1.0,
        switch: SwitchKind = "sign",
        eps: float = 0.01,
        flex_feedforward: bool = True,
    ) -> None:
        self.terms = FlexibleTerms(plant, q_ref, flex_feedforward)
        self.dt = check_positive(dt, "dt")
        self.lam = check_positive(lam, "lam")
        self.K_s = gain_matrix(K_s, "K_s")
        self.W_0 = check_positive(W_0, "W_0", allow_zero=True)
        self.switch: SwitchKind = check_switch(switch)
        self.eps = check_positive(eps, "eps")
        self.last: StepInfo | None = None

    def reset(self) -> None:
        """Nothing to forget but the last step's info (the law is static)."""
        self.last = None

    def law(self, x: ArrayLike, v: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The continuous-time law, a pure function: ``(u, sigma)`` at ``x`` (``v``: PZT command)."""
        q, w, eta, eta_dot = self.terms.split(x)
        err = self.terms.error(q, w)
        sigma = w + self.lam * err.qv
        u = self.terms.sliding_torque(
            w, eta, eta_dot, self.terms.pzt(v), sigma, self.lam * err.qv_dot, self.K_s, self.W_0,
            self.eps, self.switch,
        )
        return u, sigma

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return the plant input ``[u; v]`` (``3 + n_a``) for the measured state.

        ``inputs.pzt`` is this sample's PZT command ``v`` (from the vibration controller;
        ``None``: zero); it is passed through so that the output is the plant's whole input
        vector.
        """
        start = time.perf_counter()
        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        u, sigma = self.law(x, pzt)
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra={"sigma": sigma})
        return self.terms.command(u, pzt)

    def __repr__(self) -> str:
        return (
            f"CSMC(lam={self.lam:g}, W_0={self.W_0:g}, switch={self.switch!r}, eps={self.eps:g}, "
            f"dt={self.dt:g})"
        )
