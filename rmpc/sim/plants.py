"""Plants the simulator advances by one sample: a polytope member, or a continuous plant sampled.

Two kinds:

- :class:`LinearPlant`: a member of a polytope, ``x(k+1) = A x(k) + B (u(k) + d(t_k))``;
- :class:`SampledPlant`: any continuous-time plant with ``dynamics(x, u, d=None)``
  (:class:`models.protocols.Plant`: paper P's rigid satellite, the wheel, MRP and flexible
  satellites, or a user's own), integrated over each sample with the command held, by the
  integrator chosen by name (``"DOP853"``, ``"RK4"``, ``"Newmark"``; :mod:`rmpc.sim.integrators`),
  with an optional *input stage* between the held command and the model.

An input stage models what happens to the command inside the actuators while the plant moves:
faults, per-actuator torque and momentum limits, actuator-level noise. It is called inside the
integration (so a momentum limit reached in the middle of a sample acts there) and follows
:class:`~models.protocols.InputStage`.

:func:`as_sampled_plant` turns what the user hands to :func:`~rmpc.simulate` into one of them,
by what the object offers: a ready sampled plant (one with ``advance``) is itself, a
:class:`~models.PolytopicModel` is the linear plant, and anything with ``dynamics``, ``n_states``
and ``n_inputs`` is wrapped in a :class:`SampledPlant` with DOP853.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models import PolytopicModel
from rmpc.sim.disturbances import DisturbanceFn, disturbance_at
from rmpc.sim.integrators import Derivative, Integrator, check_finite_derivative, make_integrator
from rmpc.sim.rhs import model_dynamics, plant_derivative
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, check_positive

__all__ = ["LinearPlant", "SampledPlant", "as_sampled_plant"]


def _no_attitude(plant: Any) -> InvalidArgumentError:
    return InvalidArgumentError(
        "plant", "a plant with attitude_euler(x) (roll, pitch, yaw) for the attitude",
        f"{type(plant).__name__} without one",
    )


class LinearPlant:
    """``x(k+1) = A x(k) + B (u(k) + d(t_k))``: the disturbance enters with the input.

    The disturbance is sampled at the start of each interval (zero-order hold, like ``u``).

    Parameters
    ----------
    a, b : array_like
        The member's matrices.
    dt : float
        Sample time (s).
    attitude_euler : callable, optional
        ``attitude_euler(x)``: roll, pitch and yaw (rad) of a state (the polytope's own, see
        :meth:`models.PolytopicModel.attitude_euler`); ``None`` for a plant without attitude.
    """

    kind = "linear"

    def __init__(self, a: ArrayLike, b: ArrayLike, dt: float, attitude_euler: Any = None) -> None:
        self.A = as_matrix(a, "A")
        n = self.A.shape[0]
        self.A = as_matrix(self.A, "A", (n, n))
        self.B = as_matrix(b, "B", (n, None))
        self.dt = check_positive(dt, "dt")
        self.n_states, self.n_inputs = n, self.B.shape[1]
        if attitude_euler is not None and not callable(attitude_euler):
            raise ArgumentTypeError(
                "attitude_euler", "None or a callable attitude_euler(x)", type(attitude_euler).__name__
            )
        self._attitude_euler = attitude_euler

    @property
    def has_attitude(self) -> bool:
        """Whether :meth:`attitude_euler` gives the attitude of a state."""
        return self._attitude_euler is not None

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:
        """Roll, pitch and yaw (rad) of the state ``x``; an error for a plant without attitude."""
        if self._attitude_euler is None:
            raise _no_attitude(self)
        return np.asarray(self._attitude_euler(x), dtype=float)

    def advance(
        self, x: np.ndarray, u: np.ndarray, t: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        """State one sample later."""
        torque = u if disturbance is None else u + disturbance_at(disturbance, t, x)
        return self.A @ x + self.B @ torque


class SampledPlant:
    """A continuous plant ``x' = model.dynamics(x, u, d)`` advanced one sample with ``u`` held.

    Parameters
    ----------
    model : object
        Follows :class:`models.protocols.Plant`: has ``dynamics(x, u, d=None)``, ``n_states``
        and ``n_inputs``; optionally ``n_disturbances`` (the size of ``d``, default
        ``n_inputs``), ``normalize_state(x) -> x`` (applied after every integration step),
        ``dynamics_unchecked`` (the right-hand side without checks, used when present),
        ``attitude_euler(x)`` (stored by :func:`~rmpc.simulate`) and, for Newmark-beta,
        ``second_order_layout``.
    dt : float
        Sample time (s).
    integrator : {"DOP853", "RK4", "Newmark"} or Integrator
        ``"DOP853"`` (default): SciPy's adaptive 8th-order Dormand-Prince with ``rtol``/``atol``,
        restarted at every sample and at the disturbance's breakpoints. ``"RK4"``: classical
        fixed-step Runge-Kutta with ``substep`` (the right choice when the input stage
        switches inside a sample, e.g. a momentum limit). ``"Newmark"``: Newmark-beta for a
        plant with a ``second_order_layout`` (the flexible satellite). Or a ready
        :class:`~rmpc.sim.integrators.Integrator` (non-default Newmark parameters, say). See
        :mod:`rmpc.sim.integrators`.
    substep : float, optional
        The fixed step (s) of RK4 (default ``dt``) and Newmark (default 5 ms): the sample is
        split into ``ceil(dt / substep)`` equal steps. Ignored by DOP853.
    rtol, atol : float, optional
        DOP853 tolerances (default 1e-10 and 1e-12).
    input_stage : InputStage, optional
        Applied to the held command inside the integration (see :class:`~models.protocols.InputStage`).

    Examples
    --------
    >>> import numpy as np
    >>> from models import WheelSatellite
    >>> from rmpc.sim.plants import SampledPlant
    >>> sat = WheelSatellite.paper_w()
    >>> plant = SampledPlant(sat, 0.04, integrator="RK4", substep=0.005)
    >>> plant.integrator, plant.n_substeps, plant.n_disturbances
    (RK4(substep=0.005), 8, 3)
    >>> x1 = plant.advance(np.zeros(10), np.full(4, 0.01), 0.0, None)
    >>> bool(np.allclose(x1[6:], -0.01 * 0.04))   # each wheel's momentum after 40 ms
    True
    """

    kind = "nonlinear"

    def __init__(
        self,
        model: Any,
        dt: float,
        *,
        integrator: str | Integrator = "DOP853",
        substep: float | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        input_stage: Any = None,
    ) -> None:
        self._dynamics = model_dynamics(model)
        for attr in ("n_states", "n_inputs"):
            value = getattr(model, attr, None)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ArgumentTypeError("plant", f"a model with a positive integer {attr}", repr(value))
        self.model = model
        self.dt = check_positive(dt, "dt")
        self.integrator = make_integrator(integrator, substep=substep, rtol=rtol, atol=atol)
        self.integrator.check(model)
        if input_stage is not None and not callable(input_stage):
            expected = "None or a callable stage(t, x, u)"
            raise ArgumentTypeError("input_stage", expected, type(input_stage).__name__)
        self.input_stage = input_stage
        self.n_states, self.n_inputs = int(model.n_states), int(model.n_inputs)
        self.n_disturbances = int(getattr(model, "n_disturbances", self.n_inputs))
        attitude = getattr(model, "attitude_euler", None)
        self._attitude_euler = attitude if callable(attitude) else None

    @property
    def n_substeps(self) -> int | None:
        """Steps per sample of a fixed-step integrator (RK4, Newmark); ``None`` for DOP853."""
        return self.integrator.n_steps(self.dt)

    @property
    def has_attitude(self) -> bool:
        """Whether the model offers ``attitude_euler(x)``."""
        return self._attitude_euler is not None

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:
        """The model's roll, pitch and yaw (rad) of the state ``x``; an error for a model without."""
        if self._attitude_euler is None:
            raise _no_attitude(self.model)
        return np.asarray(self._attitude_euler(x), dtype=float)

    def applied(self, t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The input the model receives at ``(t, x)`` for the held command ``u`` (checked finite)."""
        if self.input_stage is None:
            return u
        out = np.asarray(self.input_stage(t, x, u), dtype=float)
        if not np.all(np.isfinite(out)):
            raise InvalidArgumentError(
                "input_stage", "a stage(t, x, u) returning finite inputs", f"{out.tolist()} at t = {t:.9g} s"
            )
        return out

    def derivative(self, u: np.ndarray, disturbance: DisturbanceFn | None) -> Derivative:
        """``f(t, x) = x'`` for the command ``u`` held: the input stage, the disturbance, the model.

        Every evaluation is checked: a NaN or infinite ``x'`` raises at once, naming the plant and
        the time, before an integrator can carry it into a state (or shrink its step without end).
        """
        dynamics, stage = self._dynamics, self.input_stage
        if stage is None:
            def f(t: float, x: np.ndarray) -> np.ndarray:
                dx = np.asarray(plant_derivative(dynamics, t, x, u, disturbance), dtype=float)
                return check_finite_derivative(dx, t)
        else:
            def f(t: float, x: np.ndarray) -> np.ndarray:
                applied = np.asarray(stage(t, x, u), dtype=float)
                dx = np.asarray(plant_derivative(dynamics, t, x, applied, disturbance), dtype=float)
                return check_finite_derivative(dx, t)
        return f

    def advance(
        self, x: np.ndarray, u: np.ndarray, t: float, disturbance: DisturbanceFn | None
    ) -> np.ndarray:
        """State one sample later (the command ``u`` held over ``[t, t + dt)``).

        Raises
        ------
        InvalidArgumentError
            Naming ``plant`` and the time when the right-hand side or the new state is not
            finite (a NaN from the model or its input stage).
        """
        breakpoints: Sequence[float] = ()
        if disturbance is not None:
            breakpoints = tuple(getattr(disturbance, "breakpoints", lambda: ())())
        f = self.derivative(u, disturbance)
        state = self.integrator.advance(self.model, f, x, t, self.dt, breakpoints)
        if not np.all(np.isfinite(state)):
            raise InvalidArgumentError(
                "plant", "a right-hand side (dynamics, input stage) giving finite states",
                f"x = {np.asarray(state).tolist()} at t = {t + self.dt:.9g} s ({self.integrator.name} "
                f"from t = {t:.9g} s)",
            )
        return state


def _check_dt(dt: float | None, plant_dt: float) -> None:
    if dt is None:
        return
    dt = check_positive(dt, "dt")
    if abs(dt - plant_dt) > 1e-12 * plant_dt:
        raise InvalidArgumentError("dt", f"None or the plant's dt = {plant_dt:g}", repr(dt))


def _linear_member(plant: PolytopicModel, true_plant: Any) -> LinearPlant:
    """The member of ``plant`` that ``true_plant`` picks, with the polytope's attitude."""
    if true_plant is not None and (
        isinstance(true_plant, str | bytes | bool)
        or not isinstance(true_plant, int | np.integer | Sequence | np.ndarray)
    ):
        raise ArgumentTypeError(
            "true_plant", "None, a vertex index, convex weights or an (A, B) pair",
            type(true_plant).__name__,
        )
    # a polytope built with attitude=None has no attitude (its attitude_euler raises)
    attitude = plant.attitude_euler if getattr(plant, "attitude", None) is not None else None
    try:
        if true_plant is None:
            a, b = plant.nominal
        elif isinstance(true_plant, int | np.integer):
            a, b = plant.vertex(int(true_plant))
        elif isinstance(true_plant, tuple) and len(true_plant) == 2:
            a, b = true_plant
        else:
            a, b = plant.combination(true_plant)
        out = LinearPlant(a, b, plant.dt, attitude)
    except (InvalidArgumentError, ArgumentTypeError) as err:
        # name the user's argument, not the helper's ("index", "weights", "A")
        raise type(err)("true_plant", err.expected, f"{err.found} (as {err.argument})") from None
    if out.A.shape != (plant.n_states, plant.n_states) or out.n_inputs != plant.n_inputs:
        raise InvalidArgumentError(
            "true_plant", f"(A, B) of shapes ({plant.n_states}, {plant.n_states}) and "
            f"({plant.n_states}, {plant.n_inputs})", f"{out.A.shape} and {out.B.shape}",
        )
    return out


def as_sampled_plant(
    plant: Any,
    dt: float | None,
    true_plant: Any = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> LinearPlant | SampledPlant | Any:
    """Turn the ``plant`` / ``true_plant`` arguments of :func:`~rmpc.simulate` into a sampled plant.

    By what ``plant`` offers:

    - ``advance`` (a ready :class:`SampledPlant` or :class:`LinearPlant`, which fixes the
      integrator and the input stage): ``plant`` itself (``dt`` must be ``None`` or its ``dt``);
    - a :class:`~models.PolytopicModel`: the linear plant; ``true_plant`` picks the member that is
      simulated: ``None`` (the nominal model), a vertex index, convex weights over the vertices,
      or an explicit ``(A, B)`` pair;
    - ``dynamics`` (any :class:`models.protocols.Plant`, e.g. :class:`~models.RigidSatellite`): a
      :class:`SampledPlant` with DOP853 at ``rtol``/``atol`` (``dt`` required).
    """
    if callable(getattr(plant, "advance", None)):
        missing = [name for name in ("dt", "n_states", "n_inputs", "kind") if not hasattr(plant, name)]
        if missing:
            raise ArgumentTypeError(
                "plant", "a sampled plant with advance(x, u, t, d), dt, n_states, n_inputs and kind",
                f"{type(plant).__name__} without {', '.join(missing)}",
            )
        _check_dt(dt, plant.dt)
        if true_plant is not None:
            raise InvalidArgumentError("true_plant", "None for a sampled plant", type(true_plant).__name__)
        return plant
    if isinstance(plant, PolytopicModel):
        _check_dt(dt, plant.dt)
        return _linear_member(plant, true_plant)
    if callable(getattr(plant, "dynamics", None)):
        if dt is None:
            raise InvalidArgumentError("dt", "a sample time for the nonlinear plant", "None")
        if true_plant is not None:
            raise InvalidArgumentError(
                "true_plant", "None for a nonlinear plant (pass the true model as plant)",
                type(true_plant).__name__,
            )
        return SampledPlant(plant, dt, rtol=rtol, atol=atol)
    raise ArgumentTypeError(
        "plant",
        "a models.PolytopicModel (linear), a model with dynamics(x, u, d=None) (nonlinear) or a "
        "SampledPlant",
        type(plant).__name__,
    )
