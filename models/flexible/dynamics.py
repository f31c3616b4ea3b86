"""The nonlinear hybrid-coordinate model of the flexible satellite, in solved form.

::

    J_mb w' = -w x (J w + delta' eta') + delta' M^-1 (C eta' + K eta - Gamma_a v - d_f) + u + d
    eta''   = M^-1 (Gamma_a v + d_f - C eta' - K eta - delta w')
    q0' = -q_v' w / 2,   q_v' = (q0 I + [q_v x]) w / 2

with the state ``x = [q (4, scalar first), w (3), eta (N), eta' (N)]``, the input ``u`` (three
hub torques, then the ``n_a`` PZT commands ``v``) and the disturbance ``d`` (hub torques, then
the panel forces ``d_f``). No algebraic loop: ``w'`` is solved first. These are the bodies of
:meth:`models.FlexibleSatellite.dynamics` and :meth:`~models.FlexibleSatellite.energy_rate`'s
input split.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.vectors import cross3
from models.flexible.parameters import HybridParameters
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector

__all__ = ["hybrid_rhs", "split_inputs"]


def split_inputs(
    p: HybridParameters,
    u: ArrayLike,
    d: ArrayLike,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(hub torque incl. the hub disturbance, v, d_f)`` from the checked ``u`` and ``d``.

    ``u`` holds 3 hub torques, optionally followed by the ``n_a`` PZT commands (zero when left
    out); ``d`` 3 hub torques, optionally followed by the ``N`` panel forces. ``None`` is zero.
    """
    n, n_a = p.n_modes, p.n_pzt
    if u is None:
        torque, v = np.zeros(3), np.zeros(n_a)
    else:
        u_vec = as_vector(u, "u")
        if u_vec.size == 3:
            torque, v = u_vec, np.zeros(n_a)
        elif u_vec.size == 3 + n_a:
            torque, v = u_vec[:3], u_vec[3:]
        else:
            raise InvalidArgumentError(
                "u", f"3 hub torques or 3 + n_a = {3 + n_a} inputs (torques, then PZT commands)",
                f"length {u_vec.size}",
            )
    d_f = np.zeros(n)
    if d is not None:
        d_vec = as_vector(d, "d")
        if d_vec.size == 3:
            torque = torque + d_vec
        elif d_vec.size == 3 + n:
            torque, d_f = torque + d_vec[:3], d_vec[3:]
        else:
            raise InvalidArgumentError(
                "d", f"3 hub torques or 3 + N = {3 + n} values (hub torques, then panel forces d_f)",
                f"length {d_vec.size}",
            )
    return torque, v, d_f


def hybrid_rhs(
    p: HybridParameters, x: np.ndarray, torque: np.ndarray, v: np.ndarray, d_f: np.ndarray
) -> np.ndarray:
    """Unchecked right-hand side; ``torque`` already includes the hub disturbance."""
    n = p.n_modes
    q0, qv, w = x[0], x[1:4], x[4:7]
    eta, eta_dot = x[7:7 + n], x[7 + n:]
    h = p.inertia @ w + p.coupling.T @ eta_dot
    modal_force = p.pzt_matrix @ v + d_f - p.viscous_damping * eta_dot - p.stiffness * eta
    w_dot = p.hub_inertia_inv @ (torque - cross3(w, h) - p.couple @ modal_force)
    eta_ddot = p.mass_inv @ (modal_force - p.coupling @ w_dot)
    out = np.empty_like(x)
    out[0] = -0.5 * (qv @ w)
    out[1:4] = 0.5 * (q0 * w + cross3(qv, w))
    out[4:7] = w_dot
    out[7:7 + n] = eta_dot
    out[7 + n:] = eta_ddot
    return out
