"""Paper V's moving-surface sliding-mode attitude control (MTSMC) of a flexible satellite.

Source: paper V (in Persian; its authors and title are not known), eqs. 11-15: the surface
``sigma = w + alpha(t) q_v`` whose slope ``alpha`` moves in time, a switching term
``W_s tanh(sigma/eps)`` and compensation of
the rigid-flexible coupling. The paper's equations and gain table were lost in extraction; this
module is the toolkit's documented reconstruction
(**assumed** as a whole)::

    q_v from the error quaternion (q0 >= 0);   z' = q_v while the rotation error < theta_I, else 0
    sigma = w + alpha q_v + k_I z
    u = w x (J w + delta' eta') - delta' M^-1 (C eta' + K eta - Gamma_a v)
        - J_mb (alpha' q_v + alpha q_v' + k_I z') - K_s sigma - W_s tanh(sigma / eps)

so that on the exact, unsaturated model ``J_mb sigma' = -K_s sigma - W_s tanh(sigma/eps) + d``.

``alpha_law="schedule"`` (default): ``alpha(t) = alpha_f (1 - exp(-t / tau_a))``; a state at rest
lies on the surface at ``t = 0`` (no reaching phase) and, without disturbance or saturation,
stays on it. ``alpha_law="adaptive"`` (paper V eq. 12's structure)::

    alpha' = -k1 q_v' [tanh(sigma/eps) - tanh(alpha q_v/eps)] - k2 alpha q_v' q_v,
    clipped to [alpha_min, alpha_max], alpha(0) = alpha0 > 0

``W_s`` is ``W_0`` (``g_w = 0``, default) or adapts, ``W_s' = g_w (||sigma||_1 - e_w W_s)`` with
``|W_s'| <= rho_w W_s`` (paper V eqs. 13-14's relative-rate bound). Defaults (all
**assumed**; paper V's table is blank): ``alpha_f = 0.1 1/s``, ``tau_a = 15 s``, ``K_s = 20 N m s``,
``W_0 = 1 N m``, ``eps = 0.01 rad/s``, ``k_I = 0`` (option 0.01 1/s^2 with ``theta_I = 5 deg``);
adaptive ``alpha0 = 0.02``, ``k1 = 0.005``, ``k2 = 0``, ``[alpha_min, alpha_max] = [0.005, 0.5]``;
``e_w = 0.01``, ``rho_w = 0.1 1/s`` (toolkit values).

The controller keeps its own clock ``t = k dt`` (``dt`` = its sample time) and the discrete states
``z``, ``alpha`` (adaptive) and ``W_s``, advanced by forward Euler after each sample. The modal
state ``eta, eta'`` is read from the plant state (idealised full-state measurement, as paper V);
``flex_feedforward=False`` drops it. The torque is not saturated here: the plant's limiter or
input stage clips it (``u_max = 2 N m`` per axis in paper V's scenario).
"""

from __future__ import annotations

import time
from typing import ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike

from models import FlexibleSatellite
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms, gain_matrix
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_choice, check_positive

__all__ = ["MTSMC", "AlphaLaw"]

AlphaLaw = Literal["schedule", "adaptive"]


class MTSMC:
    """Moving-surface sliding-mode attitude control with a smooth switching term (paper V).

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model (nominal parameters).
    dt : float
        Sample time (s) of the controller's clock (0.01 s in paper V's scenario, **assumed**).
    q_ref : (4,) array_like, optional
        Target attitude (unit quaternion, at rest); default the identity.
    alpha_law : {"schedule", "adaptive"}
        How the surface slope moves (see the module docstring).
    alpha_f, tau_a : float
        Final slope (1/s) and time constant (s) of the schedule.
    alpha0, k1, k2, alpha_min, alpha_max : float
        Initial value, rate constants and clip range of the adaptive slope.
    K_s : float, (3,) or (3, 3) array_like
        Proportional reaching gain (N m s).
    W_0 : float
        Switching gain (N m), initial value when it adapts.
    eps : float
        Boundary-layer width of ``tanh(sigma/eps)`` (rad/s).
    k_I, theta_I : float
        Integral gain (1/s^2) and the rotation error (rad) below which ``z`` integrates.
    g_w, e_w, rho_w : float
        Adaptation of ``W_s`` (``g_w = 0``: constant).
    flex_feedforward : bool
        Cancel the modal reaction with the measured ``eta, eta'``.

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from models.attitude.quaternion import quat_from_axis_angle
    >>> from rmpc import MTSMC
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> ctrl = MTSMC(sat)
    >>> u = ctrl.step(sat.state(quat_from_axis_angle([1, 1, 1], 0.5)))  # at rest: -J_mb alpha'(0) q_v
    >>> [round(float(val), 4) for val in u[:3]], ctrl.last.status
    ([-0.2768, -0.2462, -0.1702], 'ok')
    """

    name = "MTSMC"
    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        q_ref: ArrayLike | None = None,
        alpha_law: AlphaLaw = "schedule",
        alpha_f: float = 0.1,
        tau_a: float = 15.0,
        alpha0: float = 0.02,
        k1: float = 0.005,
        k2: float = 0.0,
        alpha_min: float = 0.005,
        alpha_max: float = 0.5,
        K_s: ArrayLike = 20.0,
        W_0: float = 1.0,
        eps: float = 0.01,
        k_I: float = 0.0,
        theta_I: float = np.deg2rad(5.0),
        g_w: float = 0.0,
        e_w: float = 0.01,
        rho_w: float = 0.1,
        flex_feedforward: bool = True,
    ) -> None:
        self.terms = FlexibleTerms(plant, q_ref, flex_feedforward)
        self.dt = check_positive(dt, "dt")
        self.alpha_law = check_choice(alpha_law, "alpha_law", ("schedule", "adaptive"))
        self.alpha_f = check_positive(alpha_f, "alpha_f")
        self.tau_a = check_positive(tau_a, "tau_a")
        self.alpha0 = check_positive(alpha0, "alpha0")
        self.k1 = check_positive(k1, "k1", allow_zero=True)
        self.k2 = check_positive(k2, "k2", allow_zero=True)
        self.alpha_min = check_positive(alpha_min, "alpha_min")
        self.alpha_max = check_positive(alpha_max, "alpha_max")
        if self.alpha_min > self.alpha_max:
            raise InvalidArgumentError(
                "alpha_min", f"at most alpha_max = {self.alpha_max:g}", repr(self.alpha_min)
            )
        if self.alpha_law == "adaptive" and not self.alpha_min <= self.alpha0 <= self.alpha_max:
            raise InvalidArgumentError(
                "alpha0", f"in [alpha_min, alpha_max] = [{self.alpha_min:g}, {self.alpha_max:g}]",
                repr(self.alpha0),
            )
        self.K_s = gain_matrix(K_s, "K_s")
        self.W_0 = check_positive(W_0, "W_0", allow_zero=True)
        self.eps = check_positive(eps, "eps")
        self.k_I = check_positive(k_I, "k_I", allow_zero=True)
        self.theta_I = check_positive(theta_I, "theta_I")
        self.g_w = check_positive(g_w, "g_w", allow_zero=True)
        self.e_w = check_positive(e_w, "e_w", allow_zero=True)
        self.rho_w = check_positive(rho_w, "rho_w")
        self.last: StepInfo | None = None
        self.reset()

    def reset(self) -> None:
        """Clock to 0, ``z = 0``, ``alpha = alpha0`` (adaptive), ``W_s = W_0``."""
        self._k = 0
        self._z = np.zeros(3)
        self._alpha = self.alpha0
        self._w_s = self.W_0
        self.last = None

    def slope(self, t: float) -> tuple[float, float]:
        """``(alpha, alpha')`` of the schedule at time ``t`` (s)."""
        decay = float(np.exp(-t / self.tau_a))
        return self.alpha_f * (1.0 - decay), self.alpha_f * decay / self.tau_a

    def adaptive_rate(self, alpha: float, qv: np.ndarray, sigma: np.ndarray) -> float:
        """``alpha'`` of the adaptive law before the clip."""
        diff = np.tanh(sigma / self.eps) - np.tanh(alpha * qv / self.eps)
        return float(-self.k1 * (qv @ diff) - self.k2 * alpha * (qv @ qv))

    def law(
        self,
        t: float,
        x: ArrayLike,
        v: ArrayLike | None = None,
        *,
        z: ArrayLike | None = None,
        alpha: float | None = None,
        w_s: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The continuous-time law, a pure function: ``(u, sigma)`` at ``(t, x)``.

        ``v`` is this sample's PZT command (``None``: none). ``z``, ``alpha`` (adaptive law
        only) and ``w_s`` default to ``0``, ``alpha0`` and ``W_0``; with the schedule,
        ``alpha`` follows ``t``. The adaptive ``alpha'`` inside the law is the unclipped rate
        (zero at a clip bound it pushes against).
        """
        q, w, eta, eta_dot = self.terms.split(x)
        v_vec = self.terms.pzt(v)
        err = self.terms.error(q, w)
        z_vec = np.zeros(3) if z is None else np.asarray(z, dtype=float)
        w_s = self.W_0 if w_s is None else float(w_s)
        z_dot = err.qv if err.angle < self.theta_I else np.zeros(3)
        if self.alpha_law == "schedule":
            a, a_dot = self.slope(t)
            sigma = w + a * err.qv + self.k_I * z_vec
        else:
            a = self.alpha0 if alpha is None else float(alpha)
            sigma = w + a * err.qv + self.k_I * z_vec
            a_dot = self.adaptive_rate(a, err.qv, sigma)
            if (a >= self.alpha_max and a_dot > 0.0) or (a <= self.alpha_min and a_dot < 0.0):
                a_dot = 0.0
        rate = a_dot * err.qv + a * err.qv_dot + self.k_I * z_dot
        u = self.terms.sliding_torque(w, eta, eta_dot, v_vec, sigma, rate, self.K_s, w_s, self.eps, "tanh")
        return u, sigma

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return the plant input ``[u; v]`` (``3 + n_a``) for the measured state.

        ``inputs.pzt`` is this sample's PZT command ``v`` (from the vibration controller;
        ``None``: zero); it is passed through so that the output is the plant's whole input
        vector.
        """
        start = time.perf_counter()
        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        t = self._k * self.dt
        u, sigma = self.law(t, x, pzt, z=self._z, alpha=self._alpha, w_s=self._w_s)
        q, w, _, _ = self.terms.split(x)
        err = self.terms.error(q, w)
        alpha = self.slope(t)[0] if self.alpha_law == "schedule" else self._alpha
        extra = {"sigma": sigma, "alpha": alpha, "W_s": self._w_s, "angle": err.angle}
        # advance the discrete states to the next sample (forward Euler)
        if self.k_I > 0.0 and err.angle < self.theta_I:
            self._z = self._z + self.dt * err.qv
        if self.alpha_law == "adaptive":
            rate = self.adaptive_rate(self._alpha, err.qv, sigma)
            self._alpha = float(np.clip(self._alpha + self.dt * rate, self.alpha_min, self.alpha_max))
        if self.g_w > 0.0:
            w_rate = self.g_w * (float(np.sum(np.abs(sigma))) - self.e_w * self._w_s)
            w_rate = float(np.clip(w_rate, -self.rho_w * self._w_s, self.rho_w * self._w_s))
            self._w_s = self._w_s + self.dt * w_rate
        self._k += 1
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra=extra)
        return self.terms.command(u, pzt)

    def __repr__(self) -> str:
        return (
            f"MTSMC(alpha_law={self.alpha_law!r}, alpha_f={self.alpha_f:g}, tau_a={self.tau_a:g}, "
            f"W_0={self.W_0:g}, eps={self.eps:g}, k_I={self.k_I:g}, dt={self.dt:g})"
        )
