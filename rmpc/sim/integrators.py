"""The integrators that advance a continuous plant over one sample: DOP853, RK4 and Newmark-beta.

Each integrator advances ``x' = f(t, x)`` from ``t`` to ``t + dt``, where ``f`` is the plant's
right-hand side for the command held over the sample (built by
:class:`~rmpc.sim.plants.SampledPlant` from the model, its input stage and the disturbance).
Pick one by name with :func:`make_integrator`:

- ``"DOP853"`` (:class:`DOP853`): SciPy's adaptive 8th-order Dormand-Prince with ``rtol`` and
  ``atol``, restarted at every sample and at every breakpoint of the disturbance, so neither
  the held input nor a step of the disturbance is smoothed over;
- ``"RK4"`` (:class:`RK4`): classical fixed-step Runge-Kutta, the sample split into equal
  steps no longer than ``substep`` (the right choice when the input stage switches inside a
  sample, e.g. a momentum limit);
- ``"Newmark"`` (:class:`Newmark`): Newmark-beta for plants with a second-order structure
  (the flexible satellite; see :class:`Newmark`).

After every step (DOP853: every piece between breakpoints; RK4: every substep) the model's
``normalize_state`` is applied when it has one (the MRP shadow-set switch, the
renormalisation of a quaternion). Newmark-beta keeps the quaternion at unit norm itself.

The right-hand side is sampled strictly inside each step: at the step's end ``f`` is called at
the left limit ``nextafter(t_end, t_start)``, so a disturbance or stage that switches at that
instant (a breakpoint, the next sample) does not leak into the step before it.

Examples
--------
>>> import numpy as np
>>> from rmpc.sim.integrators import make_integrator
>>> rk4 = make_integrator("RK4", substep=0.01)
>>> decay = lambda t, x: -x
>>> x1 = rk4.advance(None, decay, np.array([1.0]), 0.0, 0.1)
>>> rk4.n_steps(0.1), bool(abs(x1[0] - np.exp(-0.1)) < 1e-11)
(10, True)
>>> make_integrator("Euler")
Traceback (most recent call last):
...
toolkit_common.errors.InvalidArgumentError: integrator: expected one of 'DOP853', 'RK4', ...
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from itertools import pairwise
from typing import Any, ClassVar

import numpy as np

from models.attitude.quaternion import quat_multiply
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_choice, check_positive, is_integer

__all__ = [
    "DOP853",
    "INTEGRATORS",
    "RK4",
    "Integrator",
    "Newmark",
    "check_finite_derivative",
    "make_integrator",
]

#: The integrators by name, as :func:`make_integrator` and ``SampledPlant(integrator=...)`` accept them.
INTEGRATORS: tuple[str, ...] = ("DOP853", "RK4", "Newmark")

Derivative = Callable[[float, np.ndarray], np.ndarray]

#: The parts of a state :class:`Newmark` needs a plant's ``second_order_layout`` to name.
LAYOUT_PARTS: tuple[str, ...] = ("quaternion", "rate", "position", "velocity")


def check_finite_derivative(dx: np.ndarray, t: float) -> np.ndarray:
    """``dx`` if every value is finite, else an error naming the time and the derivative ``x'``."""
    if not np.all(np.isfinite(dx)):
        raise InvalidArgumentError(
            "plant", "a right-hand side x' = dynamics(x, u, d) with finite values",
            f"x' = {np.asarray(dx).tolist()} at t = {t:.9g} s",
        )
    return dx


def _normalizer(model: Any) -> Callable[[np.ndarray], np.ndarray] | None:
    normalize = getattr(model, "normalize_state", None)
    return normalize if callable(normalize) else None


def _n_steps(dt: float, substep: float) -> int:
    """Equal steps no longer than ``substep`` that make up ``dt`` (one step when ``substep >= dt``)."""
    return max(1, int(np.ceil(dt / substep - 1e-9)))


class Integrator(ABC):
    """Advances a continuous plant over one sample; see the module notes.

    Subclasses set ``name`` and define :meth:`advance`; :meth:`check` refuses a model that
    lacks what the integrator needs.
    """

    name: ClassVar[str]

    def check(self, model: Any) -> None:
        """Raise :class:`~toolkit_common.errors.InvalidArgumentError` naming ``integrator``
        when ``model`` lacks what this integrator needs (default: nothing needed)."""
        return None

    def n_steps(self, dt: float) -> int | None:
        """Steps per sample of length ``dt`` for a fixed-step integrator, ``None`` for an adaptive one."""
        return None

    @abstractmethod
    def advance(
        self, model: Any, f: Derivative, x: np.ndarray, t: float, dt: float, breakpoints: Sequence[float] = ()
    ) -> np.ndarray:
        """The state at ``t + dt`` of ``x' = f(t, x)`` from ``x`` at ``t``.

        Parameters
        ----------
        model : object
            The plant (for ``normalize_state`` and, with Newmark-beta, ``second_order_layout``).
        f : callable
            ``f(t, x) -> x'`` for the command held over the sample.
        x : ndarray
            The state at ``t``.
        t, dt : float
            Start and length of the sample (s).
        breakpoints : sequence of float
            Times inside ``(t, t + dt)`` where ``f`` is discontinuous (steps of the disturbance).
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._describe()})"

    def _describe(self) -> str:  # pragma: no cover - overridden
        return ""


class DOP853(Integrator):
    """SciPy's adaptive ``DOP853``, restarted at every sample and at every breakpoint.

    With the defaults ``rtol = 1e-10``, ``atol = 1e-12`` the state error over a 100 s closed
    loop of paper P's satellite (LQR) is about 1e-15, at round-off level: at dt = 0.1 s the
    run agrees with ``rtol = 1e-13, atol = 1e-14`` to 3e-16 and with an independent
    sub-stepped RK45 reference to 4e-16; at dt = 0.01 s each sample is a single DOP853 step
    and the error is 2e-15 (measured in ``tests/test_models_physics.py``, which asserts
    < 1e-12).

    The first right-hand side of each piece, at its start, is checked for finite values:
    ``solve_ivp`` would otherwise shrink its step without end on a NaN there.

    Parameters
    ----------
    rtol, atol : float
        Relative and absolute tolerances.
    """

    name = "DOP853"

    def __init__(self, rtol: float = 1e-10, atol: float = 1e-12) -> None:
        self.rtol = check_positive(rtol, "rtol")
        self.atol = check_positive(atol, "atol")

    def _describe(self) -> str:
        return f"rtol={self.rtol:g}, atol={self.atol:g}"

    def advance(
        self, model: Any, f: Derivative, x: np.ndarray, t: float, dt: float, breakpoints: Sequence[float] = ()
    ) -> np.ndarray:
        normalize = _normalizer(model)
        t_end = t + dt
        cuts = [t, *sorted(float(tb) for tb in breakpoints if t < tb < t_end), t_end]
        state = x
        for t0, t1 in pairwise(cuts):
            state = self._piece(f, state, t0, t1)
            if normalize is not None:
                state = np.asarray(normalize(state), dtype=float)
        return state

    def _piece(self, f: Derivative, state: np.ndarray, t0: float, t1: float) -> np.ndarray:
        # DOP853 evaluates the right-hand side at t1 itself: take the left limit there, so a
        # step at t1 (a breakpoint or the next sample) does not leak into [t0, t1)
        t_last = float(np.nextafter(t1, t0))
        checked = False

        def fun(tau: float, y: np.ndarray) -> np.ndarray:
            nonlocal checked
            dy = f(min(tau, t_last), y)
            if not checked:  # solve_ivp's first call is at (t0, state)
                checked = True
                check_finite_derivative(dy, tau)
            return dy

        from scipy.integrate import solve_ivp  # with scipy.optimize, ~0.4 s: imported on first use

        sol = solve_ivp(fun, (t0, t1), state, method="DOP853", rtol=self.rtol, atol=self.atol)
        if not sol.success:
            raise InvalidArgumentError(
                "x", "a state the integrator can advance",
                f"solve_ivp failed at t = {float(sol.t[-1]):.9g} s: {sol.message}",
            )
        return sol.y[:, -1]


class RK4(Integrator):
    """Classical fixed-step Runge-Kutta: the sample split into equal steps no longer than ``substep``.

    Parameters
    ----------
    substep : float, optional
        Longest step (s); the sample of length ``dt`` is split into ``ceil(dt / substep)``
        equal steps. Default: one step per sample.
    """

    name = "RK4"

    def __init__(self, substep: float | None = None) -> None:
        self.substep = None if substep is None else check_positive(substep, "substep")

    def _describe(self) -> str:
        return f"substep={self.substep!r}"

    def n_steps(self, dt: float) -> int:
        return 1 if self.substep is None else _n_steps(dt, self.substep)

    def advance(
        self, model: Any, f: Derivative, x: np.ndarray, t: float, dt: float, breakpoints: Sequence[float] = ()
    ) -> np.ndarray:
        normalize = _normalizer(model)
        n = self.n_steps(dt)
        h = dt / n
        state = np.asarray(x, dtype=float)
        for i in range(n):
            t0 = t + i * h
            # f is sampled strictly inside [t0, t0 + h): a step at t0 + h belongs to the next step
            t_end = float(np.nextafter(t0 + h, t0))
            k1 = f(t0, state)
            k2 = f(t0 + 0.5 * h, state + 0.5 * h * k1)
            k3 = f(t0 + 0.5 * h, state + 0.5 * h * k2)
            k4 = f(t_end, state + h * k3)
            state = state + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            if normalize is not None:
                state = np.asarray(normalize(state), dtype=float)
        return state


class Newmark(Integrator):
    """Newmark-beta for a plant with a second-order structure: the integrator paper V used.

    Paper V integrates its model with Newmark-beta (**certain**); the toolkit's default is
    adaptive Runge-Kutta between control samples, Newmark-beta with ``beta = 1/4``,
    ``gamma = 1/2`` (average acceleration, unconditionally stable, no numerical damping) is the
    option (**assumed**).

    The plant declares its structure with ``second_order_layout``: a mapping of ``"quaternion"``
    (the unit attitude quaternion, scalar first, 4 states), ``"rate"`` (the body rate ``w``, 3
    states), ``"position"`` and ``"velocity"`` (second-order coordinates ``eta`` and their rates
    ``eta'``, of equal size) to index slices that together cover the state once
    (:attr:`models.FlexibleSatellite.second_order_layout`). Each step of length ``h`` is implicit in
    the end-point accelerations ``a = [w', eta'']`` read from the plant's derivative::

        eta(n+1)  = eta(n) + h eta'(n) + h^2 ((1/2 - beta) eta''(n) + beta eta''(n+1))
        p(n+1)    = p(n) + h ((1 - gamma) a(n) + gamma a(n+1)),     p = [w, eta']
        q(n+1)    = q(n) * exp(h (w(n) + w(n+1)) / 4)               (quaternion exponential)

    solved by fixed-point iteration on ``a(n+1)`` (a contraction for ``h`` well below
    ``1/Lambda_N``). The attitude has no second-order form: it follows the trapezoidal rate
    through the exponential map, which keeps ``||q|| = 1`` to rounding (``normalize_state`` is
    not applied). Second-order accurate: the phase error of mode ``i`` grows like
    ``(h Lambda_i)^2 / 12`` per radian, so the step is much shorter than the control sample.

    Parameters
    ----------
    substep : float, optional
        Longest step (s); the sample is split into ``ceil(dt / substep)`` equal steps.
        Default 5 ms.
    beta, gamma : float
        Newmark parameters (``1/4``, ``1/2``: average acceleration); ``0 < beta <= 1/2``,
        ``0 < gamma <= 1``.
    tol : float
        Relative tolerance of the fixed-point iteration on the end-point accelerations.
    max_iterations : int
        Iterations before giving up (an error naming ``substep``).
    """

    name = "Newmark"
    default_substep: ClassVar[float] = 5e-3

    def __init__(
        self,
        substep: float | None = None,
        beta: float = 0.25,
        gamma: float = 0.5,
        tol: float = 1e-13,
        max_iterations: int = 50,
    ) -> None:
        self.substep = self.default_substep if substep is None else check_positive(substep, "substep")
        self.beta = check_positive(beta, "beta")
        self.gamma = check_positive(gamma, "gamma")
        if self.beta > 0.5 or not 0.0 < self.gamma <= 1.0:
            raise InvalidArgumentError("beta", "0 < beta <= 1/2 and 0 < gamma <= 1", f"{beta}, {gamma}")
        self.tol = check_positive(tol, "tol")
        if not is_integer(max_iterations) or max_iterations < 1:
            raise InvalidArgumentError("max_iterations", "a positive integer", repr(max_iterations))
        self.max_iterations = int(max_iterations)

    def _describe(self) -> str:
        return f"substep={self.substep:g}, beta={self.beta:g}, gamma={self.gamma:g}"

    def n_steps(self, dt: float) -> int:
        return _n_steps(dt, self.substep)

    def check(self, model: Any) -> None:
        self._layout(model)

    @staticmethod
    def _layout(model: Any) -> tuple[slice, slice, slice, slice]:
        """The model's ``(quaternion, rate, position, velocity)`` slices, checked."""
        layout = getattr(model, "second_order_layout", None)
        if not isinstance(layout, Mapping):
            raise InvalidArgumentError(
                "integrator", "'DOP853' or 'RK4' for a plant without a second_order_layout "
                "('Newmark' needs the second-order structure, e.g. models.FlexibleSatellite)",
                f"'Newmark' for {type(model).__name__}",
            )
        n = int(model.n_states)
        parts = tuple(layout.get(part) for part in LAYOUT_PARTS)
        sizes = [len(range(n)[s]) if isinstance(s, slice) else -1 for s in parts]
        covered = sorted(i for s in parts if isinstance(s, slice) for i in range(n)[s])
        if sizes[:2] != [4, 3] or sizes[2] != sizes[3] or covered != list(range(n)):
            raise InvalidArgumentError(
                "second_order_layout", "slices 'quaternion' (4), 'rate' (3), 'position' and 'velocity' "
                f"(equal sizes) covering the {n} states once", repr(dict(layout)),
            )
        return parts  # type: ignore[return-value]

    def advance(
        self, model: Any, f: Derivative, x: np.ndarray, t: float, dt: float, breakpoints: Sequence[float] = ()
    ) -> np.ndarray:
        layout = self._layout(model)
        n = self.n_steps(dt)
        h = dt / n
        state = np.asarray(x, dtype=float)
        for i in range(n):
            state = self._step(f, layout, state, t + i * h, h)
        return state

    def _step(
        self, f: Derivative, layout: tuple[slice, slice, slice, slice], x: np.ndarray, t0: float, h: float
    ) -> np.ndarray:
        quat, rate, pos, vel = layout
        beta, gamma = self.beta, self.gamma
        n_rate = 3

        def accelerations(t: float, y: np.ndarray) -> np.ndarray:
            y_dot = f(t, y)
            return np.concatenate((y_dot[rate], y_dot[vel]))

        def assemble(q1: np.ndarray, p1: np.ndarray, eta1: np.ndarray) -> np.ndarray:
            out = np.empty_like(x)
            out[quat], out[rate], out[pos], out[vel] = q1, p1[:n_rate], eta1, p1[n_rate:]
            return out

        q, p, eta, eta_dot = x[quat], np.concatenate((x[rate], x[vel])), x[pos], x[vel]
        t1 = float(np.nextafter(t0 + h, t0))  # d and the stage: left limit at the step's end
        a0 = accelerations(t0, x)
        a1 = a0
        for _ in range(self.max_iterations):
            p1 = p + h * ((1.0 - gamma) * a0 + gamma * a1)
            eta1 = eta + h * eta_dot + h * h * ((0.5 - beta) * a0[n_rate:] + beta * a1[n_rate:])
            phi = 0.5 * h * (p[:n_rate] + p1[:n_rate])
            angle = float(np.linalg.norm(phi))
            dq = np.concatenate(([np.cos(0.5 * angle)], np.sinc(0.5 * angle / np.pi) * 0.5 * phi))
            q1 = quat_multiply(q, dq)
            q1 = q1 / np.linalg.norm(q1)
            a_new = accelerations(t1, assemble(q1, p1, eta1))
            change = float(np.max(np.abs(a_new - a1)))
            a1 = a_new
            if change <= self.tol * (1.0 + float(np.max(np.abs(a1)))):
                p1 = p + h * ((1.0 - gamma) * a0 + gamma * a1)
                eta1 = eta + h * eta_dot + h * h * ((0.5 - beta) * a0[n_rate:] + beta * a1[n_rate:])
                return assemble(q1, p1, eta1)
        raise InvalidArgumentError(
            "substep", "a Newmark step short enough for the fixed-point iteration to converge",
            f"h = {h:g} s: no convergence in {self.max_iterations} iterations",
        )


def make_integrator(
    integrator: str | Integrator = "DOP853",
    *,
    substep: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
) -> Integrator:
    """The integrator named ``integrator`` (one of :data:`INTEGRATORS`), or ``integrator`` itself.

    Parameters
    ----------
    integrator : {"DOP853", "RK4", "Newmark"} or Integrator
        The name, or a ready :class:`Integrator` (for non-default Newmark parameters, say;
        then leave ``substep``, ``rtol`` and ``atol`` out).
    substep : float, optional
        The step of ``"RK4"`` (default: one step per sample) and ``"Newmark"`` (default 5 ms);
        ignored by ``"DOP853"``, whose step is adaptive.
    rtol, atol : float, optional
        The tolerances of ``"DOP853"`` (default 1e-10 and 1e-12); ignored by the fixed-step
        integrators.
    """
    if isinstance(integrator, Integrator):
        given = [name for name, value in (("substep", substep), ("rtol", rtol), ("atol", atol))
                 if value is not None]
        if given:
            raise InvalidArgumentError(
                given[0], f"None when integrator is an Integrator object (give it to {integrator!r})",
                repr({"substep": substep, "rtol": rtol, "atol": atol}[given[0]]),
            )
        return integrator
    if not isinstance(integrator, str):
        raise ArgumentTypeError(
            "integrator", "a name ('DOP853', 'RK4', 'Newmark') or an Integrator", type(integrator).__name__
        )
    check_choice(integrator, "integrator", INTEGRATORS)
    if integrator == "DOP853":
        return DOP853(1e-10 if rtol is None else rtol, 1e-12 if atol is None else atol)
    if integrator == "RK4":
        return RK4(substep)
    return Newmark(substep)
