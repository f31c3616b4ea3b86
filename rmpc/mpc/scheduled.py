"""Scheduled robust MPC: the polytope rebuilt at the measured state before every solve.

Paper P linearises the satellite once, at its initial attitude, and its robust MPC covers the
inertia uncertainty of that one linearisation. Two ways to take the nonlinear kinematics into
account (going beyond paper P):

- the *covering* polytope (``RigidSatellite.polytope(..., attitude_range=...)``): one polytope
  that contains the frozen-attitude model at every attitude of a box, so the LMI guarantees
  (invariance, the input bound, the cost bound) hold along any manoeuvre inside it; used with
  the ordinary :class:`~rmpc.RMPC`;
- *scheduling* (this module): at every step the polytope is rebuilt at the measured attitude and
  the LMIs are solved on it. Each solve certifies the model frozen at the current attitude; the
  guarantees do not extend along the manoeuvre (the next step's model differs), but the polytope
  is as small as the inertia uncertainty alone and the conservatism of the covering box is
  avoided. The price is a new problem per step: no warm start.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike

from lmi import KothareProblem, LMISolution
from models import PolytopicModel, RigidSatellite
from rmpc.controller import StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode
from rmpc.io.saveable import Saveable
from rmpc.mpc.diagnosis import diagnose
from rmpc.mpc.fallback import CertifiedGain
from rmpc.mpc.robust_mpc import input_constraint_kind
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["SatellitePolytopes", "ScheduledRMPC"]


class SatellitePolytopes:
    """``polytope_at`` of :meth:`ScheduledRMPC.for_satellite`: the rigid satellite's inertia
    polytope at the measured attitude with zero rates.

    A class rather than a closure, so that the schedule pickles and a saved controller can name
    it (:meth:`ScheduledRMPC.save`).

    Parameters
    ----------
    satellite : RigidSatellite
    dt, spread : float
    mode : {"scalar", "box"}
        As :meth:`models.RigidSatellite.polytope`.
    """

    def __init__(self, satellite: RigidSatellite, dt: float, spread: float, mode: str) -> None:
        self.satellite, self.dt, self.spread, self.mode = satellite, float(dt), float(spread), mode

    def __call__(self, x: np.ndarray) -> PolytopicModel:
        x_op = np.concatenate((np.asarray(x[:3], dtype=float), np.zeros(3)))
        return self.satellite.polytope(x_op, self.dt, self.spread, self.mode)  # type: ignore[arg-type]


class ScheduledRMPC(Saveable):
    """Robust MPC whose polytope is rebuilt at the measured state at every step.

    Parameters
    ----------
    polytope_at : callable
        ``polytope_at(x) -> PolytopicModel``: the polytope to solve on at the measured state
        ``x`` (all with the same sizes and sample time).
    Q, R, u_max, input_constraint
        As for :class:`~rmpc.RMPC`.
    backend, formulation, certificate_tol
        Passed to :class:`lmi.KothareProblem`.
    on_failure : {"fallback", "raise"}
        A failed or uncertified solve keeps the last certified gain (``"fallback"``) or raises
        :class:`~toolkit_common.errors.SolverError`.
    hold_radius : float
        Below this state norm the last gain is kept (the problem degenerates at the origin).

    Attributes
    ----------
    name : str
        ``"ScheduledRMPC"``.
    accepts : frozenset of str
        Empty: :meth:`step` takes no :class:`~rmpc.controller.StepInputs`.
    last : StepInfo or None
        As for :class:`~rmpc.RMPC`; ``extra["build_time"]`` is the time spent building the
        polytope and the problem (s), which ``solve_time`` does not include.
    certified : CertifiedGain
        The last certified gain (:mod:`rmpc.mpc.fallback`, as for :class:`~rmpc.RMPC`).

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import ScheduledRMPC
    >>> sat = RigidSatellite.paper_p()
    >>> ctrl = ScheduledRMPC.for_satellite(sat, dt=0.01, spread=0.3, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]),
    ...                                    R=np.eye(3), u_max=1.0)
    >>> u = ctrl.step(sat.initial_state())
    >>> print(ctrl.last.status, bool(np.linalg.norm(u) <= 1.0 + 1e-6))
    optimal True
    """

    name: ClassVar[str] = "ScheduledRMPC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        polytope_at: Callable[[np.ndarray], PolytopicModel],
        Q: ArrayLike,
        R: ArrayLike,
        u_max: ArrayLike | None = None,
        input_constraint: Literal["ellipsoid", "peak"] | str | None = "auto",
        *,
        backend: str = "ipm",
        formulation: Literal["delta", "delta_shared", "standard"] = "delta_shared",
        certificate_tol: float = 1e-7,
        on_failure: Literal["fallback", "raise"] = "fallback",
        hold_radius: float = 1e-9,
    ) -> None:
        if not callable(polytope_at):
            expected = "a callable x -> PolytopicModel"
            raise ArgumentTypeError("polytope_at", expected, type(polytope_at).__name__)
        input_constraint = input_constraint_kind(input_constraint, u_max)
        self.polytope_at = polytope_at
        self.options = {
            "Q": Q, "R": R, "input_constraint": input_constraint, "u_max": u_max, "backend": backend,
            "formulation": formulation, "certificate_tol": certificate_tol,
        }
        self.certified = CertifiedGain("ScheduledRMPC", on_failure, hold_radius)
        self.n_states: int | None = None
        self.n_inputs: int | None = None
        self.dt: float | None = None
        self.last: StepInfo | None = None

    @classmethod
    def for_satellite(
        cls,
        satellite: RigidSatellite,
        dt: float,
        spread: float,
        Q: ArrayLike,
        R: ArrayLike,
        u_max: ArrayLike | None = None,
        input_constraint: str | None = "auto",
        *,
        mode: Literal["scalar", "box"] = "scalar",
        **options: Any,
    ) -> ScheduledRMPC:
        """Scheduling on the rigid satellite: its inertia polytope at the measured attitude, zero rates."""
        if not isinstance(satellite, RigidSatellite):
            raise ArgumentTypeError("satellite", "a models.RigidSatellite", type(satellite).__name__)
        dt = check_positive(dt, "dt")
        satellite.inertia_vertices(spread, mode)  # checks spread and mode now, not at the first step
        return cls(SatellitePolytopes(satellite, dt, spread, mode), Q, R, u_max, input_constraint, **options)

    # -- save and load ---------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The schedule (the satellite's inertia, ``dt``, ``spread``, ``mode``) and the options; a
        schedule that is a user's function cannot be saved (a file holds data, not code)."""
        schedule = self.polytope_at
        if not isinstance(schedule, SatellitePolytopes):
            raise InvalidArgumentError(
                "polytope_at", "the schedule of ScheduledRMPC.for_satellite to save the controller (a file "
                "holds data, not code; pickle keeps a function that pickles)",
                getattr(schedule, "__qualname__", type(schedule).__name__),
            )
        return encode({
            "schedule": {"inertia": schedule.satellite.inertia, "dt": schedule.dt, "spread": schedule.spread,
                         "mode": schedule.mode},
            "options": self.options, "on_failure": self.on_failure, "hold_radius": self.hold_radius,
        }, "ScheduledRMPC design")

    @classmethod
    def _from_design(cls, design: Design) -> ScheduledRMPC:
        schedule = design.part("schedule")
        options = design.part("options")
        satellite = RigidSatellite(schedule.array("inertia", 2))
        ctrl = cls.for_satellite(
            satellite, dt=schedule.number("dt"), spread=schedule.number("spread"),
            Q=options.array("Q", 2), R=options.array("R", 2), u_max=options.bound("u_max"),
            input_constraint=options.optional_text("input_constraint"),
            mode=schedule.text("mode"),
            backend=options.text("backend"), formulation=options.text("formulation"),
            certificate_tol=options.number("certificate_tol"), on_failure=design.text("on_failure"),
            hold_radius=design.number("hold_radius"),
        )
        schedule.finish()
        options.finish()
        return ctrl

    @property
    def on_failure(self) -> str:
        """``"fallback"`` or ``"raise"``."""
        return self.certified.on_failure

    @property
    def hold_radius(self) -> float:
        """Below this state norm the last gain is kept without a solve."""
        return self.certified.hold_radius

    @property
    def gain(self) -> np.ndarray | None:
        """The gain currently applied (the last certified ``F``), or ``None``."""
        return self.certified.gain

    def reset(self) -> None:
        """Forget the last gain and step."""
        self.last = None
        self.certified.reset()

    def problem_at(self, x: ArrayLike) -> KothareProblem:
        """The Kothare problem on the polytope at ``x``."""
        poly = self.polytope_at(np.asarray(x, dtype=float))
        if not isinstance(poly, PolytopicModel):
            expected = "a callable returning a PolytopicModel"
            raise ArgumentTypeError("polytope_at", expected, type(poly).__name__)
        if self.n_states is None:
            self.n_states, self.n_inputs, self.dt = poly.n_states, poly.n_inputs, poly.dt
        elif (poly.n_states, poly.n_inputs) != (self.n_states, self.n_inputs):
            raise InvalidArgumentError(
                "polytope_at", f"polytopes of {self.n_states} states and {self.n_inputs} inputs",
                f"{poly.n_states} states and {poly.n_inputs} inputs",
            )
        return KothareProblem(poly.A, poly.B, dt=poly.dt, **self.options)

    def solve(self, x: ArrayLike) -> LMISolution:
        """Solve on the polytope at ``x``; no side effects on the controller."""
        x = as_vector(x, "x")
        return self.problem_at(x).solve(x)

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Rebuild the polytope at ``x``, solve, and return ``u = F x``.

        ``inputs`` must be ``None`` or an empty :class:`~rmpc.controller.StepInputs` (:attr:`accepts`).
        """
        x = as_vector(x, "x", self.n_states)
        check_step_inputs(inputs, self.accepts, "ScheduledRMPC")
        kept = self.certified
        if kept.near_origin(x):
            u, self.last = kept.reuse(x, self._gain_shape(x), "near origin")
            return u
        start = time.perf_counter()
        problem = self.problem_at(x)
        build = time.perf_counter() - start
        sol = problem.solve(x)
        u, self.last = kept.take(
            sol, x, self._gain_shape(x), extra={"build_time": build}, failure_extra={"build_time": build},
            diagnose=lambda: diagnose(problem.data, x, sol.status,
                                      backend="clarabel" if problem.backend == "clarabel" else "ipm"),
        )
        return u

    def _gain_shape(self, x: np.ndarray) -> tuple[int, int]:
        """``(m, n)`` of the gain (the zero gain applied before the first certified one)."""
        m = self.n_inputs if self.n_inputs is not None else self.problem_at(x).n_inputs
        return (m, x.shape[0])
