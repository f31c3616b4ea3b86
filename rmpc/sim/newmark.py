"""Newmark-beta integration of the flexible satellite, the integrator paper V used.

Paper V integrates its model with Newmark-beta (**certain**); the toolkit's default is adaptive
Runge-Kutta between control samples, Newmark-beta with ``beta = 1/4``, ``gamma = 1/2`` (average
acceleration, unconditionally stable, no numerical damping) is the option (**assumed**; seed
``papers-S-V-flexible.md`` section 3). Each step of length ``h`` is implicit in the end-point
accelerations ``a = [w', eta'']`` of :meth:`models.FlexibleSatellite.dynamics`::

    eta(n+1)  = eta(n) + h eta'(n) + h^2 ((1/2 - beta) eta''(n) + beta eta''(n+1))
    p(n+1)    = p(n) + h ((1 - gamma) a(n) + gamma a(n+1)),     p = [w, eta']
    q(n+1)    = q(n) * exp(h (w(n) + w(n+1)) / 4)               (quaternion exponential)

solved by fixed-point iteration on ``a(n+1)`` (a contraction for ``h`` well below ``1/Lambda_N``).
The attitude has no second-order form: it follows the trapezoidal rate through the exponential
map, which keeps ``||q|| = 1`` to rounding. Second-order accurate: the phase error of mode ``i``
grows like ``(h Lambda_i)^2 / 12`` per radian, so the step ``substep`` is much shorter than the
control sample (default 5 ms).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from models import FlexibleSatellite
from models.attitude.quaternion import quat_multiply
from rmpc.sim.plants import DisturbanceFn, NonlinearPlant, disturbance_at
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_positive

__all__ = ["NewmarkPlant"]


class NewmarkPlant(NonlinearPlant):
    """A :class:`models.FlexibleSatellite` advanced one sample by Newmark-beta steps.

    A :class:`~rmpc.sim.plants.NonlinearPlant` (so :func:`rmpc.sim.simulate` runs it) whose
    ``advance`` is Newmark-beta instead of DOP853/RK4.

    Parameters
    ----------
    model : FlexibleSatellite
        The plant.
    dt : float
        Sample time (s).
    substep : float
        Newmark step (s); the sample is split into ``ceil(dt / substep)`` equal steps.
    beta, gamma : float
        Newmark parameters (``1/4``, ``1/2``: average acceleration).
    tol : float
        Relative tolerance of the fixed-point iteration on the end-point accelerations.
    max_iterations : int
        Iterations before giving up (an error naming ``substep``).
    input_stage : InputStage, optional
        As for :class:`~rmpc.sim.plants.NonlinearPlant`, evaluated at each step's start.

    Examples
    --------
    >>> import numpy as np
    >>> from models import FlexibleSatellite
    >>> from rmpc.sim.newmark import NewmarkPlant
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> plant = NewmarkPlant(sat, 0.01)
    >>> x1 = plant.advance(sat.state(), np.array([1.0, 0, 0, 0, 0, 0, 0]), 0.0, None)
    >>> round(float(x1[4]), 8), round(float(np.linalg.norm(x1[:4])), 12)   # w_x after 10 ms
    (3.296e-05, 1.0)
    >>> round(float(np.linalg.inv(sat.hub_inertia)[0, 0] * 0.01), 8)   # J_mb^-1 u dt from rest
    3.296e-05
    """

    def __init__(
        self,
        model: FlexibleSatellite,
        dt: float,
        *,
        substep: float = 5e-3,
        beta: float = 0.25,
        gamma: float = 0.5,
        tol: float = 1e-13,
        max_iterations: int = 50,
        input_stage: Any = None,
    ) -> None:
        if not isinstance(model, FlexibleSatellite):
            raise ArgumentTypeError("model", "a models.FlexibleSatellite", type(model).__name__)
        super().__init__(model, dt, method="RK4", substep=substep, input_stage=input_stage)
        self.method = "Newmark"
        self.beta = check_positive(beta, "beta")
        self.gamma = check_positive(gamma, "gamma")
        if self.beta > 0.5 or not 0.0 < self.gamma <= 1.0:
            raise InvalidArgumentError("beta", "0 < beta <= 1/2 and 0 < gamma <= 1", f"{beta}, {gamma}")
        self.tol = check_positive(tol, "tol")
        if isinstance(max_iterations, bool) or not isinstance(max_iterations, int) or max_iterations < 1:
            raise InvalidArgumentError("max_iterations", "a positive integer", repr(max_iterations))
        self.max_iterations = max_iterations
        self._n_modes = model.n_modes

    def _accelerations(
        self, t: float, x: np.ndarray, u: np.ndarray, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        """``[w', eta'']`` at ``(t, x)``."""
        d = None if disturbance is None else disturbance_at(disturbance, t, x)
        x_dot = self.model.dynamics(x, self.applied(t, x, u), d)
        n = self._n_modes
        return np.concatenate((x_dot[4:7], x_dot[7 + n:]))

    def _step(
        self, x: np.ndarray, u: np.ndarray, t0: float, h: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        n, beta, gamma = self._n_modes, self.beta, self.gamma
        q, p, eta, eta_dot = x[:4], np.concatenate((x[4:7], x[7 + n:])), x[7:7 + n], x[7 + n:]
        t1 = float(np.nextafter(t0 + h, t0))  # d and the stage: left limit at the step's end
        a0 = self._accelerations(t0, x, u, disturbance)
        a1 = a0
        for _ in range(self.max_iterations):
            p1 = p + h * ((1.0 - gamma) * a0 + gamma * a1)
            eta1 = eta + h * eta_dot + h * h * ((0.5 - beta) * a0[3:] + beta * a1[3:])
            phi = 0.5 * h * (p[:3] + p1[:3])
            angle = float(np.linalg.norm(phi))
            dq = np.concatenate(([np.cos(0.5 * angle)], np.sinc(0.5 * angle / np.pi) * 0.5 * phi))
            q1 = quat_multiply(q, dq)
            x1 = np.concatenate((q1 / np.linalg.norm(q1), p1[:3], eta1, p1[3:]))
            a_new = self._accelerations(t1, x1, u, disturbance)
            change = float(np.max(np.abs(a_new - a1)))
            a1 = a_new
            if change <= self.tol * (1.0 + float(np.max(np.abs(a1)))):
                p1 = p + h * ((1.0 - gamma) * a0 + gamma * a1)
                eta1 = eta + h * eta_dot + h * h * ((0.5 - beta) * a0[3:] + beta * a1[3:])
                return np.concatenate((x1[:4], p1[:3], eta1, p1[3:]))
        raise InvalidArgumentError(
            "substep", "a Newmark step short enough for the fixed-point iteration to converge",
            f"h = {h:g} s: no convergence in {self.max_iterations} iterations",
        )

    def advance(
        self, x: np.ndarray, u: np.ndarray, t: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        """State one sample later (the command ``u`` held over ``[t, t + dt)``)."""
        h = self.dt / self.n_substeps
        state = np.asarray(x, dtype=float)
        for i in range(self.n_substeps):
            state = self._step(state, u, t + i * h, h, disturbance)
        return state
