"""CRMPC: robust MPC (Kothare et al. 1996) wrapped by a model reference adaptive system (paper P).

State feedback alone leaves an offset under a persistent input disturbance. Paper P adds a
model reference adaptive system (MRAS) around its robust MPC: a reference model, the error
between plant and model, and a parameter ``theta`` that corrects the control so that the
disturbance's effect is cancelled. Paper P tunes it by the MIT rule; this module offers that
rule (``rule="mit"``) and, as the default, the Lyapunov redesign of the same MRAS
(``rule="lyapunov"``), whose adaptation law comes with a stability argument over the whole
inertia polytope the robust MPC is designed for. ``docs/crmpc.rst`` has the block diagrams,
the derivations and the measurements behind the choice.

In deviation coordinates ``z = x - x_ref`` (``x_ref`` of the inner :class:`~rmpc.RMPC`), with
the nominal model ``(A, B)`` of the polytope and ``F(k)`` the gain the RMPC applies at step
``k``:

``rule="lyapunov"`` (default)::

    theta(k)   = Proj[theta(k-1) + Ts g (Bd' P Bd)^-1 Bd' P e(k)]     Bd = B / Ts, P = gamma Q^-1
    u_rmpc(k)  = F(k) z(k),   ||u_rmpc(k)|| <= u_max - |theta(k)|      the torque budget
    u(k)       = u_rmpc(k) - theta(k)
    zm(k+1)    = (A + B F(k)) zm(k),   zm(0) = z(0)                    nominal closed loop, never reset
    e(k)       = z(k) - zm(k)

``P`` is the cost matrix of the RMPC's last certified solution, a common Lyapunov matrix of the
closed loops ``A_j + B_j F`` at every vertex of the polytope (Kothare's LMIs certify it).

``rule="mit"`` (paper P's MIT rule, the toolkit's earlier default)::

    zm(k+1)    = A zm(k) + B u_rmpc(k),   zm(k0) = z(k0)                reset every reset_period
    s(k+1)     = A s(k) - B,   s(k0) = 0                                 sensitivity, de/dtheta = C_e s
    theta(k)   = theta(k-1) - gamma_a Ts (C_e s(k))' e(k) / (alpha + ||C_e s(k)||_F^2)

**The torque budget.** With an input bound, ``|theta_i|`` is projected onto
``theta_bound_i < u_max`` and the robust MPC gets what the correction leaves of the limit
(``torque_budget="current"``: ``u_max - max_i |theta_i(k)|`` for the ellipsoid, ``u_max_i -
|theta_i(k)|`` per axis for the peak bound, re-solved at every step; ``"split"``: the fixed
``u_max - theta_bound``). Every certified step then satisfies ``|u_i(k)| <= |u_rmpc,i(k)| +
|theta_i(k)| <= u_max`` on the nonlinear plant as on the linear one, without a limiter.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from typing import Any

import numpy as np

from models import PolytopicModel
from rmpc.controller import StepInfo
from rmpc.mpc.adaptation import LyapunovRule, MITRule, SensitivityFilter, _bound
from rmpc.mpc.robust_mpc import RMPC
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_choice, check_positive

__all__ = ["CRMPC"]

#: Default gain ``g`` of the Lyapunov rule (1/s^2): an estimator bandwidth of about 10 rad/s.
DEFAULT_GAIN_LYAPUNOV = 100.0
#: Default adaptation gain ``gamma_a`` of the normalised MIT rule (1/s), tuned on paper P's satellite.
DEFAULT_GAIN_NORMALIZED = 20.0
#: Default adaptation gain ``gamma_a`` of the plain rule, paper P's satellite: bounded but slow.
DEFAULT_GAIN_PLAIN = 0.3
#: Default regularisation ``alpha`` of the normalised rule.
DEFAULT_ALPHA = 1e-3
#: Default period (s) of the reference-model reset of the MIT rule.
DEFAULT_RESET_PERIOD = 2.0
#: Default ``theta_bound`` as a fraction of ``u_max``: the robust MPC keeps at least 20 % of the limit.
DEFAULT_THETA_FRACTION = 0.8
#: Adaptation laws.
RULES = ("lyapunov", "mit")
#: How the torque limit is shared between the robust MPC and the correction.
TORQUE_BUDGETS = ("current", "split", "none")

#: Arguments of :class:`~rmpc.RMPC` that CRMPC sets itself (not accepted in ``rmpc_options``).
_OWN_ARGUMENTS = ("self", "plant", "Q", "R", "u_max", "input_constraint")


class CRMPC:
    """Robust MPC plus a model reference adaptive system: paper P's CRMPC.

    Parameters
    ----------
    plant : PolytopicModel
        The polytope of discrete-time models; its ``nominal`` model is the reference model.
    Q, R, u_max, input_constraint
        Passed to the inner :class:`~rmpc.RMPC` (weights, input bound and its kind).
    rule : {"lyapunov", "mit"}
        The adaptation law (module notes). ``"lyapunov"`` (default): the Lyapunov redesign,
        robust over the polytope; ``"mit"``: paper P's MIT rule.
    adaptation_gain : float, optional
        ``g`` of the Lyapunov rule (1/s^2, default ``DEFAULT_GAIN_LYAPUNOV`` = 100) or
        ``gamma_a`` of the MIT rule (default ``DEFAULT_GAIN_NORMALIZED`` = 20 1/s for the
        normalised rule, ``DEFAULT_GAIN_PLAIN`` = 0.3 for the plain one). 0 turns the
        adaptation off and leaves plain RMPC.
    normalized, alpha : optional
        MIT rule only: the normalised rule (default ``True``) and its regularisation (default
        ``DEFAULT_ALPHA``). The plain rule is unstable at gains the normalised rule takes in
        its stride (the sensitivity grows like ``t^2`` inside a reset window).
    reset_period : float, None or "auto"
        MIT rule only: reset the reference model to the measured state (and the sensitivity
        to zero) every this many seconds; ``"auto"``: ``DEFAULT_RESET_PERIOD`` (2 s); ``None``:
        only at the first step. The Lyapunov rule's reference model is never reset.
    reference_gain : (m, n) array_like, optional
        MIT rule only: a fixed gain ``Fm`` for the classical reference model
        ``zm(k+1) = (A + B Fm) zm(k)`` (Schur stable on the nominal model).
    error_output : (p, n) array_like, optional
        MIT rule only: ``C_e`` of the error ``e = C_e (z - zm)`` (default the identity).
    theta_bound : "auto", float, array_like or None
        Projection ``|theta_i| <= theta_bound_i``. ``"auto"``: ``DEFAULT_THETA_FRACTION``
        (0.8) times ``u_max`` when there is an input bound, else none. With a torque budget it
        must lie below ``u_max`` (the robust MPC needs some of the limit).
    torque_budget : {"auto", "current", "split", "none"}
        How the torque limit is shared (module notes). ``"auto"``: ``"current"`` with an input
        bound, ``"none"`` without. ``"none"`` is the earlier behaviour: the RMPC's bound
        applies to ``u_rmpc`` only and the applied torque may exceed it by ``|theta|`` (put a
        limiter in the loop, ``simulate(..., limiter=TorqueLimiter(u_max))``).
    rmpc_options : dict, optional
        Further keyword arguments of :class:`~rmpc.RMPC` (``resolve_threshold``, ``backend``,
        ``x_ref``, ...). Unknown keys are errors.

    Attributes
    ----------
    rmpc : RMPC
        The inner robust MPC.
    rule : LyapunovRule or MITRule
        The adaptation law; ``rule.theta`` is the current disturbance estimate.
    last : StepInfo or None
        ``status``, ``solve_time``, ``gamma``, ``iterations`` and ``fallback`` of the inner
        RMPC step; ``extra`` holds the adaptation state: ``theta`` (applied at this step),
        ``error`` (the error the rule used), ``sensitivity`` (MIT rule; ``None`` otherwise),
        ``x_model`` (the reference model's state ``zm(k) + x_ref``), ``u_rmpc``,
        ``model_reset`` (whether the model was (re)started at this step), ``rmpc`` (the inner
        step's own :class:`StepInfo`), ``u_bound`` (the RMPC's input bound at this step,
        ``None`` without a budget) and ``budget_scaled`` (``True`` when a step without a
        certified solution for the current budget, a fallback or a kept gain, had its
        ``u_rmpc`` scaled back into the bound).

    Notes
    -----
    **Guarantee on the applied torque.** With a torque budget, every step whose RMPC solution
    is certified satisfies ``|u_i| <= u_max`` (``u_max_i`` for the peak bound) up to the
    certificate's tolerance, on any plant: the bound holds for ``u_rmpc = F z`` at the
    measured state because the state lies in the certified ellipsoid, and ``|theta_i|`` is
    what the budget left out. A step without such a solution (a failed solve, or a gain kept
    by ``resolve_threshold < 1`` that was certified for a larger bound) has ``u_rmpc`` scaled
    into the bound, so the limit holds at every step; ``last.extra["budget_scaled"]`` says
    when that happened.

    **Why the Lyapunov rule.** For ``B_t = c B`` (the scalar inertia polytope, ``c > 0``
    unknown) and a fixed gain, ``V = e' P e + c theta~' Gamma^-1 theta~`` is non-increasing
    (continuous-time argument, :class:`~rmpc.mpc.adaptation.LyapunovRule`), so the estimate cannot
    wind into a limit cycle; the MIT rule has no such argument and, with its open-loop
    reference model reset every 2 s, falls into a 2 s limit cycle at 1.7 times the nominal
    inertia. Measured on paper P's satellite, E5 settings (nonlinear plant, ``spread = 0.7``,
    0.5 N m from 10 s on all three axes or on one, ``R = 0.01 I``, re-solving at every sample;
    ``rmpc bench sweep --config paper_claims``): at true inertias of 0.3, 0.5, 0.7, 1.0, 1.3 and
    1.7 times the nominal the attitude error stays below 1e-3 rad from 0.6-1.4 s after the
    onset, peaks at 2-5e-3 rad, and the applied torque stays at 0.67-0.86 N m, never on the
    limit (``docs/crmpc.rst``).

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import CRMPC
    >>> sat = RigidSatellite.paper_p()
    >>> x0 = sat.initial_state()
    >>> plant = sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar")
    >>> ctrl = CRMPC(plant, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]), R=np.eye(3), u_max=1.0)
    >>> u = ctrl.step(x0)
    >>> ctrl.last.status, ctrl.last.extra["theta"].tolist(), ctrl.last.extra["u_bound"]
    ('optimal', [0.0, 0.0, 0.0], 1.0)
    """

    def __init__(
        self,
        plant: PolytopicModel,
        Q: Any,
        R: Any,
        u_max: Any = None,
        input_constraint: str | None = "auto",
        *,
        rule: str = "lyapunov",
        adaptation_gain: float | None = None,
        normalized: bool | None = None,
        alpha: float | None = None,
        reset_period: float | str | None = "auto",
        reference_gain: Any = None,
        error_output: Any = None,
        theta_bound: Any = "auto",
        torque_budget: str = "auto",
        rmpc_options: Mapping[str, Any] | None = None,
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            raise ArgumentTypeError("plant", "a models.PolytopicModel", type(plant).__name__)
        options = _rmpc_options(rmpc_options)
        self.plant = plant
        self.dt = plant.dt
        n, m = plant.n_states, plant.n_inputs
        self._a, self._b = (np.array(mat, dtype=float) for mat in plant.nominal)
        self.rule_name = str(check_choice(rule, "rule", RULES))
        lyapunov = self.rule_name == "lyapunov"
        if lyapunov:
            for name, value in (("normalized", normalized), ("alpha", alpha),
                                ("reference_gain", reference_gain), ("error_output", error_output)):
                if value is not None:
                    raise InvalidArgumentError(
                        name, "None with rule='lyapunov' (an MIT-rule setting)", repr(value)
                    )
            if reset_period not in ("auto", None):
                raise InvalidArgumentError(
                    "reset_period",
                    "'auto' or None with rule='lyapunov' (its reference model is never reset)",
                    repr(reset_period),
                )
        if normalized is None:
            normalized = True
        if not isinstance(normalized, bool | np.bool_):
            found = f"{type(normalized).__name__} {normalized!r}"
            raise ArgumentTypeError("normalized", "True or False", found)
        self.normalized = bool(normalized)
        self.alpha = check_positive(DEFAULT_ALPHA if alpha is None else alpha, "alpha")
        if adaptation_gain is None:
            if lyapunov:
                adaptation_gain = DEFAULT_GAIN_LYAPUNOV
            else:
                adaptation_gain = DEFAULT_GAIN_NORMALIZED if self.normalized else DEFAULT_GAIN_PLAIN
        self.adaptation_gain = check_positive(adaptation_gain, "adaptation_gain", allow_zero=True)

        if reset_period == "auto":
            reset_period = None if lyapunov else DEFAULT_RESET_PERIOD
        if reset_period is None:
            self.reset_period: float | None = None
            self._reset_steps = 0
        else:
            period = check_positive(reset_period, "reset_period")
            steps = round(period / self.dt)
            if steps < 1:
                raise InvalidArgumentError(
                    "reset_period", f"None or at least one sample (dt = {self.dt:g} s)", repr(reset_period)
                )
            self.reset_period = steps * self.dt
            self._reset_steps = steps

        if reference_gain is None:
            self.reference_gain: np.ndarray | None = None
        else:
            fm = as_matrix(reference_gain, "reference_gain", (m, n))
            radius = float(np.max(np.abs(np.linalg.eigvals(self._a + self._b @ fm))))
            if radius >= 1.0 - 1e-9:
                raise InvalidArgumentError(
                    "reference_gain",
                    "a gain Fm with A + B Fm Schur stable on the nominal model (spectral radius < 1)",
                    f"spectral radius {radius:.6g}",
                )
            self.reference_gain = fm
        c_e = np.eye(n) if error_output is None else as_matrix(error_output, "error_output", (None, n))
        if not np.any(c_e):
            raise InvalidArgumentError("error_output", "a non-zero output matrix C_e", "all zeros")
        self.error_output = c_e

        # the inner RMPC's own constraint (validated there) decides the kind of bound
        probe = RMPC(plant, Q, R, u_max=u_max, input_constraint=input_constraint, **options)
        kind = probe.input_constraint
        self.u_max = None if kind is None else np.array(probe.problem.data.u_max, dtype=float)
        budget = check_choice(torque_budget, "torque_budget", ("auto", *TORQUE_BUDGETS))
        if budget == "auto":
            budget = "none" if kind is None else "current"
        if budget != "none" and kind is None:
            raise InvalidArgumentError(
                "torque_budget", "'none' or 'auto' without an input bound (u_max)", repr(torque_budget)
            )
        self.torque_budget = str(budget)
        theta_bound = self._theta_bound(theta_bound, m)
        self.theta_bound = theta_bound
        if self.torque_budget == "split":
            assert self.u_max is not None and theta_bound is not None
            split = self._budget(theta_bound)
            self.rmpc = RMPC(plant, Q, R, u_max=split, input_constraint=kind, **options)
        else:
            self.rmpc = probe
        if lyapunov:
            self.rule: LyapunovRule | MITRule = LyapunovRule(
                m, self.adaptation_gain, self.dt, bound=theta_bound
            )
        else:
            self.rule = MITRule(
                m, self.adaptation_gain, self.dt, normalized=self.normalized, alpha=self.alpha,
                bound=theta_bound,
            )
        self._b_delta = self._b / self.dt
        self._sens = SensitivityFilter(self._a, self._b, c_e, columns=m)
        self._minus_eye = -np.eye(m)
        self._zm: np.ndarray | None = None
        self._p: np.ndarray | None = None
        self._since_reset = 0
        self.last: StepInfo | None = None

    def _theta_bound(self, value: Any, m: int) -> np.ndarray | None:
        if isinstance(value, str):
            if value != "auto":
                raise InvalidArgumentError(
                    "theta_bound", "'auto', None, a number or a vector", repr(value)
                )
            if self.u_max is None:
                return None
            return DEFAULT_THETA_FRACTION * np.broadcast_to(self.u_max, (m,)).copy()
        bound = _bound(value, "theta_bound", m)
        if self.torque_budget != "none":
            if bound is None:
                raise InvalidArgumentError(
                    "theta_bound", f"a bound below u_max with torque_budget={self.torque_budget!r}", "None"
                )
            assert self.u_max is not None
            limit = np.broadcast_to(self.u_max, (m,))
            if np.any(bound >= limit):
                raise InvalidArgumentError(
                    "theta_bound",
                    f"bounds below u_max = {limit.tolist()} (the robust MPC needs part of the torque limit)",
                    repr(bound.tolist()),
                )
        return bound

    def _budget(self, theta_abs: np.ndarray) -> float | np.ndarray:
        """What the correction ``|theta|`` leaves of the input bound, in the RMPC's kind of bound."""
        assert self.u_max is not None
        if self.rmpc_kind == "ellipsoid":
            return float(self.u_max[0] - np.max(theta_abs))
        return self.u_max - theta_abs

    @property
    def rmpc_kind(self) -> str | None:
        """The inner RMPC's input constraint (``"ellipsoid"``, ``"peak"`` or ``None``)."""
        return None if self.u_max is None else ("ellipsoid" if self.u_max.shape == (1,) else "peak")

    # -- the step(x) protocol -----------------------------------------------------------
    @property
    def theta(self) -> np.ndarray:
        """The current disturbance estimate ``theta`` (one value per input), a copy."""
        return self.rule.theta

    def reset(self) -> None:
        """Forget the adaptation, the reference model and the inner RMPC's gain."""
        self.rmpc.reset()
        self.rule.reset()
        self._sens.reset()
        self._zm = None
        self._p = None
        self._since_reset = 0
        self.last = None

    def step(self, x: Any) -> np.ndarray:
        """Adapt ``theta`` from the measured state, then return ``u = u_rmpc - theta``."""
        x = as_vector(x, "x", self.plant.n_states)
        z = x - self.rmpc.x_ref
        lyapunov = isinstance(self.rule, LyapunovRule)
        model_reset = self._zm is None or (not lyapunov and 0 < self._reset_steps <= self._since_reset)
        if model_reset:
            self._zm = z.copy()
            self._sens.reset()
            self._since_reset = 0
        assert self._zm is not None
        sens = None
        if lyapunov:
            error = z - self._zm
            if self._p is not None:
                self.rule.update(error, self._b_delta, self._p)
            theta = self.rule.theta
        else:
            sens = self._sens.output()
            error = self.error_output @ (z - self._zm)
            theta = self.rule.update(error, sens)

        bound: float | np.ndarray | None = None
        step_bound: float | np.ndarray | None = None
        if self.torque_budget == "current":
            bound = step_bound = self._budget(np.abs(theta))
        elif self.torque_budget == "split":
            step_bound = self.rmpc.problem.data.u_max[0] if self.rmpc_kind == "ellipsoid" else (
                self.rmpc.problem.data.u_max.copy())
        u_rmpc = np.asarray(self.rmpc.step(x, u_max=bound), dtype=float)
        inner = self.rmpc.last
        scaled = False
        if step_bound is not None:
            u_rmpc, scaled = _into_bound(u_rmpc, step_bound, self.rmpc_kind)
        zm = self._zm
        gain = self.rmpc.gain
        if gain is None:
            gain = np.zeros((self.plant.n_inputs, self.plant.n_states))
        if lyapunov:
            self._zm = (self._a + self._b @ gain) @ zm
            solution = None if inner is None else inner.extra.get("solution")
            if solution is not None and inner is not None and not inner.fallback and solution.Q is not None:
                self._p = solution.P
        elif self.reference_gain is None:
            self._zm = self._a @ zm + self._b @ u_rmpc
            self._sens.advance(self._minus_eye)
        else:
            self._zm = (self._a + self._b @ self.reference_gain) @ zm
            self._sens.advance(self._minus_eye, a=self._a + self._b @ gain)
        self._since_reset += 1

        self.last = StepInfo(
            status=inner.status if inner is not None else "unknown",
            solve_time=inner.solve_time if inner is not None else 0.0,
            gamma=inner.gamma if inner is not None else None,
            iterations=inner.iterations if inner is not None else None,
            fallback=inner.fallback if inner is not None else False,
            extra={
                "theta": theta, "error": error, "sensitivity": sens, "x_model": zm + self.rmpc.x_ref,
                "u_rmpc": u_rmpc, "model_reset": model_reset, "rmpc": inner,
                "u_bound": step_bound if not isinstance(step_bound, np.ndarray) else step_bound.copy(),
                "budget_scaled": scaled,
            },
        )
        return u_rmpc - theta


def _into_bound(u: np.ndarray, bound: float | np.ndarray, kind: str | None) -> tuple[np.ndarray, bool]:
    """``u`` scaled (radially) into the ellipsoid or box bound, and whether it had to be."""
    tol = 1e-6
    if kind == "ellipsoid":
        norm = float(np.linalg.norm(u))
        if norm <= float(bound) * (1.0 + tol):
            return u, False
        return u * (float(bound) / norm), True
    ratio = float(np.max(np.abs(u) / np.asarray(bound)))
    if ratio <= 1.0 + tol:
        return u, False
    return u / ratio, True


def _rmpc_options(options: Mapping[str, Any] | None) -> dict[str, Any]:
    """Check ``rmpc_options`` against :class:`~rmpc.RMPC`'s keyword arguments."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ArgumentTypeError("rmpc_options", "a dict of RMPC keyword arguments", type(options).__name__)
    accepted = [p for p in inspect.signature(RMPC.__init__).parameters if p not in _OWN_ARGUMENTS]
    unknown = sorted(str(k) for k in options if k not in accepted)
    if unknown:
        raise InvalidArgumentError(
            "rmpc_options", f"keys among {', '.join(accepted)}", f"unknown key(s) {', '.join(unknown)}"
        )
    return dict(options)
