"""Adaptive backstepping compensation of reaction-wheel faults (paper W), the ``step(x)`` protocol.

Source: paper W, two-step adaptive backstepping on
3-2-1 Euler angles and body rates with no fault detection. Design model (nominal ``J``, the
plant's gravity model, ``K`` = :func:`models.attitude.euler.kinematics_matrix`, paper W's ``R``)::

    x1 = eta, x2 = w,   x1' = K(x1) x2,   x2' = f2 + g2 u
    f2 = J^-1 (-w x J w + d_g(eta)),      g2 = J^-1 D

Law (eqs. 37-39, with the printed scalar ``-c2 e2'e2`` read as the vector ``-c2 e2``,
**certain**), reference ``y_m = 0``::

    e1 = eta (yaw wrapped to (-pi, pi], assumed)     alpha1 = K^-1(eta) (-c1 e1)
    e2 = w - alpha1                                   alpha1' = -c1 (d(K^-1)/dt e1 + w)
    nu0 = -c2 e2 - K' e1 - G_hat (f2 - alpha1') - sum_j Theta_hat_j varpi_j(t)
    nu  = g2' nu0                                     (the m wheel commands)
    G_hat'       = Gamma0 e2 (f2 - alpha1')'
    Theta_hat_j' = Gamma_j e2 varpi_j(t)'

``alpha1'`` is in closed form, from the measured rates (no numerical
differentiation). With the true ``G = (g2 sigma g2')^-1`` and ``Theta_j = G g2_j (1 - sigma_j)
delta_j'`` of the current fault state, ``V2 = 1/2 |e1|^2 + 1/2 e2' G e2 + 1/2 tr(Gt' Gamma0^-1
Gt) + 1/2 sum_j tr(Tt_j' Gamma_j^-1 Tt_j)`` obeys ``V2' = -c1 |e1|^2 - c2 |e2|^2`` in continuous
time, unsaturated, with ``f2`` and ``g2`` exact (:meth:`AdaptiveBacksteppingFTC.lyapunov`).
``V2`` jumps at every fault event (paper W is silent on this).

Values and their tags: ``c1 = 0.5``, ``c2 = 3`` (**certain**);
``Gamma0 = Gamma_j = 0.1 I3`` (**assumed**, the appendix table is lost); ``G_hat(0) = G_nom =
(g2 g2')^-1``, ``Theta_hat_j(0) = 0`` and the common basis ``varpi_j = [1, sin(0.2 t)]`` (all
**assumed**); the 40 ms zero-order hold with forward-Euler adaptation over ``Ts`` (**assumed**);
the singularity guard at ``|theta| >= 85`` deg (status ``"singular"``) and the yaw wrap
(**assumed**). Options, off by default (= paper W): projection onto a bound, leakage
(sigma-modification), freezing the adaptation while a command or momentum limit is active,
gyroscopic compensation. Saturation is not hidden here: the wheel model clips, and the
simulator logs the commanded and the applied torque.

The controller keeps its own clock (``t = k Ts`` after :meth:`~AdaptiveBacksteppingFTC.reset`)
for ``varpi(t)`` and never sees the fault (its wheel, kind or onset): it is built from the
nominal satellite and sees only the measured state.

(Length: about 480 lines, half of them documentation: one algorithm, its law, its Lyapunov
function and the true parameters it estimates, which read best together.)
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from models import WheelSatellite
from models.attitude.euler import kinematics_matrix
from models.attitude.euler_inverse import inverse_kinematics_matrix, inverse_kinematics_rate
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import (
    as_matrix,
    as_square_matrix,
    as_vector,
    check_bool,
    check_positive,
)

__all__ = ["ABFTCRates", "AdaptiveBacksteppingFTC", "wrap_angle"]

#: Default singularity guard: ``|theta| >= 85 deg`` (**assumed**), in rad.
SINGULAR_PITCH: float = math.radians(85.0)


def wrap_angle(angle: float) -> float:
    """Wrap an angle to ``(-pi, pi]``."""
    wrapped = math.remainder(angle, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


@dataclass(frozen=True)
class ABFTCRates:
    """The continuous-time law at one instant (:meth:`AdaptiveBacksteppingFTC.law`).

    Attributes
    ----------
    nu : (m,) ndarray
        Wheel commands ``g2' nu0`` (N m).
    nu0 : (3,) ndarray
        The virtual command.
    g_hat_dot : (3, 3) ndarray
        ``G_hat'``.
    theta_hat_dot : tuple of (3, q_j) ndarray
        ``Theta_hat_j'`` per wheel.
    e1, e2, alpha1, alpha1_dot, f2 : (3,) ndarray
        The backstepping signals.
    """

    nu: np.ndarray
    nu0: np.ndarray
    g_hat_dot: np.ndarray
    theta_hat_dot: tuple[np.ndarray, ...]
    e1: np.ndarray
    e2: np.ndarray
    alpha1: np.ndarray
    alpha1_dot: np.ndarray
    f2: np.ndarray


class AdaptiveBacksteppingFTC:
    """Paper W's adaptive backstepping fault-tolerant controller ("ABFTC").

    Parameters
    ----------
    plant : WheelSatellite
        The nominal design model: ``J``, ``D``, the gravity model and the wheel limits (for
        ``freeze``). The satellite it runs on may differ (S4's inertia error).
    c1, c2 : float
        Backstepping gains (defaults 0.5 and 3, paper W, **certain**).
    gamma_g : float or (3, 3) array_like
        ``Gamma0``, adaptation gain of ``G_hat`` (a scalar means ``gamma_g I3``; default 0.1,
        **assumed**).
    gamma_theta : float, (3, 3) array_like or sequence of m of them
        ``Gamma_j``, adaptation gains of ``Theta_hat_j`` (default 0.1 I3 each, **assumed**).
    dt : float
        Control period ``Ts`` (default 0.04 s, paper W's loop).
    basis_frequencies : sequence of float, or sequence of m sequences
        Sinusoid frequencies (rad/s) of the fault basis besides the constant:
        ``varpi_j = [1, sin(w_1 t), ...]``. One sequence for every wheel (default ``(0.2,)``,
        the common basis ``[1, sin 0.2t]``) or one per wheel (paper W's per-scenario lists,
        :attr:`models.WheelScenario.paper_basis`).
    g_hat0 : (3, 3) array_like, optional
        ``G_hat(0)`` (default ``G_nom = (g2 g2')^-1``).
    projection : float or (float, float), optional
        Radii of the balls ``||G_hat - G_hat(0)||_F <= r_G`` and ``||Theta_hat_j||_F <= r_T``
        the estimates are projected onto (a scalar: both). Default ``None`` (off).
    leakage : float
        Sigma-modification ``s >= 0``: ``G_hat' -= s Gamma0 (G_hat - G_hat(0))`` and
        ``Theta_hat_j' -= s Gamma_j Theta_hat_j``. Default 0 (off).
    freeze : bool
        Hold the estimates while any command exceeds its wheel's torque limit or any measured
        wheel momentum is at its limit (default ``False``).
    gyroscopic_compensation : bool
        Add ``-J^-1 (w x D h)`` to ``f2`` from the measured momenta (default ``False``).
    singular_pitch : float
        ``|theta|`` (rad) from which a step returns zero commands with status
        ``"singular"`` (default ``radians(85)``, **assumed**).
    divergence_bound : float
        Estimates with a Frobenius norm beyond this (or not finite) stop the adaptation with
        status ``"diverged"`` and zero commands (default 1e6).

    Attributes
    ----------
    name : str
        ``"ABFTC"``, the record name in reports.
    plant : WheelSatellite
        The design model.
    last : StepInfo or None
        Status ``"ok"`` (or ``"singular"``, ``"diverged"``), ``solve_time`` (the step's time)
        and ``extra``: ``t``, ``nu0``, ``e1``, ``e2``, ``frozen``, ``g_hat_eig`` (min and max
        eigenvalue of the symmetric part of ``G_hat``) and ``theta_norm`` (per wheel).

    Examples
    --------
    >>> import numpy as np
    >>> from models import WheelSatellite, paper_w_scenario
    >>> from rmpc import AdaptiveBacksteppingFTC
    >>> sat = WheelSatellite.paper_w()
    >>> ftc = AdaptiveBacksteppingFTC(sat)
    >>> nu = ftc.step(paper_w_scenario("S1").initial_state())  # 13x the wheel limit
    >>> nu.round(3).tolist(), ftc.last.status
    ([-0.262, 1.616, 0.64, 1.151], 'ok')
    """

    name = "ABFTC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: WheelSatellite,
        *,
        c1: float = 0.5,
        c2: float = 3.0,
        gamma_g: ArrayLike = 0.1,
        gamma_theta: ArrayLike = 0.1,
        dt: float = 0.04,
        basis_frequencies: ArrayLike = (0.2,),
        g_hat0: ArrayLike | None = None,
        projection: float | tuple[float, float] | None = None,
        leakage: float = 0.0,
        freeze: bool = False,
        gyroscopic_compensation: bool = False,
        singular_pitch: float = SINGULAR_PITCH,
        divergence_bound: float = 1e6,
    ) -> None:
        if not isinstance(plant, WheelSatellite):
            raise ArgumentTypeError("plant", "a models.WheelSatellite", type(plant).__name__)
        self.plant = plant
        m = plant.n_wheels
        self.c1 = check_positive(c1, "c1")
        self.c2 = check_positive(c2, "c2")
        self.gamma_g = as_square_matrix(gamma_g, "gamma_g", 3)
        if np.ndim(gamma_theta) == 0 or np.shape(gamma_theta) == (3, 3):
            self.gamma_theta = (as_square_matrix(gamma_theta, "gamma_theta", 3),) * m
        elif isinstance(gamma_theta, Sequence) and len(gamma_theta) == m:
            self.gamma_theta = tuple(
                as_square_matrix(g, f"gamma_theta[{j}]", 3) for j, g in enumerate(gamma_theta)
            )
        else:
            raise InvalidArgumentError(
                "gamma_theta", f"a scalar, a 3 x 3 matrix or one of them per wheel ({m})", repr(gamma_theta)
            )
        self.dt = check_positive(dt, "dt")
        self.basis_frequencies = self._basis_spec(basis_frequencies, m)
        self._g2 = plant.input_matrix
        self.g_nom = plant.nominal_gain()
        self.g_hat0 = self.g_nom.copy() if g_hat0 is None else as_matrix(g_hat0, "g_hat0", (3, 3))
        self.projection = self._radii(projection)
        self.leakage = check_positive(leakage, "leakage", allow_zero=True)
        self.freeze = check_bool(freeze, "freeze")
        self.gyroscopic_compensation = check_bool(gyroscopic_compensation, "gyroscopic_compensation")
        self.singular_pitch = check_positive(singular_pitch, "singular_pitch")
        if self.singular_pitch > math.pi / 2:
            raise InvalidArgumentError(
                "singular_pitch", "a pitch bound in (0, pi/2] rad", repr(singular_pitch)
            )
        self.divergence_bound = check_positive(divergence_bound, "divergence_bound")
        self._gamma_g_inv = np.linalg.inv(self.gamma_g)
        self._gamma_theta_inv = tuple(np.linalg.inv(g) for g in self.gamma_theta)
        self._j_inv = plant.inertia_inv
        self._j = plant.inertia
        self.last: StepInfo | None = None
        self.reset()

    @staticmethod
    def _basis_spec(value: Any, m: int) -> tuple[tuple[float, ...], ...]:
        if isinstance(value, str | bytes) or not isinstance(value, Sequence):
            raise ArgumentTypeError(
                "basis_frequencies",
                "a sequence of frequencies, or one such sequence per wheel",
                type(value).__name__,
            )
        nested = len(value) > 0 and all(isinstance(v, Sequence) and not isinstance(v, str) for v in value)
        per_wheel = list(value) if nested else [value] * m
        if len(per_wheel) != m:
            raise InvalidArgumentError(
                "basis_frequencies", f"one sequence per wheel ({m})", f"{len(per_wheel)}"
            )
        out = []
        for j, freqs in enumerate(per_wheel):
            out.append(tuple(check_positive(f, f"basis_frequencies[{j}]") for f in freqs))
        return tuple(out)

    @staticmethod
    def _radii(projection: Any) -> tuple[float, float] | None:
        if projection is None:
            return None
        if np.ndim(projection) == 0:
            r = check_positive(projection, "projection")
            return r, r
        r = as_vector(projection, "projection", 2)
        return check_positive(r[0], "projection"), check_positive(r[1], "projection")

    # -- state -------------------------------------------------------------------------------------
    def reset(self) -> None:
        """Restart the clock (``t = 0``) and the estimates (``G_hat(0)``, ``Theta_hat_j = 0``)."""
        self.k = 0
        self.g_hat = self.g_hat0.copy()
        self.theta_hat = [np.zeros((3, 1 + len(f))) for f in self.basis_frequencies]
        self._diverged = False
        self.last = None

    @property
    def t(self) -> float:
        """The controller's clock, ``k Ts``."""
        return self.k * self.dt

    def basis(self, t: float) -> list[np.ndarray]:
        """``varpi_j(t) = [1, sin(w_1 t), ...]`` per wheel."""
        return [np.array([1.0, *(math.sin(w * t) for w in freqs)]) for freqs in self.basis_frequencies]

    # -- the continuous-time law (pure) ---------------------------------------------------------------
    def _signals(self, x: np.ndarray) -> tuple[np.ndarray, ...]:
        phi, theta, psi = float(x[0]), float(x[1]), float(x[2])
        w = x[3:6]
        e1 = np.array([phi, theta, wrap_angle(psi)])
        k_mat = kinematics_matrix(phi, theta)
        k_inv = inverse_kinematics_matrix(phi, theta)
        alpha1 = k_inv @ (-self.c1 * e1)
        e2 = w - alpha1
        torque = self.plant.gravity_torque(x[:3]) - np.cross(w, self._j @ w)
        if self.gyroscopic_compensation:
            if x.shape[0] < 6 + self.plant.n_wheels:
                raise InvalidArgumentError(
                    "x",
                    "the full state with wheel momenta (gyroscopic_compensation=True)",
                    f"{x.shape[0]} entries",
                )
            torque = torque - np.cross(w, self.plant.wheels.D @ x[6 : 6 + self.plant.n_wheels])
        f2 = self._j_inv @ torque
        eta_dot = k_mat @ w
        k_inv_dot = inverse_kinematics_rate(phi, theta, eta_dot[0], eta_dot[1])
        alpha1_dot = -self.c1 * (k_inv_dot @ e1 + w)
        return e1, e2, alpha1, alpha1_dot, f2, k_mat

    def law(self, t: float, x: ArrayLike, g_hat: ArrayLike, theta_hat: Sequence[Any]) -> ABFTCRates:
        """The continuous-time law at ``(t, x)`` for the estimates ``G_hat``, ``Theta_hat_j``.

        A pure function of its arguments (and the constructor's parameters): nothing is stored.
        ``x`` is the plant state (``[eta, w]`` or ``[eta, w, h]``). Leakage and projection are
        part of the returned rates; ``freeze`` is not (it acts in :meth:`step`).
        """
        x = np.asarray(x, dtype=float)
        g_hat = np.asarray(g_hat, dtype=float)
        e1, e2, alpha1, alpha1_dot, f2, k_mat = self._signals(x)
        phi_f = f2 - alpha1_dot
        varpi = self.basis(t)
        nu0 = -self.c2 * e2 - k_mat.T @ e1 - g_hat @ phi_f
        for th, vp in zip(theta_hat, varpi, strict=True):
            nu0 = nu0 - np.asarray(th, dtype=float) @ vp
        nu = self._g2.T @ nu0
        g_dot = self.gamma_g @ np.outer(e2, phi_f)
        th_dot = [gam @ np.outer(e2, vp) for gam, vp in zip(self.gamma_theta, varpi, strict=True)]
        if self.leakage > 0.0:
            g_dot = g_dot - self.leakage * self.gamma_g @ (g_hat - self.g_hat0)
            th_dot = [
                d - self.leakage * gam @ np.asarray(th)
                for d, gam, th in zip(th_dot, self.gamma_theta, theta_hat, strict=True)
            ]
        if self.projection is not None:
            g_dot = _project_rate(g_hat - self.g_hat0, g_dot, self.projection[0])
            th_dot = [
                _project_rate(np.asarray(th), d, self.projection[1])
                for th, d in zip(theta_hat, th_dot, strict=True)
            ]
        return ABFTCRates(nu, nu0, g_dot, tuple(th_dot), e1, e2, alpha1, alpha1_dot, f2)

    def lyapunov(
        self,
        x: ArrayLike,
        g_hat: ArrayLike,
        theta_hat: Sequence[Any],
        g_true: ArrayLike,
        theta_true: Sequence[Any],
    ) -> float:
        """Paper W's ``V2`` (eq. 40) for the true ``G`` and ``Theta_j`` of the current fault state."""
        x = np.asarray(x, dtype=float)
        e1, e2, *_ = self._signals(x)
        gt = np.asarray(g_true, dtype=float) - np.asarray(g_hat, dtype=float)
        v = 0.5 * e1 @ e1 + 0.5 * e2 @ np.asarray(g_true, dtype=float) @ e2
        v += 0.5 * np.trace(gt.T @ self._gamma_g_inv @ gt)
        for th_true, th_hat, g_inv in zip(theta_true, theta_hat, self._gamma_theta_inv, strict=True):
            tt = np.asarray(th_true, dtype=float) - np.asarray(th_hat, dtype=float)
            v += 0.5 * np.trace(tt.T @ g_inv @ tt)
        return float(v)

    def true_parameters(
        self, sigma: ArrayLike, ubar: Sequence[Any] | None = None
    ) -> tuple[np.ndarray, list[np.ndarray]]:
        """Paper W's ``G = (g2 sigma g2')^-1`` and ``Theta_j = G g2_j (1 - sigma_j) delta_j'``.

        Parameters
        ----------
        sigma : (m,) array_like
            1 for an obeying wheel, 0 for a failed one (or the effectiveness in [0, 1]).
        ubar : sequence of m array_like, optional
            ``delta_j``: the coefficients of each failed wheel's torque in this controller's
            basis ``varpi_j`` (e.g. ``[0.01, 0]`` for a wheel stuck at 0.01 N m with the basis
            ``[1, sin 0.2t]``). Default zeros (outages).

        For tests and reports (the controller itself never sees these).
        """
        m = self.plant.n_wheels
        sig = as_vector(sigma, "sigma", m)
        g_true = self.plant.nominal_gain(sig)
        thetas = []
        for j in range(m):
            q = 1 + len(self.basis_frequencies[j])
            delta = np.zeros(q) if ubar is None else as_vector(ubar[j], f"ubar[{j}]", q)
            thetas.append((1.0 - sig[j]) * np.outer(g_true @ self._g2[:, j], delta))
        return g_true, thetas

    # -- the sampled controller ----------------------------------------------------------------------
    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return the wheel commands for the measured state and advance the estimates over ``Ts``."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        n_full = 6 + self.plant.n_wheels
        x = as_vector(x, "x")
        if x.shape[0] not in (6, n_full):
            raise InvalidArgumentError("x", f"a state of length 6 or {n_full}", f"length {x.shape[0]}")
        t = self.t
        self.k += 1
        if abs(x[1]) >= self.singular_pitch or self._diverged:
            status = Status.DIVERGED if self._diverged else Status.SINGULAR
            self.last = StepInfo(
                status=status, solve_time=time.perf_counter() - start, extra={"t": t, "frozen": True}
            )
            return np.zeros(self.plant.n_wheels)
        rates = self.law(t, x, self.g_hat, self.theta_hat)
        frozen = False
        if self.freeze:
            wheels = self.plant.wheels
            frozen = bool(np.any(np.abs(rates.nu) > wheels.torque_max))
            if x.shape[0] == n_full:
                frozen = frozen or bool(np.any(np.abs(x[6:]) >= wheels.momentum_max))
        if not frozen:
            self.g_hat = self.g_hat + self.dt * rates.g_hat_dot
            self.theta_hat = [
                th + self.dt * d for th, d in zip(self.theta_hat, rates.theta_hat_dot, strict=True)
            ]
            if self.projection is not None:
                self.g_hat = self.g_hat0 + _clip_norm(self.g_hat - self.g_hat0, self.projection[0])
                self.theta_hat = [_clip_norm(th, self.projection[1]) for th in self.theta_hat]
        norms = [float(np.linalg.norm(th)) for th in self.theta_hat]
        g_norm = float(np.linalg.norm(self.g_hat))
        if (
            not (np.all(np.isfinite(rates.nu)) and math.isfinite(g_norm) and all(map(math.isfinite, norms)))
            or max([g_norm, *norms]) > self.divergence_bound
        ):
            self._diverged = True
            self.last = StepInfo(
                status=Status.DIVERGED,
                solve_time=time.perf_counter() - start,
                extra={"t": t, "frozen": True, "g_hat_norm": g_norm, "theta_norm": norms},
            )
            return np.zeros(self.plant.n_wheels)
        eig = np.linalg.eigvalsh(0.5 * (self.g_hat + self.g_hat.T))
        self.last = StepInfo(
            status=Status.OK,
            solve_time=time.perf_counter() - start,
            extra={
                "t": t,
                "nu0": rates.nu0,
                "e1": rates.e1,
                "e2": rates.e2,
                "frozen": frozen,
                "g_hat_eig": (float(eig[0]), float(eig[-1])),
                "theta_norm": norms,
            },
        )
        return rates.nu

    def settings(self) -> dict[str, Any]:
        """Every parameter, for reports (with their tags)."""
        return {
            "controller": self.name,
            "c1": self.c1,
            "c2": self.c2,
            "gains_tag": "certain",
            "gamma_g": self.gamma_g.tolist(),
            "gamma_theta": [g.tolist() for g in self.gamma_theta],
            "adaptation_gains_tag": "assumed",
            "dt": self.dt,
            "basis_frequencies": [list(f) for f in self.basis_frequencies],
            "g_hat0": self.g_hat0.tolist(),
            "projection": None if self.projection is None else list(self.projection),
            "leakage": self.leakage,
            "freeze": self.freeze,
            "gyroscopic_compensation": self.gyroscopic_compensation,
            "singular_pitch_deg": math.degrees(self.singular_pitch),
            "gravity": self.plant.gravity,
        }

    def __repr__(self) -> str:
        return (
            f"AdaptiveBacksteppingFTC(c1={self.c1:g}, c2={self.c2:g}, dt={self.dt:g}, "
            f"basis_frequencies={[list(f) for f in self.basis_frequencies]}, freeze={self.freeze})"
        )


def _project_rate(offset: np.ndarray, rate: np.ndarray, radius: float) -> np.ndarray:
    """Remove the outward normal part of ``rate`` on (or beyond) the ball ``||offset||_F <= radius``."""
    norm2 = float(np.sum(offset * offset))
    if norm2 < radius * radius:
        return rate
    outward = float(np.sum(offset * rate))
    if outward <= 0.0:
        return rate
    return rate - outward / norm2 * offset


def _clip_norm(mat: np.ndarray, radius: float) -> np.ndarray:
    norm = float(np.linalg.norm(mat))
    return mat if norm <= radius else mat * (radius / norm)
