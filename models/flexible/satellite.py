"""The flexible satellite in hybrid coordinates: a rigid hub with N flexible modes.

Model (paper S eq. 1; modal mass ``M``, PZT forces ``Gamma_a v`` from paper V;
a reconstruction of paper V's eq. 10, **likely**)::

    J w' + delta' eta'' = -w x (J w + delta' eta') + u + d
    M eta'' + C eta' + K eta + delta w' = Gamma_a v + d_f
    C = diag(2 xi_i Lambda_i),  K = diag(Lambda_i^2)

``J`` (3 x 3, SPD) is the total inertia with the appendages undeformed, ``delta`` (N x 3) the
rigid-flexible coupling (rows = modes, columns = body x, y, z; kg^1/2 m), ``eta`` the modal
coordinates and ``v`` the PZT commands. The mass matrix ``[[J, delta'], [delta, M]]`` is
positive definite exactly when ``J_mb = J - delta' M^-1 delta`` is (the hub inertia with the
modes' participation removed); the constructor checks it.

The class holds the states and sizes and delegates each concern to its own module of
:mod:`models.flexible`: the parameters and their checks (:mod:`~models.flexible.parameters`),
the nonlinear model with a unit-quaternion attitude (``7 + 2N`` states: the large slews of
paper V cross the 3-2-1 Euler singularity; :mod:`~models.flexible.dynamics`), its energy and
angular momentum (:mod:`~models.flexible.energy`), the linearised ``6 + 2N`` model
with Euler or quaternion attitude (:mod:`~models.flexible.linear`), the uncertainty
polytope (:mod:`~models.flexible.polytope`), the single-axis transfer function and paper S's
regime label (:mod:`~models.flexible.single_axis`).

(Length: about 550 lines, half of them the documentation of the class's public methods; each
method is a thin delegate to the module of its concern, so the class reads as the plant's one
public face.)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from models.actuators import TorqueLimiter
from models.attitude.quaternion import quat_error, quat_to_dcm, quat_to_euler321, unit_quaternion
from models.flexible import energy as _energy
from models.flexible import linear as _linear
from models.flexible import single_axis as _single_axis
from models.flexible.dynamics import hybrid_rhs, split_inputs
from models.flexible.linear import POLYTOPIC_ATTITUDE, AttitudeForm, ParameterPoint
from models.flexible.parameters import (
    DI_GENNARO_COUPLING,
    DI_GENNARO_DAMPING,
    DI_GENNARO_FREQUENCIES,
    DI_GENNARO_INERTIA,
    hybrid_parameters,
)
from models.flexible.polytope import (
    DEFAULT_DAMPING_RANGE,
    DEFAULT_EFFECTIVENESS_RANGE,
    DEFAULT_FREQUENCY_RANGE,
    DEFAULT_INVERSE_INERTIA_RANGE,
    RENAMED_RANGES,
    PolytopeMode,
    flexible_polytope,
)
from models.linear import PolytopicModel, sample_time, zoh
from models.protocols import map_states
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_positive_values, as_vector, check_bool, renamed_arguments

if TYPE_CHECKING:  # python-control (with matplotlib, ~2 s) is imported where it is used
    import control

__all__ = ["FlexibleSatellite"]

#: Stand-in for "no limit" in a :class:`TorqueLimiter` (it needs finite values).
_NO_LIMIT = 1e300


class FlexibleSatellite:
    """A rigid hub with ``N`` flexible modes (hybrid coordinates), modal mass ``M``.

    Nonlinear model (:meth:`dynamics`): state ``x = [q0, q1, q2, q3, wx, wy, wz,
    eta_1..eta_N, eta_1'..eta_N']`` (``7 + 2N``; scalar-first unit quaternion of the body
    relative to the inertial frame, body rates in rad/s, modal coordinates in kg^1/2 m and
    their rates), input ``u = [Mx, My, Mz, v_1..v_na]`` (three hub torques in N m, then the
    ``n_a`` PZT commands in modal-force units; ``n_inputs = 3 + n_a``), disturbance ``d`` = hub
    torque (3; with ``panel_disturbance=True`` also the modal forces ``d_f``, ``3 + N``).

    Linear model (:meth:`linearize`): ``6 + 2N`` states ``[att (3), w, eta, eta']``
    with the attitude as 3-2-1 Euler angles (default) or the quaternion's vector part.

    Parameters
    ----------
    inertia : (3, 3) array_like
        Total inertia ``J`` (kg m^2) with the appendages undeformed, symmetric positive definite.
    frequencies : (N,) array_like
        Modal (cantilever, hub-clamped) frequencies ``Lambda_i`` > 0 (rad/s).
    damping : (N,) array_like
        Modal damping ratios ``xi_i`` >= 0.
    coupling : (N, 3) array_like
        Rigid-flexible coupling ``delta`` (rows = modes; kg^1/2 m).
    modal_mass : (N, N) array_like, optional
        Modal mass matrix ``M`` (symmetric positive definite); default the identity
        (mass-normalised modes).
    pzt_matrix : (N, n_a) array_like, optional
        PZT modal-force matrix ``Gamma_a`` (modal force = ``Gamma_a v``); default the identity
        (``n_a = N``, ``v`` in modal-force units; **assumed**).
    panel_disturbance : bool
        Whether ``d`` also carries the panel (modal) disturbance forces ``d_f`` (then
        ``n_disturbances = 3 + N``); default ``False`` (``d_f = 0``,
        **assumed**: paper V's disturbance values were lost).

    Raises
    ------
    InvalidArgumentError
        On mismatched mode counts (naming the argument), negative damping, non-positive
        frequencies, or a coupling that makes the mass matrix indefinite (naming ``coupling``,
        i.e. ``delta``).

    Examples
    --------
    >>> import numpy as np
    >>> from models import FlexibleSatellite
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> A, B = sat.linearize()
    >>> A.shape, B.shape
    ((14, 14), (14, 3))
    >>> sat.n_states, sat.n_inputs, sat.with_modes(2).n_linear_states
    (15, 7, 10)
    >>> x = sat.state(rates=[0.01, 0.0, 0.0])
    >>> float(sat.energy(x)) == 0.5 * 0.01**2 * 350.0
    True
    """

    def __init__(
        self,
        inertia: ArrayLike,
        frequencies: ArrayLike,
        damping: ArrayLike,
        coupling: ArrayLike,
        *,
        modal_mass: ArrayLike | None = None,
        pzt_matrix: ArrayLike | None = None,
        panel_disturbance: bool = False,
    ) -> None:
        self._p = hybrid_parameters(
            inertia, frequencies, damping, coupling, modal_mass=modal_mass, pzt_matrix=pzt_matrix
        )
        self._panel_disturbance = check_bool(panel_disturbance, "panel_disturbance")

    @classmethod
    def di_gennaro(cls, n_modes: int = 4, *, panel_disturbance: bool = False) -> FlexibleSatellite:
        """Di Gennaro's published 4-mode set (as re-used by Hu & Ma), or its first ``n_modes`` modes.

        Modes: S. Di Gennaro, "Output stabilization of flexible spacecraft with active
        vibration suppression", IEEE Trans. Aerospace and Electronic Systems 39(3), 2003,
        reused with the hub inertia ``J = [[350, 3, 4], [3, 270, 10], [4, 10, 190]]`` kg m^2 by
        Q. Hu and G. Ma, Aerospace Science and Technology 9(4), 2005 (attribution **likely**;
        the primary sources were not consulted). Frequencies, damping and coupling are
        **likely** (decoded; two public re-uses agree to 0.2 %, except three coupling digits:
        -1.25819, 1.11678, -1.12530 in one of them); ``J`` is **assumed** (one re-use pairs the
        modes with ``[[120, 3, 4], [3, 100, 10], [4, 10, 120]]``). ``M = I``,
        ``Gamma_a = I`` (**assumed**).
        """
        sat = cls(DI_GENNARO_INERTIA, DI_GENNARO_FREQUENCIES, DI_GENNARO_DAMPING, DI_GENNARO_COUPLING,
                  panel_disturbance=panel_disturbance)
        return sat.with_modes(n_modes)

    def with_modes(self, n_modes: int) -> FlexibleSatellite:
        """The same satellite keeping only its first ``n_modes`` modes (0 gives the rigid hub)."""
        if isinstance(n_modes, bool) or not isinstance(n_modes, int | np.integer) or not (
            0 <= n_modes <= self.n_modes
        ):
            raise InvalidArgumentError("n_modes", f"an integer in [0, {self.n_modes}]", repr(n_modes))
        k = int(n_modes)
        p = self._p
        return FlexibleSatellite(
            p.inertia, p.frequencies[:k], p.damping[:k], p.coupling[:k],
            modal_mass=p.modal_mass[:k, :k], pzt_matrix=p.pzt_matrix[:k],
            panel_disturbance=self._panel_disturbance,
        )

    def input_limiter(self, u_max: ArrayLike = 2.0, v_max: ArrayLike | None = None) -> TorqueLimiter:
        """The saturation of the input ``[u; v]``: hub torques per axis, PZT commands optional.

        Paper V bounds the hub torque (**certain** that a bound exists, value lost); the
        toolkit clips each axis to ``u_max = 2 N m`` (**assumed**) and the PZT commands to
        ``v_max`` (default none, **assumed**). Pass the result as ``limiter=`` to
        :func:`rmpc.sim.simulate`, which logs the commanded and the applied inputs.

        Examples
        --------
        >>> from models import FlexibleSatellite
        >>> lim = FlexibleSatellite.di_gennaro().input_limiter(2.0)
        >>> lim([3.0, -1.0, -2.5, 100.0, 0.0, 0.0, 0.0]).tolist()
        [2.0, -1.0, -2.0, 100.0, 0.0, 0.0, 0.0]
        """
        hub = as_positive_values(u_max, "u_max", 3, per="axis", what="limits")
        pzt = (
            np.full(self.n_pzt, _NO_LIMIT) if v_max is None
            else as_positive_values(v_max, "v_max", self.n_pzt, per="PZT input", what="limits")
        )
        return TorqueLimiter(np.concatenate((hub, pzt)))

    # -- sizes and names -----------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of flexible modes ``N``."""
        return self._p.n_modes

    @property
    def n_states(self) -> int:
        """States of the nonlinear model, ``7 + 2N`` (unit-quaternion attitude)."""
        return 7 + 2 * self.n_modes

    @property
    def n_linear_states(self) -> int:
        """States of the linear model, ``6 + 2N`` (three attitude parameters)."""
        return 6 + 2 * self.n_modes

    @property
    def n_pzt(self) -> int:
        """Number of PZT inputs ``n_a`` (columns of ``Gamma_a``)."""
        return self._p.n_pzt

    @property
    def n_inputs(self) -> int:
        """Inputs of the nonlinear model: three hub torques, then ``n_a`` PZT commands."""
        return 3 + self.n_pzt

    @property
    def n_disturbances(self) -> int:
        """Size of ``d``: 3 hub torques, plus ``N`` panel forces with ``panel_disturbance``."""
        return 3 + (self.n_modes if self._panel_disturbance else 0)

    @property
    def panel_disturbance(self) -> bool:
        """Whether ``d`` carries the panel disturbance ``d_f``."""
        return self._panel_disturbance

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the nonlinear state."""
        n = self.n_modes
        modal = [f"eta_{i + 1}" for i in range(n)] + [f"eta_dot_{i + 1}" for i in range(n)]
        return ("q0", "q1", "q2", "q3", "wx", "wy", "wz", *modal)

    @property
    def input_names(self) -> tuple[str, ...]:
        """Names of the inputs: ``Mx, My, Mz, v_1..v_na``."""
        return ("Mx", "My", "Mz", *(f"v_{j + 1}" for j in range(self.n_pzt)))

    def linear_state_names(self, attitude: AttitudeForm = "euler") -> tuple[str, ...]:
        """Names of the linear state for ``attitude`` ``"euler"`` or ``"quaternion"``."""
        return _linear.linear_state_names(self.state_names, attitude)

    # -- parameters ----------------------------------------------------------------------
    @property
    def inertia(self) -> np.ndarray:
        """Total inertia ``J`` (kg m^2, read-only)."""
        return self._p.inertia

    @property
    def frequencies(self) -> np.ndarray:
        """Modal frequencies ``Lambda_i`` (rad/s)."""
        return self._p.frequencies

    @property
    def damping(self) -> np.ndarray:
        """Modal damping ratios ``xi_i``."""
        return self._p.damping

    @property
    def coupling(self) -> np.ndarray:
        """Coupling ``delta`` (N x 3)."""
        return self._p.coupling

    @property
    def modal_mass(self) -> np.ndarray:
        """Modal mass ``M`` (N x N)."""
        return self._p.modal_mass

    @property
    def pzt_matrix(self) -> np.ndarray:
        """PZT modal-force matrix ``Gamma_a`` (N x n_a)."""
        return self._p.pzt_matrix

    @property
    def stiffness(self) -> np.ndarray:
        """``K = diag(Lambda_i^2)`` (assuming ``M = I`` scaling of the modes)."""
        return np.diag(self._p.frequencies**2)

    @property
    def damping_matrix(self) -> np.ndarray:
        """``C = diag(2 xi_i Lambda_i)``."""
        return np.diag(2.0 * self._p.damping * self._p.frequencies)

    @property
    def hub_inertia(self) -> np.ndarray:
        """``J_mb = J - delta' M^-1 delta`` (kg m^2), symmetric positive definite."""
        return self._p.hub_inertia

    def __repr__(self) -> str:
        return f"FlexibleSatellite(n_modes={self.n_modes}, frequencies={self._p.frequencies.tolist()})"

    # -- states ---------------------------------------------------------------------------
    def state(
        self,
        attitude: ArrayLike | None = None,
        rates: ArrayLike | None = None,
        modal: ArrayLike | None = None,
        modal_rates: ArrayLike | None = None,
    ) -> np.ndarray:
        """Assemble a state ``[q, w, eta, eta']``; every part defaults to zero (``q`` to identity).

        ``attitude`` is a unit quaternion (4 values, scalar first).
        """
        n = self.n_modes
        q = np.array([1.0, 0.0, 0.0, 0.0]) if attitude is None else unit_quaternion(attitude, "attitude")
        w = np.zeros(3) if rates is None else as_vector(rates, "rates", 3)
        eta = np.zeros(n) if modal is None else as_vector(modal, "modal", n)
        eta_dot = np.zeros(n) if modal_rates is None else as_vector(modal_rates, "modal_rates", n)
        return np.concatenate((q, w, eta, eta_dot))

    def split_state(self, x: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(q, w, eta, eta')`` of a state."""
        x = as_vector(x, "x", self.n_states)
        n = self.n_modes
        return x[:4], x[4:7], x[7:7 + n], x[7 + n:]

    @property
    def second_order_layout(self) -> dict[str, slice]:
        """Where the parts of the state sit, for a second-order integrator (Newmark-beta).

        ``"quaternion"`` (the unit attitude quaternion, scalar first), ``"rate"`` (``w``),
        ``"position"`` (``eta``) and ``"velocity"`` (``eta'``): index slices of the
        ``7 + 2N`` states. See :class:`rmpc.sim.integrators.Newmark`.
        """
        n = self.n_modes
        return {"quaternion": slice(0, 4), "rate": slice(4, 7), "position": slice(7, 7 + n),
                "velocity": slice(7 + n, 7 + 2 * n)}

    def normalize_state(self, x: np.ndarray) -> np.ndarray:
        """The state with its quaternion rescaled to unit norm (the simulator calls this)."""
        out = np.array(x, dtype=float)
        out[:4] /= np.linalg.norm(out[:4])
        return out

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:
        """Roll, pitch and yaw (rad, 3-2-1) of the body relative to the inertial frame.

        The angles of the state's quaternion (``quat_to_euler321``, after rescaling it to unit
        norm). ``x`` is one state or states as rows; see :class:`models.protocols.Plant`.

        Examples
        --------
        >>> import numpy as np
        >>> from models import FlexibleSatellite
        >>> sat = FlexibleSatellite.di_gennaro()
        >>> x = sat.state([np.cos(0.25), 0.0, np.sin(0.25), 0.0])   # 0.5 rad about y
        >>> np.round(sat.attitude_euler(x), 12).tolist()
        [0.0, 0.5, 0.0]
        """
        return map_states(lambda s: quat_to_euler321(s[:4] / np.linalg.norm(s[:4])), x, self.n_states)

    def linear_state(
        self,
        x: ArrayLike,
        q_ref: ArrayLike | None = None,
        attitude: AttitudeForm = "quaternion",
    ) -> np.ndarray:
        """Map a nonlinear state to the ``6 + 2N`` linear state about the reference ``q_ref``.

        The attitude is the error quaternion ``q_ref^-1 * q`` (with ``q0 >= 0``): its vector part
        (``"quaternion"``, the default) or its 3-2-1 Euler angles (``"euler"``).
        """
        _linear.linear_state_names(self.state_names, attitude)  # checks attitude
        q, w, eta, eta_dot = self.split_state(x)
        err = quat_error(q / np.linalg.norm(q), q_ref)
        att = err[1:] if attitude == "quaternion" else quat_to_euler321(err)
        return np.concatenate((att, w, eta, eta_dot))

    # -- nonlinear model (models.flexible.dynamics, models.flexible.energy) ------------------
    def dynamics(self, x: ArrayLike, u: ArrayLike | None = None, d: ArrayLike | None = None) -> np.ndarray:
        """``x'`` of the nonlinear model (solved form; :mod:`models.flexible.dynamics`).

        Parameters
        ----------
        x : (7 + 2N,) array_like
            ``[q, w, eta, eta']``.
        u : array_like, optional
            The 3 hub torques (N m), optionally followed by the ``n_a`` PZT commands ``v``
            (zero when left out). Default zero.
        d : array_like, optional
            Hub disturbance torque (3), optionally followed by the panel forces ``d_f`` (N).
        """
        x = as_vector(x, "x", self.n_states)
        q_norm = float(np.linalg.norm(x[:4]))
        if q_norm < 1e-6:
            raise InvalidArgumentError(
                "x", "a quaternion x[0:4] of norm near 1", f"norm {q_norm:.3g} ({x[:4].tolist()})"
            )
        return hybrid_rhs(self._p, x, *split_inputs(self._p, u, d))

    def angular_momentum(self, x: ArrayLike) -> np.ndarray:
        """Total angular momentum in body components, ``h = J w + delta' eta'`` (N m s)."""
        _, w, _, eta_dot = self.split_state(x)
        return _energy.angular_momentum(self._p, w, eta_dot)

    def angular_momentum_inertial(self, x: ArrayLike) -> np.ndarray:
        """``R(q) (J w + delta' eta')``: constant without external torques (PZT forces are internal)."""
        q = self.split_state(x)[0]
        return quat_to_dcm(q / np.linalg.norm(q)) @ self.angular_momentum(x)

    def energy(self, x: ArrayLike) -> float:
        """``E = w'J w/2 + w' delta' eta' + eta'' M eta'/2 + eta' K eta/2`` (J): kinetic plus strain."""
        _, w, eta, eta_dot = self.split_state(x)
        return _energy.energy(self._p, w, eta, eta_dot)

    def energy_rate(self, x: ArrayLike, u: ArrayLike | None = None, d: ArrayLike | None = None) -> float:
        """``E' = w'(u + d) + eta''(Gamma_a v + d_f) - eta'' C eta'`` (W), the power balance."""
        _, w, _, eta_dot = self.split_state(x)
        return _energy.energy_rate(self._p, w, eta_dot, *split_inputs(self._p, u, d))

    def modal_energy(self, x: ArrayLike) -> float:
        """Energy of the modes alone, ``eta'' M eta'/2 + eta' K eta/2`` (J)."""
        _, _, eta, eta_dot = self.split_state(x)
        return _energy.modal_energy(self._p, eta, eta_dot)

    # -- linear model (models.flexible.linear, models.flexible.polytope) -----------------------
    def linearize(
        self,
        x_op: ArrayLike | None = None,
        *,
        pzt: bool = False,
        attitude: AttitudeForm = "euler",
        parameters: ParameterPoint | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Continuous-time ``(A, B)`` of the ``6 + 2N`` model about zero rates and modes.

        Parameters
        ----------
        x_op : array_like, optional
            Operating point of ``6 + 2N`` entries; only its attitude (the first three) enters,
            through the kinematics matrix. Rates and modal states must be zero (the gyroscopic
            terms then vanish). Default: zero attitude.
        pzt : bool
            Append the ``n_a`` PZT inputs ``v`` to the three hub torques.
        attitude : {"euler", "quaternion"}
            ``"euler"`` (default): 3-2-1 Euler angles, ``Kin = K(phi, theta)``
            (:func:`models.kinematics_matrix`; the identity at zero attitude).
            ``"quaternion"``: the vector part ``q_v`` of the (error) quaternion,
            ``Kin = (q0 I + [q_v x]) / 2`` with ``q0 = sqrt(1 - |q_v|^2)`` (``I/2`` at zero);
            :meth:`linear_state` maps a plant state to these coordinates.
        parameters : models.flexible.linear.ParameterPoint, optional
            Replace ``J_mb^-1`` by ``kappa J_mb^-1``, the modal stiffnesses and damping
            coefficients, or scale the hub-torque columns of ``B`` (the polytope's vertices).

        Returns
        -------
        A : (6 + 2N, 6 + 2N) ndarray
        B : (6 + 2N, 3) or (6 + 2N, 3 + n_a) ndarray
            The matrices of the linear model, written out in
            :func:`models.flexible.linear.linear_matrices`.
        """
        return _linear.linearize(self._p, x_op, pzt=pzt, attitude=attitude, parameters=parameters)

    def discretize(
        self, x_op: ArrayLike | None = None, dt: float | None = None, *, pzt: bool = False,
        attitude: AttitudeForm = "euler",
    ) -> tuple[np.ndarray, np.ndarray]:
        """Zero-order-hold discretisation of :meth:`linearize` at sample time ``dt`` (required)."""
        a, b = self.linearize(x_op, pzt=pzt, attitude=attitude)
        return zoh(a, b, sample_time(dt))

    def linear_model(
        self, x_op: ArrayLike | None = None, dt: float | None = None, *, pzt: bool = False,
        attitude: AttitudeForm = "euler",
    ) -> PolytopicModel:
        """:meth:`discretize` as a one-vertex :class:`PolytopicModel`.

        Its ``attitude`` is ``"euler321"`` or ``"quaternion_vector"`` after ``attitude``.
        """
        ad, bd = self.discretize(x_op, dt, pzt=pzt, attitude=attitude)
        inputs = self.input_names[: 3 + (self.n_pzt if pzt else 0)]
        return PolytopicModel([(ad, bd)], dt, state_names=self.linear_state_names(attitude),
                              input_names=inputs, attitude=POLYTOPIC_ATTITUDE[attitude])

    @renamed_arguments(**RENAMED_RANGES)
    def polytope(
        self,
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
        """The discrete-time polytope of linear models over the parameter uncertainty (ranges **assumed**).

        Parameters
        ----------
        x_op : array_like, optional
            Operating point as in :meth:`linearize` (default zero).
        dt : float
            Sample time (s) of the zero-order hold (required).
        mode : {"groups", "box", "effectiveness"}
            ``"groups"`` (8 vertices): one multiplier each for ``kappa`` on ``J_mb^-1``, all
            modal stiffnesses and all damping coefficients. ``"box"``: ``kappa`` and each
            ``k_i``, ``c_i`` on its own (``2^(1 + 2N)`` vertices). ``"effectiveness"``: the
            hub-torque columns of ``B`` scaled by the two ends of ``effectiveness_range`` (2
            vertices).
        inverse_inertia_range, frequency_range, damping_range, effectiveness_range : (low, high)
            Ranges of multipliers of nominal values: of ``J_mb^-1`` (``kappa``), of the modal
            frequencies (``f``: ``k_i -> f^2 k_i``), of the damping ratios (``g``:
            ``c_i -> f g c_i``) and of the hub torque (all **assumed**; see
            :mod:`models.flexible.polytope`). They were called ``inertia_scale``,
            ``frequency_scale``, ``damping_scale`` and ``effectiveness``; the old names raise
            an error that gives the new one.
        attitude : {"euler", "quaternion"}
            Attitude coordinates of the linear model (the polytope's ``attitude`` is then
            ``"euler321"`` or ``"quaternion_vector"``).
        pzt : bool
            Include the PZT inputs.

        Returns
        -------
        PolytopicModel
            Vertices in the order of :func:`models.flexible.polytope.vertex_parameters`; the
            nominal model is this satellite's own discretised linearisation.

        Notes
        -----
        The continuous-time family lies exactly in the convex hull of the continuous vertices
        (``A`` multi-affine, ``B`` affine in the box parameters); after the zero-order hold only
        up to ``O(dt^2)``: check a robust gain on a parameter grid.
        """
        return flexible_polytope(
            self, x_op, dt, mode=mode, inverse_inertia_range=inverse_inertia_range,
            frequency_range=frequency_range, damping_range=damping_range,
            effectiveness_range=effectiveness_range, attitude=attitude, pzt=pzt,
        )

    # -- single axis, regime (models.flexible.single_axis) --------------------------------------
    def single_axis_tf(self, axis: int = 0, *, cancel_uncoupled: bool = True) -> control.TransferFunction:
        """The python-control ``TransferFunction`` ``theta_a / u_a`` about body axis ``axis``.

        The other axes are locked; zeros are the constrained modes (``Lambda_i``, ``xi_i``),
        poles the unconstrained (free-free) modes and a double integrator. A mode that does not
        couple to the axis (``delta_ai = 0``) cancels; with ``cancel_uncoupled`` (default) it
        is left out of both polynomials. Needs a diagonal modal mass.

        Examples
        --------
        >>> import numpy as np
        >>> from models import FlexibleSatellite
        >>> g = FlexibleSatellite.di_gennaro().single_axis_tf(axis=0)
        >>> round(float(abs(g(1e-4j))) * 350.0 * 1e-8, 6)   # J_aa s^2 G(s) -> 1 as s -> 0
        1.0
        """
        return _single_axis.single_axis_tf(self._p, axis, cancel_uncoupled=cancel_uncoupled)

    def single_axis_modes(self, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Unconstrained (free-free) natural frequencies (rad/s) and damping ratios about ``axis``.

        The roots of ``D(s)`` (the poles of :meth:`single_axis_tf` besides the double
        integrator), sorted by frequency.
        """
        return _single_axis.single_axis_modes(self._p, axis)

    def regime(self, bandwidth: float) -> str:
        """Paper S's label of a closed-loop bandwidth (rad/s) against ``Lambda_1``.

        See :func:`models.flexible.single_axis.regime`; without modes the label is ``"rigid-like"``.
        """
        if self.n_modes == 0:
            return "rigid-like"
        return _single_axis.regime(bandwidth, float(np.min(self._p.frequencies)))
