"""Scheduled robust MPC: the polytope rebuilt at the measured state before every solve.

Paper P linearises the satellite once, at its initial attitude, and its robust MPC covers the
inertia uncertainty of that one linearisation. Two ways to take the nonlinear kinematics into
account (SPEC section 1, going beyond paper P):

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

from lmi import KothareProblem, LMISolution
from lmi.status import INACCURATE, OPTIMAL
from models import PolytopicModel, RigidSatellite
from rmpc.controller import StepInfo, StepInputs, check_step_inputs
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, SolverError
from toolkit_common.validation import as_vector, check_choice, check_positive

__all__ = ["ScheduledRMPC"]

_USABLE = (OPTIMAL, INACCURATE)


class ScheduledRMPC:
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
        ``"ScheduledRMPC"``, the short name in reports.
    last : StepInfo or None
        As for :class:`~rmpc.RMPC`; ``extra["build_time"]`` is the time spent building the
        polytope and the problem (s), which ``solve_time`` does not include.

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import ScheduledRMPC
    >>> sat = RigidSatellite.paper_p()
    >>> ctrl = ScheduledRMPC.for_satellite(sat, dt=0.01, spread=0.3, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]),
    ...                                    R=np.eye(3), u_max=1.0)
    >>> u = ctrl.step(sat.initial_state())
    >>> ctrl.last.status, bool(np.linalg.norm(u) <= 1.0 + 1e-6)
    ('optimal', True)
    """

    name = "ScheduledRMPC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        polytope_at: Callable[[np.ndarray], PolytopicModel],
        Q: Any,
        R: Any,
        u_max: Any = None,
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
        if input_constraint == "auto":
            input_constraint = None if u_max is None else "ellipsoid"
        self.polytope_at = polytope_at
        self.options = {
            "Q": Q, "R": R, "input_constraint": input_constraint, "u_max": u_max, "backend": backend,
            "formulation": formulation, "certificate_tol": certificate_tol,
        }
        self.on_failure = check_choice(on_failure, "on_failure", ("fallback", "raise"))
        self.hold_radius = check_positive(hold_radius, "hold_radius", allow_zero=True)
        self.n_states: int | None = None
        self.n_inputs: int | None = None
        self.dt: float | None = None
        self.last: StepInfo | None = None
        self._gain: np.ndarray | None = None

    @classmethod
    def for_satellite(
        cls,
        satellite: RigidSatellite,
        dt: float,
        spread: float,
        Q: Any,
        R: Any,
        u_max: Any = None,
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

        def polytope_at(x: np.ndarray) -> PolytopicModel:
            x_op = np.concatenate((np.asarray(x[:3], dtype=float), np.zeros(3)))
            return satellite.polytope(x_op, dt, spread, mode)

        return cls(polytope_at, Q, R, u_max, input_constraint, **options)

    @property
    def gain(self) -> np.ndarray | None:
        """The gain currently applied (the last certified ``F``), or ``None``."""
        return None if self._gain is None else self._gain.copy()

    def reset(self) -> None:
        """Forget the last gain and step."""
        self.last = None
        self._gain = None

    def problem_at(self, x: Any) -> KothareProblem:
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

    def solve(self, x: Any) -> LMISolution:
        """Solve on the polytope at ``x``; no side effects on the controller."""
        x = as_vector(x, "x")
        return self.problem_at(x).solve(x)

    def step(self, x: Any, inputs: StepInputs | None = None) -> np.ndarray:
        """Rebuild the polytope at ``x``, solve, and return ``u = F x``."""
        check_step_inputs(inputs, self.accepts, self.name)
        x = as_vector(x, "x", self.n_states)
        if float(np.linalg.norm(x)) <= self.hold_radius:
            gain = self._current_gain(x)
            self.last = StepInfo(status="reused", extra={"solution": None, "reason": "near origin"})
            return gain @ x
        start = time.perf_counter()
        problem = self.problem_at(x)
        build = time.perf_counter() - start
        sol = problem.solve(x)
        usable = sol.status in _USABLE and sol.certificate is not None and sol.certificate.ok
        if usable:
            assert sol.F is not None
            self._gain = sol.F
            self.last = StepInfo(
                status=sol.status, solve_time=sol.solve_time, gamma=sol.gamma, iterations=sol.iterations,
                extra={"solution": sol, "build_time": build},
            )
            return self._gain @ x
        if self.on_failure == "raise":
            raise SolverError(
                f"ScheduledRMPC.step: the LMI solve at x = {x.tolist()} returned status {sol.status!r} "
                f"(solver: {sol.solver_status!r}) and on_failure='raise'"
            )
        gain = self._current_gain(x)
        self.last = StepInfo(
            status=sol.status, solve_time=sol.solve_time, iterations=sol.iterations, fallback=True,
            extra={"solution": sol, "build_time": build, "had_gain": self._gain is not None},
        )
        return gain @ x

    def _current_gain(self, x: np.ndarray) -> np.ndarray:
        if self._gain is not None:
            return self._gain
        m = self.n_inputs if self.n_inputs is not None else self.problem_at(x).n_inputs
        return np.zeros((m, x.shape[0]))
