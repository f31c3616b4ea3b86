"""The linear ``6 + 2N`` model of the flexible satellite.

:func:`linearize` is the body of :meth:`models.FlexibleSatellite.linearize`; it and the
uncertainty polytope (:mod:`models.flexible.polytope`) both build their matrices with
:func:`linear_matrices`, so a vertex of the polytope is the nominal model with some parameters
replaced, not a second implementation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.euler import kinematics_matrix
from models.attitude.vectors import skew
from models.flexible.parameters import HybridParameters
from models.linear import operating_point
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector, check_choice, check_positive

__all__ = [
    "POLYTOPIC_ATTITUDE",
    "AttitudeForm",
    "ParameterPoint",
    "linear_matrices",
    "linear_state_names",
    "linearize",
]

AttitudeForm = Literal["euler", "quaternion"]
#: The :attr:`models.PolytopicModel.attitude` of a linear model with each attitude form.
POLYTOPIC_ATTITUDE: dict[str, str] = {"euler": "euler321", "quaternion": "quaternion_vector"}


@dataclass(frozen=True)
class ParameterPoint:
    """Parameters of the linear model that the uncertainty polytope varies.

    Attributes
    ----------
    kappa : float
        Scale of the inverse hub inertia: ``P = kappa J_mb^-1`` (> 0; 1 is nominal).
    stiffness : (N,) ndarray or None
        Modal stiffnesses ``k_i`` (the diagonal of ``K``); ``None``: nominal ``Lambda_i^2``.
    viscous_damping : (N,) ndarray or None
        Modal damping coefficients ``c_i`` (the diagonal of ``C``); ``None``: nominal
        ``2 xi_i Lambda_i``.
    effectiveness : float
        Scale of the hub-torque columns of ``B`` (> 0; 1 is nominal).
    """

    kappa: float = 1.0
    stiffness: Any = None
    viscous_damping: Any = None
    effectiveness: float = 1.0

    def resolved(
        self, nominal_k: np.ndarray, nominal_c: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray, float]:
        """``(kappa, k, c, effectiveness)`` with the nominal values filled in, checked."""
        n = nominal_k.size
        kappa = check_positive(self.kappa, "kappa")
        eff = check_positive(self.effectiveness, "effectiveness")
        k = nominal_k if self.stiffness is None else as_vector(self.stiffness, "stiffness", n)
        c = nominal_c if self.viscous_damping is None else as_vector(
            self.viscous_damping, "viscous_damping", n
        )
        if np.any(k <= 0.0):
            raise InvalidArgumentError("stiffness", "modal stiffnesses > 0", repr(k.tolist()))
        if np.any(c < 0.0):
            raise InvalidArgumentError("viscous_damping", "modal damping coefficients >= 0", repr(c.tolist()))
        return kappa, k, c, eff


def linear_matrices(
    hub_inertia_inv: np.ndarray,
    mass_inv: np.ndarray,
    coupling: np.ndarray,
    stiffness: np.ndarray,
    damping: np.ndarray,
    pzt_matrix: np.ndarray,
    kinematics: np.ndarray,
    pzt: bool,
    effectiveness: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Continuous-time ``(A, B)`` of the linear model from its ingredients (no argument checks).

    With ``P`` = ``hub_inertia_inv``, ``G = M^-1 + M^-1 delta P delta' M^-1``, ``K = diag(k)``,
    ``C = diag(c)`` and ``Kin`` = ``kinematics``::

        A = [[0, Kin, 0,                 0               ],
             [0, 0,   P delta' M^-1 K,   P delta' M^-1 C ],
             [0, 0,   0,                 I               ],
             [0, 0,   -G K,              -G C            ]]
        B_u = [0; P; 0; -M^-1 delta P] * effectiveness,   B_v = [0; -P delta' M^-1; 0; G] Gamma_a

    ``A`` is affine in ``P`` times affine in ``(K, C)``: multi-affine in ``(kappa, k_i, c_i)``
    when ``P = kappa P0``; ``B`` is affine in ``kappa``.
    """
    n_m = coupling.shape[0]
    n = 6 + 2 * n_m
    p_inv = hub_inertia_inv
    k_mat, c_mat = np.diag(stiffness), np.diag(damping)
    a = np.zeros((n, n))
    a[:3, 3:6] = kinematics
    b_u = np.zeros((n, 3))
    b_u[3:6] = p_inv
    g_mat = mass_inv + mass_inv @ coupling @ p_inv @ coupling.T @ mass_inv
    if n_m:
        couple = p_inv @ coupling.T @ mass_inv
        a[3:6, 6:6 + n_m] = couple @ k_mat
        a[3:6, 6 + n_m:] = couple @ c_mat
        a[6:6 + n_m, 6 + n_m:] = np.eye(n_m)
        a[6 + n_m:, 6:6 + n_m] = -g_mat @ k_mat
        a[6 + n_m:, 6 + n_m:] = -g_mat @ c_mat
        b_u[6 + n_m:] = -mass_inv @ coupling @ p_inv
    b_u = b_u * effectiveness
    if not pzt:
        return a, b_u
    b_v = np.zeros((n, pzt_matrix.shape[1]))
    if n_m:
        b_v[3:6] = -p_inv @ coupling.T @ mass_inv @ pzt_matrix
        b_v[6 + n_m:] = g_mat @ pzt_matrix
    return a, np.hstack((b_u, b_v))


def linear_state_names(state_names: tuple[str, ...], attitude: AttitudeForm = "euler") -> tuple[str, ...]:
    """Names of the linear state for ``attitude``, from the nonlinear ``state_names`` (``q0..q3`` first)."""
    check_choice(attitude, "attitude", ("euler", "quaternion"))
    att = ("phi", "theta", "psi") if attitude == "euler" else ("q1", "q2", "q3")
    return att + state_names[4:]


def linearize(
    p: HybridParameters,
    x_op: ArrayLike | None = None,
    *,
    pzt: bool = False,
    attitude: AttitudeForm = "euler",
    parameters: ParameterPoint | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Continuous ``(A, B)`` about zero rates and modes; see :meth:`models.FlexibleSatellite.linearize`."""
    check_choice(attitude, "attitude", ("euler", "quaternion"))
    n = 6 + 2 * p.n_modes
    x = operating_point(x_op, n)
    if np.any(x[3:] != 0.0):
        raise InvalidArgumentError(
            "x_op", "zero rates and a zero modal state (the model is linearised there)",
            f"x_op[3:] = {x[3:].tolist()}",
        )
    att = x[:3]
    if attitude == "euler":
        kin = kinematics_matrix(att[0], att[1])
    else:
        norm2 = float(att @ att)
        if norm2 > 1.0:
            raise InvalidArgumentError(
                "x_op", "a quaternion vector part with |q_v| <= 1", f"|q_v| = {np.sqrt(norm2):.6g}"
            )
        kin = 0.5 * (np.sqrt(1.0 - norm2) * np.eye(3) + skew(att))
    point = ParameterPoint() if parameters is None else parameters
    if not isinstance(point, ParameterPoint):
        raise ArgumentTypeError("parameters", "None or a models.flexible.linear.ParameterPoint",
                                type(parameters).__name__)
    kappa, k, c, eff = point.resolved(p.stiffness, p.viscous_damping)
    return linear_matrices(kappa * p.hub_inertia_inv, p.mass_inv, p.coupling, k, c, p.pzt_matrix,
                           kin, pzt, eff)
