"""The inverse of the 3-2-1 Euler kinematics matrix and its derivatives (backstepping designs).

:func:`models.attitude.euler.kinematics_matrix` gives ``K(phi, theta)`` with ``eta' = K w``. Its
inverse maps Euler-angle rates to body rates, ``w = K^-1 eta'``, and is regular everywhere:

.. math::

    K^{-1}(\\phi, \\theta) = \\begin{bmatrix}
        1 & 0 & -\\sin\\theta \\\\
        0 & \\cos\\phi & \\sin\\phi \\cos\\theta \\\\
        0 & -\\sin\\phi & \\cos\\phi \\cos\\theta
    \\end{bmatrix}, \\qquad \\det K^{-1} = \\cos\\theta.

Paper W writes ``R`` for ``K`` and
needs ``d(K^-1)/dt`` in closed form for the derivative of its virtual control.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "inverse_kinematics_matrix",
    "inverse_kinematics_partials",
    "inverse_kinematics_rate",
]


def inverse_kinematics_matrix(phi: float, theta: float) -> np.ndarray:
    """Return ``K^-1(phi, theta)``, with ``w = K^-1 [phi', theta', psi']``.

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.euler import kinematics_matrix
    >>> from models.attitude.euler_inverse import inverse_kinematics_matrix
    >>> bool(np.allclose(kinematics_matrix(0.3, -0.4) @ inverse_kinematics_matrix(0.3, -0.4), np.eye(3)))
    True
    """
    s_p, c_p = np.sin(phi), np.cos(phi)
    s_t, c_t = np.sin(theta), np.cos(theta)
    return np.array([[1.0, 0.0, -s_t], [0.0, c_p, s_p * c_t], [0.0, -s_p, c_p * c_t]])


def inverse_kinematics_partials(phi: float, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(dK^-1/dphi, dK^-1/dtheta)``; ``K^-1`` does not depend on psi."""
    s_p, c_p = np.sin(phi), np.cos(phi)
    s_t, c_t = np.sin(theta), np.cos(theta)
    d_phi = np.array([[0.0, 0.0, 0.0], [0.0, -s_p, c_p * c_t], [0.0, -c_p, -s_p * c_t]])
    d_theta = np.array([[0.0, 0.0, -c_t], [0.0, 0.0, -s_p * s_t], [0.0, 0.0, -c_p * s_t]])
    return d_phi, d_theta


def inverse_kinematics_rate(phi: float, theta: float, phi_dot: float, theta_dot: float) -> np.ndarray:
    """Return ``d(K^-1)/dt = dK^-1/dphi phi' + dK^-1/dtheta theta'``."""
    d_phi, d_theta = inverse_kinematics_partials(phi, theta)
    return d_phi * phi_dot + d_theta * theta_dot
