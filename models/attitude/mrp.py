"""Modified Rodrigues parameters (MRP): rotation matrices, kinematics, shadow sets and errors.

Conventions of Schaub & Junkins ("Analytical Mechanics of Space Systems"), as paper M uses
them:

- ``sigma`` is the MRP of a frame B relative to a frame O, ``sigma = e tan(Phi/4)`` for the
  principal axis ``e`` and angle ``Phi``; from the quaternion ``(q_v, q_4)`` (scalar last),
  ``sigma = q_v / (1 + q_4)`` (**certain**).
- :func:`mrp_to_dcm` is the direction cosine matrix ``C(sigma)`` that maps O components to B
  components: ``C = I + (8 S^2 - 4 (1 - s's) S) / (1 + s's)^2`` with ``S = [sigma x]``.
- :func:`mrp_kinematics_matrix` is ``N(sigma)`` with ``sigma' = N(sigma) w``, ``w`` the rate of
  B relative to O in B components (**likely**, the standard form).
- The shadow set ``-sigma / (sigma' sigma)`` describes the same attitude
  (:func:`mrp_shadow`); :func:`mrp_switch` returns whichever of the two has
  ``sigma' sigma <= threshold`` (the short rotation for the default threshold 1).
- :func:`mrp_error` composes the attitude error so that
  ``mrp_to_dcm(se) == mrp_to_dcm(sigma) @ mrp_to_dcm(sigma_ref).T``.

3-2-1 (yaw-pitch-roll) Euler angles ``(roll, pitch, yaw)`` give ``C = R1(roll) R2(pitch)
R3(yaw)``, the same sequence as :mod:`models.attitude.euler` (whose ``rotation_matrix`` is the
transpose, body to frame). :mod:`models.mrp.tracking` builds the tracking errors of paper M's
satellite on these functions.

Quaternions here are ``(q_1, q_2, q_3, q_4)`` with the scalar last, the order
``scipy.spatial.transform.Rotation`` uses.

Examples
--------
>>> import numpy as np
>>> from models.attitude.mrp import mrp_error, mrp_from_euler321, mrp_to_dcm
>>> sigma = mrp_from_euler321(np.radians([40.0, -30.0, 20.0]))
>>> np.round(sigma, 6).tolist()
[0.195676, -0.096964, 0.130312]
>>> sr = mrp_from_euler321(np.radians([10.0, 5.0, -10.0]))
>>> se = mrp_error(sigma, sr)
>>> bool(np.allclose(mrp_to_dcm(se), mrp_to_dcm(sigma) @ mrp_to_dcm(sr).T, atol=1e-12))
True
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.euler import SINGULARITY_COS_TOL
from models.attitude.vectors import cross3, skew
from toolkit_common.errors import InvalidArgumentError, SingularityError
from toolkit_common.validation import as_matrix, as_vector, check_positive

__all__ = [
    "dcm_from_euler321",
    "euler321_from_dcm",
    "mrp_angle",
    "mrp_error",
    "mrp_error_angle",
    "mrp_from_dcm",
    "mrp_from_euler321",
    "mrp_from_quaternion",
    "mrp_kinematics_inverse",
    "mrp_kinematics_matrix",
    "mrp_shadow",
    "mrp_switch",
    "mrp_to_dcm",
    "mrp_to_quaternion",
]

#: Below this ``sigma' sigma`` an MRP is treated as zero by :func:`mrp_shadow` (its shadow
#: would be at infinity).
SHADOW_ZERO_TOL = 1e-300


def _dcm(s: np.ndarray) -> np.ndarray:
    """Unchecked ``C(sigma)`` (hot path of the plant and the controllers)."""
    ss = float(s @ s)
    sk = skew(s)
    return np.eye(3) + (8.0 * sk @ sk - 4.0 * (1.0 - ss) * sk) / (1.0 + ss) ** 2


def _kinematics(s: np.ndarray) -> np.ndarray:
    """Unchecked ``N(sigma)``."""
    ss = float(s @ s)
    return 0.25 * ((1.0 - ss) * np.eye(3) + 2.0 * skew(s) + 2.0 * np.outer(s, s))


def _switch(s: np.ndarray, threshold: float = 1.0) -> np.ndarray:
    """Unchecked shadow-set switch: ``-s / s's`` when ``s's > threshold``."""
    ss = float(s @ s)
    return -s / ss if ss > threshold else s


def _error(s: np.ndarray, sr: np.ndarray) -> np.ndarray:
    """Unchecked MRP error, the short set (``|se| <= 1``)."""
    # The composition has 0/0 when s is the shadow of sr (the error is the identity, written as
    # a 360 deg rotation). s and its shadow give the same C(se); use the one with the larger
    # denominator: D(s) = (1 - |s||sr|)^2 + 2 (|s||sr| + sr's) >= 0 and D(shadow) = |s - sr|^2/|s|^2
    # are never both small.
    ss, rr = float(s @ s), float(sr @ sr)
    den = 1.0 + rr * ss + 2.0 * float(sr @ s)
    if den < 0.5 and ss > 0.0:
        s = -s / ss
        ss = 1.0 / ss
        den = 1.0 + rr * ss + 2.0 * float(sr @ s)
    se = ((1.0 - rr) * s - (1.0 - ss) * sr + 2.0 * cross3(s, sr)) / den
    return _switch(se)


def _sigma(sigma: ArrayLike, name: str = "sigma") -> np.ndarray:
    return as_vector(sigma, name, 3)


def mrp_to_dcm(sigma: ArrayLike) -> np.ndarray:
    """The direction cosine matrix ``C(sigma)``: frame-O components to body (B) components.

    Parameters
    ----------
    sigma : (3,) array_like
        MRP of B relative to O (either set; a shadow gives the same matrix).

    Returns
    -------
    (3, 3) ndarray
        ``I + (8 S^2 - 4 (1 - s's) S) / (1 + s's)^2`` with ``S = [sigma x]``; orthonormal, det +1.

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.mrp import mrp_to_dcm
    >>> C = mrp_to_dcm([0.0, 0.0, np.tan(np.pi / 8)])   # 90 deg about z
    >>> np.round(C, 12).tolist()
    [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    return _dcm(_sigma(sigma))


def mrp_kinematics_matrix(sigma: ArrayLike) -> np.ndarray:
    """``N(sigma) = ((1 - s's) I + 2 [sigma x] + 2 sigma sigma') / 4``, with ``sigma' = N(sigma) w``.

    ``w`` is the rate of B relative to O in B components. ``N' N = ((1 + s's) / 4)^2 I``, so ``N``
    is never singular (:func:`mrp_kinematics_inverse`).
    """
    return _kinematics(_sigma(sigma))


def mrp_kinematics_inverse(sigma: ArrayLike) -> np.ndarray:
    """``N(sigma)^-1 = (4 / (1 + s's))^2 N(sigma)'``: the rate that gives ``sigma'``."""
    s = _sigma(sigma)
    return (4.0 / (1.0 + float(s @ s))) ** 2 * _kinematics(s).T


def mrp_shadow(sigma: ArrayLike) -> np.ndarray:
    """The shadow set ``-sigma / (sigma' sigma)``, the other MRP of the same attitude.

    Raises
    ------
    SingularityError
        At ``sigma = 0`` (the shadow of the identity is at infinity).

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.mrp import mrp_shadow, mrp_to_dcm
    >>> s = np.array([0.3, -0.8, 0.6])
    >>> bool(np.allclose(mrp_to_dcm(mrp_shadow(s)), mrp_to_dcm(s), atol=1e-12))
    True
    """
    s = _sigma(sigma)
    ss = float(s @ s)
    if ss <= SHADOW_ZERO_TOL:
        raise SingularityError(
            "sigma: the shadow set of the zero MRP (the identity attitude) is at infinity; found "
            f"sigma = {s.tolist()}"
        )
    return -s / ss


def mrp_switch(sigma: ArrayLike, threshold: float = 1.0) -> np.ndarray:
    """``sigma`` or its shadow: the shadow when ``sigma' sigma > threshold``.

    The attitude (:func:`mrp_to_dcm`) is the same either way. With ``threshold = 1`` the result
    is the short set (principal angle at most 180 deg). ``threshold`` must be >= 1, otherwise
    the shadow of a switched set would switch back.
    """
    thr = check_positive(threshold, "threshold")
    if thr < 1.0:
        raise InvalidArgumentError("threshold", "a shadow-set threshold >= 1 on sigma' sigma", repr(thr))
    return _switch(_sigma(sigma), thr)


def mrp_error(sigma: ArrayLike, sigma_ref: ArrayLike) -> np.ndarray:
    """The attitude error ``se`` of B relative to a reference frame R, both given relative to O.

    ``se = [(1 - |sr|^2) s - (1 - |s|^2) sr + 2 s x sr] / [1 + |sr|^2 |s|^2 + 2 sr's]``
    (Schaub & Junkins; **likely** in paper M), switched to the short set, so
    ``mrp_to_dcm(se) == mrp_to_dcm(sigma) @ mrp_to_dcm(sigma_ref).T`` and ``|se| <= 1``.
    Where the formula is 0/0 (``sigma`` the shadow of ``sigma_ref``) the shadow of ``sigma`` is
    used instead; the result is the same attitude error.

    Parameters
    ----------
    sigma : (3,) array_like
        MRP of the body B relative to O.
    sigma_ref : (3,) array_like
        MRP of the reference frame R relative to O.
    """
    return _error(_sigma(sigma), _sigma(sigma_ref, "sigma_ref"))


def mrp_angle(sigma: ArrayLike) -> np.ndarray | float:
    """The principal rotation angle ``4 atan(|sigma|)`` (rad) of an MRP, or of each row.

    For a short set (``|sigma| <= 1``) it lies in ``[0, pi]``. Accepts shape ``(3,)`` (returns a
    float) or ``(k, 3)`` (returns ``k`` angles).
    """
    arr = np.asarray(sigma, dtype=float)
    if arr.ndim not in (1, 2) or arr.shape[-1] != 3:
        raise InvalidArgumentError("sigma", "shape (3,) or (k, 3)", f"shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidArgumentError("sigma", "finite values", repr(arr.tolist()))
    angle = 4.0 * np.arctan(np.linalg.norm(arr, axis=-1))
    return float(angle) if arr.ndim == 1 else angle


def mrp_error_angle(sigma: ArrayLike, sigma_ref: ArrayLike) -> float:
    """The error angle ``Phi_e = 4 atan|se|`` (rad, in ``[0, pi]``), ``se = mrp_error(sigma, sigma_ref)``."""
    return 4.0 * float(np.arctan(np.linalg.norm(mrp_error(sigma, sigma_ref))))


def mrp_to_quaternion(sigma: ArrayLike) -> np.ndarray:
    """The unit quaternion ``(q_v, q_4)`` (scalar last) of an MRP: ``q_v = 2 s/(1 + s's)``,
    ``q_4 = (1 - s's)/(1 + s's)``."""
    s = _sigma(sigma)
    ss = float(s @ s)
    return np.concatenate((2.0 * s, [1.0 - ss])) / (1.0 + ss)


def mrp_from_quaternion(q: ArrayLike) -> np.ndarray:
    """The short MRP ``q_v / (1 + q_4)`` of a unit quaternion (scalar last; either sign of ``q``).

    Raises
    ------
    InvalidArgumentError
        When ``|q|`` differs from 1 by more than ``1e-6``.
    """
    q = as_vector(q, "q", 4)
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > 1e-6:
        raise InvalidArgumentError("q", "a unit quaternion (|q| = 1)", f"|q| = {norm:.9g}")
    q = q / norm
    if q[3] < 0.0:
        q = -q
    return q[:3] / (1.0 + q[3])


def mrp_from_dcm(dcm: ArrayLike) -> np.ndarray:
    """The short MRP of a rotation matrix (O components to B components), via Shepperd's method.

    Raises
    ------
    InvalidArgumentError
        When ``dcm`` is not orthonormal with determinant +1 (to ``1e-9``).
    """
    c = as_matrix(dcm, "dcm", (3, 3))
    err = float(np.max(np.abs(c @ c.T - np.eye(3))))
    if err > 1e-9 or np.linalg.det(c) < 0.0:
        raise InvalidArgumentError(
            "dcm", "a rotation matrix (orthonormal, det +1)",
            f"max |C C' - I| = {err:.3g}, det = {np.linalg.det(c):.6g}",
        )
    tr = float(np.trace(c))
    # Shepperd: take the largest of 4 q_4^2, 4 q_i^2 to divide by
    diag = np.diag(c)
    cand = np.array([1.0 + tr, *(1.0 + 2.0 * diag - tr)])
    k = int(np.argmax(cand))
    q = np.empty(4)  # (q1, q2, q3, q4)
    root = 0.5 * np.sqrt(cand[k])
    if k == 0:
        q[3] = root
        q[0] = (c[1, 2] - c[2, 1]) / (4.0 * root)
        q[1] = (c[2, 0] - c[0, 2]) / (4.0 * root)
        q[2] = (c[0, 1] - c[1, 0]) / (4.0 * root)
    elif k == 1:
        q[0] = root
        q[3] = (c[1, 2] - c[2, 1]) / (4.0 * root)
        q[1] = (c[0, 1] + c[1, 0]) / (4.0 * root)
        q[2] = (c[2, 0] + c[0, 2]) / (4.0 * root)
    elif k == 2:
        q[1] = root
        q[3] = (c[2, 0] - c[0, 2]) / (4.0 * root)
        q[0] = (c[0, 1] + c[1, 0]) / (4.0 * root)
        q[2] = (c[1, 2] + c[2, 1]) / (4.0 * root)
    else:
        q[2] = root
        q[3] = (c[0, 1] - c[1, 0]) / (4.0 * root)
        q[0] = (c[2, 0] + c[0, 2]) / (4.0 * root)
        q[1] = (c[1, 2] + c[2, 1]) / (4.0 * root)
    if q[3] < 0.0:
        q = -q
    return q[:3] / (1.0 + q[3])


def dcm_from_euler321(angles: ArrayLike) -> np.ndarray:
    """``C = R1(roll) R2(pitch) R3(yaw)`` for 3-2-1 Euler angles ``(roll, pitch, yaw)`` in rad.

    The frame-O-to-body matrix; :func:`models.attitude.euler.rotation_matrix` is its transpose.
    """
    roll, pitch, yaw = as_vector(angles, "angles", 3)
    return _euler_dcm(roll, pitch, yaw)


def _euler_dcm(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    r1 = np.array([[1.0, 0.0, 0.0], [0.0, cr, sr], [0.0, -sr, cr]])
    r2 = np.array([[cp, 0.0, -sp], [0.0, 1.0, 0.0], [sp, 0.0, cp]])
    r3 = np.array([[cy, sy, 0.0], [-sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return r1 @ r2 @ r3


def _euler(c: np.ndarray) -> np.ndarray:
    """Unchecked 3-2-1 angles of a rotation matrix; raises at pitch = +-90 deg."""
    sin_p = float(np.clip(-c[0, 2], -1.0, 1.0))
    cos_p = float(np.hypot(c[0, 0], c[0, 1]))
    if cos_p < SINGULARITY_COS_TOL:
        raise SingularityError(
            "pitch: the 3-2-1 Euler angles are not unique at +-90 deg pitch; found "
            f"|cos(pitch)| = {cos_p:.2e} < {SINGULARITY_COS_TOL:g}"
        )
    return np.array([np.arctan2(c[1, 2], c[2, 2]), np.arctan2(sin_p, cos_p), np.arctan2(c[0, 1], c[0, 0])])


def euler321_from_dcm(dcm: ArrayLike) -> np.ndarray:
    """3-2-1 Euler angles ``(roll, pitch, yaw)`` (rad) of ``C = R1(roll) R2(pitch) R3(yaw)``.

    Pitch lies in ``[-pi/2, pi/2]``, roll and yaw in ``(-pi, pi]``.

    Raises
    ------
    SingularityError
        Within :data:`models.attitude.euler.SINGULARITY_COS_TOL` of pitch = +-90 deg, where roll and
        yaw are not unique (and the Euler kinematics are singular).
    """
    return _euler(as_matrix(dcm, "dcm", (3, 3)))


def mrp_from_euler321(angles: ArrayLike) -> np.ndarray:
    """The short MRP of the attitude with 3-2-1 Euler angles ``(roll, pitch, yaw)`` (rad)."""
    return mrp_from_dcm(dcm_from_euler321(angles))
