"""Tuning-function adaptive backstepping ("TFAB"), the baseline of paper M's Fig. 16.

Krstic, Kanellakopoulos & Kokotovic, "Nonlinear and Adaptive Control Design", Wiley 1995
(integral adaptation with tuning functions). Paper M compares against it (**certain**; its
gains were lost). The toolkit's form (**likely**) has no command
filter: ``alpha1'`` is computed analytically::

    z1 = se;   alpha1 = -4 c1 se / (1 + s) - n c2(sigma);   z2 = w - alpha1      (s = |se|^2)
    alpha1' = -c1 [4 se' / (1 + s) - 8 se (se' se) / (1 + s)^2] + n w_BO x c2,   se' = N(se) w_BO
    u = w x J0 w + J0 (alpha1' - c2 z2 - N(se)' z1) - Tdhat;     Tdhat' = Gamma J0^-T z2

The unknown torque appears only in the last step, so the tuning functions reduce to
``tau1 = 0``, ``tau2 = J0^-T z2``. With ``V = (|z1|^2 + |z2|^2 + Tt' Gamma^-1 Tt) / 2``,
``Tt = Td - Tdhat``, a constant ``Td`` and ``J = J0``: ``V' = -c1 |z1|^2 - c2 |z2|^2``.
``Gamma = 10`` (**assumed**). Under a torque limit TF-AB clips plainly: the estimate keeps
integrating (no anti-windup), the toolkit's choice (paper M shows no torque limit).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models import MRPSatellite
from models.attitude.vectors import cross3
from models.mrp.tracking import MRPTrackingError, tracking_error
from rmpc.laws.continuous import ContinuousTimeController, LawOutput
from toolkit_common.errors import ArgumentTypeError
from toolkit_common.validation import as_positive_values, as_vector, check_positive

__all__ = ["TuningFunctionAB"]


class TuningFunctionAB(ContinuousTimeController):
    """Adaptive backstepping with tuning functions, estimating a constant disturbance torque.

    Parameters
    ----------
    plant : MRPSatellite
        The controller's model (``J0``, ``n``).
    target : (3,) array_like, optional
        Target MRP relative to the orbital frame (default 0).
    c1, c2 : float
        Backstepping gains (1/s), > 0 (defaults 0.5 and 2, as for BS and MAB).
    gamma : float or (3,) array_like
        Adaptation gain ``Gamma`` (a scalar or a diagonal), > 0 (default 10, **assumed**).
    dt : float
        Sample time (s).
    u_max : float, (3,) array_like or None
        Per-axis torque limit (N m); the output is clipped plainly.

    Notes
    -----
    Internal state: ``Tdhat`` (3 entries, N m), zero at the first sample (**assumed**).
    ``last.extra`` holds ``"attitude_error"``, ``"error_angle"`` (rad), ``"virtual_rate"``
    (``alpha1``), ``"virtual_rate_derivative"`` (``alpha1'``), ``"torque_estimate"`` and
    ``"u_unclipped"``.

    Examples
    --------
    >>> import numpy as np
    >>> from models import paper_m_scenario
    >>> from rmpc import TuningFunctionAB
    >>> m1 = paper_m_scenario("M1")
    >>> tfab = TuningFunctionAB(m1.model(), target=m1.sigma_ref)
    >>> u = tfab.step(m1.initial_state())
    >>> round(float(np.abs(u).max()), 2)       # 1.88 N m at t = 0
    1.88
    """

    name = "TFAB"

    def __init__(
        self,
        plant: MRPSatellite,
        target: ArrayLike | None = None,
        *,
        c1: float = 0.5,
        c2: float = 2.0,
        gamma: ArrayLike = 10.0,
        dt: float = 0.01,
        u_max: ArrayLike | None = None,
    ) -> None:
        super().__init__(dt, u_max)
        if not isinstance(plant, MRPSatellite):
            raise ArgumentTypeError("plant", "a models.MRPSatellite", type(plant).__name__)
        self.plant = plant
        self._j0 = plant.inertia
        self._j0_inv = plant.inertia_inv
        self.mean_motion = plant.mean_motion
        self.target = np.zeros(3) if target is None else as_vector(target, "target", 3).copy()
        self.target.setflags(write=False)
        self.c1 = check_positive(c1, "c1")
        self.c2 = check_positive(c2, "c2")
        self.gamma = as_positive_values(gamma, "gamma", 3, per="axis", what="gains")
        self.gamma.setflags(write=False)
        self.n_internal = 3

    def __repr__(self) -> str:
        return (
            f"TuningFunctionAB(c1={self.c1!r}, c2={self.c2!r}, gamma={self.gamma.tolist()}, "
            f"dt={self.dt!r}, u_max={self.u_max})"
        )

    def settings(self) -> dict[str, Any]:
        """Every parameter, for reports (the adaptation gain ``Gamma`` included)."""
        out = super().settings()
        out.update(c1=self.c1, c2=self.c2, gamma=self.gamma.tolist(), target=self.target.tolist(),
                   model_inertia=self._j0.tolist(), mean_motion=self.mean_motion)
        return out

    # -- the law -----------------------------------------------------------------------------------
    def _geometry(self, x: np.ndarray) -> MRPTrackingError:
        return tracking_error(x, self.target, self.mean_motion)

    def virtual_rate(self, error: MRPTrackingError) -> tuple[np.ndarray, np.ndarray]:
        """``(alpha1, alpha1')`` along the plant's kinematics (no disturbance enters them)."""
        se, w_bo, c2 = error.se, error.relative_rate, error.c2
        s = float(se @ se)
        se_dot = error.kinematics @ w_bo
        n = self.mean_motion
        alpha1 = -4.0 * self.c1 * se / (1.0 + s) - n * c2
        alpha1_dot = (
            -self.c1 * (4.0 * se_dot / (1.0 + s) - 8.0 * se * float(se @ se_dot) / (1.0 + s) ** 2)
            + n * cross3(w_bo, c2)
        )
        return alpha1, alpha1_dot

    def initial_internal(self, x: ArrayLike) -> np.ndarray:
        """``Tdhat(0) = 0``."""
        as_vector(x, "x", 6)
        return np.zeros(3)

    def _z2(self, x: np.ndarray, g: MRPTrackingError) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        alpha1, alpha1_dot = self.virtual_rate(g)
        return x[3:6] - alpha1, alpha1, alpha1_dot

    def _evaluate(self, x: np.ndarray, z: np.ndarray, g: MRPTrackingError) -> LawOutput:
        w = x[3:6]
        z2, alpha1, alpha1_dot = self._z2(x, g)
        u0 = cross3(w, self._j0 @ w) + self._j0 @ (alpha1_dot - self.c2 * z2 - g.kinematics.T @ g.se) - z
        u = self._clip(u0)
        extra = {
            "attitude_error": g.se.copy(),
            "error_angle": 4.0 * float(np.arctan(np.linalg.norm(g.se))),
            "virtual_rate": alpha1,
            "virtual_rate_derivative": alpha1_dot,
            "torque_estimate": z.copy(),
            "u_unclipped": u0,
        }
        return LawOutput(u=u, u_unclipped=u0, extra=extra)

    def _derivative(self, x: np.ndarray, z: np.ndarray, u: np.ndarray, g: MRPTrackingError) -> np.ndarray:
        z2, _, _ = self._z2(x, g)
        return self.gamma * (self._j0_inv.T @ z2)

    # -- analysis ----------------------------------------------------------------------------------
    def errors(self, x: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``(z1, z2) = (se, w - alpha1)``."""
        x = as_vector(x, "x", 6)
        g = self._geometry(x)
        return g.se, self._z2(x, g)[0]

    def lyapunov(self, x: ArrayLike, z: ArrayLike, true_torque: ArrayLike) -> float:
        """``V = (|z1|^2 + |z2|^2 + Tt' Gamma^-1 Tt) / 2`` with ``Tt = true_torque - Tdhat``."""
        z = as_vector(z, "z", 3)
        tt = as_vector(true_torque, "true_torque", 3) - z
        z1, z2 = self.errors(x)
        return 0.5 * float(z1 @ z1 + z2 @ z2 + tt @ (tt / self.gamma))
