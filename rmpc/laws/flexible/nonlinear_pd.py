"""Nonlinear (saturated) PD attitude control (one of paper S's surveyed baselines).

Paper S (Fathi and Bolandi's survey of flexible satellites, in Persian) lists nonlinear PD among
the industrial baselines without an
equation. The toolkit's form (**assumed**) saturates the proportional term per axis::

    u = -K_d w - K_p sat(q_v, q_s),   sat(q_v, q_s)_i = min(max(q_v,i, -q_s), q_s)

on the error quaternion's vector part ``q_v``: near the target (``|q_v,i| <= q_s``) it is the PD
of :class:`rmpc.AttitudePD` with a stiffer ``K_p``; along a large slew the proportional torque is
at most ``K_p q_s`` per axis (diagonal gains), so the loop cruises at about ``K_p q_s / K_d`` per
axis (plus the gyroscopic torque's share) instead of at a rate that grows with the slew angle.
This is the saturated proportional term of the eigenaxis slew logic of B. Wie and J. Lu, "Feedback
control logic for spacecraft eigenaxis rotations under slew rate and control constraints", Journal
of Guidance, Control, and Dynamics 18(6), 1995 (there ``u = -J (2 k sat(q_v) + c w)``; here
without the inertia factor, so that the gains compare with PD's). Defaults (**assumed**):
``K_p = 6 N m``, ``K_d = 40 N m s`` (about the published axes: natural frequency ~0.1 rad/s, damping ~0.7
near the target), ``q_s = 0.2`` (proportional torque at most 1.2 N m per axis, cruise rate about
0.03 rad/s per axis; 0.033 rad/s measured on the 160 deg V-slew).
"""

from __future__ import annotations

import time
from typing import Any, ClassVar

import numpy as np

from models import FlexibleSatellite
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms, gain_matrix
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_positive

__all__ = ["NonlinearPD"]


class NonlinearPD:
    """``u = -K_d w - K_p sat(q_v, q_s)`` on the error quaternion; record name "NPD".

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model (only its sizes are used: the law cancels nothing).
    dt : float
        Sample time (s; the law is static, ``dt`` is kept for the protocol's reports).
    q_ref : (4,) array_like, optional
        Target attitude (default the identity).
    K_p, K_d : float, (3,) or (3, 3) array_like
        Attitude (N m) and rate (N m s) gains.
    q_s : float
        Per-axis saturation of ``q_v`` in the proportional term, in ``(0, 1]`` (``1``: no
        saturation, the law is PD).

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from models.attitude.quaternion import quat_from_axis_angle
    >>> from rmpc.laws.flexible.nonlinear_pd import NonlinearPD
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> npd = NonlinearPD(sat)
    >>> u = npd.step(sat.state(quat_from_axis_angle([0, 0, 1], 2.0)))   # q_v,z = sin(1) > q_s
    >>> round(float(u[2]), 6), npd.name                                  # -K_p q_s
    (-1.2, 'NPD')
    """

    name = "NPD"
    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        q_ref: Any = None,
        K_p: Any = 6.0,
        K_d: Any = 40.0,
        q_s: float = 0.2,
    ) -> None:
        self.terms = FlexibleTerms(plant, q_ref, flex_feedforward=False)
        self.dt = check_positive(dt, "dt")
        self.K_p = gain_matrix(K_p, "K_p")
        self.K_d = gain_matrix(K_d, "K_d")
        self.q_s = check_positive(q_s, "q_s")
        if self.q_s > 1.0:
            raise InvalidArgumentError("q_s", "a saturation level in (0, 1] (|q_v,i| <= 1)", f"{self.q_s:g}")
        self.last: StepInfo | None = None

    def reset(self) -> None:
        """Nothing to forget (the law is static)."""
        self.last = None

    def law(self, x: Any) -> np.ndarray:
        """The continuous-time law, a pure function: the hub torque at ``x``."""
        q, w, _, _ = self.terms.split(x)
        qv = self.terms.error(q, w).qv
        return -self.K_d @ w - self.K_p @ np.clip(qv, -self.q_s, self.q_s)

    def step(self, x: Any, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``[u; v]`` for the measured state (``v = inputs.pzt``, this sample's PZT command, or 0)."""
        start = time.perf_counter()
        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        u = self.law(x)
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start)
        return self.terms.command(u, pzt)

    def __repr__(self) -> str:
        return f"NonlinearPD(q_s={self.q_s:g}, dt={self.dt:g})"
