"""The nonlinear rigid satellite of paper P, its linearisation and its inertia polytope.

State ``x = [phi, theta, psi, p, q, r]`` (3-2-1 Euler angles in rad, body rates in rad/s),
input ``u = [Mx, My, Mz]`` (control torques, N m) and an optional disturbance torque ``d``:

.. math::

    [\\phi, \\theta, \\psi]' = K(\\phi, \\theta)\\, \\omega, \\qquad
    J \\omega' = -\\omega \\times (J \\omega) + u + d, \\qquad \\omega = [p, q, r].
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.euler import (
    SINGULARITY_COS_TOL,
    euler_rates_jacobian,
    kinematics_cover,
    kinematics_matrix,
    rotation_matrix,
)
from models.attitude.vectors import skew
from models.linear import PolytopicModel, operating_point, relative_spread, sample_time, zoh
from models.protocols import map_states
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_inertia, as_vector, check_choice, check_real

if TYPE_CHECKING:  # python-control is imported where it is used
    import control

__all__ = [
    "INPUT_NAMES",
    "PAPER_P_INERTIA",
    "PAPER_P_INITIAL_STATE",
    "PAPER_P_SAMPLE_TIME",
    "PAPER_P_TORQUE_LIMIT",
    "STATE_NAMES",
    "RigidSatellite",
]

#: Principal inertias ``(Ixx, Iyy, Izz)`` of paper P in kg m^2 (**likely**, decoded).
PAPER_P_INERTIA: tuple[float, float, float] = (1.2928, 1.2928, 4.2953)
#: Initial state of paper P: ``phi0 = 0.362`` (**likely**), ``theta0 = 0.524``,
#: ``psi0 = -0.262`` rad (**certain**), zero rates.
PAPER_P_INITIAL_STATE: tuple[float, ...] = (0.362, 0.524, -0.262, 0.0, 0.0, 0.0)
#: Sample time of paper P in s (**likely**).
PAPER_P_SAMPLE_TIME: float = 0.01
#: Torque limit of paper P, N m per axis (**certain**).
PAPER_P_TORQUE_LIMIT: float = 1.0

STATE_NAMES: tuple[str, ...] = ("phi", "theta", "psi", "p", "q", "r")
INPUT_NAMES: tuple[str, ...] = ("Mx", "My", "Mz")

PolytopeMode = Literal["scalar", "box"]


class RigidSatellite:
    """A rigid satellite with a symmetric positive definite inertia matrix.

    Parameters
    ----------
    inertia : array_like
        Either the three principal inertias ``[Ixx, Iyy, Izz]`` (a diagonal matrix) or a full
        symmetric positive definite ``3 x 3`` matrix, in kg m^2.

    Notes
    -----
    The satellite follows :class:`models.protocols.Plant`: ``n_states``, ``n_inputs``,
    ``state_names``, ``input_names``, :meth:`dynamics` and :meth:`attitude_euler`. Its
    linearisation family (:meth:`linearize`, :meth:`discretize`, :meth:`linear_model`,
    :meth:`polytope`) takes the operating point ``x_op`` first (default: at rest at zero
    attitude) and the sample time ``dt`` next, as every satellite's does.

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> sat = RigidSatellite.paper_p()
    >>> x0 = sat.initial_state()
    >>> float(sat.dynamics(x0, u=[1.0, 0.0, 0.0])[3])  # p' = Mx / Ixx
    0.7735148514851485
    >>> poly = sat.polytope(x0, dt=0.01, spread=0.3, mode="box")
    >>> poly.n_vertices
    8
    """

    n_states = 6
    n_inputs = 3
    state_names = STATE_NAMES
    input_names = INPUT_NAMES

    def __init__(self, inertia: ArrayLike) -> None:
        self._inertia = as_inertia(inertia)
        self._inertia.setflags(write=False)
        self._inertia_inv = np.linalg.inv(self._inertia)
        self._inertia_inv.setflags(write=False)

    @classmethod
    def paper_p(cls) -> RigidSatellite:
        """The satellite of paper P: ``diag(1.2928, 1.2928, 4.2953)`` kg m^2.

        The inertias were decoded from a damaged table and are **likely**, not certain.
        Paper P's other values are module constants: :data:`PAPER_P_INITIAL_STATE`
        (roll 0.362 rad **likely**; pitch 0.524 and yaw -0.262 rad **certain**; zero rates),
        :data:`PAPER_P_TORQUE_LIMIT` (1 N m per axis, **certain**) and
        :data:`PAPER_P_SAMPLE_TIME` (0.01 s, **likely**).
        """
        return cls(PAPER_P_INERTIA)

    @staticmethod
    def initial_state(scale: float = 1.0) -> np.ndarray:
        """Paper P's initial state, the attitude multiplied by ``scale`` (E6 uses 1.3)."""
        return np.asarray(PAPER_P_INITIAL_STATE) * check_real(scale, "scale")

    @property
    def inertia(self) -> np.ndarray:
        """The inertia matrix ``J`` (kg m^2, read-only)."""
        return self._inertia

    @property
    def inertia_inv(self) -> np.ndarray:
        """``J^-1`` (read-only)."""
        return self._inertia_inv

    def __repr__(self) -> str:
        j = self._inertia
        if np.count_nonzero(j - np.diag(np.diag(j))) == 0:
            return f"RigidSatellite(inertia={np.diag(j).tolist()})"
        return f"RigidSatellite(inertia={j.tolist()})"

    # -- nonlinear model ---------------------------------------------------------------
    def _inputs(self, u: ArrayLike, d: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        u_vec = np.zeros(3) if u is None else as_vector(u, "u", 3)
        d_vec = np.zeros(3) if d is None else as_vector(d, "d", 3)
        return u_vec, d_vec

    def dynamics(self, x: ArrayLike, u: ArrayLike | None = None, d: ArrayLike | None = None) -> np.ndarray:
        """Return ``x'`` for the state ``x``, control torque ``u`` and disturbance torque ``d``.

        Raises :class:`~toolkit_common.errors.SingularityError` at pitch = +-90 deg.
        """
        x = as_vector(x, "x", 6)
        u_vec, d_vec = self._inputs(u, d)
        return self._rhs(x, u_vec + d_vec)

    def dynamics_unchecked(self, x: np.ndarray, u: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        """:meth:`dynamics` without argument checks, for the inner loop of an integrator.

        ``x`` (6) and ``u`` (3) are finite float arrays, ``d`` is ``None`` or 3 values; the
        simulator calls this thousands of times per run (an optional member of
        :class:`models.protocols.Plant`).
        """
        return self._rhs(x, u if d is None else u + d)

    def _rhs(self, x: np.ndarray, torque: np.ndarray) -> np.ndarray:
        """Unchecked right-hand side (hot path of the simulator)."""
        w = x[3:]
        jw = self._inertia @ w
        w_dot = self._inertia_inv @ (torque - np.cross(w, jw))
        return np.concatenate((kinematics_matrix(x[0], x[1]) @ w, w_dot))

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:
        """Roll, pitch and yaw (rad, 3-2-1) of the body relative to the inertial frame: ``x[:3]``.

        ``x`` is one state ``(6,)`` or states as rows ``(k, 6)``; see :class:`models.protocols.Plant`.
        """
        return map_states(lambda s: s[:3].copy(), x, self.n_states)

    def kinetic_energy(self, x: ArrayLike) -> float:
        """Rotational kinetic energy ``w' J w / 2`` (J)."""
        w = as_vector(x, "x", 6)[3:]
        return 0.5 * float(w @ self._inertia @ w)

    def angular_momentum_inertial(self, x: ArrayLike) -> np.ndarray:
        """Angular momentum in the inertial frame, ``R(phi, theta, psi) J w`` (N m s)."""
        x = as_vector(x, "x", 6)
        return rotation_matrix(x[:3]) @ (self._inertia @ x[3:])

    # -- linearisation -----------------------------------------------------------------
    def linearize(
        self,
        x_op: ArrayLike | None = None,
        u_op: ArrayLike | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Continuous-time Jacobians ``(A, B)`` of the nonlinear model at ``(x_op, u_op)``.

        ``x_op`` (6 values) defaults to the rest state at zero attitude, ``np.zeros(6)``.

        Derived analytically, gyroscopic terms included:

        - attitude rows: ``d(eta')/d(eta)`` from :func:`~models.attitude.euler.euler_rates_jacobian`
          and ``d(eta')/dw = K(phi, theta)``;
        - rate rows: ``dw'/dw = J^-1 ([J w]x - [w]x J)``; ``B = [0; J^-1]``.

        At zero rates (paper P's operating point) this is ``A = [[0, K], [0, 0]]``. The model
        is affine in the torque, so ``u_op`` does not change ``A`` or ``B``; it is accepted for
        symmetry with python-control's ``linearize``.
        """
        x_op = operating_point(x_op, 6)
        if u_op is not None:
            as_vector(u_op, "u_op", 3)
        w = x_op[3:]
        a = np.zeros((6, 6))
        a[:3, :3] = euler_rates_jacobian(x_op[:3], w)
        a[:3, 3:] = kinematics_matrix(x_op[0], x_op[1])
        a[3:, 3:] = self._inertia_inv @ (skew(self._inertia @ w) - skew(w) @ self._inertia)
        b = np.zeros((6, 3))
        b[3:, :] = self._inertia_inv
        return a, b

    def discretize(
        self, x_op: ArrayLike | None = None, dt: float | None = None, u_op: ArrayLike | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Zero-order-hold discretisation of :meth:`linearize` at sample time ``dt`` (required)."""
        a, b = self.linearize(x_op, u_op)
        return zoh(a, b, sample_time(dt))

    def linear_model(self, x_op: ArrayLike | None = None, dt: float | None = None) -> PolytopicModel:
        """The discretised linearisation as a one-vertex :class:`PolytopicModel` (Euler attitude)."""
        ad, bd = self.discretize(x_op, dt)
        return PolytopicModel(
            [(ad, bd)], dt, state_names=STATE_NAMES, input_names=INPUT_NAMES, attitude="euler321"
        )

    # -- uncertainty -------------------------------------------------------------------
    def inertia_vertices(self, spread: float, mode: PolytopeMode = "scalar") -> list[np.ndarray]:
        """Inertia matrices at the corners of the uncertainty set.

        Parameters
        ----------
        spread : float
            Relative inertia uncertainty ``s`` in ``[0, 1)``: each inertia lies in
            ``[(1 - s), (1 + s)]`` times its nominal value.
        mode : {"scalar", "box"}
            ``"scalar"``: ``J = c J0`` with one scalar ``c`` (2 vertices). ``"box"``: each
            principal inertia of ``J0`` varies independently (8 vertices; for a diagonal
            ``J0`` these are the body axes).

        Notes
        -----
        ``B`` is affine in ``J^-1``, so the exact polytope has its corners in ``1/J_i``:
        ``1/((1 + s) J_i)`` and ``1/((1 - s) J_i)``. Every inertia inside the box maps to a
        ``J^-1`` inside their convex hull, which is what the returned matrices span.
        """
        s = relative_spread(spread)
        check_choice(mode, "mode", ("scalar", "box"))
        if mode == "scalar":
            return [(1.0 + s) * self._inertia, (1.0 - s) * self._inertia]
        lam, vec = np.linalg.eigh(self._inertia)
        if np.count_nonzero(self._inertia - np.diag(np.diag(self._inertia))) == 0:
            lam, vec = np.diag(self._inertia).copy(), np.eye(3)
        corners = []
        for sx in (1.0 + s, 1.0 - s):
            for sy in (1.0 + s, 1.0 - s):
                for sz in (1.0 + s, 1.0 - s):
                    scaled = lam * np.array([sx, sy, sz])
                    corners.append(vec @ np.diag(scaled) @ vec.T)
        return corners

    def polytope(
        self,
        x_op: ArrayLike | None = None,
        dt: float | None = None,
        spread: float | None = None,
        mode: PolytopeMode = "scalar",
        attitude_range: ArrayLike | None = None,
    ) -> PolytopicModel:
        """The discrete-time polytope of linearisations over the inertia uncertainty.

        Parameters
        ----------
        x_op : array_like, shape (6,), optional
            Operating point of the linearisation (paper P: the initial attitude, zero rates);
            default the rest state at zero attitude.
        dt : float
            Sample time (s) of the zero-order-hold discretisation (required).
        spread : float
            Relative inertia uncertainty ``s`` in ``[0, 1)``, ``J in [(1 - s) J, (1 + s) J]``
            (required). Paper P leaves the base level out; the toolkit assumes 0.3, and E5 uses
            0.7.
        mode : {"scalar", "box"}
            See :meth:`inertia_vertices`.
        attitude_range : (3,) array_like, optional
            Half-widths (rad, >= 0) of a box of attitudes around ``x_op``'s: the polytope then
            also covers the kinematics ``eta' = K(phi, theta) w`` at every attitude in the box
            (going beyond paper P), so the LMIs' guarantees hold along a
            manoeuvre through it and not only at ``x_op``. Yaw does not enter ``K``. ``x_op``
            must have zero rates. The box must keep the pitch inside ``(-90, 90)`` deg.

        Returns
        -------
        PolytopicModel
            One vertex per inertia corner (times the kinematics vertices with
            ``attitude_range``); the nominal model is the linearisation at ``x_op`` with this
            satellite's own inertia; ``attitude="euler321"``.

        Notes
        -----
        At zero operating rates ``A`` does not depend on ``J`` and the discrete ``B`` is
        linear in ``J^-1``, so the polytope contains every plant of the uncertainty set
        exactly. At non-zero rates the gyroscopic block of ``A`` is not affine in ``J``;
        the vertices are then the corner linearisations, an approximation.

        With ``attitude_range`` the model is the frozen-attitude (quasi-LPV) form of the
        nonlinear model, ``x' = [[0, K(eta)], [0, 0]] x + [0; J^-1] u``, exact for the
        kinematics at every attitude of the box (the gyroscopic term ``w x J w``, second
        order in the rates, is left out). ``A_c`` is nilpotent, so its ZOH is
        ``A_d = I + Ts A_c``, ``B_d = [Ts^2/2 K J^-1; Ts J^-1]``: affine in ``K`` and bilinear in
        ``(K, J^-1)``. ``K`` over the box lies in the convex hull of the matrices of
        :func:`~models.attitude.euler.kinematics_cover` (at most 9), so the products of those
        with the inertia corners (at most 18 vertices in ``"scalar"`` mode, 72 in ``"box"``)
        contain every frozen-attitude model of the box and the uncertainty set. The attitude
        is taken as constant over a sample, an error of the order of ``Ts`` times its rate.

        Examples
        --------
        >>> import numpy as np
        >>> from models import RigidSatellite
        >>> sat = RigidSatellite.paper_p()
        >>> x_op = np.array([0.2, 0.3, 0.0, 0.0, 0.0, 0.0])
        >>> sat.polytope(x_op, dt=0.01, spread=0.3, attitude_range=np.radians([15, 20, 0])).n_vertices
        18
        """
        x_op = operating_point(x_op, 6)
        dt = sample_time(dt)
        if attitude_range is not None:
            return self._covering_polytope(x_op, dt, spread, mode, attitude_range)
        verts = []
        for inertia in self.inertia_vertices(spread, mode):
            verts.append(RigidSatellite(inertia).discretize(x_op, dt))
        nominal = self.discretize(x_op, dt)
        return PolytopicModel(
            verts, dt, nominal=nominal, state_names=STATE_NAMES, input_names=INPUT_NAMES, attitude="euler321"
        )

    def _covering_polytope(
        self, x_op: np.ndarray, dt: float, spread: float, mode: PolytopeMode, attitude_range: ArrayLike
    ) -> PolytopicModel:
        half = as_vector(attitude_range, "attitude_range", 3)
        if np.any(half < 0.0):
            raise InvalidArgumentError(
                "attitude_range", "half-widths >= 0 (rad) of a non-empty box", f"{half.tolist()}"
            )
        if np.any(x_op[3:] != 0.0):
            raise InvalidArgumentError(
                "x_op", "zero rates with attitude_range (the covering model is the frozen-attitude one)",
                f"rates {x_op[3:].tolist()}",
            )
        phi = (float(x_op[0] - half[0]), float(x_op[0] + half[0]))
        theta = (float(x_op[1] - half[1]), float(x_op[1] + half[1]))
        limit = 0.5 * np.pi - np.arccos(SINGULARITY_COS_TOL)
        if theta[0] <= -0.5 * np.pi + limit or theta[1] >= 0.5 * np.pi - limit:
            raise InvalidArgumentError(
                "attitude_range",
                "a box whose pitch stays inside (-90, 90) deg (3-2-1 Euler angles are singular there)",
                f"pitch from {np.degrees(theta[0]):.2f} to {np.degrees(theta[1]):.2f} deg",
            )
        if phi[1] - phi[0] >= np.pi:
            raise InvalidArgumentError(
                "attitude_range", "a roll half-width below 90 deg", f"{np.degrees(half[0]):.2f} deg"
            )
        verts = []
        for inertia in self.inertia_vertices(spread, mode):
            j_inv = np.linalg.inv(inertia)
            for k_mat in kinematics_cover(phi, theta):
                a = np.eye(6)
                a[:3, 3:] = dt * k_mat
                b = np.zeros((6, 3))
                b[:3] = 0.5 * dt * dt * k_mat @ j_inv
                b[3:] = dt * j_inv
                verts.append((a, b))
        nominal = self.discretize(x_op, dt)
        return PolytopicModel(
            verts, dt, nominal=nominal, state_names=STATE_NAMES, input_names=INPUT_NAMES, attitude="euler321"
        )

    # -- python-control ----------------------------------------------------------------
    def to_nlsys(self, with_disturbance: bool = False) -> control.NonlinearIOSystem:
        """The nonlinear model as a python-control ``NonlinearIOSystem`` (full-state output).

        Inputs are ``[Mx, My, Mz]``, followed by ``[dx, dy, dz]`` with ``with_disturbance``.
        """
        import control

        def update(t: float, x: np.ndarray, u: np.ndarray, params: dict) -> np.ndarray:
            torque = u[:3] + (u[3:6] if with_disturbance else 0.0)
            return self._rhs(np.asarray(x, dtype=float), np.asarray(torque, dtype=float))

        inputs = list(INPUT_NAMES) + (["dx", "dy", "dz"] if with_disturbance else [])
        return control.nlsys(
            update, None, inputs=inputs, outputs=list(STATE_NAMES), states=list(STATE_NAMES),
            name="rigid_satellite",
        )
