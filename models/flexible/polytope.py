"""The uncertainty polytope of the flexible satellite's linear model.

Uncertain parameters: ``kappa`` scaling the inverse hub inertia ``J_mb^-1``, the modal
stiffnesses ``k_i = Lambda_i^2`` (through a scale ``f`` on the frequencies, ``k_i -> f^2 k_i``)
and the modal damping coefficients ``c_i = 2 xi_i Lambda_i`` (through the frequency scale and a
scale ``g`` on the damping ratios, ``c_i -> f g c_i``). The continuous-time ``A`` is
multi-affine in ``(kappa, k_i, c_i)`` and ``B`` is affine in ``kappa``
(:func:`models.flexible.linear.linear_matrices`), so every model with parameters inside the box
is a convex combination of the models at its corners, with the multilinear (tensor-product)
weights. Treating ``k`` and ``c`` as independent (``c`` over ``[f_lo g_lo, f_hi g_hi]`` whatever
``f``) over-bounds the set: valid, conservative.

Each uncertain parameter is given by the ``(low, high)`` range of a multiplier of its nominal
value, an argument ending in ``_range``: ``inverse_inertia_range`` (``kappa``),
``frequency_range`` (``f``), ``damping_range`` (``g``) and ``effectiveness_range``. (A single
multiplier, a point, is a ``*_scale`` elsewhere in the toolkit; an inertia uncertainty symmetric
about ``J``, ``J in [(1 - s) J, (1 + s) J]``, is a ``spread``.)

Modes (all ranges **assumed**, the toolkit's choice):

- ``"groups"`` (default): one scale each for ``kappa``, all ``k_i`` and all ``c_i``: 8 vertices;
- ``"box"``: ``kappa`` and every ``k_i``, ``c_i`` independently: ``2^(1 + 2N)`` vertices (512
  for four modes);
- ``"effectiveness"``: the hub-torque columns of ``B`` scaled by each end of ``effectiveness_range``,
  ``A`` nominal: 2 vertices (the torque-effectiveness polytope used for the LMI work).

**Zero-order hold.** The discrete vertices are the ZOH of the continuous ones. ``e^{A dt}`` is
not multi-affine in the parameters, so a discretised interior model is in the hull of the
discretised vertices only up to a residual of order ``dt^2`` (measured in
``tests/test_flexible_polytope.py``): verify a robust gain on a dense parameter grid.
"""

from __future__ import annotations

import itertools
from typing import Any, Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike

from models.flexible.linear import POLYTOPIC_ATTITUDE, AttitudeForm, ParameterPoint
from models.linear import PolytopicModel, sample_time, zoh
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector, check_choice, check_positive

__all__ = [
    "DEFAULT_DAMPING_RANGE",
    "DEFAULT_EFFECTIVENESS_RANGE",
    "DEFAULT_FREQUENCY_RANGE",
    "DEFAULT_INVERSE_INERTIA_RANGE",
    "RENAMED_RANGES",
    "PolytopeMode",
    "flexible_polytope",
    "vertex_parameters",
]

PolytopeMode = Literal["groups", "box", "effectiveness"]

#: Range of ``kappa``, the multiplier of ``J_mb^-1`` (**assumed**; +-20 %).
DEFAULT_INVERSE_INERTIA_RANGE: tuple[float, float] = (0.8, 1.2)
#: Range of the multiplier of the modal frequencies (**assumed**; +-10 %).
DEFAULT_FREQUENCY_RANGE: tuple[float, float] = (0.9, 1.1)
#: Range of the multiplier of the damping ratios, the least known parameter (**assumed**).
DEFAULT_DAMPING_RANGE: tuple[float, float] = (0.5, 2.0)
#: Range of the hub-torque effectiveness of the ``"effectiveness"`` mode (**assumed**).
DEFAULT_EFFECTIVENESS_RANGE: tuple[float, float] = (0.8, 1.2)
#: The old names of the ranges (a call with one raises an error naming the new one).
RENAMED_RANGES: dict[str, str] = {
    "inertia_scale": "inverse_inertia_range",
    "frequency_scale": "frequency_range",
    "damping_scale": "damping_range",
    "effectiveness": "effectiveness_range",
}


class FlexibleLinearisation(Protocol):
    """What the polytope reads of its satellite (the members of :class:`models.FlexibleSatellite`).

    A structural type, so that this module does not import the satellite's (which imports it).
    """

    @property
    def n_modes(self) -> int: ...  # pragma: no cover
    @property
    def n_pzt(self) -> int: ...  # pragma: no cover
    @property
    def stiffness(self) -> np.ndarray: ...  # pragma: no cover
    @property
    def damping_matrix(self) -> np.ndarray: ...  # pragma: no cover
    @property
    def input_names(self) -> tuple[str, ...]: ...  # pragma: no cover

    def linear_state_names(
        self, attitude: AttitudeForm = "euler"
    ) -> tuple[str, ...]: ...  # pragma: no cover

    def linearize(
        self, x_op: ArrayLike | None = None, *, pzt: bool = False, attitude: AttitudeForm = "euler",
        parameters: ParameterPoint | None = None,
    ) -> tuple[np.ndarray, np.ndarray]: ...  # pragma: no cover


def _interval(value: Any, name: str) -> tuple[float, float]:
    arr = as_vector(value, name, 2)
    lo, hi = float(arr[0]), float(arr[1])
    check_positive(lo, f"{name}[0]")
    if hi < lo:
        raise InvalidArgumentError(name, "an interval (low, high) with 0 < low <= high", repr((lo, hi)))
    return lo, hi


def vertex_parameters(
    sat: FlexibleLinearisation,
    mode: PolytopeMode = "groups",
    inverse_inertia_range: ArrayLike = DEFAULT_INVERSE_INERTIA_RANGE,
    frequency_range: ArrayLike = DEFAULT_FREQUENCY_RANGE,
    damping_range: ArrayLike = DEFAULT_DAMPING_RANGE,
    effectiveness_range: ArrayLike = DEFAULT_EFFECTIVENESS_RANGE,
) -> list[ParameterPoint]:
    """The parameter points at the corners of the uncertainty box, in vertex order.

    Order: ``itertools.product`` over the uncertain coordinates, low end first, in the order
    ``kappa``, then the stiffness scale(s), then the damping scale(s) (``"groups"``: 3
    coordinates; ``"box"``: ``kappa, k_1..k_N, c_1..c_N``; ``"effectiveness"``: one).
    """
    check_choice(mode, "mode", ("groups", "box", "effectiveness"))
    if mode == "effectiveness":
        lo, hi = _interval(effectiveness_range, "effectiveness_range")
        return [ParameterPoint(effectiveness=e) for e in (lo, hi)]
    kap = _interval(inverse_inertia_range, "inverse_inertia_range")
    f_lo, f_hi = _interval(frequency_range, "frequency_range")
    g_lo, g_hi = _interval(damping_range, "damping_range")
    k0 = np.diag(sat.stiffness).copy()
    c0 = np.diag(sat.damping_matrix).copy()
    k_scales = (f_lo**2, f_hi**2)
    c_scales = (f_lo * g_lo, f_hi * g_hi)
    points = []
    if mode == "groups":
        for kappa, sk, sc in itertools.product(kap, k_scales, c_scales):
            points.append(ParameterPoint(kappa=kappa, stiffness=sk * k0, viscous_damping=sc * c0))
        return points
    n = sat.n_modes
    for corner in itertools.product((0, 1), repeat=1 + 2 * n):
        kappa = kap[corner[0]]
        k = np.array([k_scales[j] for j in corner[1:1 + n]]) * k0
        c = np.array([c_scales[j] for j in corner[1 + n:]]) * c0
        points.append(ParameterPoint(kappa=kappa, stiffness=k, viscous_damping=c))
    return points


def flexible_polytope(
    sat: FlexibleLinearisation,
    x_op: ArrayLike | None = None,
    dt: float | None = None,
    *,
    mode: PolytopeMode = "groups",
    inverse_inertia_range: ArrayLike = DEFAULT_INVERSE_INERTIA_RANGE,
    frequency_range: ArrayLike = DEFAULT_FREQUENCY_RANGE,
    damping_range: ArrayLike = DEFAULT_DAMPING_RANGE,
    effectiveness_range: ArrayLike = DEFAULT_EFFECTIVENESS_RANGE,
    attitude: AttitudeForm = "euler",
    pzt: bool = False,
) -> PolytopicModel:
    """The ZOH-discretised polytope; see :meth:`models.FlexibleSatellite.polytope`."""
    a_nom, b_nom = sat.linearize(x_op, pzt=pzt, attitude=attitude)  # checks x_op before dt
    dt = sample_time(dt)
    points = vertex_parameters(
        sat, mode, inverse_inertia_range, frequency_range, damping_range, effectiveness_range
    )
    verts = [zoh(*sat.linearize(x_op, pzt=pzt, attitude=attitude, parameters=p), dt) for p in points]
    nominal = zoh(a_nom, b_nom, dt)
    return PolytopicModel(
        verts, dt, nominal=nominal, state_names=sat.linear_state_names(attitude),
        input_names=sat.input_names[: 3 + (sat.n_pzt if pzt else 0)], attitude=POLYTOPIC_ATTITUDE[attitude],
    )
