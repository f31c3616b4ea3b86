"""The closed-loop simulator: a sampled controller with zero-order hold on a plant."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models import PolytopicModel, ReactionWheelActuator, TorqueLimiter
from models.protocols import Plant
from rmpc.controller import Controller, StepInputs
from rmpc.sim.disturbances import as_disturbance, disturbance_at
from rmpc.sim.plants import SampledPlant, as_sampled_plant
from rmpc.sim.trajectory import Trajectory
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["MAX_STEPS", "NOISE_KINDS", "simulate"]


MAX_STEPS = 10_000_000
"""Default bound on a run's samples (10 million samples of 14 states: about 1.1 GB of states)."""

#: The distributions of :func:`simulate`'s measurement noise.
NOISE_KINDS = ("gaussian", "uniform")


def simulate(
    controller: Controller,
    plant: PolytopicModel | Plant | SampledPlant,
    x0: ArrayLike,
    duration: float | None = None,
    *,
    n_steps: int | None = None,
    dt: float | None = None,
    true_plant: int | ArrayLike | tuple[ArrayLike, ArrayLike] | None = None,
    actuator: ReactionWheelActuator | None = None,
    limiter: TorqueLimiter | None = None,
    disturbance: Callable[..., ArrayLike] | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    reset: bool = True,
    progress: Callable[[int, int], object] | None = None,
    sensor: Callable[[float, np.ndarray], ArrayLike] | None = None,
    max_steps: int = MAX_STEPS,
    measurement: ArrayLike | None = None,
    noise: float | ArrayLike | None = None,
    estimator: Any = None,
    noise_seed: int = 0,
    noise_kind: str = "gaussian",
) -> Trajectory:
    """Run ``controller`` in closed loop on ``plant`` from ``x0``.

    At each sample ``t_k = k dt`` the controller gets the measured state and returns
    ``u_cmd``; the limiter (if any) clips it, the actuator (if any) turns it into the torque,
    and the plant advances one sample with that torque held (zero-order hold) plus the
    disturbance.

    Parameters
    ----------
    controller : object with ``step(x)``
        Any controller of the toolkit (see :class:`rmpc.controller.Controller`).
    plant : PolytopicModel, a Plant or a SampledPlant
        A polytope (the linear plant; ``true_plant`` picks the member), any continuous plant
        with ``dynamics(x, u, d=None)`` (:class:`models.protocols.Plant`: paper P's
        :class:`~models.RigidSatellite`, the wheel, MRP and flexible satellites, a user's
        model; ``dt`` required; integrated by DOP853 at ``rtol``/``atol``), or a
        :class:`~rmpc.sim.plants.SampledPlant` that fixes the integrator (``"DOP853"``,
        ``"RK4"``, ``"Newmark"``) and an input stage (faults, actuator limits; see
        :class:`~models.protocols.InputStage`). See :func:`rmpc.sim.plants.as_sampled_plant`.
    x0 : array_like
        Initial state.
    duration : float, optional
        Simulated time (s); ``n_steps = round(duration / dt)``. Give this or ``n_steps``.
    n_steps : int, optional
        Number of controller steps.
    dt : float, optional
        Sample time; for a polytope it defaults to (and must equal) ``plant.dt``.
    true_plant : None, int, weights or (A, B), optional
        For a polytope: the nominal model (default), a vertex, a convex combination, or an
        explicit pair.
    actuator : ReactionWheelActuator, optional
        Actuator dynamics between command and torque; reset at the start.
    limiter : TorqueLimiter, optional
        Saturation applied to the controller output.
    disturbance : callable, optional
        Disturbance torque ``d(t)`` (e.g. :class:`rmpc.StepDisturbance`), or ``d(t, x)`` for an
        object whose ``state_dependent`` attribute is true.
    rtol, atol : float
        Tolerances of DOP853 for a plant given as a model (a ready
        :class:`~rmpc.sim.plants.SampledPlant` keeps its own integrator).
    reset : bool
        Call ``controller.reset()`` first (default).
    progress : callable, optional
        Called as ``progress(k, n_steps)`` after each step.
    sensor : callable, optional
        ``sensor(t, x) -> y``: what the controller measures (sensor noise, say); the
        trajectory keeps the true state. Its ``reset()`` is called before the run when present.
        Default: the controller sees the true state.
    measurement : (p, n) array_like, optional
        ``C`` of the sensor ``y = C x + v``: the controller then sees ``y`` (with an
        ``estimator``: the estimate from it) instead of the state. Not with ``sensor``.
    noise : float or (p,) array_like, optional
        The measurement noise ``v`` per output (with ``measurement``), drawn from
        ``numpy.random.default_rng(noise_seed)``: the standard deviation of white Gaussian noise,
        or with ``noise_kind="uniform"`` the bound of noise uniform in ``[-noise_i, noise_i]``
        (the bounded noise :class:`rmpc.estimators.RobustObserver` certifies its bound for).
    estimator : object with ``update(y, u_prev)`` and ``reset()``, optional
        Turns each measurement into the state estimate the controller steps on
        (:mod:`rmpc.estimators`); it gets the input applied at the previous sample (after the
        limiter and actuator). Reset at the start; the estimates are kept in
        ``Trajectory.stage_log["x_hat"]`` (and ``"d_hat"`` where it estimates a disturbance).
        Needs ``measurement``.
    noise_seed : int
        Seed of the measurement noise.
    noise_kind : {"gaussian", "uniform"}
        The distribution of the measurement noise (see ``noise``).
    max_steps : int
        The largest number of samples a run may have (default :data:`MAX_STEPS`, 10 million:
        the trajectory's arrays are allocated up front); a longer run is refused with an error
        naming this limit. Pass a larger value to lift it.

    Returns
    -------
    Trajectory
        With the roll, pitch and yaw of every sample (:attr:`Trajectory.attitude_euler`)
        computed by the plant's ``attitude_euler(x)`` when it has one.

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import LQR, simulate
    >>> sat = RigidSatellite.paper_p()
    >>> x0 = sat.initial_state()
    >>> lqr = LQR(sat.linear_model(x0, 0.01), Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]), R=np.eye(3))
    >>> traj = simulate(lqr, sat, x0, duration=20.0, dt=0.01)
    >>> bool(np.all(np.abs(traj.x[-1, :3]) < 1e-3))
    True
    """
    if not callable(getattr(controller, "step", None)):
        raise ArgumentTypeError("controller", "an object with a step(x) method", type(controller).__name__)
    sim_plant = as_sampled_plant(plant, dt, true_plant, rtol=rtol, atol=atol)
    step_dt = sim_plant.dt
    n, m = sim_plant.n_states, sim_plant.n_inputs
    x = as_vector(x0, "x0", n)
    if (duration is None) == (n_steps is None):
        raise InvalidArgumentError(
            "duration", "exactly one of duration or n_steps", f"duration={duration}, n_steps={n_steps}"
        )
    if duration is not None:
        duration = check_positive(duration, "duration")
        n_steps = round(duration / step_dt)
        if n_steps < 1:
            raise InvalidArgumentError(
                "duration", f"at least half a sample time (dt = {step_dt:g} s)", f"{duration:g} s"
            )
    if isinstance(n_steps, bool) or not isinstance(n_steps, int | np.integer) or n_steps < 1:
        raise InvalidArgumentError("n_steps", "a positive integer", repr(n_steps))
    if isinstance(max_steps, bool) or not isinstance(max_steps, int | np.integer) or max_steps < 1:
        raise InvalidArgumentError("max_steps", "a positive integer", repr(max_steps))
    if n_steps > max_steps:
        asked = f"duration {duration:g} s / dt {step_dt:g} s = " if duration is not None else ""
        raise InvalidArgumentError(
            "duration" if duration is not None else "n_steps",
            f"at most max_steps = {max_steps} samples (pass a larger max_steps to lift the limit)",
            f"{asked}{n_steps} samples",
        )
    n_d = int(getattr(sim_plant, "n_disturbances", m))
    d_fn = as_disturbance(disturbance, n_d, x)
    stage = getattr(sim_plant, "input_stage", None)
    if stage is not None and callable(getattr(stage, "reset", None)):
        stage.reset()
    begin_sample = getattr(stage, "begin_sample", None) if stage is not None else None
    stage_rows: list[dict[str, Any]] = []
    if actuator is not None:
        if not isinstance(actuator, ReactionWheelActuator) or actuator.n_axes != m:
            raise InvalidArgumentError(
                "actuator", f"a ReactionWheelActuator with {m} axes", repr(actuator)
            )
        actuator.reset()
    if limiter is not None and not callable(limiter):
        raise ArgumentTypeError("limiter", "a TorqueLimiter or callable", type(limiter).__name__)
    if reset and callable(getattr(controller, "reset", None)):
        controller.reset()
    read = _measurement_chain(measurement, noise, estimator, noise_seed, sensor, n, noise_kind)
    if sensor is not None:
        if not callable(sensor):
            raise ArgumentTypeError("sensor", "None or a callable sensor(t, x)", type(sensor).__name__)
        if callable(getattr(sensor, "reset", None)):
            sensor.reset()

    xs = np.empty((n_steps + 1, n))
    u_cmd = np.empty((n_steps, m))
    u_app = np.empty((n_steps, m))
    d_log = np.zeros((n_steps, n_d))
    solve_time = np.empty(n_steps)
    step_time = np.empty(n_steps)
    gamma = np.full(n_steps, np.nan)
    status: list[str] = []
    info: list[Any] = []
    xs[0] = x
    for k in range(n_steps):
        t = k * step_dt
        if read is not None:
            measured = read(x, u_app[k - 1] if k else None)
        else:
            measured = (x if sensor is None
                        else _finite_output(sensor(t, x), "sensor", "sensor(t, x)", t, None))
        start = time.perf_counter()
        step_inputs = read.step_inputs(controller) if read is not None else None
        u = np.asarray(
            controller.step(measured) if step_inputs is None else controller.step(measured, step_inputs),
            dtype=float,
        ).reshape(-1)
        step_time[k] = time.perf_counter() - start
        if u.shape != (m,) or not np.all(np.isfinite(u)):
            raise InvalidArgumentError(
                "controller", f"step(x) returning {m} finite values", f"{u!r} at step {k}"
            )
        last = getattr(controller, "last", None)
        status.append(str(getattr(last, "status", "unknown")))
        solve_time[k] = float(getattr(last, "solve_time", step_time[k]))
        g = getattr(last, "gamma", None)
        if g is not None:
            gamma[k] = float(g)
        info.append(last)
        u_cmd[k] = u
        applied = _finite_output(limiter(u), "limiter", "limiter(u)", t, m) if limiter is not None else u
        if actuator is not None:
            applied = _finite_output(actuator.step(applied), "actuator", "actuator.step(u)", t, m)
        if callable(begin_sample):
            stage_rows.append(dict(begin_sample(t, x, applied) or {}))
        u_app[k] = applied if stage is None else sim_plant.applied(t, x, applied)
        if d_fn is not None:
            d_log[k] = disturbance_at(d_fn, t, x)
        x = sim_plant.advance(x, applied, t, d_fn)
        xs[k + 1] = x
        if progress is not None:
            progress(k + 1, n_steps)
    attitude = (
        np.array([sim_plant.attitude_euler(x_k) for x_k in xs])
        if getattr(sim_plant, "has_attitude", False) else None
    )
    return Trajectory(
        t=np.arange(n_steps + 1) * step_dt, x=xs, u_cmd=u_cmd, u_applied=u_app, d=d_log,
        status=status, solve_time=solve_time, step_time=step_time, gamma=gamma, info=info,
        plant=sim_plant.kind, dt=step_dt,
        stage_log={**_stack_rows(stage_rows), **({} if read is None else read.log())},
        attitude_euler=attitude,
        state_names=_plant_names(plant, "state_names", n), input_names=_plant_names(plant, "input_names", m),
    )


def _finite_output(value: Any, name: str, call: str, t: float, size: int | None) -> np.ndarray:
    """A callback's output as finite floats (``size`` of them if given), else an error naming it and ``t``."""
    out = np.asarray(value, dtype=float)
    if size is not None:
        out = out.reshape(-1)
    if (size is not None and out.shape != (size,)) or not np.all(np.isfinite(out)):
        count = f"{size} " if size is not None else ""
        expected = f"{call} returning {count}finite values"
        raise InvalidArgumentError(name, expected, f"{out.tolist()} at t = {t:.9g} s")
    return out


def _stack_rows(rows: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Per-sample mappings of the input stage, stacked into one array per name."""
    if not rows:
        return {}
    names = sorted({name for row in rows for name in row})
    out = {}
    for name in names:
        if all(name in row for row in rows):
            out[name] = np.asarray([row[name] for row in rows])
    return out


class _MeasurementChain:
    """Sensor ``y = C x + v`` and, optionally, an estimator: what the controller steps on."""

    def __init__(self, c: np.ndarray, sigma: np.ndarray, estimator: Any, seed: int,
                 noise_kind: str = "gaussian") -> None:
        self.c, self.sigma, self.estimator = c, sigma, estimator
        self.uniform = noise_kind == "uniform"
        self.rng = np.random.default_rng(seed)
        self.x_hat: list[np.ndarray] = []
        self.d_hat: list[np.ndarray] = []
        if estimator is not None and callable(getattr(estimator, "reset", None)):
            estimator.reset()

    def __call__(self, x: np.ndarray, u_prev: np.ndarray | None) -> np.ndarray:
        p = self.c.shape[0]
        draw = self.rng.uniform(-1.0, 1.0, p) if self.uniform else self.rng.standard_normal(p)
        y = self.c @ x + self.sigma * draw
        if self.estimator is None:
            return y
        x_hat = np.asarray(self.estimator.update(y, u_prev), dtype=float)
        self.x_hat.append(x_hat.copy())
        d_hat = getattr(self.estimator, "d_hat", None)
        if d_hat is not None and np.size(d_hat):
            self.d_hat.append(np.asarray(d_hat, dtype=float).copy())
        return x_hat

    def step_inputs(self, controller: Any) -> StepInputs | None:
        """``StepInputs(d_hat=...)`` for a controller that takes the disturbance estimate."""
        if self.d_hat and "d_hat" in getattr(controller, "accepts", ()):
            return StepInputs(d_hat=self.d_hat[-1])
        return None

    def log(self) -> dict[str, np.ndarray]:
        out = {}
        if self.x_hat:
            out["x_hat"] = np.asarray(self.x_hat)
        if self.d_hat:
            out["d_hat"] = np.asarray(self.d_hat)
        return out


def _measurement_chain(
    measurement: ArrayLike | None, noise: float | ArrayLike | None, estimator: Any, seed: int,
    sensor: Any, n: int, noise_kind: str = "gaussian",
) -> _MeasurementChain | None:
    """The checked sensor-estimator chain of :func:`simulate`, or ``None`` without ``measurement``."""
    if noise_kind not in NOISE_KINDS:
        raise InvalidArgumentError("noise_kind", f"one of {NOISE_KINDS}", repr(noise_kind))
    if measurement is None:
        for name, value in (("noise", noise), ("estimator", estimator)):
            if value is not None:
                raise InvalidArgumentError(name, "measurement=C with it (what is measured)", "no measurement")
        return None
    if sensor is not None:
        raise InvalidArgumentError("sensor", "None with measurement= (one sensor)", "both given")
    try:
        c = np.atleast_2d(np.asarray(measurement, dtype=float))
    except (TypeError, ValueError) as err:
        raise InvalidArgumentError("measurement", f"a real p x {n} matrix", str(err)) from None
    if c.ndim != 2 or c.shape[1] != n or not np.all(np.isfinite(c)):
        raise InvalidArgumentError("measurement", f"a finite p x {n} matrix", f"shape {c.shape}")
    p = c.shape[0]
    sigma = np.zeros(p) if noise is None else np.broadcast_to(np.asarray(noise, dtype=float), (p,)).copy()
    if not np.all(np.isfinite(sigma)) or np.any(sigma < 0.0):
        raise InvalidArgumentError("noise", "standard deviations >= 0 (a float or one per output)",
                                   repr(np.asarray(noise).tolist()))
    if estimator is not None:
        if not callable(getattr(estimator, "update", None)):
            raise ArgumentTypeError("estimator", "an object with update(y, u_prev)", type(estimator).__name__)
        c_est = getattr(estimator, "C", None)
        if c_est is not None and np.shape(c_est) != c.shape:
            raise InvalidArgumentError("estimator", f"an estimator of {p} outputs (measurement's)",
                                       f"one built for C of shape {np.shape(c_est)}")
    return _MeasurementChain(c, sigma, estimator, int(seed), noise_kind)


def _plant_names(plant: Any, attribute: str, size: int) -> tuple[str, ...]:
    """The plant's (or its model's) names of one kind when it gives ``size`` of them, else ``()``."""
    names = getattr(plant, attribute, None)
    if names is None:
        names = getattr(getattr(plant, "model", None), attribute, None)
    try:
        names = tuple(str(name) for name in names)
    except TypeError:
        return ()
    return names if len(names) == size else ()
