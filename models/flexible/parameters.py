"""The parameters of the flexible satellite, checked, with the matrices the model derives from them.

:func:`hybrid_parameters` reads the constructor arguments of :class:`models.FlexibleSatellite`
(``J``, ``Lambda_i``, ``xi_i``, ``delta``, ``M``, ``Gamma_a``) and returns them, read-only, as a
:class:`HybridParameters` with the derived ``M^-1``, ``J_mb = J - delta' M^-1 delta`` and its
inverse, ``delta' M^-1``, ``k_i = Lambda_i^2`` and ``c_i = 2 xi_i Lambda_i``. The dynamics, the
energy, the linear model and the single-axis transfer function all read this one object.

The published 4-mode set is here too (``DI_GENNARO_*``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_array, as_matrix, check_pd

__all__ = [
    "DI_GENNARO_COUPLING",
    "DI_GENNARO_DAMPING",
    "DI_GENNARO_FREQUENCIES",
    "DI_GENNARO_INERTIA",
    "HybridParameters",
    "hybrid_parameters",
]

#: Modal frequencies ``Lambda_i`` (rad/s) of the published 4-mode set (**likely**; Di Gennaro 2003).
DI_GENNARO_FREQUENCIES: tuple[float, ...] = (0.7681, 1.1038, 1.8733, 2.5496)
#: Modal damping ratios ``xi_i`` of the published set (**likely**).
DI_GENNARO_DAMPING: tuple[float, ...] = (0.0056, 0.0086, 0.0128, 0.0252)
#: Coupling ``delta`` (rows = modes, columns = x, y, z; kg^1/2 m) of the published set (**likely**).
DI_GENNARO_COUPLING: tuple[tuple[float, float, float], ...] = (
    (6.45637, 1.27814, 2.15629),
    (-1.25619, 0.91756, -1.67264),
    (1.11687, 2.48901, -0.83674),
    (1.23637, -2.65810, -1.12503),
)
#: Hub inertia (kg m^2) paired with the published modes by Hu & Ma (2005) (**assumed**).
DI_GENNARO_INERTIA: tuple[tuple[float, float, float], ...] = (
    (350.0, 3.0, 4.0),
    (3.0, 270.0, 10.0),
    (4.0, 10.0, 190.0),
)


@dataclass(frozen=True)
class HybridParameters:
    """The checked parameters of the hybrid-coordinate model and what it derives from them.

    Every array is read-only. ``N`` modes, ``n_a`` PZT inputs.

    Attributes
    ----------
    inertia : (3, 3) ndarray
        ``J`` (kg m^2), symmetric positive definite.
    frequencies, damping : (N,) ndarray
        ``Lambda_i`` (rad/s) and ``xi_i``.
    coupling : (N, 3) ndarray
        ``delta`` (kg^1/2 m).
    modal_mass, mass_inv : (N, N) ndarray
        ``M`` and ``M^-1``.
    pzt_matrix : (N, n_a) ndarray
        ``Gamma_a``.
    hub_inertia, hub_inertia_inv : (3, 3) ndarray
        ``J_mb = J - delta' M^-1 delta`` and its inverse.
    couple : (3, N) ndarray
        ``delta' M^-1``.
    stiffness, viscous_damping : (N,) ndarray
        ``k_i = Lambda_i^2`` and ``c_i = 2 xi_i Lambda_i``: the diagonals of ``K`` and ``C``.
    """

    inertia: np.ndarray
    frequencies: np.ndarray
    damping: np.ndarray
    coupling: np.ndarray
    modal_mass: np.ndarray
    pzt_matrix: np.ndarray
    mass_inv: np.ndarray
    hub_inertia: np.ndarray
    hub_inertia_inv: np.ndarray
    couple: np.ndarray
    stiffness: np.ndarray
    viscous_damping: np.ndarray

    @property
    def n_modes(self) -> int:
        """Number of modes ``N``."""
        return int(self.frequencies.size)

    @property
    def n_pzt(self) -> int:
        """Number of PZT inputs ``n_a``."""
        return int(self.pzt_matrix.shape[1])


def _modal(value: Any, name: str, shape: tuple[int, int | None] | tuple[int]) -> np.ndarray:
    """A per-mode array of the given shape (``None``: any width); the message names the argument."""
    arr = as_array(value, name)
    if shape[0] == 0 and arr.size == 0:
        return arr.reshape((0, *(0 if s is None else s for s in shape[1:])))
    ok = arr.ndim == len(shape) and all(s is None or a == s for a, s in zip(arr.shape, shape, strict=True))
    if not ok:
        want = "(" + ", ".join("n_a" if s is None else str(s) for s in shape) + ")"
        raise InvalidArgumentError(
            name, f"shape {want}: one entry (row) per mode, {shape[0]} modes as in frequencies",
            f"shape {arr.shape}",
        )
    return arr


def hybrid_parameters(
    inertia: ArrayLike,
    frequencies: ArrayLike,
    damping: ArrayLike,
    coupling: ArrayLike,
    *,
    modal_mass: ArrayLike | None = None,
    pzt_matrix: ArrayLike | None = None,
) -> HybridParameters:
    """Check the parameters of :class:`models.FlexibleSatellite` and derive the model's matrices.

    Raises
    ------
    InvalidArgumentError
        On mismatched mode counts (naming the argument), negative damping, non-positive
        frequencies, or a coupling that makes the mass matrix indefinite (naming ``coupling``).

    Examples
    --------
    >>> from models.flexible.parameters import DI_GENNARO_INERTIA, hybrid_parameters
    >>> p = hybrid_parameters(DI_GENNARO_INERTIA, [1.0], [0.01], [[1.0, 0.0, 0.0]])
    >>> p.n_modes, float(p.hub_inertia[0, 0])
    (1, 349.0)
    """
    j = check_pd(as_matrix(inertia, "inertia", (3, 3)), "inertia")
    freq = as_array(frequencies, "frequencies").ravel()
    n_modes = int(freq.size)
    if np.any(freq <= 0.0):
        raise InvalidArgumentError("frequencies", "modal frequencies > 0 (rad/s)", repr(freq.tolist()))
    damp = _modal(damping, "damping", (n_modes,))
    if np.any(damp < 0.0):
        raise InvalidArgumentError("damping", "damping ratios >= 0", repr(damp.tolist()))
    delta = _modal(coupling, "coupling", (n_modes, 3))
    mass = np.eye(n_modes)
    if modal_mass is not None:
        mass = _modal(modal_mass, "modal_mass", (n_modes, n_modes))
        if n_modes:
            check_pd(mass, "modal_mass")
    gamma_a = np.eye(n_modes)
    if pzt_matrix is not None:
        gamma_a = _modal(pzt_matrix, "pzt_matrix", (n_modes, None))
    mass_inv = np.linalg.inv(mass) if n_modes else np.zeros((0, 0))
    j_mb = j - delta.T @ mass_inv @ delta
    j_mb = 0.5 * (j_mb + j_mb.T)
    lam_min = float(np.linalg.eigvalsh(j_mb)[0])
    if lam_min <= 0.0:
        raise InvalidArgumentError(
            "coupling",
            "a coupling delta with J - delta' M^-1 delta positive definite (a positive definite "
            "mass matrix)",
            f"smallest eigenvalue of J - delta' M^-1 delta = {lam_min:.6g}",
        )
    params = HybridParameters(
        inertia=j, frequencies=freq, damping=damp, coupling=delta, modal_mass=mass, pzt_matrix=gamma_a,
        mass_inv=mass_inv, hub_inertia=j_mb, hub_inertia_inv=np.linalg.inv(j_mb),
        couple=delta.T @ mass_inv, stiffness=freq**2, viscous_damping=2.0 * damp * freq,
    )
    for arr in vars(params).values():
        arr.setflags(write=False)
    return params
