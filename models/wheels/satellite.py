"""The satellite (air-bearing platform) of paper W: rigid body, reaction-wheel array, imbalance torque.

State ``x = [phi, theta, psi, p, q, r, h_1..h_m]`` (3-2-1 Euler angles in rad, body rates in
rad/s, wheel momenta along their own axes in N m s), input ``u`` = the torques the ``m`` wheels
actually apply to the platform (N m; faults and limits act before, in
:class:`~models.WheelInputStage`), disturbance ``d`` = a body torque (3, N m). Paper W's model::

    eta' = K(phi, theta) w                                   (models.attitude.euler)
    J w' = -w x (J w) [- w x (D h)] + D (u - f) + d_g(eta) + d
    h'   = -u + f

- ``d_g = s m g (r x k(eta))``, ``k = [-sin(theta), sin(phi) cos(theta), cos(phi) cos(theta)]``
  the gravity direction in body axes (z down at level), ``m g r`` the imbalance (N m) and
  ``s = +1`` (``gravity="pendulous"``, default, **likely**), ``-1`` (``"inverted"``, paper W's
  eq. 13 sign) or ``0`` (``"off"``). Paper W prints ``k_y = cos(phi) sin(theta)``, a misprint
  (**certain**): eq. (7) needs ``sin(phi) cos(theta)``, used here.
- ``-w x (D h)`` (the wheels' gyroscopic torque) is left out by default, as paper W does by
  folding it into ``u`` (**assumed**); ``wheel_gyroscopic=True`` adds it to the plant only.
- ``f_j = -b Omega_j - c sign(Omega_j)`` is the bearing friction on wheel ``j`` with
  ``Omega_j = h_j / I_w`` (the body rate is neglected next to the wheel speed): off by default
  (``b = c = 0``, **assumed**). Friction is internal: it slows the wheel and drags the platform
  along, and leaves the total angular momentum unchanged.

With the gyroscopic term on, gravity off and ``d = 0`` the inertial angular momentum
``R(eta) (J w + D h)`` is conserved (:meth:`WheelSatellite.angular_momentum_inertial`).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.euler import kinematics_matrix, rotation_matrix
from models.attitude.vectors import skew
from models.linear import PolytopicModel, sample_time, zoh
from models.protocols import map_states
from models.wheels import linear
from models.wheels.array import WheelArray, _rank
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import (
    as_inertia,
    as_positive_values,
    as_vector,
    check_bool,
    check_choice,
    renamed_arguments,
)

__all__ = [
    "PAPER_W_ATTITUDE_RANGE_DEG",
    "PAPER_W_IMBALANCE",
    "PAPER_W_INERTIA",
    "PAPER_W_SAMPLE_TIME",
    "WheelSatellite",
    "gravity_direction",
]

#: Inertia of paper W's platform, kg m^2 (**certain**); eig = 1.6491, 1.8993, 3.4326.
PAPER_W_INERTIA: tuple[tuple[float, float, float], ...] = (
    (1.814, -0.1185, 0.02749),
    (-0.1185, 1.735, 0.01697),
    (0.02749, 0.01697, 3.432),
)
#: Imbalance ``m g r`` of paper W, N m: ``m g r_z = 0.326`` (**certain** as printed), ``r_x = r_y = 0``.
PAPER_W_IMBALANCE: tuple[float, float, float] = (0.0, 0.0, 0.326)
#: Control period of paper W's hardware loop, s (**certain**).
PAPER_W_SAMPLE_TIME: float = 0.04
#: Attitude range of paper W's platform, deg: ``|phi|, |theta| <= 40``, ``|psi| <= 180`` (**certain**).
PAPER_W_ATTITUDE_RANGE_DEG: tuple[float, float, float] = (40.0, 40.0, 180.0)

GravityMode = Literal["pendulous", "inverted", "off"]
_GRAVITY_SIGN = {"pendulous": 1.0, "inverted": -1.0, "off": 0.0}


def gravity_direction(phi: float, theta: float) -> np.ndarray:
    """The gravity direction in body axes, ``k = [-s_th, s_ph c_th, c_ph c_th]`` (z down at level)."""
    s_p, c_p = np.sin(phi), np.cos(phi)
    s_t, c_t = np.sin(theta), np.cos(theta)
    return np.array([-s_t, s_p * c_t, c_p * c_t])


class WheelSatellite:
    """A rigid platform with a reaction-wheel array and an imbalance (gravity) torque.

    Parameters
    ----------
    inertia : array_like
        Platform inertia ``J`` (wheels included): three principal inertias or a symmetric
        positive definite 3 x 3 matrix (kg m^2).
    wheels : WheelArray
        The wheel array (``D``, limits, wheel inertia).
    imbalance : float or (3,) array_like
        ``m g r`` in N m, ``r`` from the rotation centre to the centre of mass in body axes.
        A scalar means ``m g r_z`` (``r_x = r_y = 0``).
    gravity : {"pendulous", "inverted", "off"}
        Sign of the imbalance torque (see the module notes). Default ``"pendulous"``.
    wheel_gyroscopic : bool
        Add ``-w x (D h)`` to the rate equation (default ``False``, as paper W).
    viscous_friction : float or (m,) array_like
        ``b`` in N m s/rad per wheel (default 0).
    coulomb_friction : float or (m,) array_like
        ``c`` in N m per wheel (default 0).

    Notes
    -----
    The satellite follows :class:`models.protocols.Plant`. Its linear model
    (:mod:`models.wheels.linear`: :meth:`linearize`, :meth:`discretize`, :meth:`linear_model`,
    :meth:`polytope`) takes the operating point ``x_op`` first, the level attitude at rest
    (default, and the only point where the model is linearised), and the sample time ``dt``
    next, as every satellite's does.

    Examples
    --------
    >>> import numpy as np
    >>> from models import WheelSatellite
    >>> sat = WheelSatellite.paper_w()
    >>> sat.n_states, sat.n_inputs, sat.n_disturbances
    (10, 4, 3)
    >>> x0 = sat.state(np.radians([40.0, 0.0, 0.0]))
    >>> sat.gravity_torque(x0[:3]).round(4).tolist()  # restoring roll torque
    [-0.2095, 0.0, 0.0]
    >>> sat.polytope(dt=0.04).n_vertices  # healthy + one outage per wheel
    5
    """

    n_disturbances = 3

    def __init__(
        self,
        inertia: ArrayLike,
        wheels: WheelArray,
        imbalance: ArrayLike = PAPER_W_IMBALANCE,
        gravity: GravityMode = "pendulous",
        *,
        wheel_gyroscopic: bool = False,
        viscous_friction: ArrayLike = 0.0,
        coulomb_friction: ArrayLike = 0.0,
    ) -> None:
        self._inertia = as_inertia(inertia)
        if not isinstance(wheels, WheelArray):
            raise ArgumentTypeError("wheels", "a models.WheelArray", type(wheels).__name__)
        self._wheels = wheels
        if np.ndim(imbalance) == 0:
            imb = np.array([0.0, 0.0, float(as_vector([imbalance], "imbalance", 1)[0])])
        else:
            imb = as_vector(imbalance, "imbalance", 3)
        self._imbalance = imb
        self._gravity = check_choice(gravity, "gravity", tuple(_GRAVITY_SIGN))
        self._sign = _GRAVITY_SIGN[gravity]
        self._gyroscopic = check_bool(wheel_gyroscopic, "wheel_gyroscopic")
        m = wheels.n_wheels
        friction = {"allow_zero": True, "per": "wheel", "what": "friction coefficients"}
        self._viscous = as_positive_values(viscous_friction, "viscous_friction", m, **friction)
        self._coulomb = as_positive_values(coulomb_friction, "coulomb_friction", m, **friction)
        self._inertia_inv = np.linalg.inv(self._inertia)
        self._g2 = self._inertia_inv @ wheels.D
        for arr in (self._inertia, self._inertia_inv, self._imbalance, self._viscous, self._coulomb):
            arr.setflags(write=False)
        self._g2.setflags(write=False)

    @classmethod
    def paper_w(cls, gravity: GravityMode = "pendulous", **options: Any) -> WheelSatellite:
        """Paper W's platform: paper W's ``J``, :meth:`WheelArray.paper_w`, ``m g r_z = 0.326`` N m.

        ``gravity`` and the keyword options of the constructor (``wheel_gyroscopic``,
        ``viscous_friction``, ``coulomb_friction``) may be changed.
        """
        return cls(PAPER_W_INERTIA, WheelArray.paper_w(), PAPER_W_IMBALANCE, gravity, **options)

    def replace(self, **changes: Any) -> WheelSatellite:
        """A copy with some constructor arguments changed, e.g. ``replace(inertia=1.2 * sat.inertia)``."""
        args: dict[str, Any] = {
            "inertia": self._inertia,
            "wheels": self._wheels,
            "imbalance": self._imbalance,
            "gravity": self._gravity,
            "wheel_gyroscopic": self._gyroscopic,
            "viscous_friction": self._viscous,
            "coulomb_friction": self._coulomb,
        }
        unknown = sorted(set(changes) - set(args))
        if unknown:
            raise InvalidArgumentError("changes", f"constructor arguments ({', '.join(args)})", repr(unknown))
        args.update(changes)
        inertia, wheels, imbalance, gravity = (
            args.pop(k) for k in ("inertia", "wheels", "imbalance", "gravity")
        )
        return WheelSatellite(inertia, wheels, imbalance, gravity, **args)

    # -- parameters ------------------------------------------------------------------------
    @property
    def n_wheels(self) -> int:
        """Number of wheels ``m``."""
        return self._wheels.n_wheels

    @property
    def n_states(self) -> int:
        """``6 + m``: attitude, rates and wheel momenta."""
        return 6 + self.n_wheels

    @property
    def n_inputs(self) -> int:
        """``m`` wheel torques."""
        return self.n_wheels

    @property
    def state_names(self) -> tuple[str, ...]:
        """``phi, theta, psi, p, q, r, h1..hm``."""
        return (*linear.LINEAR_STATE_NAMES, *(f"h{j + 1}" for j in range(self.n_wheels)))

    @property
    def input_names(self) -> tuple[str, ...]:
        """``u1..um``: the wheel torques."""
        return tuple(f"u{j + 1}" for j in range(self.n_wheels))

    @property
    def inertia(self) -> np.ndarray:
        """Platform inertia ``J`` (kg m^2, read-only)."""
        return self._inertia

    @property
    def inertia_inv(self) -> np.ndarray:
        """``J^-1`` (read-only)."""
        return self._inertia_inv

    @property
    def wheels(self) -> WheelArray:
        """The wheel array."""
        return self._wheels

    @property
    def imbalance(self) -> np.ndarray:
        """``m g r`` (N m, read-only)."""
        return self._imbalance

    @property
    def gravity(self) -> str:
        """``"pendulous"``, ``"inverted"`` or ``"off"``."""
        return self._gravity

    @property
    def wheel_gyroscopic(self) -> bool:
        """Whether the plant includes ``-w x (D h)``."""
        return self._gyroscopic

    @property
    def input_matrix(self) -> np.ndarray:
        """``g2 = J^-1 D`` (3 x m, read-only): the rate equation's input matrix (paper W's ``g2``)."""
        return self._g2

    def nominal_gain(self, effectiveness: ArrayLike | None = None) -> np.ndarray:
        """Paper W's ``G = (g2 Lambda g2')^-1`` (3 x 3); all wheels healthy by default (``G_nom``).

        Raises :class:`~toolkit_common.errors.InvalidArgumentError` naming ``effectiveness`` when
        ``rank(D Lambda) < 3`` (``G`` does not exist).
        """
        lam = (
            np.ones(self.n_wheels)
            if effectiveness is None
            else as_vector(effectiveness, "effectiveness", self.n_wheels)
        )
        self._wheels.effective_matrix(lam)  # checks [0, 1]
        if _rank(self._wheels.D * lam) < 3:
            raise InvalidArgumentError(
                "effectiveness", "wheels that span three axes (rank(D Lambda) = 3)", repr(lam.tolist())
            )
        return np.linalg.inv((self._g2 * lam) @ self._g2.T)

    def __repr__(self) -> str:
        return (
            f"WheelSatellite(n_wheels={self.n_wheels}, gravity={self._gravity!r}, "
            f"imbalance={self._imbalance.tolist()}, wheel_gyroscopic={self._gyroscopic})"
        )

    def state(
        self,
        attitude: ArrayLike,
        rates: ArrayLike | None = None,
        momenta: ArrayLike | None = None,
    ) -> np.ndarray:
        """The full state from the attitude (rad), rates (default 0) and wheel momenta (default 0)."""
        att = as_vector(attitude, "attitude", 3)
        w = np.zeros(3) if rates is None else as_vector(rates, "rates", 3)
        h = np.zeros(self.n_wheels) if momenta is None else as_vector(momenta, "momenta", self.n_wheels)
        return np.concatenate((att, w, h))

    # -- nonlinear model -------------------------------------------------------------------
    def gravity_torque(self, attitude: ArrayLike) -> np.ndarray:
        """``d_g(eta) = s m g (r x k(eta))`` in body axes (N m); yaw does not enter."""
        att = np.asarray(attitude, dtype=float)
        # + 0.0 turns the -0.0 of a zero component into 0.0
        return self._sign * np.cross(self._imbalance, gravity_direction(att[0], att[1])) + 0.0

    def friction_torque(self, momenta: ArrayLike) -> np.ndarray:
        """Bearing friction ``f_j`` on each wheel (N m), zero unless friction is switched on."""
        omega = np.asarray(momenta, dtype=float) / self._wheels.wheel_inertia
        return -self._viscous * omega - self._coulomb * np.sign(omega)

    def dynamics(self, x: ArrayLike, u: ArrayLike | None = None, d: ArrayLike | None = None) -> np.ndarray:
        """``x'`` for the state ``x``, applied wheel torques ``u`` (m) and body torque ``d`` (3).

        Raises :class:`~toolkit_common.errors.SingularityError` at pitch = +-90 deg.
        """
        x = as_vector(x, "x", self.n_states)
        u_vec = np.zeros(self.n_wheels) if u is None else as_vector(u, "u", self.n_wheels)
        d_vec = np.zeros(3) if d is None else as_vector(d, "d", 3)
        return self._rhs(x, u_vec, d_vec)

    def _rhs(self, x: np.ndarray, u: np.ndarray, d: np.ndarray) -> np.ndarray:
        w, h = x[3:6], x[6:]
        dmat = self._wheels.D
        wheel_torque = u - self.friction_torque(h) if (self._viscous.any() or self._coulomb.any()) else u
        torque = dmat @ wheel_torque + self.gravity_torque(x[:3]) + d - np.cross(w, self._inertia @ w)
        if self._gyroscopic:
            torque = torque - np.cross(w, dmat @ h)
        eta_dot = kinematics_matrix(x[0], x[1]) @ w
        return np.concatenate((eta_dot, self._inertia_inv @ torque, -wheel_torque))

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:
        """Roll, pitch and yaw (rad, 3-2-1) of the platform relative to the level frame: ``x[:3]``.

        The level frame is the reference of the state's Euler angles (z down along gravity).
        ``x`` is one state or states as rows; see :class:`models.protocols.Plant`.
        """
        return map_states(lambda s: s[:3].copy(), x, self.n_states)

    def angular_momentum_body(self, x: ArrayLike) -> np.ndarray:
        """Total angular momentum in body axes, ``J w + D h`` (N m s)."""
        x = as_vector(x, "x", self.n_states)
        return self._inertia @ x[3:6] + self._wheels.D @ x[6:]

    def angular_momentum_inertial(self, x: ArrayLike) -> np.ndarray:
        """Total angular momentum in the inertial frame, ``R(eta) (J w + D h)`` (N m s)."""
        x = as_vector(x, "x", self.n_states)
        return rotation_matrix(x[:3]) @ self.angular_momentum_body(x)

    # -- linear model at level attitude ----------------------------------------------------
    def gravity_stiffness(self) -> np.ndarray:
        """``K_g = -d(d_g)/d(eta)`` at level attitude (3 x 3; pendulous paper W: ``0.326 diag(1, 1, 0)``)."""
        dk = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])  # [dk/dphi, dk/dtheta, dk/dpsi]
        return -self._sign * skew(self._imbalance) @ dk

    def linearize(
        self,
        x_op: ArrayLike | None = None,
        effectiveness: ArrayLike | None = None,
        inertia_scale: float = 1.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Continuous ``(A, B)`` of the attitude and rates at level attitude, zero rates and momenta.

        ``A = [[0, I3], [-J^-1 K_g, 0]]``, ``B = [0; J^-1 D Lambda]`` with
        ``Lambda = diag(effectiveness)`` (default all wheels healthy) and ``J`` scaled by
        ``inertia_scale`` (one multiplier, a point). The wheel momenta do not enter the attitude
        (``h' = -u`` is left out; it is the plant's business, through the momentum limit).

        ``x_op`` = ``[phi, theta, psi, p, q, r]`` is the level attitude at rest (default zero; any
        yaw); any other point is an error naming ``x_op``.
        """
        return linear.linearize(
            self._wheels, self._inertia_inv, self.gravity_stiffness(), x_op, effectiveness, inertia_scale
        )

    def discretize(
        self,
        x_op: ArrayLike | None = None,
        dt: float | None = None,
        effectiveness: ArrayLike | None = None,
        inertia_scale: float = 1.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Zero-order-hold discretisation of :meth:`linearize` at sample time ``dt`` (required)."""
        a, b = self.linearize(x_op, effectiveness, inertia_scale)
        return zoh(a, b, sample_time(dt))

    def linear_model(
        self,
        x_op: ArrayLike | None = None,
        dt: float | None = None,
        effectiveness: ArrayLike | None = None,
        inertia_scale: float = 1.0,
    ) -> PolytopicModel:
        """:meth:`discretize` as a one-vertex :class:`PolytopicModel` (Euler attitude, ``m`` wheel inputs)."""
        ad, bd = self.discretize(x_op, dt, effectiveness, inertia_scale)
        return PolytopicModel(
            [(ad, bd)], dt, state_names=linear.LINEAR_STATE_NAMES, input_names=self.input_names,
            attitude="euler321",
        )

    def effectiveness_vertices(
        self, effectiveness: ArrayLike = "single_outage", lambda_min: float = 0.2
    ) -> np.ndarray:
        """The wheel-effectiveness vertices ``lambda`` (one row per vertex, ``(k, m)``).

        Parameters
        ----------
        effectiveness : {"single_outage", "box"} or (k, m) array_like
            ``"single_outage"`` (default): the healthy array and each single outage,
            ``conv{1, 1 - e_j}`` (``m + 1`` vertices). ``"box"``:
            ``[lambda_min, 1]^m`` (``2^m`` vertices, healthy first). Or explicit vertices, each in
            ``[0, 1]^m``.
        lambda_min : float
            Lower corner of the box, in ``[0, 1)`` (default 0.2, **assumed**).
        """
        return linear.effectiveness_vertices(self.n_wheels, effectiveness, lambda_min)

    @renamed_arguments(inertia_spread="spread")
    def polytope(
        self,
        x_op: ArrayLike | None = None,
        dt: float | None = None,
        effectiveness: ArrayLike = "single_outage",
        *,
        lambda_min: float = 0.2,
        spread: float | None = None,
    ) -> PolytopicModel:
        """The wheel-effectiveness polytope of the linear model.

        Parameters
        ----------
        x_op : (6,) array_like, optional
            The level attitude at rest, as in :meth:`linearize` (default zero).
        dt : float
            Sample time of the zero-order hold (required; paper W's loop: 0.04 s,
            :data:`PAPER_W_SAMPLE_TIME`).
        effectiveness, lambda_min
            The effectiveness vertices, see :meth:`effectiveness_vertices`.
        spread : float, optional
            Relative inertia uncertainty ``s`` in ``[0, 1)``, ``J in [(1 - s) J, (1 + s) J]``:
            the product with the scalar inertia polytope ``J in {(1 + s) J, (1 - s) J}`` (S4:
            0.2, 2 x 5 = 10 vertices). ``None`` (default): the nominal inertia only.

        Returns
        -------
        PolytopicModel
            ``x = [phi, theta, psi, p, q, r]`` (``attitude="euler321"``), ``m`` wheel-torque
            inputs; vertices ordered inertia scale first (``1 + s``, then ``1 - s``),
            effectiveness inside; the nominal model is the healthy array at the nominal inertia.

        Raises
        ------
        InvalidArgumentError
            Naming ``effectiveness`` and the vertex when a vertex has ``B = 0`` or
            ``rank(D Lambda) < 3``: there the vertex LMI is infeasible (``A`` is
            not Schur and nothing acts on some axis), which a conic solver may hide behind an
            "inaccurate" status with a finite gamma.

        Notes
        -----
        The effectiveness vertices are exact; with ``spread`` they approximate the discrete set
        (see :mod:`models.wheels.linear`).
        """
        platform = (self._wheels, self._inertia_inv, self.gravity_stiffness())
        return linear.wheel_polytope(*platform, x_op, dt, effectiveness, lambda_min, spread)
