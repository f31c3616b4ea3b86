"""The flexible satellite in hybrid coordinates: a rigid hub with N flexible modes.

Model (paper S eq. 1; modal mass ``M``, PZT forces ``Gamma_a v`` from paper V; seeds
``papers-S-V-flexible.md`` section 2)::

    J w' + delta' eta'' = -w x (J w + delta' eta') + u + d
    M eta'' + C eta' + K eta + delta w' = Gamma_a v + d_f
    C = diag(2 xi_i Lambda_i),  K = diag(Lambda_i^2)

``J`` (3 x 3, SPD) is the total inertia with the appendages undeformed, ``delta`` (N x 3) the
rigid-flexible coupling (rows = modes, columns = body x, y, z; kg^1/2 m), ``eta`` the modal
coordinates and ``v`` the PZT commands. The mass matrix ``[[J, delta'], [delta, M]]`` is
positive definite exactly when ``J_mb = J - delta' M^-1 delta`` is (the hub inertia with the
modes' participation removed); the constructor checks it.

This module holds the parameters and the linearised ``6 + 2N`` model (seed section 2.2):
about zero rates and a zero modal state, with the attitude as 3-2-1 Euler angles,
``x = [phi, theta, psi, p, q, r, eta_1..eta_N, eta_1'..eta_N']`` and the inputs the three hub
torques (and, optionally, the PZT commands).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from models.discretize import zoh
from models.kinematics import kinematics_matrix
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_pd

__all__ = [
    "DI_GENNARO_COUPLING",
    "DI_GENNARO_DAMPING",
    "DI_GENNARO_FREQUENCIES",
    "DI_GENNARO_INERTIA",
    "FlexibleSatellite",
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


def _real_array(value: Any, name: str) -> np.ndarray:
    if isinstance(value, str | bytes):
        raise ArgumentTypeError(name, "a numeric array", f"{type(value).__name__} {value!r}")
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ArgumentTypeError(name, "a numeric array", f"{type(value).__name__} ({err})") from None
    if not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(name, "finite values", repr(arr.tolist()))
    return arr


def _modal(value: Any, name: str, shape: tuple[int, int | None] | tuple[int]) -> np.ndarray:
    """A per-mode array of the given shape (``None``: any width); the message names the argument."""
    arr = _real_array(value, name)
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


class FlexibleSatellite:
    """A rigid hub with ``N`` flexible modes (hybrid coordinates), modal mass ``M``.

    Parameters
    ----------
    inertia : (3, 3) array_like
        Total inertia ``J`` (kg m^2) with the appendages undeformed, symmetric positive definite.
    frequencies : (N,) array_like
        Modal (cantilever, hub-clamped) frequencies ``Lambda_i`` > 0 (rad/s).
    damping : (N,) array_like
        Modal damping ratios ``xi_i`` >= 0.
    coupling : (N, 3) array_like
        Rigid-flexible coupling ``delta`` (rows = modes; kg^1/2 m).
    modal_mass : (N, N) array_like, optional
        Modal mass matrix ``M`` (symmetric positive definite); default the identity
        (mass-normalised modes).
    pzt_matrix : (N, n_a) array_like, optional
        PZT modal-force matrix ``Gamma_a`` (modal force = ``Gamma_a v``); default the identity
        (``n_a = N``, ``v`` in modal-force units; **assumed**).

    Raises
    ------
    InvalidArgumentError
        On mismatched mode counts (naming the argument), negative damping, non-positive
        frequencies, or a coupling that makes the mass matrix indefinite (naming ``coupling``,
        i.e. ``delta``).

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> A, B = sat.linearize()
    >>> A.shape, B.shape
    ((14, 14), (14, 3))
    >>> sat.with_modes(2).n_states
    10
    """

    def __init__(
        self,
        inertia: Any,
        frequencies: Any,
        damping: Any,
        coupling: Any,
        *,
        modal_mass: Any = None,
        pzt_matrix: Any = None,
    ) -> None:
        self._inertia = check_pd(as_matrix(inertia, "inertia", (3, 3)), "inertia")
        self._freq = _real_array(frequencies, "frequencies").ravel()
        n_modes = int(self._freq.size)
        if np.any(self._freq <= 0.0):
            found = repr(self._freq.tolist())
            raise InvalidArgumentError("frequencies", "modal frequencies > 0 (rad/s)", found)
        self._damp = _modal(damping, "damping", (n_modes,))
        if np.any(self._damp < 0.0):
            raise InvalidArgumentError("damping", "damping ratios >= 0", repr(self._damp.tolist()))
        self._delta = _modal(coupling, "coupling", (n_modes, 3))
        self._mass = np.eye(n_modes)
        if modal_mass is not None:
            self._mass = _modal(modal_mass, "modal_mass", (n_modes, n_modes))
            if n_modes:
                check_pd(self._mass, "modal_mass")
        self._gamma_a = np.eye(n_modes)
        if pzt_matrix is not None:
            self._gamma_a = _modal(pzt_matrix, "pzt_matrix", (n_modes, None))
        self._mass_inv = np.linalg.inv(self._mass) if n_modes else np.zeros((0, 0))
        j_mb = self._inertia - self._delta.T @ self._mass_inv @ self._delta
        j_mb = 0.5 * (j_mb + j_mb.T)
        lam_min = float(np.linalg.eigvalsh(j_mb)[0])
        if lam_min <= 0.0:
            raise InvalidArgumentError(
                "coupling",
                "a coupling delta with J - delta' M^-1 delta positive definite (a positive definite "
                "mass matrix)",
                f"smallest eigenvalue of J - delta' M^-1 delta = {lam_min:.6g}",
            )
        self._j_mb = j_mb
        for arr in (self._inertia, self._freq, self._damp, self._delta, self._mass, self._gamma_a, j_mb):
            arr.setflags(write=False)

    @classmethod
    def di_gennaro(cls, n_modes: int = 4) -> FlexibleSatellite:
        """The published 4-mode set (seed section 2.5), or its first ``n_modes`` modes.

        Modes: S. Di Gennaro, "Output stabilization of flexible spacecraft with active
        vibration suppression", IEEE Trans. Aerospace and Electronic Systems 39(3), 2003,
        reused with the hub inertia ``J = [[350, 3, 4], [3, 270, 10], [4, 10, 190]]`` kg m^2 by
        Q. Hu and G. Ma, Aerospace Science and Technology 9(4), 2005 (attribution **likely**;
        the primary sources were not consulted). Frequencies, damping and coupling are
        **likely** (decoded; two public re-uses agree to 0.2 %); ``J`` is **assumed**.
        ``M = I``, ``Gamma_a = I``.
        """
        sat = cls(DI_GENNARO_INERTIA, DI_GENNARO_FREQUENCIES, DI_GENNARO_DAMPING, DI_GENNARO_COUPLING)
        return sat.with_modes(n_modes)

    def with_modes(self, n_modes: int) -> FlexibleSatellite:
        """The same satellite keeping only its first ``n_modes`` modes (0 gives the rigid hub)."""
        if isinstance(n_modes, bool) or not isinstance(n_modes, int | np.integer) or not (
            0 <= n_modes <= self.n_modes
        ):
            raise InvalidArgumentError("n_modes", f"an integer in [0, {self.n_modes}]", repr(n_modes))
        k = int(n_modes)
        return FlexibleSatellite(
            self._inertia, self._freq[:k], self._damp[:k], self._delta[:k],
            modal_mass=self._mass[:k, :k], pzt_matrix=self._gamma_a[:k],
        )

    # -- parameters ----------------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of flexible modes ``N``."""
        return int(self._freq.size)

    @property
    def n_states(self) -> int:
        """States of the linear model, ``6 + 2N`` (Euler-angle attitude)."""
        return 6 + 2 * self.n_modes

    @property
    def n_pzt(self) -> int:
        """Number of PZT inputs ``n_a`` (columns of ``Gamma_a``)."""
        return int(self._gamma_a.shape[1])

    @property
    def inertia(self) -> np.ndarray:
        """Total inertia ``J`` (kg m^2, read-only)."""
        return self._inertia

    @property
    def frequencies(self) -> np.ndarray:
        """Modal frequencies ``Lambda_i`` (rad/s)."""
        return self._freq

    @property
    def damping(self) -> np.ndarray:
        """Modal damping ratios ``xi_i``."""
        return self._damp

    @property
    def coupling(self) -> np.ndarray:
        """Coupling ``delta`` (N x 3)."""
        return self._delta

    @property
    def modal_mass(self) -> np.ndarray:
        """Modal mass ``M`` (N x N)."""
        return self._mass

    @property
    def pzt_matrix(self) -> np.ndarray:
        """PZT modal-force matrix ``Gamma_a`` (N x n_a)."""
        return self._gamma_a

    @property
    def stiffness(self) -> np.ndarray:
        """``K = diag(Lambda_i^2)`` (assuming ``M = I`` scaling of the modes)."""
        return np.diag(self._freq**2)

    @property
    def damping_matrix(self) -> np.ndarray:
        """``C = diag(2 xi_i Lambda_i)``."""
        return np.diag(2.0 * self._damp * self._freq)

    @property
    def hub_inertia(self) -> np.ndarray:
        """``J_mb = J - delta' M^-1 delta`` (kg m^2), symmetric positive definite."""
        return self._j_mb

    def __repr__(self) -> str:
        return f"FlexibleSatellite(n_modes={self.n_modes}, frequencies={self._freq.tolist()})"

    # -- linear model -----------------------------------------------------------------------
    def linearize(self, x_op: Any = None, *, pzt: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Continuous-time ``(A, B)`` of the ``6 + 2N`` model about zero rates and modes.

        Parameters
        ----------
        x_op : array_like, optional
            Operating point; only its attitude (3-2-1 Euler angles, the first three entries)
            enters, through the kinematics matrix. Rates and modal states must be zero
            (the gyroscopic terms then vanish). Default: zero attitude.
        pzt : bool
            Append the ``n_a`` PZT inputs ``v`` to the three hub torques.

        Returns
        -------
        A : (6 + 2N, 6 + 2N) ndarray
        B : (6 + 2N, 3) or (6 + 2N, 3 + n_a) ndarray

        Notes
        -----
        With ``P = J_mb^-1`` and ``G = M^-1 + M^-1 delta P delta' M^-1`` (seed section 2.2)::

            A = [[0, Kin, 0,                 0               ],
                 [0, 0,   P delta' M^-1 K,   P delta' M^-1 C ],
                 [0, 0,   0,                 I               ],
                 [0, 0,   -G K,              -G C            ]]
            B_u = [0; P; 0; -M^-1 delta P],   B_v = [0; -P delta' M^-1; 0; G] Gamma_a
        """
        n_m = self.n_modes
        n = 6 + 2 * n_m
        if x_op is None:
            att = np.zeros(3)
        else:
            x = as_vector(x_op, "x_op", n)
            if np.any(x[3:] != 0.0):
                raise InvalidArgumentError(
                    "x_op", "zero rates and a zero modal state (the model is linearised there)",
                    f"x_op[3:] = {x[3:].tolist()}",
                )
            att = x[:3]
        p_inv = np.linalg.inv(self._j_mb)
        m_inv = self._mass_inv
        k_mat, c_mat = self.stiffness, self.damping_matrix
        g_mat = m_inv + m_inv @ self._delta @ p_inv @ self._delta.T @ m_inv
        a = np.zeros((n, n))
        a[:3, 3:6] = kinematics_matrix(att[0], att[1])
        if n_m:
            couple = p_inv @ self._delta.T @ m_inv
            a[3:6, 6:6 + n_m] = couple @ k_mat
            a[3:6, 6 + n_m:] = couple @ c_mat
            a[6:6 + n_m, 6 + n_m:] = np.eye(n_m)
            a[6 + n_m:, 6:6 + n_m] = -g_mat @ k_mat
            a[6 + n_m:, 6 + n_m:] = -g_mat @ c_mat
        b_u = np.zeros((n, 3))
        b_u[3:6] = p_inv
        if n_m:
            b_u[6 + n_m:] = -m_inv @ self._delta @ p_inv
        if not pzt:
            return a, b_u
        b_v = np.zeros((n, self.n_pzt))
        if n_m:
            b_v[3:6] = -p_inv @ self._delta.T @ m_inv @ self._gamma_a
            b_v[6 + n_m:] = g_mat @ self._gamma_a
        return a, np.hstack((b_u, b_v))

    def discretize(self, dt: float, x_op: Any = None, *, pzt: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Zero-order-hold discretisation of :meth:`linearize` at sample time ``dt``."""
        a, b = self.linearize(x_op, pzt=pzt)
        return zoh(a, b, dt)
