"""Plants the simulator advances by one sample: linear (a polytope member) or nonlinear."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from itertools import pairwise
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from models import PolytopicModel, RigidSatellite
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, check_positive

__all__ = ["LinearPlant", "NonlinearSatellitePlant", "make_plant"]

DisturbanceFn = Callable[[float], np.ndarray]


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
        torque = u if disturbance is None else u + disturbance(t)
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
                    return rhs(y, u + disturbance(min(_t, t_last)))
            sol = solve_ivp(fun, (t0, t1), state, method="DOP853", rtol=self.rtol, atol=self.atol)
            if not sol.success:  # pragma: no cover - DOP853 fails only on NaN input
                raise InvalidArgumentError(
                    "x", "a state the integrator can advance", f"solve_ivp failed: {sol.message}"
                )
            state = sol.y[:, -1]
        return state


def make_plant(
    plant: Any,
    dt: float | None,
    true_plant: Any = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> LinearPlant | NonlinearSatellitePlant:
    """Turn the user's ``plant`` / ``true_plant`` arguments of :func:`~rmpc.simulate` into a plant.

    ``plant`` is a :class:`~models.PolytopicModel` (linear) or a
    :class:`~models.RigidSatellite` (nonlinear). For a polytope, ``true_plant`` picks the
    member that is simulated: ``None`` (the nominal model), a vertex index, convex weights
    over the vertices, or an explicit ``(A, B)`` pair.
    """
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
    raise ArgumentTypeError(
        "plant", "a models.PolytopicModel (linear) or models.RigidSatellite (nonlinear)",
        type(plant).__name__,
    )
