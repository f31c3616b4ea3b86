"""Unit quaternions (scalar first, Hamilton product) and their 3-2-1 Euler angles.

Convention: ``q = [q0, q1, q2, q3] = [cos(a/2), sin(a/2) e]`` describes the rotation of the body
frame by the angle ``a`` about the unit axis ``e``; :func:`quat_to_dcm` returns the matrix
``R(q)`` that maps body components to inertial (reference) components, the same direction as
:func:`models.attitude.euler.rotation_matrix` for 3-2-1 Euler angles. With body rates ``w`` the
kinematics are ``q' = q * [0, w] / 2``, i.e.::

    q0' = -q_v' w / 2,    q_v' = (q0 I + [q_v x]) w / 2,

and ``R(q)' = R(q) [w x]``. ``q`` and ``-q`` are the same attitude; :func:`quat_error` picks
the representative with ``q0 >= 0`` (the short way round).

Examples
--------
>>> import numpy as np
>>> from models.attitude.quaternion import euler321_to_quat, quat_to_euler321
>>> q = euler321_to_quat([0.1, -0.2, 0.3])
>>> np.round(quat_to_euler321(q), 12).tolist()
[0.1, -0.2, 0.3]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.euler import euler321_from_matrix
from models.attitude.vectors import skew
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector

__all__ = [
    "UNIT_NORM_TOL",
    "euler321_to_quat",
    "quat_conjugate",
    "quat_error",
    "quat_from_axis_angle",
    "quat_kinematics_matrix",
    "quat_multiply",
    "quat_to_dcm",
    "quat_to_euler321",
    "rotation_angle",
    "unit_quaternion",
]

#: How far from 1 the norm of a quaternion given by the user may be before it is rejected.
UNIT_NORM_TOL = 1e-6


def unit_quaternion(q: ArrayLike, name: str) -> np.ndarray:
    """``q`` checked to be a unit quaternion (norm within :data:`UNIT_NORM_TOL` of 1), normalised."""
    return _unit(q, name)


def _unit(q: ArrayLike, name: str) -> np.ndarray:
    vec = as_vector(q, name, 4)
    norm = float(np.linalg.norm(vec))
    if abs(norm - 1.0) > UNIT_NORM_TOL:
        raise InvalidArgumentError(name, "a unit quaternion [q0, q1, q2, q3]", f"norm {norm:.9g}")
    return vec / norm


def quat_multiply(p: ArrayLike, q: ArrayLike) -> np.ndarray:
    """Hamilton product ``p * q`` (scalar first): the rotation ``q`` followed by ``p`` in body terms.

    Examples
    --------
    >>> from models.attitude.quaternion import quat_multiply
    >>> quat_multiply([0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]).tolist()   # i j = k
    [0.0, 0.0, 0.0, 1.0]
    """
    p = as_vector(p, "p", 4)
    q = as_vector(q, "q", 4)
    p0, pv = p[0], p[1:]
    q0, qv = q[0], q[1:]
    return np.concatenate(([p0 * q0 - pv @ qv], p0 * qv + q0 * pv + np.cross(pv, qv)))


def quat_conjugate(q: ArrayLike) -> np.ndarray:
    """``[q0, -q_v]``: the inverse rotation of a unit quaternion."""
    q = as_vector(q, "q", 4)
    return np.concatenate(([q[0]], -q[1:]))


def quat_from_axis_angle(axis: ArrayLike, angle: float) -> np.ndarray:
    """The rotation by ``angle`` (rad) about ``axis`` (normalised here; must be non-zero)."""
    e = as_vector(axis, "axis", 3)
    norm = float(np.linalg.norm(e))
    if norm == 0.0:
        raise InvalidArgumentError("axis", "a non-zero rotation axis", repr(e.tolist()))
    half = 0.5 * float(angle)
    return np.concatenate(([np.cos(half)], np.sin(half) * e / norm))


def quat_to_dcm(q: ArrayLike) -> np.ndarray:
    """``R(q) = (q0^2 - q_v'q_v) I + 2 q_v q_v' + 2 q0 [q_v x]`` (body to inertial components)."""
    q = as_vector(q, "q", 4)
    q0, qv = q[0], q[1:]
    return (q0 * q0 - qv @ qv) * np.eye(3) + 2.0 * np.outer(qv, qv) + 2.0 * q0 * skew(qv)


def quat_kinematics_matrix(q: ArrayLike) -> np.ndarray:
    """The ``4 x 3`` matrix ``E(q)`` with ``q' = E(q) w``: rows ``-q_v'/2`` and ``(q0 I + [q_v x])/2``."""
    q = as_vector(q, "q", 4)
    q0, qv = q[0], q[1:]
    return 0.5 * np.vstack((-qv, q0 * np.eye(3) + skew(qv)))


def quat_error(q: ArrayLike, q_ref: ArrayLike | None = None) -> np.ndarray:
    """The attitude of the body relative to the reference, ``q_ref^-1 * q``, with ``q0 >= 0``.

    ``q_ref`` defaults to the identity ``[1, 0, 0, 0]``. Its vector part ``q_v`` is what the
    sliding-mode and PD laws feed back; ``q_v = sin(a/2) e`` for an error rotation ``a`` about
    ``e``.
    """
    q = _unit(q, "q")
    if q_ref is None:
        err = q
    else:
        err = quat_multiply(quat_conjugate(_unit(q_ref, "q_ref")), q)
    return err if err[0] >= 0.0 else -err


def rotation_angle(q: ArrayLike, q_ref: ArrayLike | None = None) -> float:
    """The rotation angle (rad, in ``[0, pi]``) between ``q`` and ``q_ref`` (default identity).

    Computed as ``2 atan2(||q_v||, |q0|)``, accurate near zero where ``2 acos(q0)`` is not.
    """
    err = quat_error(q, q_ref)
    return 2.0 * float(np.arctan2(np.linalg.norm(err[1:]), abs(err[0])))


def euler321_to_quat(attitude: ArrayLike) -> np.ndarray:
    """The quaternion of 3-2-1 Euler angles ``[phi, theta, psi]`` (``R = Rz(psi) Ry(theta) Rx(phi)``)."""
    phi, theta, psi = as_vector(attitude, "attitude", 3) * 0.5
    cx, sx = np.cos(phi), np.sin(phi)
    cy, sy = np.cos(theta), np.sin(theta)
    cz, sz = np.cos(psi), np.sin(psi)
    q = np.array([
        cz * cy * cx + sz * sy * sx,
        cz * cy * sx - sz * sy * cx,
        cz * sy * cx + sz * cy * sx,
        sz * cy * cx - cz * sy * sx,
    ])
    return q if q[0] >= 0.0 else -q


def quat_to_euler321(q: ArrayLike) -> np.ndarray:
    """3-2-1 Euler angles ``[phi, theta, psi]`` (rad) of a unit quaternion.

    ``theta`` is in ``[-pi/2, pi/2]``, ``phi`` and ``psi`` in ``(-pi, pi]``. At gimbal lock
    (``|cos(theta)| < SINGULARITY_COS_TOL`` of :mod:`models.attitude.euler`) only ``psi - phi``
    (``theta = +90 deg``) or ``psi + phi`` (``-90 deg``) is defined: the function then returns
    ``phi = 0`` and puts the whole rotation about the vertical into ``psi`` (exact at
    ``theta = +-90 deg``, within about ``1e-3`` rad inside the band). Never NaN.
    (:func:`models.attitude.euler.euler321_from_matrix` of :func:`quat_to_dcm`.)
    """
    return euler321_from_matrix(quat_to_dcm(_unit(q, "q")))
