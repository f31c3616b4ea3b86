"""3-2-1 (yaw-pitch-roll) Euler-angle kinematics and their derivatives.

The attitude ``eta = [phi, theta, psi]`` (roll, pitch, yaw) evolves with the body rates
``w = [p, q, r]`` as ``eta' = K(phi, theta) w`` with

.. math::

    K(\\phi, \\theta) = \\begin{bmatrix}
        1 & \\sin\\phi \\tan\\theta & \\cos\\phi \\tan\\theta \\\\
        0 & \\cos\\phi & -\\sin\\phi \\\\
        0 & \\sin\\phi / \\cos\\theta & \\cos\\phi / \\cos\\theta
    \\end{bmatrix}.

``K`` is singular at ``theta = +-pi/2`` (gimbal lock); the functions here raise
:class:`~toolkit_common.errors.SingularityError` when ``|cos(theta)|`` falls below
:data:`SINGULARITY_COS_TOL` instead of returning huge numbers or NaN.
"""

from __future__ import annotations

import numpy as np

from toolkit_common.errors import SingularityError

__all__ = [
    "SINGULARITY_COS_TOL",
    "euler_rates",
    "euler_rates_jacobian",
    "kinematics_matrix",
    "rotation_matrix",
]

#: Smallest ``|cos(theta)|`` accepted before the 3-2-1 kinematics are declared singular
#: (about 0.057 deg from +-90 deg).
SINGULARITY_COS_TOL = 1e-3


def _check_pitch(theta: float) -> float:
    cos_t = float(np.cos(theta))
    if abs(cos_t) < SINGULARITY_COS_TOL:
        raise SingularityError(
            f"theta (pitch): the 3-2-1 Euler kinematics are singular at +-90 deg; found "
            f"theta = {np.degrees(theta):.4f} deg (|cos(theta)| = {abs(cos_t):.2e} < "
            f"{SINGULARITY_COS_TOL:g}). Use a quaternion attitude for such manoeuvres."
        )
    return cos_t


def kinematics_matrix(phi: float, theta: float) -> np.ndarray:
    """Return ``K(phi, theta)`` with ``[phi', theta', psi'] = K [p, q, r]``.

    Examples
    --------
    >>> import numpy as np
    >>> from models.kinematics import kinematics_matrix
    >>> np.allclose(kinematics_matrix(0.0, 0.0), np.eye(3))
    True
    """
    cos_t = _check_pitch(theta)
    s_p, c_p = np.sin(phi), np.cos(phi)
    t_t = np.sin(theta) / cos_t
    return np.array(
        [
            [1.0, s_p * t_t, c_p * t_t],
            [0.0, c_p, -s_p],
            [0.0, s_p / cos_t, c_p / cos_t],
        ]
    )


def euler_rates(attitude: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Return ``[phi', theta', psi']`` for the attitude ``[phi, theta, psi]`` and body rates."""
    return kinematics_matrix(attitude[0], attitude[1]) @ rates


def euler_rates_jacobian(attitude: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Return ``d(eta')/d(eta)``, the 3 x 3 derivative of the Euler rates w.r.t. the angles.

    The derivative with respect to the rates is :func:`kinematics_matrix` itself; yaw does
    not enter the kinematics, so the last column is zero.
    """
    phi, theta = float(attitude[0]), float(attitude[1])
    cos_t = _check_pitch(theta)
    _, q, r = (float(v) for v in rates)
    s_p, c_p = np.sin(phi), np.cos(phi)
    sin_t = np.sin(theta)
    a = q * s_p + r * c_p  # enters through theta
    b = q * c_p - r * s_p  # derivative of a w.r.t. phi
    jac = np.zeros((3, 3))
    jac[0, 0] = b * sin_t / cos_t
    jac[0, 1] = a / cos_t**2
    jac[1, 0] = -a
    jac[2, 0] = b / cos_t
    jac[2, 1] = a * sin_t / cos_t**2
    return jac


def rotation_matrix(attitude: np.ndarray) -> np.ndarray:
    """Return the body-to-inertial rotation ``R = Rz(psi) Ry(theta) Rx(phi)`` (3-2-1)."""
    phi, theta, psi = (float(v) for v in attitude)
    cx, sx = np.cos(phi), np.sin(phi)
    cy, sy = np.cos(theta), np.sin(theta)
    cz, sz = np.cos(psi), np.sin(psi)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx
