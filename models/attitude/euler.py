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

from toolkit_common.errors import InvalidArgumentError, SingularityError

__all__ = [
    "SINGULARITY_COS_TOL",
    "euler321_from_matrix",
    "euler_rates",
    "euler_rates_jacobian",
    "kinematics_cover",
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
    >>> from models.attitude.euler import kinematics_matrix
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


def euler321_from_matrix(r: np.ndarray) -> np.ndarray:
    """3-2-1 Euler angles ``[phi, theta, psi]`` (rad) of a body-to-reference rotation matrix.

    The inverse of :func:`rotation_matrix`: ``theta`` in ``[-pi/2, pi/2]``, ``phi`` and ``psi``
    in ``(-pi, pi]``. At gimbal lock (``cos(theta) <`` :data:`SINGULARITY_COS_TOL`) only
    ``psi - phi`` (``theta = +90 deg``) or ``psi + phi`` (``-90 deg``) is defined: the function
    then returns ``phi = 0`` and puts the whole rotation about the vertical into ``psi`` (exact
    at ``theta = +-90 deg``, within about ``1e-3`` rad inside the band). Never NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.euler import euler321_from_matrix, rotation_matrix
    >>> np.round(euler321_from_matrix(rotation_matrix([0.1, -0.2, 0.3])), 12).tolist()
    [0.1, -0.2, 0.3]
    """
    sin_t = float(np.clip(-r[2, 0], -1.0, 1.0))
    theta = float(np.arcsin(sin_t))
    if np.cos(theta) < SINGULARITY_COS_TOL:
        # R = [[0, s(phi - psi)... ]]: with phi = 0, R[0, 1] = -sin(psi), R[1, 1] = cos(psi)
        psi = float(np.arctan2(-r[0, 1], r[1, 1]))
        return np.array([0.0, theta, psi])
    phi = float(np.arctan2(r[2, 1], r[2, 2]))
    psi = float(np.arctan2(r[1, 0], r[0, 0]))
    return np.array([phi, theta, psi])


def _arc_triangle(lo: float, hi: float) -> list[np.ndarray]:
    """Points whose convex hull contains ``(sin a, cos a)`` for every ``a`` in ``[lo, hi]``.

    The arc lies between its chord and the tangents at its ends: the two end points and the
    tangents' intersection (``(sin m, cos m) / cos h``, ``m`` the middle, ``h`` the half width).
    """
    if hi - lo <= 0.0:
        return [np.array([np.sin(lo), np.cos(lo)])]
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    apex = np.array([np.sin(mid), np.cos(mid)]) / np.cos(half)
    return [np.array([np.sin(lo), np.cos(lo)]), np.array([np.sin(hi), np.cos(hi)]), apex]


def _secant_triangle(lo: float, hi: float) -> list[np.ndarray]:
    """Points whose convex hull contains ``(tan t, sec t)`` for every ``t`` in ``[lo, hi]``.

    On ``|t| < 90 deg`` the curve is ``y = sqrt(1 + x^2)``, convex: it lies below its chord and
    above its end tangents ``y = sin(t_i) x + cos(t_i)``; their intersection closes the triangle.
    """
    ends = [np.array([np.tan(t), 1.0 / np.cos(t)]) for t in (lo, hi)]
    if hi - lo <= 0.0:
        return ends[:1]
    s_lo, s_hi = np.sin(lo), np.sin(hi)
    x = (np.cos(hi) - np.cos(lo)) / (s_lo - s_hi)
    return [*ends, np.array([x, s_lo * x + np.cos(lo)])]


def kinematics_cover(phi_bounds: tuple[float, float], theta_bounds: tuple[float, float]) -> list[np.ndarray]:
    """Kinematics matrices whose convex hull contains ``K(phi, theta)`` over a box of attitudes.

    ``K`` is affine in ``(sin phi, cos phi)`` for a fixed pitch and affine in
    ``(tan theta, sec theta)`` for a fixed roll. Each pair runs along a curve that a triangle
    contains (an arc of the unit circle; a branch of ``y = sqrt(1 + x^2)``), so ``K`` over the
    box lies in the convex hull of ``K`` at the 3 x 3 pairs of triangle corners (at most 9
    matrices; fewer when a range is a single value). The corners of the box alone do not
    suffice: ``K`` is not affine in the angles.

    Parameters
    ----------
    phi_bounds, theta_bounds : (float, float)
        ``(lower, upper)`` roll and pitch (rad); the pitch interval must stay inside
        ``(-90, 90)`` deg (a :class:`~toolkit_common.errors.SingularityError` otherwise).

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.euler import kinematics_cover
    >>> len(kinematics_cover((0.0, 0.5), (-0.2, 0.6)))
    9
    >>> np.allclose(kinematics_cover((0.1, 0.1), (0.2, 0.2))[0], kinematics_matrix(0.1, 0.2))
    True
    """
    phi_lo, phi_hi = (float(v) for v in phi_bounds)
    theta_lo, theta_hi = (float(v) for v in theta_bounds)
    if not (phi_lo <= phi_hi and phi_hi - phi_lo < np.pi):
        raise InvalidArgumentError(
            "phi_bounds", "lower <= upper, less than 180 deg apart", f"({phi_lo!r}, {phi_hi!r})"
        )
    if not theta_lo <= theta_hi:
        raise InvalidArgumentError("theta_bounds", "lower <= upper", f"({theta_lo!r}, {theta_hi!r})")
    for t in (theta_lo, theta_hi):
        _check_pitch(t)
    if theta_lo <= -0.5 * np.pi or theta_hi >= 0.5 * np.pi:
        _check_pitch(0.5 * np.pi)  # the interval contains the singularity
    mats = []
    for s_p, c_p in _arc_triangle(phi_lo, phi_hi):
        for t_t, sec_t in _secant_triangle(theta_lo, theta_hi):
            mats.append(
                np.array(
                    [
                        [1.0, s_p * t_t, c_p * t_t],
                        [0.0, c_p, -s_p],
                        [0.0, s_p * sec_t, c_p * sec_t],
                    ]
                )
            )
    return mats
