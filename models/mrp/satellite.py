"""The rigid satellite of paper M in MRP relative to the rotating orbital (LVLH) frame.

State ``x = [sigma, w]``: ``sigma`` the MRP of the body B relative to the orbital frame O,
``w`` the body rate relative to inertial space (rad/s, B components). Input ``u`` = control
torque, ``d`` = external body torque (N m). Paper M's model:

.. math::

    \\dot\\sigma = N(\\sigma)\\, \\omega_{BO}, \\qquad \\omega_{BO} = \\omega + n\\, c_2(\\sigma), \\qquad
    J \\dot\\omega = -\\omega \\times (J \\omega) + u + d + T_g,

with ``c_i`` the i-th column of ``C(sigma)`` (:func:`models.attitude.mrp.mrp_to_dcm`) and
``T_g = 3 n^2 c_3 x (J c_3)`` the gravity-gradient torque (off by default, as in paper M).

Frames (**likely**): O is LVLH on a circular orbit, ``o_3`` towards the Earth's centre,
``o_2`` along the negative orbit normal, ``o_1 = o_2 x o_3``, so ``w_OI = -n o_2``; this
reproduces paper M's signs ``w_BO = w + n c_2`` and ``R = -|R| c_3``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.euler import euler321_from_matrix
from models.attitude.mrp import _dcm, _kinematics
from models.attitude.vectors import cross3
from models.protocols import map_states
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_inertia, as_vector, check_positive, check_real

__all__ = [
    "EARTH_MU",
    "EARTH_RADIUS",
    "PAPER_M_ALTITUDE",
    "PAPER_M_INERTIA",
    "MRPSatellite",
]

#: Earth's gravitational parameter (m^3/s^2; **assumed** in paper M, the standard value).
EARTH_MU: float = 3.986004418e14
#: Earth's equatorial radius (m; **assumed** in paper M).
EARTH_RADIUS: float = 6378137.0
#: Orbit altitude of paper M (m; **certain**).
PAPER_M_ALTITUDE: float = 650e3
#: Principal inertias of paper M, kg m^2 (**likely**; J2 and J3 may be swapped).
PAPER_M_INERTIA: tuple[float, float, float] = (3.0, 3.0, 2.0)


class MRPSatellite:
    """A rigid satellite on a circular orbit, attitude in MRP relative to the orbital frame.

    Parameters
    ----------
    inertia : array_like
        Principal inertias ``[J1, J2, J3]`` or a full symmetric positive definite ``3 x 3``
        matrix (kg m^2).
    altitude : float
        Altitude of the circular orbit above the Earth's radius (m), >= 0.
    gravity_gradient : bool
        Add the gravity-gradient torque ``T_g = 3 n^2 c_3 x (J c_3)`` (paper M derives it and
        leaves it out of its simulations: off by default).
    shadow_threshold : float
        :meth:`normalize_state` switches ``sigma`` to its shadow set when
        ``sigma' sigma > shadow_threshold`` (**assumed**: 1, paper M mentions no shadow set).
        Must be >= 1.
    mu : float
        Gravitational parameter (m^3/s^2).
    earth_radius : float
        Earth's radius (m).

    Examples
    --------
    >>> import numpy as np
    >>> from models import MRPSatellite
    >>> sat = MRPSatellite.paper_m()
    >>> sat
    MRPSatellite(inertia=[3.0, 3.0, 2.0], altitude=650000.0, gravity_gradient=False)
    >>> round(sat.mean_motion, 9)
    0.00107154
    >>> x = sat.state_at_rest([0.1, 0.0, 0.0])   # w_BO = 0: w = -n c2(sigma)
    >>> bool(np.allclose(sat.dynamics(x)[:3], 0.0))
    True
    """

    n_states = 6
    n_inputs = 3
    n_disturbances = 3
    state_names = ("sigma1", "sigma2", "sigma3", "wx", "wy", "wz")
    input_names = ("Mx", "My", "Mz")

    def __init__(
        self,
        inertia: ArrayLike,
        altitude: float = PAPER_M_ALTITUDE,
        *,
        gravity_gradient: bool = False,
        shadow_threshold: float = 1.0,
        mu: float = EARTH_MU,
        earth_radius: float = EARTH_RADIUS,
    ) -> None:
        self._inertia = as_inertia(inertia)
        self._inertia.setflags(write=False)
        self._inertia_inv = np.linalg.inv(self._inertia)
        self._inertia_inv.setflags(write=False)
        self.mu = check_positive(mu, "mu")
        self.earth_radius = check_positive(earth_radius, "earth_radius")
        self.altitude = check_real(altitude, "altitude")
        if self.altitude < 0.0:
            raise InvalidArgumentError(
                "altitude", "an altitude >= 0 m above the Earth's surface (radius "
                f"{self.earth_radius:g} m)", f"{self.altitude!r} m (below the surface)",
            )
        if not isinstance(gravity_gradient, bool | np.bool_):
            raise InvalidArgumentError("gravity_gradient", "True or False", repr(gravity_gradient))
        self.gravity_gradient = bool(gravity_gradient)
        thr = check_positive(shadow_threshold, "shadow_threshold")
        if thr < 1.0:
            raise InvalidArgumentError(
                "shadow_threshold", "a threshold >= 1 on sigma' sigma (below 1 the shadow of a "
                "switched set would switch back)", repr(thr),
            )
        self.shadow_threshold = thr
        self.orbit_radius = self.earth_radius + self.altitude
        self.mean_motion = float(np.sqrt(self.mu / self.orbit_radius**3))

    @classmethod
    def paper_m(cls, **options: Any) -> MRPSatellite:
        """Paper M's satellite: ``J = diag(3, 3, 2)`` kg m^2 (**likely**), 650 km (**certain**).

        Gravity gradient off (**certain**: paper M leaves it out of its simulations). Keyword
        ``options`` go to the constructor (``gravity_gradient=True``, say).
        """
        return cls(PAPER_M_INERTIA, PAPER_M_ALTITUDE, **options)

    def with_inertia(self, inertia: ArrayLike) -> MRPSatellite:
        """The same orbit and options with another inertia (the true plant of paper M's M3)."""
        return MRPSatellite(
            inertia, self.altitude, gravity_gradient=self.gravity_gradient,
            shadow_threshold=self.shadow_threshold, mu=self.mu, earth_radius=self.earth_radius,
        )

    @property
    def inertia(self) -> np.ndarray:
        """The inertia matrix ``J`` (kg m^2, read-only)."""
        return self._inertia

    @property
    def inertia_inv(self) -> np.ndarray:
        """``J^-1`` (read-only)."""
        return self._inertia_inv

    @property
    def orbit_period(self) -> float:
        """``2 pi / n`` (s)."""
        return 2.0 * np.pi / self.mean_motion

    def __repr__(self) -> str:
        j = self._inertia
        shown = np.diag(j).tolist() if np.count_nonzero(j - np.diag(np.diag(j))) == 0 else j.tolist()
        return (
            f"MRPSatellite(inertia={shown}, altitude={self.altitude!r}, "
            f"gravity_gradient={self.gravity_gradient})"
        )

    # -- model ---------------------------------------------------------------------------
    def dynamics(self, x: ArrayLike, u: ArrayLike | None = None, d: ArrayLike | None = None) -> np.ndarray:
        """``x'`` for the state ``x = [sigma, w]``, control torque ``u`` and external torque ``d``.

        ``sigma' = N(sigma) (w + n c2(sigma))``,
        ``J w' = -w x (J w) + u + d (+ T_g with gravity_gradient)``.
        """
        x = as_vector(x, "x", 6)
        torque = np.zeros(3) if u is None else as_vector(u, "u", 3)
        if d is not None:
            torque = torque + as_vector(d, "d", 3)
        return self._rhs(x, torque)

    def _rhs(self, x: np.ndarray, torque: np.ndarray) -> np.ndarray:
        """Unchecked right-hand side."""
        s, w = x[:3], x[3:6]
        c = _dcm(s)
        w_bo = w + self.mean_motion * c[:, 1]
        jw = self._inertia @ w
        total = torque - cross3(w, jw)
        if self.gravity_gradient:
            c3 = c[:, 2]
            total = total + 3.0 * self.mean_motion**2 * cross3(c3, self._inertia @ c3)
        return np.concatenate((_kinematics(s) @ w_bo, self._inertia_inv @ total))

    def normalize_state(self, x: ArrayLike) -> np.ndarray:
        """The shadow-set switch: ``sigma := -sigma / sigma' sigma`` when ``sigma' sigma > threshold``.

        :class:`rmpc.sim.plants.SampledPlant` applies it after every integration step. The
        attitude ``C(sigma)`` and the rate are unchanged.
        """
        x = np.asarray(x, dtype=float)
        s = x[:3]
        ss = float(s @ s)
        if ss <= self.shadow_threshold:
            return x
        return np.concatenate((-s / ss, x[3:]))

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:
        """Roll, pitch and yaw (rad, 3-2-1) of the body relative to the **orbital (LVLH) frame O**.

        The angles of ``C(sigma)`` (:func:`models.attitude.mrp.mrp_to_dcm`, O to body
        components): the body is reached from O by the yaw ``psi`` about ``o_3``, the pitch
        ``theta`` about the new 2-axis and the roll ``phi`` about the body 1-axis. Either MRP
        set gives the same angles. ``x`` is one state or states as rows; see
        :class:`models.protocols.Plant`.

        Examples
        --------
        >>> import numpy as np
        >>> from models import MRPSatellite
        >>> sat = MRPSatellite.paper_m()
        >>> x = np.array([np.tan(0.5 / 4), 0.0, 0.0, 0.0, 0.0, 0.0])   # 0.5 rad about o_1
        >>> bool(np.allclose(sat.attitude_euler(x), [0.5, 0.0, 0.0]))
        True
        """
        return map_states(lambda s: euler321_from_matrix(_dcm(s[:3]).T), x, self.n_states)

    def relative_rate(self, x: ArrayLike) -> np.ndarray:
        """``w_BO = w + n c2(sigma)``: the body rate relative to the orbital frame (B components)."""
        x = as_vector(x, "x", 6)
        return x[3:6] + self.mean_motion * _dcm(x[:3])[:, 1]

    def state_at_rest(self, sigma: ArrayLike, relative_rate: ArrayLike | None = None) -> np.ndarray:
        """The state ``[sigma, w]`` with the given rate relative to O (default 0: ``w = -n c2``)."""
        s = as_vector(sigma, "sigma", 3)
        w_bo = np.zeros(3) if relative_rate is None else as_vector(relative_rate, "relative_rate", 3)
        return np.concatenate((s, w_bo - self.mean_motion * _dcm(s)[:, 1]))

    def gravity_gradient_torque(self, sigma: ArrayLike) -> np.ndarray:
        """``T_g = 3 n^2 c3 x (J c3)`` (N m), whether or not the model includes it.

        Equal to ``3 mu / |R|^5  R x (J R)`` with ``R = -|R| c3`` the position of the satellite
        from the Earth's centre in body components.
        """
        c3 = _dcm(as_vector(sigma, "sigma", 3))[:, 2]
        return 3.0 * self.mean_motion**2 * cross3(c3, self._inertia @ c3)

    def kinetic_energy(self, x: ArrayLike) -> float:
        """Rotational kinetic energy ``w' J w / 2`` (J), with ``w`` relative to inertial space."""
        w = as_vector(x, "x", 6)[3:6]
        return 0.5 * float(w @ self._inertia @ w)
