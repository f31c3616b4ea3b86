"""The adaptation rules of CRMPC's model reference adaptive system (MRAS), in discrete time.

A model reference adaptive system compares the plant with a reference model and adjusts a
parameter vector ``theta`` so that the error ``e`` between them becomes small. :class:`rmpc.CRMPC`
estimates an input disturbance this way around its robust MPC and takes the rule as an object:

- :class:`LyapunovRule` (the default): the Lyapunov redesign, with a stability argument over the
  whole polytope the robust MPC is designed for;
- :class:`MITRule`: the (normalised) MIT rule of paper P (Astrom & Wittenmark, *Adaptive
  Control*, 2nd ed., section 5.2), which descends the gradient of ``J(theta) = e' e / 2``::

      dtheta/dt = -gamma (de/dtheta)' e                              (plain MIT rule)
      dtheta/dt = -gamma (de/dtheta)' e / (alpha + |de/dtheta|^2)    (normalised MIT rule)

  with the *sensitivity derivative* ``de/dtheta`` produced by a filter
  (:class:`~rmpc.mpc.mras.SensitivityFilter`). The plain rule's speed scales with the square of
  the signal levels, so a large command or a soft loop can make it unstable; the normalised rule
  divides that scale out and its speed is set by ``gamma`` alone (Astrom & Wittenmark, chapter 5).

A rule is built with its settings (plain defaults) and knows nothing of a plant; CRMPC binds a
copy of it to the plant's nominal model, sample time and projection bound (:meth:`~AdaptationRule.bind`).
The bound rule owns the reference model (and, for the MIT rule, the sensitivity filter and the
reset period) and is driven by two calls per sample, the interface of CRMPC's step loop::

    adapted = rule.update(z)                  # theta(k) from the deviation z(k) = x(k) - x_ref
    ...                                       # the robust MPC step: u_rmpc(k), its gain F(k)
    rule.advance(u_rmpc, gain, solution)      # the reference model (and filter) to k + 1

Both rules integrate their rate by forward Euler, ``Ts / (1 - z^-1)``, with a projection
(:class:`~rmpc.mpc.mras.ParameterIntegrator`). Their :meth:`rate` is usable on its own: the tests
reproduce Astrom & Wittenmark's example 5.2 with :meth:`MITRule.rate`, a
:class:`~rmpc.mpc.mras.ParameterIntegrator` and two :class:`~rmpc.mpc.mras.SensitivityFilter`.
"""

from __future__ import annotations

import copy
from abc import ABC, abstractmethod
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar, Self

import numpy as np
from numpy.typing import ArrayLike

from lmi import LMISolution
from rmpc.mpc.mras import ParameterIntegrator, SensitivityFilter
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_bool, check_positive

__all__ = [
    "DEFAULT_ALPHA",
    "DEFAULT_GAIN_LYAPUNOV",
    "DEFAULT_GAIN_NORMALIZED",
    "DEFAULT_GAIN_PLAIN",
    "DEFAULT_RESET_PERIOD",
    "RULES",
    "AdaptationRule",
    "AdaptationStep",
    "LyapunovRule",
    "MITRule",
    "ParameterIntegrator",
    "SensitivityFilter",
    "rule_from_settings",
]

#: Default gain ``g`` of the Lyapunov rule (1/s^2): an estimator bandwidth of about 10 rad/s.
DEFAULT_GAIN_LYAPUNOV = 100.0
#: Default adaptation gain ``gamma`` of the normalised MIT rule (1/s), tuned on paper P's satellite.
DEFAULT_GAIN_NORMALIZED = 20.0
#: A gain for the plain MIT rule (``normalized=False``) on paper P's satellite: bounded but slow
#: (the plain rule diverges at the normalised rule's default; pass it as ``gain``).
DEFAULT_GAIN_PLAIN = 0.3
#: Default regularisation ``alpha`` of the normalised MIT rule.
DEFAULT_ALPHA = 1e-3
#: Default period (s) of the MIT rule's reference-model reset.
DEFAULT_RESET_PERIOD = 2.0

#: Relative eigenvalue below which ``B' P B`` counts as singular (inputs that B maps onto each other).
RANK_TOL = 1e-10


@dataclass(frozen=True)
class AdaptationStep:
    """What a bound rule's :meth:`~AdaptationRule.update` gives for one sample.

    Attributes
    ----------
    theta : (m,) ndarray
        The estimate to apply at this sample.
    error : ndarray
        The error the rule used (``z - zm``; ``C_e (z - zm)`` for the MIT rule).
    sensitivity : ndarray or None
        ``de/dtheta`` (MIT rule), ``None`` for the Lyapunov rule.
    model : (n,) ndarray
        The reference model's state ``zm(k)`` (deviation coordinates).
    model_reset : bool
        Whether the model was (re)started at the measured state at this sample.
    """

    theta: np.ndarray
    error: np.ndarray
    sensitivity: np.ndarray | None
    model: np.ndarray
    model_reset: bool


class AdaptationRule(ABC):
    """An adaptation rule of CRMPC: its settings, and once bound its reference model and estimate.

    A rule sets :attr:`name` and implements four methods: :meth:`prepare` and
    :meth:`reset_model`, which :meth:`bind` and :meth:`reset` call, and :meth:`update` and
    :meth:`advance`, which CRMPC's step loop calls; the base class holds the estimate
    (:attr:`estimate`, a :class:`~rmpc.mpc.mras.ParameterIntegrator` with the projection).
    """

    #: The rule's name in reports (``"lyapunov"``, ``"mit"``).
    name: ClassVar[str]

    _estimate: ParameterIntegrator | None = None

    def bind(self, a: ArrayLike, b: ArrayLike, dt: float, bound: ArrayLike | None = None) -> Self:
        """A copy of this rule bound to a nominal model ``z(k+1) = A z(k) + B u(k)``.

        Parameters
        ----------
        a : (n, n) array_like
        b : (n, m) array_like
            The nominal discrete-time model (one parameter per input).
        dt : float
            The sample time (s).
        bound : float or (m,) array_like, optional
            The projection ``|theta_i| <= bound_i`` (``None``: none).

        Returns
        -------
        AdaptationRule
            A new rule of the same settings, ``theta = 0`` and no model yet; this rule is left
            as it is (one rule may be bound to several controllers).
        """
        a_mat = as_matrix(a, "a")
        n = a_mat.shape[0]
        a_mat = as_matrix(a_mat, "a", (n, n))
        b_mat = as_matrix(b, "b", (n, None))
        dt = check_positive(dt, "dt")
        bound_rule = copy.copy(self)
        bound_rule._estimate = ParameterIntegrator(b_mat.shape[1], dt, bound=bound)
        bound_rule.prepare(a_mat, b_mat, dt)
        return bound_rule

    def settings(self) -> dict[str, Any]:
        """The constructor's arguments of this rule (what a saved controller holds of it).

        A rule of the toolkit (:data:`RULES`) has them; any other rule is refused here, so a
        CRMPC with a rule of the user's own cannot be saved (pickle keeps one that pickles).
        """
        raise InvalidArgumentError(
            "adaptation", "a rule of rmpc.mpc.adaptation.RULES (lyapunov, mit) to save the controller",
            type(self).__name__,
        )

    @abstractmethod
    def prepare(self, a: np.ndarray, b: np.ndarray, dt: float) -> None:
        """Set up the reference model for the checked nominal model (called by :meth:`bind` on the
        copy, after :attr:`estimate` exists); check the settings that need the model here."""

    @property
    def estimate(self) -> ParameterIntegrator:
        """The integrator that holds ``theta`` (a bound rule only)."""
        if self._estimate is None:
            found = f"an unbound {type(self).__name__}"
            raise InvalidArgumentError("adaptation", "a rule bound to a model (AdaptationRule.bind)", found)
        return self._estimate

    @property
    def theta(self) -> np.ndarray:
        """The current estimate (a copy; a bound rule only)."""
        return self.estimate.theta

    def reset(self) -> None:
        """Return to ``theta = 0`` and forget the reference model (a bound rule only)."""
        self.estimate.reset()
        self.reset_model()

    @abstractmethod
    def reset_model(self) -> None:
        """Forget the reference model's state (called by :meth:`reset` and :meth:`prepare`)."""

    @abstractmethod
    def update(self, z: np.ndarray) -> AdaptationStep:
        """Adapt ``theta`` from the measured deviation ``z(k)``; the first call starts the model at ``z``."""

    @abstractmethod
    def advance(self, u_rmpc: np.ndarray, gain: np.ndarray, solution: LMISolution | None) -> None:
        """Take the reference model to the next sample.

        Parameters
        ----------
        u_rmpc : (m,) ndarray
            The robust MPC's control at this sample.
        gain : (m, n) ndarray
            The gain it applied (zero before its first certified gain).
        solution : LMISolution or None
            Its solution when this sample solved and certified one, else ``None``.
        """


class LyapunovRule(AdaptationRule):
    """Lyapunov-based adaptation of an input-disturbance estimate (MRAS with a stability proof).

    For a plant ``z' = A z + B_t (u + d)`` whose input matrix is ``B_t = c B`` with an unknown
    ``c > 0`` (an inertia scale), the control ``u = F z - theta``, the reference model
    ``zm' = (A + B F) zm`` and the error ``e = z - zm``, the law::

        dtheta/dt = Gamma B' P e,    Gamma = g (B' P B)^-1

    with ``P > 0`` a common Lyapunov matrix of the closed loops ``A + c B F`` over the
    uncertainty set, makes ``V = e' P e + c (d - theta)' Gamma^-1 (d - theta)`` non-increasing
    for a constant ``d`` (``V' = e' ((A + cBF)' P + P (A + cBF)) e`` plus a term in ``zm``,
    which decays): ``e`` and ``theta`` stay bounded and, with ``zm -> 0``, ``theta -> d``
    (Astrom & Wittenmark, *Adaptive Control*, 2nd ed., section 5.3, the Lyapunov redesign of the
    MIT rule; the argument needs only the sign of ``c``). The normalisation by
    ``B' P B`` gives ``g`` the unit 1/s^2 whatever the scale of ``P`` and ``B``: ``sqrt(g)`` is
    of the order of the estimator's bandwidth in rad/s.

    Bound to a sampled model (sample ``Ts``), the law is integrated by forward Euler, with the
    delta-operator input matrix ``B_delta = B_d / Ts`` (which tends to ``B`` as ``Ts -> 0``) and
    ``P`` the cost matrix of the robust MPC's last certified solution (:meth:`advance`)::

        theta(k)  = Proj[ theta(k-1) + Ts g (B_delta' P B_delta)^-1 B_delta' P e(k) ]
        zm(k+1)   = (A + B F(k)) zm(k),   zm(0) = z(0)      the nominal closed loop, never reset

    and the projection clips ``|theta_i| <= bound_i``. Until a certified ``P`` exists the
    estimate does not move. With more inputs than ``B`` has rank (four reaction wheels for three
    axes), ``B' P B`` is singular and its pseudo-inverse is used: the rate is the minimum-norm
    one, in the range of ``B'``; a combination of inputs that ``B`` maps to zero cannot be
    estimated and is not moved.

    Parameters
    ----------
    gain : float
        ``g`` (1/s^2, >= 0; 0 freezes the estimate at zero). Default
        :data:`DEFAULT_GAIN_LYAPUNOV` (100).

    Examples
    --------
    One input, ``B = [0, 1]'`` (a double integrator), ``P = I``, an error purely in the rate:
    the rate is ``g e_rate``.

    >>> import numpy as np
    >>> from rmpc.mpc.adaptation import LyapunovRule
    >>> rule = LyapunovRule(gain=100.0)
    >>> rule.rate(np.array([0.0, 0.5]), np.array([[0.0], [1.0]]), np.eye(2)).tolist()
    [50.0]
    """

    name: ClassVar[str] = "lyapunov"

    def __init__(self, gain: float = DEFAULT_GAIN_LYAPUNOV) -> None:
        self.gain = check_positive(gain, "gain", allow_zero=True)

    def rate(self, error: ArrayLike, b_delta: ArrayLike, p_mat: ArrayLike) -> np.ndarray:
        """``dtheta/dt = g (B' P B)^-1 B' P e`` for the error, input matrix and Lyapunov matrix.

        Parameters
        ----------
        error : (n,) array_like
            ``e = z - zm``.
        b_delta : (n, m) array_like
            The input matrix ``B`` (continuous time, or ``B_d / Ts`` of the sampled model).
        p_mat : (n, n) array_like
            The Lyapunov matrix ``P`` (symmetric positive definite).
        """
        e = as_vector(error, "error")
        b = as_matrix(b_delta, "b_delta", (e.shape[0], None))
        p = as_matrix(p_mat, "p_mat", (e.shape[0], e.shape[0]))
        pb = p @ b
        gram = b.T @ pb
        eig = np.linalg.eigvalsh(gram)
        if eig[0] > RANK_TOL * eig[-1]:
            return self.gain * np.linalg.solve(gram, pb.T @ e)
        # More inputs than B has rank (e.g. four wheels for three axes): the minimum-norm rate,
        # in the range of B'; components of theta that B maps to zero are left where they are.
        return self.gain * (np.linalg.pinv(gram, rcond=RANK_TOL, hermitian=True) @ (pb.T @ e))

    def settings(self) -> dict[str, Any]:
        return {"gain": self.gain}

    def prepare(self, a: np.ndarray, b: np.ndarray, dt: float) -> None:
        self._a, self._b = a, b
        self._b_delta = b / dt
        self.reset_model()

    def reset_model(self) -> None:
        self._zm: np.ndarray | None = None
        self._p: np.ndarray | None = None

    def update(self, z: np.ndarray) -> AdaptationStep:
        estimate = self.estimate
        model_reset = self._zm is None
        if model_reset:
            self._zm = z.copy()
        assert self._zm is not None
        error = z - self._zm
        if self._p is not None:
            estimate.step(self.rate(error, self._b_delta, self._p))
        return AdaptationStep(estimate.theta, error, None, self._zm, model_reset)

    def advance(self, u_rmpc: np.ndarray, gain: np.ndarray, solution: LMISolution | None) -> None:
        assert self._zm is not None
        self._zm = (self._a + self._b @ gain) @ self._zm
        if solution is not None and solution.Q is not None:
            self._p = solution.P

    def __repr__(self) -> str:
        return f"LyapunovRule(gain={self.gain:g})"


class MITRule(AdaptationRule):
    """Paper P's MIT rule: gradient adaptation with an open-loop reference model reset periodically.

    Bound to a sampled nominal model ``(A, B)`` (sample ``Ts``), in deviation coordinates::

        zm(k+1) = A zm(k) + B u_rmpc(k),   zm(k0) = z(k0)            reset every reset_period
        s(k+1)  = A s(k) - B,              s(k0) = 0                  de/dtheta = C_e s
        e(k)    = C_e (z(k) - zm(k))
        theta(k) = Proj[theta(k-1) - gamma Ts (C_e s(k))' e(k) / (alpha + ||C_e s(k)||_F^2)]

    (the last line without the division for the plain rule). With a ``reference_gain`` ``Fm``
    the model is the classical ``zm(k+1) = (A + B Fm) zm(k)`` and the sensitivity filter runs on
    the robust MPC's closed loop ``A + B F(k)``.

    Parameters
    ----------
    gain : float
        ``gamma`` (>= 0; 0 freezes the estimate): 1/s for the normalised rule (default
        :data:`DEFAULT_GAIN_NORMALIZED`, 20), ``theta`` per second per unit of
        ``(de/dtheta)' e`` for the plain one (e.g. :data:`DEFAULT_GAIN_PLAIN`).
    normalized : bool
        The normalised rule (default) or the plain one. The plain rule is unstable at gains the
        normalised rule takes in its stride (the sensitivity grows like ``t^2`` inside a reset
        window).
    alpha : float
        The normalised rule's regularisation ``alpha > 0`` (default :data:`DEFAULT_ALPHA`).
    reset_period : float or None
        Reset the model to the measured state (and the sensitivity to zero) every this many
        seconds, rounded to whole samples when bound (default :data:`DEFAULT_RESET_PERIOD`,
        2 s); ``None``: only at the first sample.
    reference_gain : (m, n) array_like, optional
        A fixed gain ``Fm`` for the classical reference model (Schur stable on the nominal
        model; checked when bound).
    error_output : (p, n) array_like, optional
        ``C_e`` of the error ``e = C_e (z - zm)`` (default the identity).

    Examples
    --------
    One parameter, ``e = theta - 3`` (so ``de/dtheta = 1``), the plain rule integrated with a
    :class:`~rmpc.mpc.mras.ParameterIntegrator`: ``theta`` goes to 3.

    >>> import numpy as np
    >>> from rmpc.mpc.adaptation import MITRule, ParameterIntegrator
    >>> rule, theta = MITRule(gain=5.0, normalized=False), ParameterIntegrator(1, dt=0.01)
    >>> for _ in range(2000):
    ...     _ = theta.step(rule.rate(theta.theta - 3.0, np.ones((1, 1))))
    >>> round(float(theta.theta[0]), 6)
    3.0
    """

    name: ClassVar[str] = "mit"

    def __init__(
        self,
        gain: float = DEFAULT_GAIN_NORMALIZED,
        *,
        normalized: bool = True,
        alpha: float = DEFAULT_ALPHA,
        reset_period: float | None = DEFAULT_RESET_PERIOD,
        reference_gain: ArrayLike | None = None,
        error_output: ArrayLike | None = None,
    ) -> None:
        self.normalized = check_bool(normalized, "normalized")
        self.alpha = check_positive(alpha, "alpha")
        self.gain = check_positive(gain, "gain", allow_zero=True)
        self.reset_period = None if reset_period is None else check_positive(reset_period, "reset_period")
        self.reference_gain = None if reference_gain is None else as_matrix(reference_gain, "reference_gain")
        self.error_output = None if error_output is None else as_matrix(error_output, "error_output")
        if self.error_output is not None and not np.any(self.error_output):
            raise InvalidArgumentError("error_output", "a non-zero output matrix C_e", "all zeros")

    def rate(self, error: ArrayLike, sensitivity: ArrayLike) -> np.ndarray:
        """``dtheta/dt`` of the (plain or normalised) MIT rule for this error and sensitivity.

        Parameters
        ----------
        error : array_like, shape (p,)
            The model-following error ``e = y - ym``.
        sensitivity : array_like, shape (p, n_params)
            ``de/dtheta``, column ``i`` the sensitivity of ``e`` to ``theta_i``.
        """
        e = as_vector(error, "error")
        return self._rate(e, as_matrix(sensitivity, "sensitivity", (e.shape[0], None)))

    def _rate(self, e: np.ndarray, sens: np.ndarray) -> np.ndarray:
        """:meth:`rate` without the argument checks (hot loops that built valid arrays)."""
        grad = sens.T @ e
        if self.normalized:
            grad = grad / (self.alpha + float(np.sum(sens * sens)))
        return -self.gain * grad

    def settings(self) -> dict[str, Any]:
        return {
            "gain": self.gain, "normalized": self.normalized, "alpha": self.alpha,
            "reset_period": self.reset_period, "reference_gain": self.reference_gain,
            "error_output": self.error_output,
        }

    def prepare(self, a: np.ndarray, b: np.ndarray, dt: float) -> None:
        n, m = b.shape
        self._a, self._b = a, b
        self._reset_steps = 0
        if self.reset_period is not None:
            self._reset_steps = round(self.reset_period / dt)
            if self._reset_steps < 1:
                raise InvalidArgumentError(
                    "reset_period", f"None or at least one sample (dt = {dt:g} s)", repr(self.reset_period)
                )
            self.reset_period = self._reset_steps * dt
        if self.reference_gain is not None:
            fm = as_matrix(self.reference_gain, "reference_gain", (m, n))
            radius = float(np.max(np.abs(np.linalg.eigvals(a + b @ fm))))
            if radius >= 1.0 - 1e-9:
                raise InvalidArgumentError(
                    "reference_gain",
                    "a gain Fm with A + B Fm Schur stable on the nominal model (spectral radius < 1)",
                    f"spectral radius {radius:.6g}",
                )
        c_e = np.eye(n)
        if self.error_output is not None:
            c_e = as_matrix(self.error_output, "error_output", (None, n))
        self._c_e = c_e
        self._sens = SensitivityFilter(a, b, c_e, columns=m)
        self._minus_eye = -np.eye(m)
        self.reset_model()

    def reset_model(self) -> None:
        self._sens.reset()
        self._zm: np.ndarray | None = None
        self._since_reset = 0

    def update(self, z: np.ndarray) -> AdaptationStep:
        estimate = self.estimate
        model_reset = self._zm is None or 0 < self._reset_steps <= self._since_reset
        if model_reset:
            self._zm = z.copy()
            self._sens.reset()
            self._since_reset = 0
        assert self._zm is not None
        sens = self._sens.output()
        error = self._c_e @ (z - self._zm)
        theta = estimate.step(self.rate(error, sens))
        return AdaptationStep(theta, error, sens, self._zm, model_reset)

    def advance(self, u_rmpc: np.ndarray, gain: np.ndarray, solution: LMISolution | None) -> None:
        assert self._zm is not None
        if self.reference_gain is None:
            self._zm = self._a @ self._zm + self._b @ u_rmpc
            self._sens.advance(self._minus_eye)
        else:
            self._zm = (self._a + self._b @ self.reference_gain) @ self._zm
            self._sens.advance(self._minus_eye, a=self._a + self._b @ gain)
        self._since_reset += 1

    def __repr__(self) -> str:
        kind = "normalised" if self.normalized else "plain"
        period = "None" if self.reset_period is None else f"{self.reset_period:g}"
        return f"MITRule(gain={self.gain:g}, {kind}, alpha={self.alpha:g}, reset_period={period})"


#: The adaptation rules by :attr:`~AdaptationRule.name` (a saved CRMPC names its rule so).
RULES: MappingProxyType[str, type[AdaptationRule]] = MappingProxyType({
    LyapunovRule.name: LyapunovRule, MITRule.name: MITRule,
})


def rule_from_settings(name: str, settings: dict[str, Any]) -> AdaptationRule:
    """The (unbound) rule called ``name`` with ``settings`` (:meth:`AdaptationRule.settings`).

    Examples
    --------
    >>> from rmpc.mpc.adaptation import MITRule, rule_from_settings
    >>> rule = MITRule(gain=5.0, reset_period=1.0)
    >>> rule_from_settings(rule.name, rule.settings())
    MITRule(gain=5, normalised, alpha=0.001, reset_period=1)
    """
    if name not in RULES:
        raise InvalidArgumentError("adaptation", f"a rule among {', '.join(RULES)}", repr(name))
    return RULES[name](**settings)
