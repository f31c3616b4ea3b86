"""Controllers defined in continuous time and run sampled: the ``step(x)`` protocol over a pure law.

A controller of this kind has an internal state ``z`` (filter, compensating signals, estimates)
and two pure functions of it:

- the law ``u = law(x, z)`` (:meth:`ContinuousTimeController.law`);
- the internal right-hand side ``z' = internal_derivative(x, z, u)``, where ``u`` is the torque
  actually applied (after the controller's own clip).

:meth:`ContinuousTimeController.closed_loop_rhs` joins them with a plant's ``dynamics`` for
``scipy.integrate.solve_ivp`` (the continuous-time closed loop the Lyapunov analyses talk
about). :meth:`ContinuousTimeController.step` runs them sampled, as paper M's seed (section 8)
prescribes: compute ``u_k`` from ``x_k`` and ``z_k``, then advance ``z`` one RK4 step of length
``dt`` with ``x_k`` and ``u_k`` held.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.sim.rhs import model_dynamics, plant_derivative
from toolkit_common.validation import as_optional_limits, as_vector, check_positive

__all__ = ["ContinuousTimeController", "LawOutput"]


@dataclass(frozen=True)
class LawOutput:
    """The law evaluated at ``(x, z)``: the applied torque, the unclipped one, and details."""

    u: np.ndarray
    u_unclipped: np.ndarray
    extra: dict[str, Any] = field(default_factory=dict)


class ContinuousTimeController:
    """Base class: a continuous-time law with an internal state, stepped at ``dt`` (see module).

    Subclasses define ``n_internal``, :meth:`initial_internal`, ``_geometry(x)``,
    ``_evaluate(x, z, geometry)`` and ``_derivative(x, z, u, geometry)``; the geometry (what
    depends on ``x`` only) is computed once per sample.

    Parameters
    ----------
    dt : float
        Sample time (s).
    u_max : float, (3,) array_like or None
        Per-axis torque limit (N m): the controller clips its own output and tells its
        internal dynamics the clipped value.
    n_states : int
        Size of the measured state.

    Attributes
    ----------
    name : str
        The short name in reports (each law sets its own: ``"BS"``, ``"MAB"``, ``"TFAB"``).
    accepts : frozenset of str
        The :class:`~rmpc.StepInputs` fields :meth:`step` uses (none).
    """

    name = "controller"
    accepts: ClassVar[frozenset[str]] = frozenset()
    n_internal = 0

    def __init__(self, dt: float, u_max: ArrayLike | None, n_states: int = 6) -> None:
        self.dt = check_positive(dt, "dt")
        self.u_max = as_optional_limits(u_max, "u_max", 3, per="axis")
        self.n_states = n_states
        self._z: np.ndarray | None = None
        self.last: StepInfo | None = None

    # -- to implement ------------------------------------------------------------------------
    def initial_internal(self, x: ArrayLike) -> np.ndarray:  # pragma: no cover - abstract
        """The internal state at the first sample, given the measured state."""
        raise NotImplementedError

    def _geometry(self, x: np.ndarray) -> Any:  # pragma: no cover - abstract
        raise NotImplementedError

    def _evaluate(self, x: np.ndarray, z: np.ndarray, geometry: Any) -> LawOutput:  # pragma: no cover
        raise NotImplementedError

    def _derivative(
        self, x: np.ndarray, z: np.ndarray, u: np.ndarray, geometry: Any
    ) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def project_internal(self, z: np.ndarray) -> np.ndarray:
        """Map the internal state back to its admissible set after a discrete step (default: none)."""
        return z

    def settings(self) -> dict[str, Any]:
        """Every parameter of the controller, for reports."""
        return {"controller": self.name, "dt": self.dt,
                "u_max": None if self.u_max is None else self.u_max.tolist()}

    # -- pure continuous-time functions --------------------------------------------------------
    def _clip(self, u0: np.ndarray) -> np.ndarray:
        return u0 if self.u_max is None else np.clip(u0, -self.u_max, self.u_max)

    def _checked(self, x: ArrayLike, z: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        return as_vector(x, "x", self.n_states), as_vector(z, "z", self.n_internal)

    def evaluate(self, x: ArrayLike, z: ArrayLike) -> LawOutput:
        """The law at ``(x, z)`` with its details (pure)."""
        x, z = self._checked(x, z)
        return self._evaluate(x, z, self._geometry(x))

    def law(self, x: ArrayLike, z: ArrayLike) -> np.ndarray:
        """The applied torque ``u = law(x, z)`` (pure; clipped to ``u_max``)."""
        return self.evaluate(x, z).u

    def internal_derivative(self, x: ArrayLike, z: ArrayLike, u: ArrayLike) -> np.ndarray:
        """``z'`` for the measured state ``x``, internal state ``z`` and applied torque ``u`` (pure)."""
        x, z = self._checked(x, z)
        return self._derivative(x, z, as_vector(u, "u", 3), self._geometry(x))

    def closed_loop_rhs(
        self, plant: Any, disturbance: Any = None
    ) -> Callable[[float, np.ndarray], np.ndarray]:
        """``f(t, y)`` of the joint closed loop ``y = [x, z]`` for ``scipy.integrate.solve_ivp``.

        Parameters
        ----------
        plant : object with ``dynamics(x, u, d=None)``
            The true plant, evaluated through :func:`rmpc.sim.rhs.plant_derivative` as the
            simulator does (its ``normalize_state`` is not applied: keep joint runs away from
            shadow-set switches).
        disturbance : callable, optional
            ``d(t)``, or ``d(t, x)`` when its ``state_dependent`` attribute is true.
        """
        dynamics = model_dynamics(plant)
        n = self.n_states

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            x, z = y[:n], y[n:]
            geometry = self._geometry(x)
            u = self._evaluate(x, z, geometry).u
            x_dot = plant_derivative(dynamics, t, x, u, disturbance)
            return np.concatenate((x_dot, self._derivative(x, z, u, geometry)))

        return rhs

    # -- sampled ---------------------------------------------------------------------------------
    @property
    def internal(self) -> np.ndarray | None:
        """A copy of the internal state (``None`` before the first step)."""
        return None if self._z is None else self._z.copy()

    def reset(self) -> None:
        """Forget the internal state; the next :meth:`step` initialises it from its measurement."""
        self._z = None
        self.last = None

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``u_k`` for the measured ``x_k``, then advance the internal state by ``dt``.

        The advance is one classical RK4 step of :meth:`internal_derivative` with ``x_k`` and
        ``u_k`` held, followed by :meth:`project_internal`. ``last`` is a
        :class:`~rmpc.StepInfo` with status ``"ok"`` (a control law, no optimiser), the wall
        time of the step as ``solve_time``, and the law's details in ``extra`` (plus
        ``"saturated"``: whether the clip acted).
        """
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        x = as_vector(x, "x", self.n_states)
        if self._z is None:
            self._z = self.initial_internal(x)
        z = self._z
        geometry = self._geometry(x)
        out = self._evaluate(x, z, geometry)
        u, h = out.u, self.dt
        k1 = self._derivative(x, z, u, geometry)
        k2 = self._derivative(x, z + 0.5 * h * k1, u, geometry)
        k3 = self._derivative(x, z + 0.5 * h * k2, u, geometry)
        k4 = self._derivative(x, z + h * k3, u, geometry)
        self._z = self.project_internal(z + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
        extra = dict(out.extra)
        extra["saturated"] = bool(np.any(out.u != out.u_unclipped))
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra=extra)
        return u.copy()
