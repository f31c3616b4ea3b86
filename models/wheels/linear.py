"""The linear model of paper W's satellite at level attitude and its effectiveness polytope.

The attitude and the rates about the level attitude at rest (the wheel momenta do not enter:
``h' = -u`` is left out, the plant's business through the momentum limit)::

    A = [[0, I3], [-J^-1 K_g, 0]],    B = [0; J^-1 D Lambda]

with ``K_g`` the gravity stiffness (:meth:`models.WheelSatellite.gravity_stiffness`),
``Lambda = diag(lambda)`` the wheel effectiveness (1 healthy, 0 an outage) and ``J`` possibly
scaled. :class:`models.WheelSatellite` delegates its ``linearize``, ``discretize``,
``linear_model``, ``effectiveness_vertices`` and ``polytope`` here; the functions take the
pieces they need (the array, ``J^-1``, ``K_g``), not the satellite.

``B`` is linear in ``Lambda`` and the zero-order hold at a fixed ``A`` is linear in ``B``, so
the effectiveness vertices of the polytope are exact. ``A`` and ``B`` are also affine in
``J^-1``, but the hold is not linear in ``A``: with an inertia ``spread`` the vertex products
cover the continuous-time set, and their discretisations approximate the discrete one.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from models.linear import PolytopicModel, operating_point, relative_spread, sample_time, zoh
from models.wheels.array import WheelArray, _rank
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector, check_choice, check_positive

__all__ = [
    "LINEAR_STATE_NAMES",
    "effectiveness_vertices",
    "level_operating_point",
    "linearize",
    "wheel_polytope",
]

#: The states of the linear model: 3-2-1 Euler angles (rad) and body rates (rad/s).
LINEAR_STATE_NAMES: tuple[str, ...] = ("phi", "theta", "psi", "p", "q", "r")


def level_operating_point(x_op: ArrayLike) -> np.ndarray:
    """``x_op`` (6 values ``[phi, theta, psi, p, q, r]``, default zero) checked to be level and at rest.

    The model is linearised at the level attitude with zero rates (any yaw: yaw enters neither
    the kinematics nor the gravity torque); another ``x_op`` is an error naming it.
    """
    x = operating_point(x_op, 6)
    if np.any(x[[0, 1, 3, 4, 5]] != 0.0):
        raise InvalidArgumentError(
            "x_op",
            "the level attitude at rest (roll = pitch = 0, zero rates; any yaw), where the wheel "
            "satellite is linearised",
            f"{x.tolist()}",
        )
    return x


def linearize(
    wheels: WheelArray,
    inertia_inv: np.ndarray,
    gravity_stiffness: np.ndarray,
    x_op: ArrayLike | None = None,
    effectiveness: ArrayLike | None = None,
    inertia_scale: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Continuous ``(A, B)`` with ``J^-1 = inertia_inv``, ``K_g = gravity_stiffness``.

    See :meth:`models.WheelSatellite.linearize`.
    """
    level_operating_point(x_op)
    s = check_positive(inertia_scale, "inertia_scale")
    m = wheels.n_wheels
    lam = np.ones(m) if effectiveness is None else as_vector(effectiveness, "effectiveness", m)
    d_lam = wheels.effective_matrix(lam)
    j_inv = inertia_inv / s
    a = np.zeros((6, 6))
    a[:3, 3:] = np.eye(3)
    a[3:, :3] = -j_inv @ gravity_stiffness
    b = np.zeros((6, m))
    b[3:, :] = j_inv @ d_lam
    return a, b


def effectiveness_vertices(
    n_wheels: int, effectiveness: ArrayLike = "single_outage", lambda_min: float = 0.2
) -> np.ndarray:
    """The wheel-effectiveness vertices; see :meth:`models.WheelSatellite.effectiveness_vertices`."""
    m = n_wheels
    if isinstance(effectiveness, str):
        check_choice(effectiveness, "effectiveness", ("single_outage", "box"))
        if effectiveness == "single_outage":
            return np.vstack((np.ones(m), 1.0 - np.eye(m)))
        lo = check_positive(lambda_min, "lambda_min", allow_zero=True)
        if lo >= 1.0:
            raise InvalidArgumentError("lambda_min", "a lower corner in [0, 1)", repr(lambda_min))
        grid = np.array(np.meshgrid(*([[1.0, lo]] * m), indexing="ij")).reshape(m, -1).T
        return grid
    verts = np.array(effectiveness, dtype=float) if not isinstance(effectiveness, bytes) else None
    if verts is None or verts.ndim != 2 or verts.shape[1] != m or verts.shape[0] == 0:
        raise InvalidArgumentError(
            "effectiveness",
            f"'single_outage', 'box' or a (k, {m}) array of vertices",
            repr(effectiveness),
        )
    for i, row in enumerate(verts):
        if not np.all(np.isfinite(row)) or np.any((row < 0.0) | (row > 1.0)):
            raise InvalidArgumentError(f"effectiveness[{i}]", "values in [0, 1]", repr(row.tolist()))
    return verts


def wheel_polytope(
    wheels: WheelArray,
    inertia_inv: np.ndarray,
    gravity_stiffness: np.ndarray,
    x_op: ArrayLike | None = None,
    dt: float | None = None,
    effectiveness: ArrayLike = "single_outage",
    lambda_min: float = 0.2,
    spread: float | None = None,
) -> PolytopicModel:
    """The effectiveness (and inertia) polytope; see :meth:`models.WheelSatellite.polytope`."""
    x_op = level_operating_point(x_op)
    dt = sample_time(dt)
    lam = effectiveness_vertices(wheels.n_wheels, effectiveness, lambda_min)
    for i, row in enumerate(lam):
        rank = _rank(wheels.D * row)
        if rank < 3:
            raise InvalidArgumentError(
                "effectiveness",
                "vertices whose healthy wheels span three axes (B != 0, rank(D Lambda) = 3)",
                f"vertex {i} (lambda = {row.tolist()}) with rank(D Lambda) = {rank}",
            )
    scales = [1.0]
    if spread is not None:
        s = relative_spread(spread)
        scales = [1.0 + s, 1.0 - s]
    platform = (wheels, inertia_inv, gravity_stiffness)
    verts = [zoh(*linearize(*platform, x_op, row, scale), dt) for scale in scales for row in lam]
    nominal = zoh(*linearize(*platform, x_op), dt)
    names = tuple(f"u{j + 1}" for j in range(wheels.n_wheels))
    return PolytopicModel(
        verts, dt, nominal=nominal, state_names=LINEAR_STATE_NAMES, input_names=names, attitude="euler321"
    )
