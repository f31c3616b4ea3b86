"""TEMPORARY shim, to delete once every plant has ``attitude_euler`` in ``models``.

The simulator stores the roll, pitch and yaw of every sample from the plant's
``attitude_euler(x)`` (:class:`models.protocols.Plant`; ``PolytopicModel`` with its
``attitude`` argument). The satellites and ``PolytopicModel`` gain these members in another
part of the same restructuring; until then this adds them, for the tests only and only where
they are missing, so the tests (and the documentation examples they run) exercise
``Trajectory.attitude_deg``. Every conversion is the toolkit's own.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from models import FlexibleSatellite, MRPSatellite, PolytopicModel, RigidSatellite, WheelSatellite
from models.attitude.mrp import euler321_from_dcm, mrp_to_dcm
from models.attitude.quaternion import quat_to_euler321
from toolkit_common.errors import InvalidArgumentError


def _euler_states(self: Any, x: Any) -> np.ndarray:
    return np.array(np.asarray(x, dtype=float)[:3])


def _mrp(self: Any, x: Any) -> np.ndarray:
    return euler321_from_dcm(mrp_to_dcm(np.asarray(x, dtype=float)[:3]))


def _quaternion(self: Any, x: Any) -> np.ndarray:
    return quat_to_euler321(np.asarray(x, dtype=float)[:4])


def _polytope(self: Any, x: Any) -> np.ndarray:
    if getattr(self, "attitude", None) != "euler321":
        raise InvalidArgumentError("attitude", "'euler321' for attitude_euler (the shim's only form)",
                                   repr(getattr(self, "attitude", None)))
    return np.array(np.asarray(x, dtype=float)[:3])


def _with_euler_attitude(method: Any) -> Any:
    @functools.wraps(method)
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        model = method(*args, **kwargs)
        model.attitude = "euler321"
        return model

    return wrapped


def _install() -> None:
    for cls, fn in ((RigidSatellite, _euler_states), (WheelSatellite, _euler_states),
                    (MRPSatellite, _mrp), (FlexibleSatellite, _quaternion)):
        if not hasattr(cls, "attitude_euler"):
            cls.attitude_euler = fn
    if not hasattr(PolytopicModel, "attitude_euler"):
        PolytopicModel.attitude = None
        PolytopicModel.attitude_euler = _polytope
        # the rigid satellite's linear models keep its Euler-angle states
        RigidSatellite.linear_model = _with_euler_attitude(RigidSatellite.linear_model)
        RigidSatellite.polytope = _with_euler_attitude(RigidSatellite.polytope)


_install()
