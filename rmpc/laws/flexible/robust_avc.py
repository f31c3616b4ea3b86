"""Robust active vibration control (AVC) of a flexible satellite's modes by PZT (paper V, theorem 2).

Source: paper V (in Persian; its authors and title are not known), theorem 2: a sliding variable on
the modal error,
cancellation of the known ("nominal") part of the modal equation and a robust term against the
bounded unknown part, with a Lyapunov function ``V = s' M s / 2``. Structure **likely**, details
**assumed**::

    e = eta - eta_d,   eta_d = eta(t0) exp(-beta (t - t0)),   s = e' + Lam e
    rho = b0 + b1 ||eta|| + b2 ||eta'||,   eps_a(t) = max(e1 exp(-e2 t), e_min)
    Psi = M0 (eta_d'' - Lam e') + C0 eta' + K0 eta + delta0 wdot_prev
    Gamma_a v = Psi - K_v s - rho^2 s / (rho ||s|| + eps_a(t))

On the modal equation ``M eta'' + C eta' + K eta + delta w' = Gamma_a v + d_f`` this gives
``M s' = -K_v s - rho^2 s/(rho ||s|| + eps_a) + delta (wdot_prev - w') + (model error) + d_f``.
``wdot_prev`` is the hub acceleration over the previous sample, the finite difference of the
measured rates (zero at the first sample): ``w'`` depends on ``v`` through ``delta``, and the
one-sample delay breaks the algebraic loop (**assumed**). ``e_min > 0`` is a toolkit deviation
from the proof (against late chattering). ``v = Gamma_a^-1 (...)``: paper V inverts ``Gamma_a``
(``n_a = N``); a singular square ``Gamma_a`` is an error naming ``pzt_matrix``, a non-square one
uses the pseudo-inverse with a warning. Defaults (all **assumed**): ``Lam = I``, ``K_v = 2 I``
(1/s), ``(b0, b1, b2) = (0.01, 0.1, 0.1)``, ``e1 = 0.01``, ``e2 = 0.05 1/s``, ``e_min = 1e-3``,
``beta = 0.5 1/s``; ``t0 = 0`` is the first sample after ``reset()``.
"""

from __future__ import annotations

import time
import warnings
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from models import FlexibleSatellite
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_positive_values, as_vector, check_positive

__all__ = ["RobustAVC"]

#: Condition number of ``Gamma_a`` above which it is taken as not invertible.
PZT_COND_MAX = 1e12


class RobustAVC:
    """Robust sliding-mode vibration control of the modal coordinates through the PZT channel.

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model; its ``M, C, K, delta`` are the nominal ``M0, C0, K0, delta0``.
    dt : float
        Sample time (s).
    Lam, K_v : float or (N,) array_like
        Sliding-surface slope (1/s) and proportional gain (1/s), diagonal.
    b0, b1, b2 : float
        Bound of the unknown modal terms, ``rho = b0 + b1 ||eta|| + b2 ||eta'||``.
    e1, e2, e_min : float
        Smoothing ``eps_a(t) = max(e1 exp(-e2 t), e_min)``.
    beta : float
        Decay rate (1/s) of the desired modal trajectory ``eta_d``.
    v_max : float, optional
        Clip of each PZT command (default none); the plant's limiter may clip as well.

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from rmpc import RobustAVC
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> avc = RobustAVC(sat)
    >>> u = avc.step(sat.state(modal_rates=[0.01, 0.0, 0.0, 0.0]))
    >>> u.shape, round(float(u[3]), 5), avc.last.status
    ((7,), -0.03003, 'ok')
    """

    name = "AVC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        Lam: ArrayLike = 1.0,
        K_v: ArrayLike = 2.0,
        b0: float = 0.01,
        b1: float = 0.1,
        b2: float = 0.1,
        e1: float = 0.01,
        e2: float = 0.05,
        e_min: float = 1e-3,
        beta: float = 0.5,
        v_max: float | None = None,
    ) -> None:
        self.terms = FlexibleTerms(plant, None, True)
        n = plant.n_modes
        if n == 0:
            raise InvalidArgumentError("plant", "a satellite with flexible modes", "n_modes = 0")
        self.dt = check_positive(dt, "dt")
        self.Lam = as_positive_values(Lam, "Lam", n, per="mode")
        self.K_v = as_positive_values(K_v, "K_v", n, per="mode")
        self.b0 = check_positive(b0, "b0", allow_zero=True)
        self.b1 = check_positive(b1, "b1", allow_zero=True)
        self.b2 = check_positive(b2, "b2", allow_zero=True)
        self.e1 = check_positive(e1, "e1")
        self.e2 = check_positive(e2, "e2", allow_zero=True)
        self.e_min = check_positive(e_min, "e_min")
        self.beta = check_positive(beta, "beta", allow_zero=True)
        self.v_max = None if v_max is None else check_positive(v_max, "v_max")
        gamma = plant.pzt_matrix
        if gamma.shape[0] == gamma.shape[1]:
            cond = float(np.linalg.cond(gamma)) if gamma.size else np.inf
            if not cond < PZT_COND_MAX:
                raise InvalidArgumentError(
                    "pzt_matrix", "an invertible Gamma_a (RobustAVC solves Gamma_a v = ...)",
                    f"condition number {cond:.3g}",
                )
            self._gamma_inv = np.linalg.inv(gamma)
        else:
            warnings.warn(
                f"pzt_matrix is {gamma.shape[0]} x {gamma.shape[1]} (modes x actuators): RobustAVC "
                "uses its pseudo-inverse, so the modal force is matched only in the least-squares sense",
                stacklevel=2,
            )
            self._gamma_inv = np.linalg.pinv(gamma)
        self._mass = plant.modal_mass
        self._c = np.diag(plant.damping_matrix)
        self._k = np.diag(plant.stiffness)
        self._delta = plant.coupling
        self.last: StepInfo | None = None
        self.reset()

    def reset(self) -> None:
        """Clock to 0; ``eta(t0)`` and the previous rate are taken at the next sample."""
        self._step = 0
        self._eta0: np.ndarray | None = None
        self._w_prev: np.ndarray | None = None
        self.last = None

    def smoothing(self, t: float) -> float:
        """``eps_a(t) = max(e1 exp(-e2 t), e_min)``."""
        return max(self.e1 * float(np.exp(-self.e2 * t)), self.e_min)

    def law(
        self, t: float, x: ArrayLike, eta0: ArrayLike | None = None, wdot_prev: ArrayLike | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The continuous-time law, a pure function: ``(v, s)`` at ``(t, x)``.

        ``eta0`` is ``eta(t0)`` with ``t0 = 0`` (default zero: ``eta_d = 0``), ``wdot_prev``
        the hub acceleration fed forward (default zero). ``v`` is not clipped here.
        """
        _, _, eta, eta_dot = self.terms.split(x)
        n = self.terms.n_modes
        eta0 = np.zeros(n) if eta0 is None else as_vector(eta0, "eta0", n)
        wdot = np.zeros(3) if wdot_prev is None else as_vector(wdot_prev, "wdot_prev", 3)
        decay = float(np.exp(-self.beta * t))
        eta_d, eta_d_dot, eta_d_ddot = eta0 * decay, -self.beta * eta0 * decay, self.beta**2 * eta0 * decay
        e, e_dot = eta - eta_d, eta_dot - eta_d_dot
        s = e_dot + self.Lam * e
        rho = self.b0 + self.b1 * float(np.linalg.norm(eta)) + self.b2 * float(np.linalg.norm(eta_dot))
        psi = (
            self._mass @ (eta_d_ddot - self.Lam * e_dot) + self._c * eta_dot + self._k * eta
            + self._delta @ wdot
        )
        force = psi - self.K_v * s - rho**2 * s / (rho * float(np.linalg.norm(s)) + self.smoothing(t))
        return self._gamma_inv @ force, s

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return the plant input ``[0 (3 hub torques); v]`` for the measured state."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        t = self._step * self.dt
        _, w, eta, _ = self.terms.split(x)
        if self._eta0 is None:
            self._eta0 = eta.copy()
        wdot = np.zeros(3) if self._w_prev is None else (w - self._w_prev) / self.dt
        v, s = self.law(t, x, self._eta0, wdot)
        if self.v_max is not None:
            v = np.clip(v, -self.v_max, self.v_max)
        self._w_prev = w.copy()
        self._step += 1
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra={"s": s, "v": v})
        return np.concatenate((np.zeros(3), v))

    def __repr__(self) -> str:
        return (
            f"RobustAVC(n_modes={self.terms.n_modes}, beta={self.beta:g}, e_min={self.e_min:g}, "
            f"dt={self.dt:g})"
        )
