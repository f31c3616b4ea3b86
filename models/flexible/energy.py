"""Energy and angular momentum of the flexible satellite: the physical invariants its tests check.

With ``h = J w + delta' eta'`` the total angular momentum in body components,

- ``E = w'J w/2 + w' delta' eta' + eta'' M eta'/2 + eta' K eta/2`` (kinetic plus strain energy),
  whose rate is the power balance ``E' = w'(u + d) + eta''(Gamma_a v + d_f) - eta'' C eta'``;
- ``R(q) h`` is constant without external torques (the PZT forces are internal).

The bodies of :meth:`models.FlexibleSatellite.energy`, ``energy_rate``, ``modal_energy``,
``angular_momentum`` and ``angular_momentum_inertial``; they take the state already split.
"""

from __future__ import annotations

import numpy as np

from models.flexible.parameters import HybridParameters

__all__ = ["angular_momentum", "energy", "energy_rate", "modal_energy"]


def angular_momentum(p: HybridParameters, w: np.ndarray, eta_dot: np.ndarray) -> np.ndarray:
    """``h = J w + delta' eta'`` (N m s, body components)."""
    return p.inertia @ w + p.coupling.T @ eta_dot


def energy(p: HybridParameters, w: np.ndarray, eta: np.ndarray, eta_dot: np.ndarray) -> float:
    """``E = w'J w/2 + w' delta' eta' + eta'' M eta'/2 + eta' K eta/2`` (J)."""
    return float(0.5 * w @ p.inertia @ w + w @ p.coupling.T @ eta_dot
                 + 0.5 * eta_dot @ p.modal_mass @ eta_dot + 0.5 * eta @ (p.stiffness * eta))


def energy_rate(
    p: HybridParameters, w: np.ndarray, eta_dot: np.ndarray, torque: np.ndarray, v: np.ndarray,
    d_f: np.ndarray,
) -> float:
    """``E' = w'(u + d) + eta''(Gamma_a v + d_f) - eta'' C eta'`` (W); ``torque`` includes ``d``."""
    return float(w @ torque + eta_dot @ (p.pzt_matrix @ v + d_f) - eta_dot @ (p.viscous_damping * eta_dot))


def modal_energy(p: HybridParameters, eta: np.ndarray, eta_dot: np.ndarray) -> float:
    """``eta'' M eta'/2 + eta' K eta/2`` (J): the energy of the modes alone."""
    return float(0.5 * eta_dot @ p.modal_mass @ eta_dot + 0.5 * eta @ (p.stiffness * eta))
