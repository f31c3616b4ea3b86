"""LQR on the linearised 6 + 2N flexible-satellite model, the unconstrained one-vertex RMPC reference.

Discrete LQR (python-control ``dlqr``, through
:class:`rmpc.LQR`) on the ZOH of :meth:`models.FlexibleSatellite.linearize` with the quaternion
attitude (``Theta = q_v`` of the error quaternion, ``Kin = I/2``), run on the nonlinear plant
through :class:`rmpc.MappedController`: the measured ``[q, w, eta, eta']`` is mapped to
``[q_v, w, eta, eta']`` of the error against ``q_ref`` (:meth:`~models.FlexibleSatellite.linear_state`)
and the PZT commands are zero. Default weights (**assumed**): ``Q = diag(4 I_3, 0, 0, 0)``
(``q_v`` only: ``4 q_v' q_v ~ theta' theta`` for small angles; the stable, lightly damped modes
and the rates carry no weight) and ``R = I_3``: per axis about a rigid-like loop of natural
frequency ~0.06 rad/s, damping 0.7 at ``J ~ 250 kg m^2``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from models import FlexibleSatellite
from rmpc.mpc.lqr import LQR
from rmpc.wrappers import MappedController
from toolkit_common.errors import ArgumentTypeError
from toolkit_common.validation import check_positive

__all__ = ["flexible_lqr"]


def flexible_lqr(
    plant: FlexibleSatellite,
    dt: float = 0.01,
    *,
    Q: ArrayLike | None = None,
    R: ArrayLike | None = None,
    q_ref: ArrayLike | None = None,
) -> MappedController:
    """LQR designed on the 6 + 2N model, wrapped to run on the nonlinear plant (name "LQR").

    Parameters
    ----------
    plant : FlexibleSatellite
        The design model (linearised at rest, quaternion attitude).
    dt : float
        Sample time (s) of the ZOH.
    Q, R : array_like, optional
        Weights on ``[q_v, w, eta, eta']`` (6 + 2N) and on the hub torques (3).
    q_ref : (4,) array_like, optional
        Target attitude (default the identity).

    Returns
    -------
    MappedController
        ``step(x)`` returns ``[u; 0 (PZT)]``; its ``controller`` is the :class:`rmpc.LQR`.

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from rmpc import flexible_lqr
    >>> ctrl = flexible_lqr(FlexibleSatellite.di_gennaro())
    >>> ctrl.name, ctrl.controller.F.shape
    ('LQR', (3, 14))
    """
    if not isinstance(plant, FlexibleSatellite):
        raise ArgumentTypeError("plant", "a models.FlexibleSatellite", type(plant).__name__)
    dt = check_positive(dt, "dt")
    n = plant.n_linear_states
    model = plant.linear_model(dt=dt, attitude="quaternion")
    if Q is None:
        Q = np.zeros((n, n))
        Q[:3, :3] = 4.0 * np.eye(3)
    if R is None:
        R = np.eye(3)
    lqr = LQR(model, Q, R)
    q_ref_vec = None if q_ref is None else np.asarray(q_ref, dtype=float)
    n_pzt = plant.n_pzt

    def measure(x: np.ndarray) -> np.ndarray:
        return plant.linear_state(x, q_ref_vec, attitude="quaternion")

    def output(u: np.ndarray) -> np.ndarray:
        return np.concatenate((u, np.zeros(n_pzt)))

    return MappedController(lqr, measure, output=output, name="LQR")
