"""Tracking errors of the satellite in MRPs on its orbit: what its controllers measure.

A target attitude fixed in the rotating orbital frame O and the orbit rate ``n`` turn the
plant state ``x = [sigma, w]`` of :class:`models.MRPSatellite` into

- :func:`rmpc_state` / :class:`RMPCStateMap`: the 3-2-1 Euler error angles and the rate
  relative to O, the state a robust MPC designed on ``[roll, pitch, yaw, p, q, r]`` works on;
- :func:`tracking_error`: the MRP error, its kinematics matrix and the relative rate, what
  backstepping needs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

# the unchecked kernels of the MRP maths: the public wrappers check what these skip
from models.attitude.mrp import _dcm, _error, _euler, _kinematics, _sigma
from toolkit_common.validation import as_vector, check_positive

__all__ = ["MRPTrackingError", "RMPCStateMap", "rmpc_state", "tracking_error"]


def rmpc_state(x: ArrayLike, sigma_ref: ArrayLike, mean_motion: float) -> np.ndarray:
    """The robust-MPC state ``X = [roll_e, pitch_e, yaw_e, w_BO]`` of an MRP state.

    Parameters
    ----------
    x : (6,) array_like
        ``[sigma, w]``: MRP of the body relative to the orbital frame O, body rate relative to
        inertial space (rad/s, body components), as in :class:`models.MRPSatellite`.
    sigma_ref : (3,) array_like
        The target attitude, an MRP relative to O (fixed in O).
    mean_motion : float
        Orbit rate ``n`` (rad/s), :attr:`models.MRPSatellite.mean_motion`.

    Returns
    -------
    (6,) ndarray
        The 3-2-1 Euler angles (rad) of ``C(se)``, ``se = mrp_error(sigma, sigma_ref)``, then the
        body rate relative to O (equal to the rate relative to the target frame),
        ``w_BO = w + n c2(sigma)`` in body components. ``X = 0`` exactly at the target with
        ``w = -n c2(sigma_ref)``.

    Raises
    ------
    SingularityError
        When the error's pitch is within 0.057 deg of +-90 deg.

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.mrp import mrp_from_euler321
    >>> from models.mrp.tracking import rmpc_state
    >>> s0 = mrp_from_euler321(np.radians([40.0, -30.0, 20.0]))
    >>> sr = mrp_from_euler321(np.radians([10.0, 5.0, -10.0]))
    >>> X = rmpc_state(np.concatenate((s0, np.zeros(3))), sr, mean_motion=0.0)
    >>> np.round(np.degrees(X[:3]), 2).tolist()
    [27.27, -28.67, 36.69]
    """
    x = as_vector(x, "x", 6)
    sr = _sigma(sigma_ref, "sigma_ref")
    n = check_positive(mean_motion, "mean_motion", allow_zero=True)
    return _rmpc_state(x, sr, n)


def _rmpc_state(x: np.ndarray, sr: np.ndarray, n: float) -> np.ndarray:
    s = x[:3]
    angles = _euler(_dcm(_error(s, sr)))
    w_bo = x[3:6] + n * _dcm(s)[:, 1]
    return np.concatenate((angles, w_bo))


class RMPCStateMap:
    """:func:`rmpc_state` as a callable ``map(x) -> X`` for a fixed target and orbit rate.

    Use it as the ``measure`` of :class:`rmpc.MappedController` to run a robust MPC designed
    on ``[roll, pitch, yaw, p, q, r]`` on the MRP satellite.

    Parameters
    ----------
    sigma_ref : (3,) array_like
        The target, an MRP relative to the orbital frame.
    mean_motion : float
        Orbit rate ``n`` (rad/s).

    Examples
    --------
    >>> import numpy as np
    >>> from models import MRPSatellite
    >>> from models.mrp.tracking import RMPCStateMap
    >>> sat = MRPSatellite.paper_m()
    >>> to_x = RMPCStateMap(sigma_ref=np.zeros(3), mean_motion=sat.mean_motion)
    >>> bool(np.all(to_x(sat.state_at_rest(np.zeros(3))) == 0.0))   # at the target, at rest in O
    True
    """

    def __init__(self, sigma_ref: ArrayLike, mean_motion: float) -> None:
        self.sigma_ref = _sigma(sigma_ref, "sigma_ref").copy()
        self.sigma_ref.setflags(write=False)
        self.mean_motion = check_positive(mean_motion, "mean_motion", allow_zero=True)

    def __call__(self, x: ArrayLike) -> np.ndarray:
        return _rmpc_state(as_vector(x, "x", 6), self.sigma_ref, self.mean_motion)

    def __repr__(self) -> str:
        return f"RMPCStateMap(sigma_ref={self.sigma_ref.tolist()}, mean_motion={self.mean_motion:.6e})"


@dataclass(frozen=True)
class MRPTrackingError:
    """The error kinematics of a target fixed in the orbital frame (what backstepping needs).

    Attributes
    ----------
    se : (3,) ndarray
        ``mrp_error(sigma, sigma_ref)``, the short set.
    kinematics : (3, 3) ndarray
        ``N(se)``: ``se' = N(se) w_BO``.
    c2 : (3,) ndarray
        Second column of ``C(sigma)``: the orbit normal ``o_2`` in body components.
    relative_rate : (3,) ndarray
        ``w_BO = w + n c2``, the body rate relative to O (and to the target).
    """

    se: np.ndarray
    kinematics: np.ndarray
    c2: np.ndarray
    relative_rate: np.ndarray


def tracking_error(x: ArrayLike, sigma_ref: ArrayLike, mean_motion: float) -> MRPTrackingError:
    """``se``, ``N(se)``, ``c2(sigma)`` and ``w_BO`` for the state ``x = [sigma, w]`` and a target.

    Paper M's reference is constant and relative to O (**likely**), so ``se' = N(se) w_BO``.

    Examples
    --------
    >>> import numpy as np
    >>> from models.mrp.tracking import tracking_error
    >>> err = tracking_error([0.1, 0.0, 0.0, 0.0, -1e-3, 0.0], np.zeros(3), mean_motion=1e-3)
    >>> err.se.tolist(), np.round(err.relative_rate, 12).tolist()
    ([0.1, 0.0, 0.0], [0.0, -7.8423684e-05, -0.000388197236])
    """
    x = as_vector(x, "x", 6)
    sr = _sigma(sigma_ref, "sigma_ref")
    n = check_positive(mean_motion, "mean_motion", allow_zero=True)
    return _tracking_error(x, sr, n)


def _tracking_error(x: np.ndarray, sr: np.ndarray, n: float) -> MRPTrackingError:
    s = x[:3]
    se = _error(s, sr)
    c2 = _dcm(s)[:, 1]
    return MRPTrackingError(se=se, kinematics=_kinematics(se), c2=c2, relative_rate=x[3:6] + n * c2)
