"""Plants the simulator advances by one sample: linear (a polytope member) or nonlinear.

Three kinds:

- :class:`LinearPlant`: a member of a polytope, ``x(k+1) = A x(k) + B (u(k) + d(t_k))``;
- :class:`NonlinearSatellitePlant`: paper P's :class:`~models.RigidSatellite` (DOP853);
- :class:`NonlinearPlant`: any continuous-time model with ``dynamics(x, u, d=None)`` (the wheel,
  MRP and flexible satellites, or a user's own), integrated by DOP853 or fixed-step RK4, with an
  optional *input stage* between the held command and the model.

An input stage models what happens to the command inside the actuators while the plant moves:
faults, per-actuator torque and momentum limits, actuator-level noise. It is called inside the
integration (so a momentum limit reached in the middle of a sample acts there) and follows
:class:`~models.protocols.InputStage`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from itertools import pairwise
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from models import PolytopicModel, RigidSatellite
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, check_positive

__all__ = [
    "LinearPlant",
    "NonlinearPlant",
    "NonlinearSatellitePlant",
    "disturbance_at",
    "make_plant",
]

DisturbanceFn = Callable[..., np.ndarray]


def disturbance_at(disturbance: DisturbanceFn, t: float, x: np.ndarray) -> np.ndarray:
    """``d(t, x)`` for a state-dependent disturbance (``state_dependent = True``), else ``d(t)``."""
    if getattr(disturbance, "state_dependent", False):
        return disturbance(t, x)
    return disturbance(t)


class LinearPlant:
    """``x(k+1) = A x(k) + B (u(k) + d(t_k))``: the disturbance enters with the input.

    The disturbance is sampled at the start of each interval (zero-order hold, like ``u``).
    """

    kind = "linear"

    def __init__(self, a: Any, b: Any, dt: float) -> None:
        self.A = as_matrix(a, "A")
        n = self.A.shape[0]
        self.A = as_matrix(self.A, "A", (n, n))
        self.B = as_matrix(b, "B", (n, None))
        self.dt = check_positive(dt, "dt")
        self.n_states, self.n_inputs = n, self.B.shape[1]

    def advance(
        self, x: np.ndarray, u: np.ndarray, t: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        """State one sample later."""
        torque = u if disturbance is None else u + disturbance_at(disturbance, t, x)
        return self.A @ x + self.B @ torque


class NonlinearSatellitePlant:
    """The nonlinear satellite integrated over each sample with the torque held constant.

    Integration: SciPy's ``DOP853`` (8th-order Dormand-Prince) with ``rtol`` and ``atol``
    (defaults 1e-10 and 1e-12), restarted at every sample and at every disturbance
    breakpoint, so the held input and the steps of the disturbance are never smoothed over.
    With the defaults the state error over a 100 s closed loop (paper P, LQR) is about 1e-15,
    at round-off level: at dt = 0.1 s the run agrees with ``rtol = 1e-13, atol = 1e-14`` to
    3e-16 and with an independent sub-stepped RK45 reference to 4e-16; at dt = 0.01 s each
    sample is a single DOP853 step and the error is 2e-15 (measured in
    ``tests/test_models_physics.py``, which asserts < 1e-12). The disturbance ``d(t)`` is
    evaluated continuously inside each interval.
    """

    kind = "nonlinear"

    def __init__(
        self, satellite: RigidSatellite, dt: float, rtol: float = 1e-10, atol: float = 1e-12
    ) -> None:
        if not isinstance(satellite, RigidSatellite):
            raise ArgumentTypeError("satellite", "a models.RigidSatellite", type(satellite).__name__)
        self.satellite = satellite
        self.dt = check_positive(dt, "dt")
        self.rtol = check_positive(rtol, "rtol")
        self.atol = check_positive(atol, "atol")
        self.n_states, self.n_inputs = 6, 3

    def advance(
        self, x: np.ndarray, u: np.ndarray, t: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        """State one sample later (the torque ``u`` held over ``[t, t + dt)``)."""
        t_end = t + self.dt
        inner: list[float] = []
        if disturbance is not None:
            for tb in getattr(disturbance, "breakpoints", lambda: ())():
                if t < tb < t_end:
                    inner.append(float(tb))
        cuts = [t, *sorted(inner), t_end]
        rhs = self.satellite._rhs
        state = x
        for t0, t1 in pairwise(cuts):
            if disturbance is None:
                def fun(_t: float, y: np.ndarray) -> np.ndarray:
                    return rhs(y, u)
            else:
                # DOP853 evaluates the right-hand side at t1 itself; take d's left limit there,
                # so a step at t1 (a breakpoint or the next sample) does not leak into [t0, t1)
                t_last = float(np.nextafter(t1, t0))

                def fun(_t: float, y: np.ndarray, t_last: float = t_last) -> np.ndarray:
                    return rhs(y, u + disturbance_at(disturbance, min(_t, t_last), y))
            sol = solve_ivp(fun, (t0, t1), state, method="DOP853", rtol=self.rtol, atol=self.atol)
            if not sol.success:  # pragma: no cover - DOP853 fails only on NaN input
                raise InvalidArgumentError(
                    "x", "a state the integrator can advance", f"solve_ivp failed: {sol.message}"
                )
            state = sol.y[:, -1]
        return state


class NonlinearPlant:
    """Any continuous-time model ``x' = model.dynamics(x, u, d)``, advanced one sample with ``u`` held.

    Parameters
    ----------
    model : object
        Has ``dynamics(x, u, d=None)``, ``n_states`` and ``n_inputs``; optionally
        ``n_disturbances`` (the size of ``d``, default ``n_inputs``) and
        ``normalize_state(x) -> x``, applied after every integration step (the MRP shadow-set
        switch, the renormalisation of a quaternion).
    dt : float
        Sample time (s).
    method : {"DOP853", "RK4"}
        ``"DOP853"``: SciPy's adaptive 8th-order Dormand-Prince with ``rtol``/``atol``,
        restarted at every sample and at the disturbance's breakpoints (as for paper P's
        satellite). ``"RK4"``: classical fixed-step Runge-Kutta with ``substep`` (the right
        choice when the input stage switches inside a sample, e.g. a momentum limit).
    substep : float, optional
        RK4 step (s); the sample is split into ``ceil(dt / substep)`` equal steps. Default
        ``dt`` (one step per sample).
    rtol, atol : float
        DOP853 tolerances.
    input_stage : InputStage, optional
        Applied to the held command inside the integration (see :class:`~models.protocols.InputStage`).
    """

    kind = "nonlinear"

    def __init__(
        self,
        model: Any,
        dt: float,
        *,
        method: str = "DOP853",
        substep: float | None = None,
        rtol: float = 1e-10,
        atol: float = 1e-12,
        input_stage: Any = None,
    ) -> None:
        if not callable(getattr(model, "dynamics", None)):
            expected = "a model with a dynamics(x, u, d=None) method"
            raise ArgumentTypeError("plant", expected, type(model).__name__)
        for attr in ("n_states", "n_inputs"):
            value = getattr(model, attr, None)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ArgumentTypeError("plant", f"a model with a positive integer {attr}", repr(value))
        self.model = model
        self.dt = check_positive(dt, "dt")
        if method not in ("DOP853", "RK4"):
            raise InvalidArgumentError("method", "'DOP853' or 'RK4'", repr(method))
        self.method = method
        h = self.dt if substep is None else check_positive(substep, "substep")
        self.n_substeps = max(1, int(np.ceil(self.dt / h - 1e-9)))
        self.rtol = check_positive(rtol, "rtol")
        self.atol = check_positive(atol, "atol")
        if input_stage is not None and not callable(input_stage):
            expected = "None or a callable stage(t, x, u)"
            raise ArgumentTypeError("input_stage", expected, type(input_stage).__name__)
        self.input_stage = input_stage
        self.n_states, self.n_inputs = int(model.n_states), int(model.n_inputs)
        self.n_disturbances = int(getattr(model, "n_disturbances", self.n_inputs))
        normalize = getattr(model, "normalize_state", None)
        self._normalize = normalize if callable(normalize) else None

    def applied(self, t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The input the model receives at ``(t, x)`` for the held command ``u``."""
        return u if self.input_stage is None else np.asarray(self.input_stage(t, x, u), dtype=float)

    def _rhs(self, t: float, x: np.ndarray, u: np.ndarray, disturbance: DisturbanceFn | None) -> np.ndarray:
        d = None if disturbance is None else disturbance_at(disturbance, t, x)
        return np.asarray(self.model.dynamics(x, self.applied(t, x, u), d), dtype=float)

    def advance(
        self, x: np.ndarray, u: np.ndarray, t: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        """State one sample later (the command ``u`` held over ``[t, t + dt)``)."""
        if self.method == "RK4":
            return self._advance_rk4(x, u, t, disturbance)
        t_end = t + self.dt
        inner = []
        if disturbance is not None:
            inner = [float(tb) for tb in getattr(disturbance, "breakpoints", lambda: ())() if t < tb < t_end]
        cuts = [t, *sorted(inner), t_end]
        state = x
        for t0, t1 in pairwise(cuts):
            # the right-hand side is evaluated at t1 itself: take the left limit of d there
            t_last = float(np.nextafter(t1, t0))

            def fun(tau: float, y: np.ndarray, t_last: float = t_last) -> np.ndarray:
                return self._rhs(min(tau, t_last), y, u, disturbance)

            sol = solve_ivp(fun, (t0, t1), state, method="DOP853", rtol=self.rtol, atol=self.atol)
            if not sol.success:  # pragma: no cover - DOP853 fails only on NaN input
                raise InvalidArgumentError(
                    "x", "a state the integrator can advance", f"solve_ivp failed: {sol.message}"
                )
            state = sol.y[:, -1]
            if self._normalize is not None:
                state = np.asarray(self._normalize(state), dtype=float)
        return state

    def _advance_rk4(
        self, x: np.ndarray, u: np.ndarray, t: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        h = self.dt / self.n_substeps
        state = np.asarray(x, dtype=float)
        for i in range(self.n_substeps):
            t0 = t + i * h
            # the stage and d are sampled strictly inside [t0, t0 + h): a step at t0 + h belongs
            # to the next substep
            t_end = float(np.nextafter(t0 + h, t0))
            k1 = self._rhs(t0, state, u, disturbance)
            k2 = self._rhs(t0 + 0.5 * h, state + 0.5 * h * k1, u, disturbance)
            k3 = self._rhs(t0 + 0.5 * h, state + 0.5 * h * k2, u, disturbance)
            k4 = self._rhs(t_end, state + h * k3, u, disturbance)
            state = state + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            if self._normalize is not None:
                state = np.asarray(self._normalize(state), dtype=float)
        return state


def make_plant(
    plant: Any,
    dt: float | None,
    true_plant: Any = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> LinearPlant | NonlinearSatellitePlant | NonlinearPlant:
    """Turn the user's ``plant`` / ``true_plant`` arguments of :func:`~rmpc.sim.simulate` into a plant.

    ``plant`` is a :class:`~models.PolytopicModel` (linear), a
    :class:`~models.RigidSatellite` (nonlinear), a ready :class:`NonlinearPlant` (for RK4,
    an input stage, ...) or any model with ``dynamics(x, u, d=None)`` (wrapped in a
    :class:`NonlinearPlant` with DOP853). For a polytope, ``true_plant`` picks the member that
    is simulated: ``None`` (the nominal model), a vertex index, convex weights over the
    vertices, or an explicit ``(A, B)`` pair.
    """
    if isinstance(plant, NonlinearPlant):
        if dt is not None and abs(dt - plant.dt) > 1e-12 * plant.dt:
            raise InvalidArgumentError("dt", f"None or the plant's dt = {plant.dt:g}", repr(dt))
        if true_plant is not None:
            raise InvalidArgumentError("true_plant", "None for a nonlinear plant", type(true_plant).__name__)
        return plant
    if isinstance(plant, RigidSatellite):
        if dt is None:
            raise InvalidArgumentError("dt", "a sample time for the nonlinear plant", "None")
        if true_plant is not None:
            raise InvalidArgumentError(
                "true_plant", "None for a nonlinear plant (pass the true RigidSatellite as plant)",
                type(true_plant).__name__,
            )
        return NonlinearSatellitePlant(plant, dt, rtol=rtol, atol=atol)
    if isinstance(plant, PolytopicModel):
        if dt is not None and abs(dt - plant.dt) > 1e-12 * plant.dt:
            raise InvalidArgumentError("dt", f"None or the plant's dt = {plant.dt:g}", repr(dt))
        if true_plant is not None and (
            isinstance(true_plant, str | bytes | bool)
            or not isinstance(true_plant, int | np.integer | Sequence | np.ndarray)
        ):
            raise ArgumentTypeError(
                "true_plant", "None, a vertex index, convex weights or an (A, B) pair",
                type(true_plant).__name__,
            )
        try:
            if true_plant is None:
                a, b = plant.nominal
            elif isinstance(true_plant, int | np.integer):
                a, b = plant.vertex(int(true_plant))
            elif isinstance(true_plant, tuple) and len(true_plant) == 2:
                a, b = true_plant
            else:
                a, b = plant.combination(true_plant)
            out = LinearPlant(a, b, plant.dt)
        except (InvalidArgumentError, ArgumentTypeError) as err:
            # name the user's argument, not the helper's ("index", "weights", "A")
            raise type(err)("true_plant", err.expected, f"{err.found} (as {err.argument})") from None
        if out.A.shape != (plant.n_states, plant.n_states) or out.n_inputs != plant.n_inputs:
            raise InvalidArgumentError(
                "true_plant", f"(A, B) of shapes ({plant.n_states}, {plant.n_states}) and "
                f"({plant.n_states}, {plant.n_inputs})", f"{out.A.shape} and {out.B.shape}",
            )
        return out
    if callable(getattr(plant, "dynamics", None)):
        if dt is None:
            raise InvalidArgumentError("dt", "a sample time for the nonlinear plant", "None")
        if true_plant is not None:
            raise InvalidArgumentError("true_plant", "None for a nonlinear plant", type(true_plant).__name__)
        return NonlinearPlant(plant, dt, rtol=rtol, atol=atol)
    raise ArgumentTypeError(
        "plant",
        "a models.PolytopicModel (linear), a models.RigidSatellite, a NonlinearPlant or a model with "
        "dynamics(x, u, d=None) (nonlinear)",
        type(plant).__name__,
    )
