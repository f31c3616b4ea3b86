"""The flexible satellite in hybrid coordinates: a rigid hub with N flexible modes.

Model (paper S eq. 1; modal mass ``M``, PZT forces ``Gamma_a v`` from paper V; seeds
``papers-S-V-flexible.md`` section 2)::

    J w' + delta' eta'' = -w x (J w + delta' eta') + u + d
    M eta'' + C eta' + K eta + delta w' = Gamma_a v + d_f
    C = diag(2 xi_i Lambda_i),  K = diag(Lambda_i^2)

``J`` (3 x 3, SPD) is the total inertia with the appendages undeformed, ``delta`` (N x 3) the
rigid-flexible coupling (rows = modes, columns = body x, y, z; kg^1/2 m), ``eta`` the modal
coordinates and ``v`` the PZT commands. The mass matrix ``[[J, delta'], [delta, M]]`` is
positive definite exactly when ``J_mb = J - delta' M^-1 delta`` is (the hub inertia with the
modes' participation removed); the constructor checks it.

The class holds the parameters, the nonlinear model with a unit-quaternion attitude
(``7 + 2N`` states: the large slews of paper V cross the 3-2-1 Euler singularity), its energy
and angular momentum, the linearised ``6 + 2N`` model (seed section 2.2) with Euler or
quaternion attitude and its ZOH, the uncertainty polytope (:mod:`models.flexible.polytope`), the
single-axis transfer function and paper S's regime label (:mod:`models.flexible.single_axis`).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from models.actuators import TorqueLimiter
from models.attitude.euler import kinematics_matrix
from models.attitude.quaternion import cross3, quat_error, quat_to_dcm, quat_to_euler321, unit_quaternion
from models.flexible.linear import ParameterPoint, linear_matrices
from models.flexible.polytope import (
    DEFAULT_DAMPING_SCALE,
    DEFAULT_EFFECTIVENESS,
    DEFAULT_FREQUENCY_SCALE,
    DEFAULT_INERTIA_SCALE,
    PolytopeMode,
    flexible_polytope,
)
from models.flexible.single_axis import regime, single_axis_polynomials
from models.linear import PolytopicModel, zoh
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_choice, check_pd, check_positive

__all__ = [
    "DI_GENNARO_COUPLING",
    "DI_GENNARO_DAMPING",
    "DI_GENNARO_FREQUENCIES",
    "DI_GENNARO_INERTIA",
    "AttitudeForm",
    "FlexibleSatellite",
]

AttitudeForm = Literal["euler", "quaternion"]

#: Modal frequencies ``Lambda_i`` (rad/s) of the published 4-mode set (**likely**; Di Gennaro 2003).
DI_GENNARO_FREQUENCIES: tuple[float, ...] = (0.7681, 1.1038, 1.8733, 2.5496)
#: Modal damping ratios ``xi_i`` of the published set (**likely**).
DI_GENNARO_DAMPING: tuple[float, ...] = (0.0056, 0.0086, 0.0128, 0.0252)
#: Coupling ``delta`` (rows = modes, columns = x, y, z; kg^1/2 m) of the published set (**likely**).
DI_GENNARO_COUPLING: tuple[tuple[float, float, float], ...] = (
    (6.45637, 1.27814, 2.15629),
    (-1.25619, 0.91756, -1.67264),
    (1.11687, 2.48901, -0.83674),
    (1.23637, -2.65810, -1.12503),
)
#: Hub inertia (kg m^2) paired with the published modes by Hu & Ma (2005) (**assumed**).
DI_GENNARO_INERTIA: tuple[tuple[float, float, float], ...] = (
    (350.0, 3.0, 4.0),
    (3.0, 270.0, 10.0),
    (4.0, 10.0, 190.0),
)


#: Stand-in for "no limit" in a :class:`TorqueLimiter` (it needs finite values).
_NO_LIMIT = 1e300


def _real_array(value: Any, name: str) -> np.ndarray:
    if isinstance(value, str | bytes):
        raise ArgumentTypeError(name, "a numeric array", f"{type(value).__name__} {value!r}")
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ArgumentTypeError(name, "a numeric array", f"{type(value).__name__} ({err})") from None
    if not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(name, "finite values", repr(arr.tolist()))
    return arr


def _modal(value: Any, name: str, shape: tuple[int, int | None] | tuple[int]) -> np.ndarray:
    """A per-mode array of the given shape (``None``: any width); the message names the argument."""
    arr = _real_array(value, name)
    if shape[0] == 0 and arr.size == 0:
        return arr.reshape((0, *(0 if s is None else s for s in shape[1:])))
    ok = arr.ndim == len(shape) and all(s is None or a == s for a, s in zip(arr.shape, shape, strict=True))
    if not ok:
        want = "(" + ", ".join("n_a" if s is None else str(s) for s in shape) + ")"
        raise InvalidArgumentError(
            name, f"shape {want}: one entry (row) per mode, {shape[0]} modes as in frequencies",
            f"shape {arr.shape}",
        )
    return arr


class FlexibleSatellite:
    """A rigid hub with ``N`` flexible modes (hybrid coordinates), modal mass ``M``.

    Nonlinear model (seed 2.1; :meth:`dynamics`): state ``x = [q0, q1, q2, q3, wx, wy, wz,
    eta_1..eta_N, eta_1'..eta_N']`` (``7 + 2N``; scalar-first unit quaternion of the body
    relative to the inertial frame, body rates in rad/s, modal coordinates in kg^1/2 m and
    their rates), input ``u = [Mx, My, Mz, v_1..v_na]`` (three hub torques in N m, then the
    ``n_a`` PZT commands in modal-force units; ``n_inputs = 3 + n_a``), disturbance ``d`` = hub
    torque (3; with ``panel_disturbance=True`` also the modal forces ``d_f``, ``3 + N``).

    Linear model (seed 2.2; :meth:`linearize`): ``6 + 2N`` states ``[att (3), w, eta, eta']``
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
        ``n_disturbances = 3 + N``); default ``False`` (``d_f = 0``, seed section 3).

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
        inertia: Any,
        frequencies: Any,
        damping: Any,
        coupling: Any,
        *,
        modal_mass: Any = None,
        pzt_matrix: Any = None,
        panel_disturbance: bool = False,
    ) -> None:
        self._inertia = check_pd(as_matrix(inertia, "inertia", (3, 3)), "inertia")
        self._freq = _real_array(frequencies, "frequencies").ravel()
        n_modes = int(self._freq.size)
        if np.any(self._freq <= 0.0):
            found = repr(self._freq.tolist())
            raise InvalidArgumentError("frequencies", "modal frequencies > 0 (rad/s)", found)
        self._damp = _modal(damping, "damping", (n_modes,))
        if np.any(self._damp < 0.0):
            raise InvalidArgumentError("damping", "damping ratios >= 0", repr(self._damp.tolist()))
        self._delta = _modal(coupling, "coupling", (n_modes, 3))
        self._mass = np.eye(n_modes)
        if modal_mass is not None:
            self._mass = _modal(modal_mass, "modal_mass", (n_modes, n_modes))
            if n_modes:
                check_pd(self._mass, "modal_mass")
        self._gamma_a = np.eye(n_modes)
        if pzt_matrix is not None:
            self._gamma_a = _modal(pzt_matrix, "pzt_matrix", (n_modes, None))
        if not isinstance(panel_disturbance, bool | np.bool_):
            raise ArgumentTypeError("panel_disturbance", "a bool", type(panel_disturbance).__name__)
        self._panel_disturbance = bool(panel_disturbance)
        self._mass_inv = np.linalg.inv(self._mass) if n_modes else np.zeros((0, 0))
        j_mb = self._inertia - self._delta.T @ self._mass_inv @ self._delta
        j_mb = 0.5 * (j_mb + j_mb.T)
        lam_min = float(np.linalg.eigvalsh(j_mb)[0])
        if lam_min <= 0.0:
            raise InvalidArgumentError(
                "coupling",
                "a coupling delta with J - delta' M^-1 delta positive definite (a positive definite "
                "mass matrix)",
                f"smallest eigenvalue of J - delta' M^-1 delta = {lam_min:.6g}",
            )
        self._j_mb = j_mb
        self._j_mb_inv = np.linalg.inv(j_mb)
        self._couple = self._delta.T @ self._mass_inv  # delta' M^-1 (3 x N)
        self._k_diag = self._freq**2
        self._c_diag = 2.0 * self._damp * self._freq
        for arr in (self._inertia, self._freq, self._damp, self._delta, self._mass, self._gamma_a, j_mb,
                    self._j_mb_inv, self._mass_inv, self._couple, self._k_diag, self._c_diag):
            arr.setflags(write=False)

    @classmethod
    def di_gennaro(cls, n_modes: int = 4, *, panel_disturbance: bool = False) -> FlexibleSatellite:
        """The published 4-mode set (seed section 2.5), or its first ``n_modes`` modes.

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
        return FlexibleSatellite(
            self._inertia, self._freq[:k], self._damp[:k], self._delta[:k],
            modal_mass=self._mass[:k, :k], pzt_matrix=self._gamma_a[:k],
            panel_disturbance=self._panel_disturbance,
        )

    def input_limiter(self, u_max: Any = 2.0, v_max: Any = None) -> TorqueLimiter:
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
        hub = np.broadcast_to(np.asarray(check_positive(u_max, "u_max") if np.ndim(u_max) == 0 else
                                         as_vector(u_max, "u_max", 3), dtype=float), (3,))
        if v_max is None:
            pzt = np.full(self.n_pzt, _NO_LIMIT)
        elif np.ndim(v_max) == 0:
            pzt = np.full(self.n_pzt, check_positive(v_max, "v_max"))
        else:
            pzt = as_vector(v_max, "v_max", self.n_pzt)
        return TorqueLimiter(np.concatenate((hub, pzt)))

    # -- sizes and names -----------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of flexible modes ``N``."""
        return int(self._freq.size)

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
        return int(self._gamma_a.shape[1])

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
        check_choice(attitude, "attitude", ("euler", "quaternion"))
        att = ("phi", "theta", "psi") if attitude == "euler" else ("q1", "q2", "q3")
        return att + self.state_names[4:]

    # -- parameters ----------------------------------------------------------------------
    @property
    def inertia(self) -> np.ndarray:
        """Total inertia ``J`` (kg m^2, read-only)."""
        return self._inertia

    @property
    def frequencies(self) -> np.ndarray:
        """Modal frequencies ``Lambda_i`` (rad/s)."""
        return self._freq

    @property
    def damping(self) -> np.ndarray:
        """Modal damping ratios ``xi_i``."""
        return self._damp

    @property
    def coupling(self) -> np.ndarray:
        """Coupling ``delta`` (N x 3)."""
        return self._delta

    @property
    def modal_mass(self) -> np.ndarray:
        """Modal mass ``M`` (N x N)."""
        return self._mass

    @property
    def pzt_matrix(self) -> np.ndarray:
        """PZT modal-force matrix ``Gamma_a`` (N x n_a)."""
        return self._gamma_a

    @property
    def stiffness(self) -> np.ndarray:
        """``K = diag(Lambda_i^2)`` (assuming ``M = I`` scaling of the modes)."""
        return np.diag(self._freq**2)

    @property
    def damping_matrix(self) -> np.ndarray:
        """``C = diag(2 xi_i Lambda_i)``."""
        return np.diag(2.0 * self._damp * self._freq)

    @property
    def hub_inertia(self) -> np.ndarray:
        """``J_mb = J - delta' M^-1 delta`` (kg m^2), symmetric positive definite."""
        return self._j_mb

    def __repr__(self) -> str:
        return f"FlexibleSatellite(n_modes={self.n_modes}, frequencies={self._freq.tolist()})"

    # -- states ---------------------------------------------------------------------------
    def state(
        self, attitude: Any = None, rates: Any = None, modal: Any = None, modal_rates: Any = None
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

    def split_state(self, x: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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

    def euler_angles(self, x: Any) -> np.ndarray:
        """3-2-1 Euler angles (rad) of the state's attitude (``quat_to_euler321``)."""
        return quat_to_euler321(self.split_state(x)[0])

    def linear_state(self, x: Any, q_ref: Any = None, attitude: AttitudeForm = "quaternion") -> np.ndarray:
        """Map a nonlinear state to the ``6 + 2N`` linear state about the reference ``q_ref``.

        The attitude is the error quaternion ``q_ref^-1 * q`` (with ``q0 >= 0``): its vector part
        (``"quaternion"``, the default) or its 3-2-1 Euler angles (``"euler"``).
        """
        check_choice(attitude, "attitude", ("euler", "quaternion"))
        q, w, eta, eta_dot = self.split_state(x)
        err = quat_error(q / np.linalg.norm(q), q_ref)
        att = err[1:] if attitude == "quaternion" else quat_to_euler321(err)
        return np.concatenate((att, w, eta, eta_dot))

    # -- nonlinear model ------------------------------------------------------------------
    def _split_inputs(self, u: Any, d: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(hub torque incl. d, v, d_f)`` from the checked ``u`` and ``d``."""
        n, n_a = self.n_modes, self.n_pzt
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

    def dynamics(self, x: Any, u: Any = None, d: Any = None) -> np.ndarray:
        """``x'`` of the nonlinear model (seed 2.1, solved form; no algebraic loop).

        ::

            J_mb w' = -w x (J w + delta' eta') + delta' M^-1 (C eta' + K eta - Gamma_a v - d_f) + u + d
            eta''   = M^-1 (Gamma_a v + d_f - C eta' - K eta - delta w')
            q0' = -q_v' w / 2,   q_v' = (q0 I + [q_v x]) w / 2

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
        torque, v, d_f = self._split_inputs(u, d)
        return self._rhs(x, torque, v, d_f)

    def _rhs(self, x: np.ndarray, torque: np.ndarray, v: np.ndarray, d_f: np.ndarray) -> np.ndarray:
        """Unchecked right-hand side; ``torque`` already includes the hub disturbance."""
        n = self.n_modes
        q0, qv, w = x[0], x[1:4], x[4:7]
        eta, eta_dot = x[7:7 + n], x[7 + n:]
        h = self._inertia @ w + self._delta.T @ eta_dot
        modal_force = self._gamma_a @ v + d_f - self._c_diag * eta_dot - self._k_diag * eta
        w_dot = self._j_mb_inv @ (torque - cross3(w, h) - self._couple @ modal_force)
        eta_ddot = self._mass_inv @ (modal_force - self._delta @ w_dot)
        out = np.empty_like(x)
        out[0] = -0.5 * (qv @ w)
        out[1:4] = 0.5 * (q0 * w + cross3(qv, w))
        out[4:7] = w_dot
        out[7:7 + n] = eta_dot
        out[7 + n:] = eta_ddot
        return out

    def angular_momentum(self, x: Any) -> np.ndarray:
        """Total angular momentum in body components, ``h = J w + delta' eta'`` (N m s)."""
        _, w, _, eta_dot = self.split_state(x)
        return self._inertia @ w + self._delta.T @ eta_dot

    def angular_momentum_inertial(self, x: Any) -> np.ndarray:
        """``R(q) (J w + delta' eta')``: constant without external torques (PZT forces are internal)."""
        q = self.split_state(x)[0]
        return quat_to_dcm(q / np.linalg.norm(q)) @ self.angular_momentum(x)

    def energy(self, x: Any) -> float:
        """``E = w'J w/2 + w' delta' eta' + eta'' M eta'/2 + eta' K eta/2`` (J): kinetic plus strain."""
        _, w, eta, eta_dot = self.split_state(x)
        return float(0.5 * w @ self._inertia @ w + w @ self._delta.T @ eta_dot
                     + 0.5 * eta_dot @ self._mass @ eta_dot + 0.5 * eta @ (self._k_diag * eta))

    def energy_rate(self, x: Any, u: Any = None, d: Any = None) -> float:
        """``E' = w'(u + d) + eta''(Gamma_a v + d_f) - eta'' C eta'`` (W), the power balance."""
        x = as_vector(x, "x", self.n_states)
        torque, v, d_f = self._split_inputs(u, d)
        w, eta_dot = x[4:7], x[7 + self.n_modes:]
        return float(w @ torque + eta_dot @ (self._gamma_a @ v + d_f) - eta_dot @ (self._c_diag * eta_dot))

    def modal_energy(self, x: Any) -> float:
        """Energy of the modes alone, ``eta'' M eta'/2 + eta' K eta/2`` (J)."""
        _, _, eta, eta_dot = self.split_state(x)
        return float(0.5 * eta_dot @ self._mass @ eta_dot + 0.5 * eta @ (self._k_diag * eta))

    # -- linear model -----------------------------------------------------------------------
    def linearize(
        self,
        x_op: Any = None,
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

        Notes
        -----
        With ``P = J_mb^-1`` and ``G = M^-1 + M^-1 delta P delta' M^-1`` (seed section 2.2)::

            A = [[0, Kin, 0,                 0               ],
                 [0, 0,   P delta' M^-1 K,   P delta' M^-1 C ],
                 [0, 0,   0,                 I               ],
                 [0, 0,   -G K,              -G C            ]]
            B_u = [0; P; 0; -M^-1 delta P],   B_v = [0; -P delta' M^-1; 0; G] Gamma_a
        """
        check_choice(attitude, "attitude", ("euler", "quaternion"))
        n = self.n_linear_states
        if x_op is None:
            att = np.zeros(3)
        else:
            x = as_vector(x_op, "x_op", n)
            if np.any(x[3:] != 0.0):
                raise InvalidArgumentError(
                    "x_op", "zero rates and a zero modal state (the model is linearised there)",
                    f"x_op[3:] = {x[3:].tolist()}",
                )
            att = x[:3]
        if attitude == "euler":
            kin = kinematics_matrix(att[0], att[1])
        else:
            norm2 = float(att @ att)
            if norm2 > 1.0:
                raise InvalidArgumentError(
                    "x_op", "a quaternion vector part with |q_v| <= 1", f"|q_v| = {np.sqrt(norm2):.6g}"
                )
            kin = 0.5 * (np.sqrt(1.0 - norm2) * np.eye(3) + np.array(
                [[0.0, -att[2], att[1]], [att[2], 0.0, -att[0]], [-att[1], att[0], 0.0]]
            ))
        point = ParameterPoint() if parameters is None else parameters
        if not isinstance(point, ParameterPoint):
            raise ArgumentTypeError("parameters", "None or a models.flexible.linear.ParameterPoint",
                                    type(parameters).__name__)
        kappa, k, c, eff = point.resolved(self._k_diag, self._c_diag)
        return linear_matrices(kappa * self._j_mb_inv, self._mass_inv, self._delta, k, c, self._gamma_a,
                               kin, pzt, eff)

    def discretize(
        self, dt: float, x_op: Any = None, *, pzt: bool = False, attitude: AttitudeForm = "euler"
    ) -> tuple[np.ndarray, np.ndarray]:
        """Zero-order-hold discretisation of :meth:`linearize` at sample time ``dt``."""
        a, b = self.linearize(x_op, pzt=pzt, attitude=attitude)
        return zoh(a, b, dt)

    def polytope(
        self,
        dt: float,
        *,
        x_op: Any = None,
        mode: PolytopeMode = "groups",
        inertia_scale: Any = DEFAULT_INERTIA_SCALE,
        frequency_scale: Any = DEFAULT_FREQUENCY_SCALE,
        damping_scale: Any = DEFAULT_DAMPING_SCALE,
        effectiveness: Any = DEFAULT_EFFECTIVENESS,
        attitude: AttitudeForm = "euler",
        pzt: bool = False,
    ) -> PolytopicModel:
        """The discrete-time polytope of linear models over the parameter uncertainty (seed 9).

        Parameters
        ----------
        dt : float
            Sample time (s) of the zero-order hold.
        x_op : array_like, optional
            Operating attitude as in :meth:`linearize`.
        mode : {"groups", "box", "effectiveness"}
            ``"groups"`` (8 vertices): one scale each for ``kappa`` on ``J_mb^-1``, all modal
            stiffnesses and all damping coefficients. ``"box"``: ``kappa`` and each ``k_i``,
            ``c_i`` on its own (``2^(1 + 2N)`` vertices). ``"effectiveness"``: the hub-torque
            columns of ``B`` scaled by the two ends of ``effectiveness`` (2 vertices).
        inertia_scale, frequency_scale, damping_scale, effectiveness : (low, high)
            Ranges of ``kappa``, of the frequency scale ``f`` (``k_i -> f^2 k_i``) and of the
            damping-ratio scale ``g`` (``c_i -> f g c_i``), and of the torque effectiveness
            (all **assumed**; see :mod:`models.flexible.polytope`).
        attitude : {"euler", "quaternion"}
            Attitude coordinates of the linear model.
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
            self, dt, x_op=x_op, mode=mode, inertia_scale=inertia_scale, frequency_scale=frequency_scale,
            damping_scale=damping_scale, effectiveness=effectiveness, attitude=attitude, pzt=pzt,
        )

    # -- single axis, regime ------------------------------------------------------------------
    def single_axis_tf(self, axis: int = 0, *, cancel_uncoupled: bool = True) -> Any:
        """The python-control ``TransferFunction`` ``theta_a / u_a`` about body axis ``axis`` (seed 2.3).

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
        if isinstance(axis, bool) or not isinstance(axis, int | np.integer) or not 0 <= axis <= 2:
            raise InvalidArgumentError("axis", "0, 1 or 2 (body x, y, z)", repr(axis))
        masses = np.diag(self._mass)
        if np.any(self._mass != np.diag(masses)):
            raise InvalidArgumentError("modal_mass", "a diagonal modal mass for the single-axis model",
                                       "off-diagonal entries")
        num, den = single_axis_polynomials(
            float(self._inertia[axis, axis]), self._delta[:, axis], masses, self._k_diag, self._c_diag,
            cancel_uncoupled=cancel_uncoupled,
        )
        import control

        return control.tf(num, den)

    def single_axis_modes(self, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Unconstrained (free-free) natural frequencies (rad/s) and damping ratios about ``axis``.

        The roots of ``D(s)`` (the poles of :meth:`single_axis_tf` besides the double
        integrator), sorted by frequency.
        """
        g = self.single_axis_tf(axis)
        poles = np.asarray(g.poles())
        osc = poles[np.abs(poles) > 1e-9 * max(1.0, float(np.max(np.abs(poles))))]
        osc = osc[osc.imag >= 0.0] if np.any(osc.imag > 0) else osc
        w_n = np.abs(osc)
        order = np.argsort(w_n)
        return w_n[order], (-osc.real / w_n)[order]

    def regime(self, bandwidth: float) -> str:
        """Paper S's label of a closed-loop bandwidth (rad/s) against ``Lambda_1``.

        See :func:`models.flexible.single_axis.regime`; without modes the label is ``"rigid-like"``.
        """
        if self.n_modes == 0:
            return "rigid-like"
        return regime(bandwidth, float(np.min(self._freq)))
