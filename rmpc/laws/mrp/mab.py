"""Modular adaptive backstepping ("MAB"): command-filtered backstepping with nonlinear damping
and a separately designed disturbance estimator (paper M; structure
**certain**).

Krstic, Kanellakopoulos & Kokotovic, "Nonlinear and Adaptive Control Design", Wiley 1995
(modular design: an input-to-state stabilising controller plus any estimator with bounded
error). On top of :class:`rmpc.CFBackstepping`::

    u0 = w x J0 w + J0 (x_c' - C2 z2 - N(se)' zb1) - kappa J0^-T zb2 - Tdhat

``Tdhat`` comes from a pluggable estimator (default :class:`rmpc.NESO`). With
``Tt = J0 d - Tdhat`` the estimation error, ``V = (|zb1|^2 + |zb2|^2)/2`` obeys
``V' <= -c_min |zb|^2 + |Tt|^2 / (4 kappa)``, so ``limsup |zb| <= sup |Tt| / (2 sqrt(c_min kappa))``
(input-to-state stable with respect to the estimation error; ``Tdhat`` enters only the last
step, so no update-rate term appears). Paper M's scalar lemma behind it: for
``x' = f + g u + phi Delta(t)``, ``u = g^-1 (-f - c x - kappa phi^2 x)`` gives
``V' <= -c x^2 + Delta^2 / (4 kappa)``. ``kappa = 3`` (**assumed**, SI).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from models import MRPSatellite
from models.mrp.tracking import MRPTrackingError
from rmpc.laws.continuous import LawOutput
from rmpc.laws.mrp.cf_backstepping import CFBackstepping
from rmpc.laws.mrp.command_filter import CommandFilter
from rmpc.laws.mrp.neso import NESO
from toolkit_common.errors import ArgumentTypeError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["MAB", "TorqueEstimator"]


@runtime_checkable
class TorqueEstimator(Protocol):
    """What :class:`MAB` needs from an estimator of the disturbance torque (e.g. :class:`rmpc.NESO`).

    The estimator is pure: its state ``z`` lives in the controller's internal state.
    """

    n_states: int

    def initial_state(self, w: ArrayLike) -> np.ndarray:  # pragma: no cover - protocol
        """The estimator state at the first sample, given the measured rate."""
        ...

    def derivative(self, z: np.ndarray, w: np.ndarray, torque: np.ndarray) -> np.ndarray:  # pragma: no cover
        """``z'`` for the measured rate and the applied control torque."""
        ...

    def project(self, z: np.ndarray) -> np.ndarray:  # pragma: no cover - protocol
        """Map ``z`` back into its admissible set after a discrete step."""
        ...

    def torque_estimate(self, z: np.ndarray) -> np.ndarray:  # pragma: no cover - protocol
        """The estimated disturbance torque ``Tdhat`` (N m)."""
        ...


class MAB(CFBackstepping):
    """Modular adaptive backstepping: :class:`CFBackstepping` + nonlinear damping + an estimator.

    Parameters
    ----------
    plant : MRPSatellite
        The controller's model (``J0``, ``n``).
    target : (3,) array_like, optional
        Target MRP relative to the orbital frame (default 0).
    c1, c2 : float
        Backstepping gains (1/s). Defaults 0.5 and 2 (**assumed**).
    kappa : float
        Nonlinear-damping gain, > 0 (default 3, **assumed**).
    estimator : "neso", TorqueEstimator or None
        ``"neso"`` (default): :meth:`NESO.from_bandwidth` on ``J0`` with paper M's assumed
        ``w_o = 10`` rad/s, ``alpha = (0.5, 0.25)``, ``delta = 0.01``, ``B = 0.05``; an estimator
        object (e.g. ``NESO.linear(J0)``, the linear ESO); or ``None`` (damping only,
        ``Tdhat = 0``).
    command_filter : CommandFilter, optional
        As in :class:`CFBackstepping`.
    dt : float
        Sample time (s).
    u_max : float, (3,) array_like or None
        Per-axis torque limit (N m).

    Notes
    -----
    Internal state ``[q1, q2, chi1, chi2, z_est]``; ``last.extra`` adds
    ``"torque_estimate"`` (``Tdhat``, N m) to :class:`CFBackstepping`'s entries.

    Examples
    --------
    >>> import numpy as np
    >>> from models import paper_m_scenario
    >>> from rmpc import MAB, simulate
    >>> from rmpc.sim.plants import SampledPlant
    >>> m2 = paper_m_scenario("M2")
    >>> mab = MAB(m2.model(), target=m2.sigma_ref, dt=0.05)
    >>> plant = SampledPlant(m2.true_satellite(), 0.05, integrator="RK4")
    >>> traj = simulate(mab, plant, m2.initial_state(), duration=20.0, disturbance=m2.disturbance())
    >>> err = np.abs(traj.info[-1].extra["torque_estimate"] - traj.d[-1])
    >>> bool(err.max() < 2e-3)     # the disk's torque is estimated to 2e-3 N m
    True
    """

    name = "MAB"

    def __init__(
        self,
        plant: MRPSatellite,
        target: ArrayLike | None = None,
        *,
        c1: float = 0.5,
        c2: float = 2.0,
        kappa: float = 3.0,
        estimator: Any = "neso",
        command_filter: CommandFilter | None = None,
        dt: float = 0.01,
        u_max: ArrayLike | None = None,
    ) -> None:
        super().__init__(plant, target, c1=c1, c2=c2, command_filter=command_filter, dt=dt, u_max=u_max)
        self.kappa = check_positive(kappa, "kappa")
        if isinstance(estimator, str) and estimator == "neso":
            estimator = NESO.from_bandwidth(plant.inertia)
        if estimator is not None and not isinstance(estimator, TorqueEstimator):
            raise ArgumentTypeError(
                "estimator", "'neso', None or an object with n_states, initial_state, derivative, "
                "project and torque_estimate (e.g. rmpc.NESO)", type(estimator).__name__,
            )
        self.estimator = estimator
        self._n_est = 0 if estimator is None else int(estimator.n_states)
        self.n_internal = 12 + self._n_est

    def __repr__(self) -> str:
        return (
            f"MAB(c1={self.c1!r}, c2={self.c2!r}, kappa={self.kappa!r}, estimator={self.estimator!r}, "
            f"dt={self.dt!r}, u_max={self.u_max})"
        )

    def settings(self) -> dict[str, Any]:
        """Every parameter, including the estimator's (``w_o`` and the gains)."""
        out = super().settings()
        est = self.estimator
        out.update(kappa=self.kappa, estimator=None if est is None else (
            est.settings() if callable(getattr(est, "settings", None)) else type(est).__name__
        ))
        return out

    def torque_estimate(self, z: ArrayLike) -> np.ndarray:
        """``Tdhat`` for the internal state ``z`` (zero without an estimator)."""
        z = as_vector(z, "z", self.n_internal)
        return self._estimate(z)

    def _estimate(self, z: np.ndarray) -> np.ndarray:
        if self.estimator is None:
            return np.zeros(3)
        return self.estimator.torque_estimate(z[12:])

    def _extra_torque(self, x: np.ndarray, z: np.ndarray, zb2: np.ndarray) -> np.ndarray:
        return -self.kappa * (self._j0_inv.T @ zb2) - self._estimate(z)

    def initial_internal(self, x: ArrayLike) -> np.ndarray:
        """:class:`CFBackstepping`'s start, then the estimator's ``initial_state(w(0))``."""
        x = as_vector(x, "x", 6)
        z = super().initial_internal(x)
        if self.estimator is None:
            return z
        return np.concatenate((z, self.estimator.initial_state(x[3:6])))

    def _evaluate(self, x: np.ndarray, z: np.ndarray, g: MRPTrackingError) -> LawOutput:
        out = super()._evaluate(x, z, g)
        out.extra["torque_estimate"] = self._estimate(z)
        return out

    def _derivative(self, x: np.ndarray, z: np.ndarray, u: np.ndarray, g: MRPTrackingError) -> np.ndarray:
        base = super()._derivative(x, z, u, g)
        if self.estimator is None:
            return base
        return np.concatenate((base, self.estimator.derivative(z[12:], x[3:6], u)))

    def project_internal(self, z: np.ndarray) -> np.ndarray:
        """The estimator's projection on its part of the state."""
        if self.estimator is None:
            return z
        return np.concatenate((z[:12], self.estimator.project(z[12:])))
