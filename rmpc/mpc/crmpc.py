"""CRMPC: robust MPC (Kothare et al. 1996) wrapped by a model reference adaptive system (paper P).

State feedback alone leaves an offset under a persistent input disturbance. Paper P adds a
model reference adaptive system (MRAS) around its robust MPC: a reference model, the error
between plant and model, and a parameter ``theta`` that corrects the control so that the
disturbance's effect is cancelled. The adaptation rule is an object of
:mod:`rmpc.mpc.adaptation`: paper P tunes its MRAS by the MIT rule
(``adaptation=MITRule()``); the default is the Lyapunov redesign of the same MRAS
(``adaptation=LyapunovRule()``), whose adaptation law comes with a stability argument over the
whole inertia polytope the robust MPC is designed for. ``docs/crmpc.rst`` has the block
diagrams, the derivations and the measurements behind the choice.

In deviation coordinates ``z = x - x_ref`` (``x_ref`` of the inner :class:`~rmpc.RMPC`), with
the nominal model ``(A, B)`` of the polytope and ``F(k)`` the gain the RMPC applies at step
``k``, each step is::

    theta(k)   = rule.update(z(k))                     the rule's reference model and law
    u_rmpc(k)  = F(k) z(k),   ||u_rmpc(k)|| <= u_max - |theta(k)|      the torque budget
    u(k)       = u_rmpc(k) - theta(k)
    rule.advance(u_rmpc(k), F(k), solution)            the reference model to k + 1

:class:`~rmpc.mpc.adaptation.LyapunovRule` (default)::

    theta(k)   = Proj[theta(k-1) + Ts g (Bd' P Bd)^-1 Bd' P e(k)]     Bd = B / Ts, P = gamma Q^-1
    zm(k+1)    = (A + B F(k)) zm(k),   zm(0) = z(0)                    nominal closed loop, never reset
    e(k)       = z(k) - zm(k)

``P`` is the cost matrix of the RMPC's last certified solution, a common Lyapunov matrix of the
closed loops ``A_j + B_j F`` at every vertex of the polytope (Kothare's LMIs certify it).

:class:`~rmpc.mpc.adaptation.MITRule` (paper P's MIT rule, the toolkit's earlier default)::

    zm(k+1)    = A zm(k) + B u_rmpc(k),   zm(k0) = z(k0)                reset every reset_period
    s(k+1)     = A s(k) - B,   s(k0) = 0                                 sensitivity, de/dtheta = C_e s
    theta(k)   = theta(k-1) - gamma_a Ts (C_e s(k))' e(k) / (alpha + ||C_e s(k)||_F^2)

**The torque budget.** With an input bound, ``|theta_i|`` is projected onto
``theta_bound_i < u_max`` and the robust MPC gets what the correction leaves of the limit
(``torque_budget="current"``: ``u_max - max_i |theta_i(k)|`` for the ellipsoid, ``u_max_i -
|theta_i(k)|`` per axis for the peak bound, re-solved at every step and passed to the RMPC as
``StepInputs(u_max=...)``; ``"split"``: the fixed ``u_max - theta_bound``). Every certified step
then satisfies ``|u_i(k)| <= |u_rmpc,i(k)| + |theta_i(k)| <= u_max`` on the nonlinear plant as on
the linear one, without a limiter.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from lmi.data import input_bound_vector
from models import PolytopicModel
from rmpc.controller import StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode, plant_design, snapshot
from rmpc.io.saveable import Saveable
from rmpc.mpc.adaptation import RULES, AdaptationRule, LyapunovRule, rule_from_settings
from rmpc.mpc.robust_mpc import RMPC, input_constraint_kind, read_target, rmpc_arguments, target_design
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_optional_limits, as_vector, check_choice

__all__ = ["CRMPC"]

#: Default ``theta_bound`` as a fraction of ``u_max``: the robust MPC keeps at least 20 % of the limit.
DEFAULT_THETA_FRACTION = 0.8
#: How the torque limit is shared between the robust MPC and the correction.
TORQUE_BUDGETS = ("current", "split", "none")

#: Arguments of :class:`~rmpc.RMPC` that CRMPC sets itself (not accepted in ``rmpc_options``).
_OWN_ARGUMENTS = ("self", "plant", "Q", "R", "u_max", "input_constraint")


class CRMPC(Saveable):
    """Robust MPC plus a model reference adaptive system: paper P's CRMPC.

    Parameters
    ----------
    plant : PolytopicModel
        The polytope of discrete-time models; its ``nominal`` model is the reference model's.
    Q, R, u_max, input_constraint
        Passed to the inner :class:`~rmpc.RMPC` (weights, input bound and its kind).
    adaptation : LyapunovRule, MITRule or None
        The adaptation rule (:mod:`rmpc.mpc.adaptation`) with its settings; CRMPC binds a copy of
        it to the nominal model, the sample time and ``theta_bound``
        (:meth:`~rmpc.mpc.adaptation.AdaptationRule.bind`). ``None`` (default):
        ``LyapunovRule()``, robust over the polytope; ``MITRule()`` is paper P's rule.
        ``LyapunovRule(gain=0)`` turns the adaptation off and leaves plain RMPC.
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
    name : str
        ``"CRMPC"``.
    accepts : frozenset of str
        Empty: :meth:`step` takes no :class:`~rmpc.controller.StepInputs`.
    rmpc : RMPC
        The inner robust MPC (built once, with ``u_max - theta_bound`` for the ``"split"``
        budget).
    adaptation : LyapunovRule or MITRule
        The bound adaptation rule; ``adaptation.theta`` is the current disturbance estimate.
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
    >>> print(ctrl.last.status, ctrl.last.extra["theta"].tolist(), ctrl.last.extra["u_bound"])
    optimal [0.0, 0.0, 0.0] 1.0
    >>> ctrl.adaptation
    LyapunovRule(gain=100)

    Paper P's MIT rule, normalised, its gain and reset period set:

    >>> from rmpc.mpc.adaptation import MITRule
    >>> mit = CRMPC(plant, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]), R=np.eye(3), u_max=1.0,
    ...             adaptation=MITRule(gain=20.0, reset_period=1.0))
    >>> mit.adaptation.name, mit.torque_budget, mit.theta_bound.tolist()
    ('mit', 'current', [0.8, 0.8, 0.8])
    """

    name: ClassVar[str] = "CRMPC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: PolytopicModel,
        Q: ArrayLike,
        R: ArrayLike,
        u_max: ArrayLike | None = None,
        input_constraint: str | None = "auto",
        *,
        adaptation: AdaptationRule | None = None,
        theta_bound: ArrayLike | None = "auto",
        torque_budget: str = "auto",
        rmpc_options: Mapping[str, Any] | None = None,
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            raise ArgumentTypeError("plant", "a models.PolytopicModel", type(plant).__name__)
        options = _rmpc_options(rmpc_options)
        if adaptation is None:
            adaptation = LyapunovRule()
        elif not isinstance(adaptation, AdaptationRule):
            expected = "None or an adaptation rule (rmpc.mpc.adaptation.LyapunovRule or MITRule)"
            raise ArgumentTypeError("adaptation", expected, type(adaptation).__name__)
        self.plant = plant
        self.dt = plant.dt
        m = plant.n_inputs
        # the kind and size of the bound, checked as the inner RMPC's problem will hold it
        kind = input_constraint_kind(input_constraint, u_max)
        bound = input_bound_vector(kind, u_max, m)
        self._kind = kind
        self.u_max = None if kind is None else np.array(bound, dtype=float)
        budget = check_choice(torque_budget, "torque_budget", ("auto", *TORQUE_BUDGETS))
        if budget == "auto":
            budget = "none" if kind is None else "current"
        if budget != "none" and kind is None:
            raise InvalidArgumentError(
                "torque_budget", "'none' or 'auto' without an input bound (u_max)", repr(torque_budget)
            )
        self.torque_budget = str(budget)
        self.theta_bound = self._theta_bound(theta_bound, m)
        rmpc_bound = u_max
        if self.torque_budget == "split":
            assert self.theta_bound is not None
            rmpc_bound = self._budget(self.theta_bound)
        self.rmpc = RMPC(plant, Q, R, u_max=rmpc_bound, input_constraint=kind, **options)
        a_nom, b_nom = (np.array(mat, dtype=float) for mat in plant.nominal)
        self.adaptation = adaptation.bind(a_nom, b_nom, self.dt, self.theta_bound)
        self.last: StepInfo | None = None
        self._arguments: dict[str, Any] = snapshot({
            "Q": Q, "R": R, "u_max": u_max, "input_constraint": kind, "rmpc_options": options,
        })

    # -- save and load ---------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The plant, the constructor's arguments, the adaptation rule by name with its settings
        and the inner RMPC's set-point; not the estimate ``theta`` nor the reference model's state
        (run-time state: a loaded CRMPC is as after :meth:`reset`)."""
        rule = self.adaptation
        if RULES.get(rule.name) is not type(rule):
            AdaptationRule.settings(rule)  # refused, naming the rule
        return {
            "plant": plant_design(self.plant),
            "arguments": encode({**self._arguments, "theta_bound": self.theta_bound,
                                 "torque_budget": self.torque_budget}, "CRMPC arguments"),
            "adaptation": {"rule": self.adaptation.name,
                           "settings": encode(self.adaptation.settings(), "CRMPC adaptation")},
            "reference": target_design(self.rmpc.target),
        }

    @classmethod
    def _from_design(cls, design: Design) -> CRMPC:
        arguments, adaptation = design.part("arguments"), design.part("adaptation")
        options = arguments.part("rmpc_options")
        rule = rule_from_settings(str(adaptation.text("rule")), adaptation.plain("settings"))
        adaptation.finish()
        ctrl = cls(
            design.plant(), arguments.array("Q", 2), arguments.array("R", 2), arguments.bound("u_max"),
            arguments.optional_text("input_constraint"), adaptation=rule,
            theta_bound=arguments.optional_array("theta_bound", 1),
            torque_budget=arguments.text("torque_budget"),
            rmpc_options=rmpc_arguments(options, partial=True),
        )
        options.finish()
        arguments.finish()
        ctrl.rmpc._restore_target(read_target(design, "reference", ctrl.plant))
        return ctrl

    def _theta_bound(self, value: Any, m: int) -> np.ndarray | None:
        if isinstance(value, str):
            if value != "auto":
                raise InvalidArgumentError(
                    "theta_bound", "'auto', None, a number or a vector", repr(value)
                )
            if self.u_max is None:
                return None
            return DEFAULT_THETA_FRACTION * np.broadcast_to(self.u_max, (m,)).copy()
        bound = as_optional_limits(value, "theta_bound", m, per="input")
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
        return self._kind

    # -- the step(x) protocol -----------------------------------------------------------
    @property
    def theta(self) -> np.ndarray:
        """The current disturbance estimate ``theta`` (one value per input), a copy."""
        return self.adaptation.theta

    def reset(self) -> None:
        """Forget the adaptation, the reference model and the inner RMPC's gain."""
        self.rmpc.reset()
        self.adaptation.reset()
        self.last = None

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Adapt ``theta`` from the measured state, then return ``u = u_rmpc - theta``.

        ``inputs`` must be ``None`` or an empty :class:`~rmpc.controller.StepInputs` (:attr:`accepts`).
        """
        x = as_vector(x, "x", self.plant.n_states)
        check_step_inputs(inputs, self.accepts, "CRMPC")
        z = x - self.rmpc.x_ref
        adapted = self.adaptation.update(z)
        theta = adapted.theta

        bound: float | np.ndarray | None = None
        step_bound: float | np.ndarray | None = None
        if self.torque_budget == "current":
            bound = step_bound = self._budget(np.abs(theta))
        elif self.torque_budget == "split":
            step_bound = self.rmpc.problem.data.u_max[0] if self.rmpc_kind == "ellipsoid" else (
                self.rmpc.problem.data.u_max.copy())
        step_inputs = None if bound is None else StepInputs(u_max=bound)
        u_rmpc = np.asarray(self.rmpc.step(x, step_inputs), dtype=float)
        inner = self.rmpc.last
        scaled = False
        if step_bound is not None:
            u_rmpc, scaled = _into_bound(u_rmpc, step_bound, self.rmpc_kind)
        gain = self.rmpc.gain
        if gain is None:
            gain = np.zeros((self.plant.n_inputs, self.plant.n_states))
        certified = None if inner is None or inner.fallback else inner.extra.get("solution")
        self.adaptation.advance(u_rmpc, gain, certified)

        self.last = StepInfo(
            status=inner.status if inner is not None else "unknown",
            solve_time=inner.solve_time if inner is not None else 0.0,
            gamma=inner.gamma if inner is not None else None,
            iterations=inner.iterations if inner is not None else None,
            fallback=inner.fallback if inner is not None else False,
            extra={
                "theta": theta, "error": adapted.error, "sensitivity": adapted.sensitivity,
                "x_model": adapted.model + self.rmpc.x_ref, "u_rmpc": u_rmpc,
                "model_reset": adapted.model_reset, "rmpc": inner,
                "u_bound": step_bound if not isinstance(step_bound, np.ndarray) else step_bound.copy(),
                "budget_scaled": scaled,
            },
        )
        return u_rmpc - theta

    def __repr__(self) -> str:
        return f"CRMPC(adaptation={self.adaptation!r}, torque_budget={self.torque_budget!r})"


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
