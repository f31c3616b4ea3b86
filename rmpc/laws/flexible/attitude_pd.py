"""Quaternion PD attitude control, optionally with a disturbance observer (paper S's baselines).

Source: paper S (Fathi and Bolandi's survey of flexible satellites, in Persian), section on PD/PID
control of flexible spacecraft:
``u = -K_d w - K_p rho`` (**certain**), the industrial anchor, with ``rho = q_v`` of the error
quaternion here; vibration decays only by the structural damping. With
``disturbance_observer=True``, paper S's ``u = -K_d w - K_p rho - d_hat`` (**certain**), ``d_hat``
lumping the disturbance and the appendages' reaction, from the observer
(**assumed**)::

    d_hat = z + L_o J_mb w,   z' = -L_o z - L_o (-w x J_mb w + u + L_o J_mb w)

which gives ``d_hat' = L_o (d_lumped - d_hat)``. ``u`` in the observer is this controller's own
output: when the plant clips it (``u_max``), pass ``u_max`` so that the observer uses the clipped
value (the controller then clips its output itself). Defaults (all **assumed**): ``K_p = 2 N m``,
``K_d = 30 N m s`` (a rigid-like loop, natural frequency ~0.06 rad/s, damping ~0.95 about the
axes of the published set), ``L_o = 0.5 1/s``.
"""

from __future__ import annotations

import time
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from models import FlexibleSatellite
from models.attitude.vectors import cross3
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms, gain_matrix
from toolkit_common.validation import check_bool, check_positive

__all__ = ["AttitudePD"]


class AttitudePD:
    """``u = -K_d w - K_p q_v (- d_hat)`` on the error quaternion; record name "PD" or "PD-DOB".

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model (``J_mb`` for the observer).
    dt : float
        Sample time (s); the observer advances by forward Euler.
    q_ref : (4,) array_like, optional
        Target attitude (default the identity).
    K_p, K_d : float, (3,) or (3, 3) array_like
        Attitude (N m) and rate (N m s) gains.
    disturbance_observer : bool
        Subtract the observer's estimate ``d_hat``.
    L_o : float
        Observer bandwidth (1/s).
    u_max : float, optional
        Per-axis clip of the output (so the observer sees the applied torque).

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from models.attitude.quaternion import quat_from_axis_angle
    >>> from rmpc.laws.flexible.attitude_pd import AttitudePD
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> pd = AttitudePD(sat)
    >>> u = pd.step(sat.state(quat_from_axis_angle([0, 0, 1], 0.2)))   # -K_p sin(0.1) about z
    >>> round(float(u[2]), 6), pd.name
    (-0.199667, 'PD')
    """

    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        q_ref: ArrayLike | None = None,
        K_p: ArrayLike = 2.0,
        K_d: ArrayLike = 30.0,
        disturbance_observer: bool = False,
        L_o: float = 0.5,
        u_max: float | None = None,
    ) -> None:
        self.terms = FlexibleTerms(plant, q_ref, flex_feedforward=False)
        self.dt = check_positive(dt, "dt")
        self.K_p = gain_matrix(K_p, "K_p")
        self.K_d = gain_matrix(K_d, "K_d")
        self.disturbance_observer = check_bool(disturbance_observer, "disturbance_observer")
        self.L_o = check_positive(L_o, "L_o")
        self.u_max = None if u_max is None else check_positive(u_max, "u_max")
        self.name: str = "PD-DOB" if disturbance_observer else "PD"
        self.last: StepInfo | None = None
        self.reset()

    def reset(self) -> None:
        """Observer state to zero (``d_hat = L_o J_mb w`` at the first sample)."""
        self._z = np.zeros(3)
        self.last = None

    def estimate(self, w: np.ndarray) -> np.ndarray:
        """The observer's ``d_hat`` for the current ``z`` and rate ``w``."""
        return self._z + self.L_o * (self.terms.hub_inertia @ w)

    def law(self, x: ArrayLike, d_hat: ArrayLike | None = None) -> np.ndarray:
        """The continuous-time law, a pure function: hub torque at ``x`` given ``d_hat`` (default 0)."""
        q, w, _, _ = self.terms.split(x)
        err = self.terms.error(q, w)
        u = -self.K_d @ w - self.K_p @ err.qv
        return u if d_hat is None else u - np.asarray(d_hat, dtype=float)

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``[u; v]`` for the measured state (``v = inputs.pzt``, this sample's PZT command, or 0).

        The law ignores ``v`` (PD cancels nothing); it is passed through so that
        :class:`~rmpc.FlexibleHybrid` can pair PD with vibration control.
        """
        start = time.perf_counter()
        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        _, w, _, _ = self.terms.split(x)
        d_hat = self.estimate(w) if self.disturbance_observer else None
        u = self.law(x, d_hat)
        if self.u_max is not None:
            u = np.clip(u, -self.u_max, self.u_max)
        extra: dict[str, Any] = {}
        if d_hat is not None:
            j_w = self.terms.hub_inertia @ w
            z_dot = -self.L_o * self._z - self.L_o * (-cross3(w, j_w) + u + self.L_o * j_w)
            self._z = self._z + self.dt * z_dot
            extra["d_hat"] = d_hat
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra=extra)
        return self.terms.command(u, pzt)

    def __repr__(self) -> str:
        return f"AttitudePD(name={self.name!r}, L_o={self.L_o:g}, dt={self.dt:g})"
