"""The single-axis picture of a flexible satellite and paper S's regime label.

Rotation ``theta`` about one body axis ``a``, the other axes locked, modal mass ``M`` diagonal::

    J_aa theta'' + delta_a' eta'' = u_a,     M eta'' + C eta' + K eta = -delta_a theta''

    theta / u_a = prod_i p_i(s) / (s^2 D(s)),      p_i(s) = m_i s^2 + c_i s + k_i,
    D(s) = J_aa prod_i p_i(s) - s^2 sum_i delta_ai^2 prod_{j != i} p_j(s).

The zeros are the constrained (hub-clamped) modes, the roots of ``p_i``; the poles besides the
double integrator are the unconstrained (free-free) modes, the roots of ``D``. The gain is
``1/(J_aa s^2)`` at low and ``1/((J_aa - sum_i delta_ai^2/m_i) s^2)`` at high frequency.

Paper S writes the same plant as ``G_p = G_pr G_pf`` with ``G_pr = 1/(J s^2)`` and the flexible
factor :func:`flexible_factor`, and labels a closed loop by its bandwidth relative to the first
appendage frequency (:func:`regime`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from models.flexible.parameters import HybridParameters
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

if TYPE_CHECKING:  # python-control (with matplotlib, ~2 s) is imported where it is used
    import control

__all__ = [
    "REGIME_LABELS",
    "flexible_factor",
    "regime",
    "single_axis_modes",
    "single_axis_polynomials",
    "single_axis_tf",
]

#: Paper S's three regimes (thresholds ``w_1/3`` and ``w_1/2`` **certain**, labels **likely**):
#: below ``w_1/3`` the structure is rigid enough, between ``w_1/3`` and ``w_1/2`` it is
#: flexible and its vibration not negligible, above ``w_1/2`` it is flexible and hardest.
REGIME_LABELS: tuple[str, str, str] = ("rigid-like", "flexible", "flexible-hard")


def single_axis_polynomials(
    j_aa: float,
    coupling: np.ndarray,
    masses: np.ndarray,
    stiffness: np.ndarray,
    damping: np.ndarray,
    cancel_uncoupled: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Numerator ``prod p_i`` and denominator ``s^2 D(s)`` (highest power first).

    ``coupling`` is ``delta_a`` (one entry per mode), ``masses``, ``stiffness`` and ``damping``
    the diagonals of ``M``, ``K`` and ``C``. A mode with ``delta_ai = 0`` divides both
    polynomials (the pair cancels); with ``cancel_uncoupled`` it is left out of both.
    """
    keep = np.ones(coupling.size, dtype=bool)
    if cancel_uncoupled:
        keep = coupling != 0.0
    quads = [
        np.array([m, c, k]) for m, c, k in zip(masses[keep], damping[keep], stiffness[keep], strict=True)
    ]
    deltas = coupling[keep]
    num = np.array([1.0])
    for p in quads:
        num = np.polymul(num, p)
    d_poly = j_aa * num
    for i, delta in enumerate(deltas):
        others = np.array([1.0])
        for j, p in enumerate(quads):
            if j != i:
                others = np.polymul(others, p)
        d_poly = np.polysub(d_poly, delta**2 * np.polymul([1.0, 0.0, 0.0], others))
    return num, np.polymul(d_poly, [1.0, 0.0, 0.0])


def flexible_factor(
    constrained: ArrayLike,
    unconstrained: ArrayLike,
    zeta_constrained: ArrayLike,
    zeta_unconstrained: ArrayLike,
) -> control.TransferFunction:
    """Paper S's flexible factor ``G_pf = prod ((s/w_c)^2 + 2 zeta_c s/w_c + 1) / prod (... w_u ...)``.

    ``G_pf(0) = 1`` and ``|G_pf(j inf)| = prod (w_u / w_c)^2`` (**certain**).

    Parameters
    ----------
    constrained, unconstrained : array_like
        The frequencies ``w_c,i`` (zeros) and ``w_u,i`` (poles), rad/s, > 0, as many of each.
    zeta_constrained, zeta_unconstrained : array_like or float
        Their damping ratios (>= 0), one per frequency or one for all.

    Examples
    --------
    >>> import numpy as np
    >>> from models.flexible.single_axis import flexible_factor
    >>> g = flexible_factor([3.0], [3.3], 0.01, 0.01)   # paper S's SISO pair
    >>> round(float(abs(g(0.0))), 12), round(float(abs(g(1e4j))), 4)
    (1.0, 1.21)
    """
    w_c = as_vector(np.atleast_1d(constrained), "constrained")
    w_u = as_vector(np.atleast_1d(unconstrained), "unconstrained", w_c.size)
    z_c = np.broadcast_to(as_vector(np.atleast_1d(zeta_constrained), "zeta_constrained"), w_c.shape)
    z_u = np.broadcast_to(as_vector(np.atleast_1d(zeta_unconstrained), "zeta_unconstrained"), w_u.shape)
    for name, arr, lo in (("constrained", w_c, 0.0), ("unconstrained", w_u, 0.0)):
        if np.any(arr <= lo):
            raise InvalidArgumentError(name, "frequencies > 0 (rad/s)", repr(arr.tolist()))
    for name, arr in (("zeta_constrained", z_c), ("zeta_unconstrained", z_u)):
        if np.any(arr < 0.0):
            raise InvalidArgumentError(name, "damping ratios >= 0", repr(arr.tolist()))
    num, den = np.array([1.0]), np.array([1.0])
    for wc, zc, wu, zu in zip(w_c, z_c, w_u, z_u, strict=True):
        num = np.polymul(num, [1.0 / wc**2, 2.0 * zc / wc, 1.0])
        den = np.polymul(den, [1.0 / wu**2, 2.0 * zu / wu, 1.0])
    import control

    return control.tf(num, den)


def regime(bandwidth: float, first_frequency: float) -> str:
    """Paper S's label of a closed loop with bandwidth ``w_bw`` against the first mode ``w_1``.

    Returns ``"rigid-like"`` for ``w_bw < w_1/3``, ``"flexible"`` for
    ``w_1/3 <= w_bw <= w_1/2`` and ``"flexible-hard"`` above (see :data:`REGIME_LABELS`).

    Examples
    --------
    >>> from models.flexible.single_axis import regime
    >>> regime(0.05, 0.7681), regime(0.3, 0.7681), regime(0.5, 0.7681)
    ('rigid-like', 'flexible', 'flexible-hard')
    """
    w_bw = check_positive(bandwidth, "bandwidth", allow_zero=True)
    w_1 = check_positive(first_frequency, "first_frequency")
    if w_bw < w_1 / 3.0:
        return REGIME_LABELS[0]
    if w_bw <= w_1 / 2.0:
        return REGIME_LABELS[1]
    return REGIME_LABELS[2]


def single_axis_tf(
    p: HybridParameters, axis: int = 0, *, cancel_uncoupled: bool = True
) -> control.TransferFunction:
    """``theta_a / u_a`` about body axis ``axis``; see :meth:`models.FlexibleSatellite.single_axis_tf`."""
    if isinstance(axis, bool) or not isinstance(axis, int | np.integer) or not 0 <= axis <= 2:
        raise InvalidArgumentError("axis", "0, 1 or 2 (body x, y, z)", repr(axis))
    masses = np.diag(p.modal_mass)
    if np.any(p.modal_mass != np.diag(masses)):
        raise InvalidArgumentError("modal_mass", "a diagonal modal mass for the single-axis model",
                                   "off-diagonal entries")
    num, den = single_axis_polynomials(
        float(p.inertia[axis, axis]), p.coupling[:, axis], masses, p.stiffness, p.viscous_damping,
        cancel_uncoupled=cancel_uncoupled,
    )
    import control

    return control.tf(num, den)


def single_axis_modes(p: HybridParameters, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Free-free frequencies and damping ratios; see :meth:`models.FlexibleSatellite.single_axis_modes`."""
    g = single_axis_tf(p, axis)
    poles = np.asarray(g.poles())
    osc = poles[np.abs(poles) > 1e-9 * max(1.0, float(np.max(np.abs(poles))))]
    osc = osc[osc.imag >= 0.0] if np.any(osc.imag > 0) else osc
    w_n = np.abs(osc)
    order = np.argsort(w_n)
    return w_n[order], (-osc.real / w_n)[order]
