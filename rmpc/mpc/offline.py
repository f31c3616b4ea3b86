"""Off-line robust MPC (Wan & Kothare 2003): nested invariant ellipsoids looked up on-line.

Reference: Z. Wan, M. V. Kothare, "An efficient off-line formulation of robust model predictive
control using linear matrix inequalities", Automatica 39(5), 837-846, 2003.

Off-line, :class:`lmi.offline.NestedKothareProblem` computes ellipsoids
``E_1 ⊇ E_2 ⊇ ... ⊇ E_N`` (``E_i = {x : x' Q_i^-1 x <= 1}``) with gains ``F_i``. On-line, the
controller finds the smallest ``E_i`` that contains ``x`` and applies ``u = F x`` with
``F = alpha F_i + (1 - alpha) F_{i+1}``, ``alpha`` solving
``x' (alpha Q_i^-1 + (1 - alpha) Q_{i+1}^-1) x = 1`` in closed form. See
``docs/offline_rmpc.rst`` for what is guaranteed.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike

from lmi.status import INFEASIBLE, OPTIMAL
from models import PolytopicModel
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode, plant_design, snapshot
from rmpc.io.saveable import Saveable
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_bool, check_choice, check_positive

if TYPE_CHECKING:  # lmi.offline is imported when a controller is built
    from lmi.offline import OfflineTable

__all__ = ["OUTSIDE", "OfflineRMPC"]

#: Status of a step whose state lies outside the largest ellipsoid (``F_1`` applied, no guarantee).
OUTSIDE = Status.OUTSIDE
#: A state with ``x' Q_i^-1 x <= 1 + LEVEL_TOL`` counts as inside ``E_i``. Each design state lies on
#: the boundary of its own ellipsoid (the LMI ``[[1, x'], [x, Q]] >= 0`` is tight at the optimum),
#: and the solver's accuracy (1e-8) puts it at levels up to ``1 + 9e-8`` (measured on paper P's
#: satellite). At level ``1 + LEVEL_TOL`` the input bound holds to a factor ``1 + 5e-7``.
LEVEL_TOL = 1e-6
_ONE = 1.0 + LEVEL_TOL


class OfflineRMPC(Saveable):
    """Off-line robust MPC over a polytopic model (Wan & Kothare 2003), the ``step(x)`` protocol.

    Parameters
    ----------
    plant : PolytopicModel
        The polytope ``Co{[A_j B_j]}`` of discrete-time models.
    Q, R, u_max, input_constraint
        As :class:`rmpc.RMPC` (``input_constraint="auto"``: ``"ellipsoid"`` when ``u_max`` is
        given, none otherwise).
    output_matrix, y_max : array_like, optional
        Output constraints ``|(C x(k+i))_r| <= y_max_r``, as :class:`rmpc.RMPC`.
    x_design : array_like, optional
        One state ``(n,)``: the design states are generated from it along ``path``. Several
        states ``(k, n)``: used as given, outermost first (states not strictly inside the
        previous ellipsoid are skipped and listed in ``table.skipped``). ``None`` (default):
        the table is designed from the first state passed to :meth:`step`, and designed anew
        whenever a run (after :meth:`reset`) starts outside its largest ellipsoid.
    n_ellipsoids : int
        Number of ellipsoids generated along ``path`` (default 15).
    shrink : float
        In ``(0, 1)``. ``"ray"``: ``x_{i+1} = shrink x_i``. ``"trajectory"``: ``x_{i+1}`` is
        the first state of the nominal closed loop under ``F_i`` with
        ``x' Q_i^-1 x <= shrink^2``. Default 0.5.
    path : {"ray", "trajectory"}
        How design states are generated from one state: geometrically spaced along its ray
        (default) or along the closed loop of the nominal model.
    interpolate : bool
        Interpolate between neighbouring gains (default). Between neighbours where Wan &
        Kothare's condition (18) fails, the outer gain is applied instead (recorded in
        ``table.interpolable``).
    backend : {"ipm", "clarabel", "cvxpy"}
        The design's back-end (:class:`lmi.offline.NestedKothareProblem`): ``"ipm"`` (default),
        the on-line problem's interior-point method with the nesting block; ``"cvxpy"`` with
        ``solver`` (default ``"CLARABEL"``) the LMIs written with cvxpy.
    solver, solver_options, formulation, certificate_tol
        Passed to :class:`lmi.offline.NestedKothareProblem` (``solver`` only with
        ``backend="cvxpy"``).
    cost : {"worst_case", "nominal"}
        ``"nominal"``: each ellipsoid bounds the cost on ``plant.nominal`` with robust invariance
        on every vertex (the nominal form of :mod:`lmi.forms`, nested).
    lyapunov : {"common"}
        The only Lyapunov form the nesting argument holds for (see
        :class:`lmi.offline.NestedKothareProblem`); the vertex forms raise an error.

    Attributes
    ----------
    name : str
        ``"OfflineRMPC"``, the short name in reports.
    table : OfflineTable or None
        The designed sequence (certified entries only).
    last : StepInfo or None
        The last step: ``status`` (``"optimal"`` inside ``E_1``, ``"outside"`` beyond it, or the
        design's failure word when no ellipsoid could be designed), ``solve_time`` (the lookup
        time, plus the design time on a step that designed the table), ``gamma`` (the stored
        bound ``gamma_i`` of the ellipsoid in use) and ``extra = {"index": i, "alpha": alpha}``
        (``i`` counted from 0; ``alpha = 1`` applies ``F_i`` alone).

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import OfflineRMPC
    >>> sat = RigidSatellite.paper_p()
    >>> x0 = sat.initial_state()
    >>> plant = sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar")
    >>> ctrl = OfflineRMPC(plant, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]), R=np.eye(3), u_max=1.0,
    ...                    x_design=x0, n_ellipsoids=4)
    >>> ctrl.table.n_ellipsoids
    4
    >>> u = ctrl.step(x0)
    >>> ctrl.last.status, ctrl.last.extra["index"], bool(np.linalg.norm(u) <= 1.0)
    ('optimal', 0, True)
    """

    name = "OfflineRMPC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: PolytopicModel,
        Q: ArrayLike,
        R: ArrayLike,
        u_max: ArrayLike | None = None,
        input_constraint: Literal["ellipsoid", "peak"] | str | None = "auto",
        *,
        output_matrix: ArrayLike | None = None,
        y_max: ArrayLike | None = None,
        x_design: ArrayLike | None = None,
        n_ellipsoids: int = 15,
        shrink: float = 0.5,
        path: Literal["ray", "trajectory"] = "ray",
        interpolate: bool = True,
        backend: str = "ipm",
        solver: str | None = None,
        solver_options: dict[str, Any] | None = None,
        formulation: Literal["delta", "delta_shared", "standard"] = "delta_shared",
        certificate_tol: float = 1e-7,
        cost: Literal["worst_case", "nominal"] = "worst_case",
        lyapunov: Literal["common"] = "common",
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            raise ArgumentTypeError("plant", "a models.PolytopicModel", type(plant).__name__)
        if input_constraint == "auto":
            input_constraint = None if u_max is None else "ellipsoid"
        if not check_positive(shrink, "shrink") < 1.0:
            raise InvalidArgumentError("shrink", "a number in (0, 1)", repr(shrink))
        from lmi.offline import check_ellipsoid_count

        check_ellipsoid_count(n_ellipsoids, shrink)
        check_bool(interpolate, "interpolate")
        self.path = check_choice(path, "path", ("ray", "trajectory"))
        self.plant = plant
        from lmi.offline import NestedKothareProblem

        self.problem = NestedKothareProblem(
            plant.A, plant.B, Q, R, dt=plant.dt, input_constraint=input_constraint, u_max=u_max,
            output_matrix=output_matrix, y_max=y_max, backend=backend, solver=solver,
            solver_options=solver_options,
            formulation=formulation, certificate_tol=certificate_tol,
            cost=cost, lyapunov=lyapunov, nominal=plant.nominal,
        )
        self.n_ellipsoids = int(n_ellipsoids)
        self.shrink = float(shrink)
        self._interpolate = interpolate
        self.dt = plant.dt
        self._n, self._m = plant.n_states, plant.n_inputs
        self.last: StepInfo | None = None
        self.table: OfflineTable | None = None
        self._auto = x_design is None
        self._fresh = True
        self._count = 0
        # the constructor's arguments as save writes them (copies: later changes by the caller do not leak in)
        self._arguments: dict[str, Any] = snapshot({
            "Q": Q, "R": R, "u_max": u_max, "input_constraint": input_constraint,
            "output_matrix": output_matrix, "y_max": y_max, "n_ellipsoids": self.n_ellipsoids,
            "shrink": self.shrink, "path": self.path, "backend": backend, "solver": solver,
            "solver_options": solver_options, "formulation": formulation,
            "certificate_tol": certificate_tol, "cost": cost, "lyapunov": lyapunov,
        })
        if x_design is not None:
            self._design_table(x_design)

    @classmethod
    def from_table(
        cls,
        plant: PolytopicModel,
        table: OfflineTable,
        Q: ArrayLike,
        R: ArrayLike,
        u_max: ArrayLike | None = None,
        input_constraint: Literal["ellipsoid", "peak"] | str | None = "auto",
        **options: Any,
    ) -> OfflineRMPC:
        """The controller of an ellipsoid table designed before (nothing is solved).

        Parameters
        ----------
        plant, Q, R, u_max, input_constraint, options
            As the constructor (``x_design`` excepted): the problem the table was designed for.
        table : lmi.offline.OfflineTable
            The table, e.g. ``other.table`` of a designed controller; its ellipsoids must have the
            plant's sizes. It is kept as the controller's table, never redesigned.

        Examples
        --------
        >>> import numpy as np
        >>> from models import PolytopicModel
        >>> from rmpc import OfflineRMPC
        >>> plant = PolytopicModel([(np.array([[1.1]]), np.array([[1.0]])),
        ...                         (np.array([[1.1]]), np.array([[0.5]]))], dt=1.0)
        >>> ctrl = OfflineRMPC(plant, Q=np.eye(1), R=np.eye(1), u_max=1.0, x_design=[1.0], n_ellipsoids=3)
        >>> copy = OfflineRMPC.from_table(plant, ctrl.table, Q=np.eye(1), R=np.eye(1), u_max=1.0)
        >>> bool(copy.step([0.4]) == ctrl.step([0.4])), copy.table is ctrl.table
        (True, True)
        """
        if "x_design" in options:
            raise InvalidArgumentError("x_design", "no x_design (the table is given)",
                                       repr(options["x_design"]))
        from lmi.offline import OfflineTable

        if not isinstance(table, OfflineTable):
            raise ArgumentTypeError("table", "an lmi.offline.OfflineTable", type(table).__name__)
        ctrl = cls(plant, Q, R, u_max, input_constraint, **options)
        n, m = plant.n_states, plant.n_inputs
        for i, entry in enumerate(table.ellipsoids):
            shapes = (np.shape(entry.Q), np.shape(entry.F))
            if shapes != ((n, n), (m, n)):
                raise InvalidArgumentError(
                    f"table.ellipsoids[{i}]",
                    f"Q of shape {(n, n)} and F of shape {(m, n)} (the plant's sizes)",
                    f"{shapes[0]} and {shapes[1]}",
                )
        if table.interpolable.shape != (max(table.n_ellipsoids - 1, 0),):
            raise InvalidArgumentError("table.interpolable", f"{max(table.n_ellipsoids - 1, 0)} flags",
                                       f"shape {table.interpolable.shape}")
        ctrl._store(table)
        ctrl._auto = False
        return ctrl

    @property
    def input_constraint(self) -> str | None:
        return self.problem.data.input_constraint

    @property
    def interpolate(self) -> bool:
        """Whether neighbouring gains are interpolated (may be switched on a designed table)."""
        return self._interpolate

    @interpolate.setter
    def interpolate(self, value: bool) -> None:
        self._interpolate = check_bool(value, "interpolate")
        if self.table is not None:
            self._store(self.table)

    # -- off-line ----------------------------------------------------------------------------
    def design(self, x_design: ArrayLike) -> OfflineTable:
        """Compute (and store) the table from one state (along ``path``) or from ``(k, n)`` states.

        A table designed here is kept until the next call (no automatic redesign).
        """
        table = self._design_table(x_design)
        self._auto = False
        return table

    def _design_table(self, x_design: ArrayLike) -> OfflineTable:
        arr = np.asarray(x_design, dtype=float) if not isinstance(x_design, str) else None
        if arr is None or arr.ndim not in (1, 2):
            raise InvalidArgumentError(
                "x_design", f"one state ({self._n},) or a sequence of states (k, {self._n})", repr(x_design)
            )
        if arr.ndim == 2:
            states = as_matrix(arr, "x_design", (None, self._n))
            zero = np.flatnonzero(~states.any(axis=1))
            if states.shape[0] == 0 or zero.size:
                found = "no states" if states.shape[0] == 0 else f"x = 0 at row {int(zero[0])}"
                raise InvalidArgumentError("x_design", "one or more non-zero states", found)
            table = self.problem.design(states)
        else:
            x0 = as_vector(arr, "x_design", self._n)
            if not np.any(x0):
                raise InvalidArgumentError("x_design", "a non-zero state", "x_design = 0")
            if self.path == "ray":
                table = self.problem.design_ray(x0, self.n_ellipsoids, self.shrink)
            else:
                a_nom, b_nom = self.plant.nominal
                table = self.problem.design_trajectory(
                    x0, self.n_ellipsoids, self.shrink, A=a_nom, B=b_nom
                )
        self._store(table)
        return table

    def _store(self, table: OfflineTable) -> None:
        """Precompute the lookup: one matrix whose product with ``x`` gives every level and gain."""
        self.table = table
        count, n = table.n_ellipsoids, self._n
        self._count = count
        if count == 0:
            return
        # x' Q_i^-1 x = ||C_i' x||^2 with C_i C_i' = Q_i^-1 (Cholesky).
        chol = [np.linalg.cholesky(np.linalg.inv(e.Q)).T for e in table.ellipsoids]  # type: ignore[arg-type]
        gains = [e.F for e in table.ellipsoids]
        self._lookup = np.ascontiguousarray(np.vstack([*chol, *gains]))  # type: ignore[list-item]
        self._split = count * n
        self._gammas = table.gammas.tolist()
        self._interp = (table.interpolable & self._interpolate).tolist() if count > 1 else []

    # -- save and load ------------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The plant, the constructor's arguments, whether the table is redesigned for a run that
        starts outside it (``x_design=None``), and the table (nothing designed yet: an error)."""
        if self.table is None:
            raise InvalidArgumentError(
                "OfflineRMPC", "a designed table to save (x_design=..., design(x), or a first step)",
                "no table yet",
            )
        return {
            "plant": plant_design(self.plant),
            "arguments": encode({**self._arguments, "interpolate": self._interpolate},
                                "OfflineRMPC arguments"),
            "redesign_outside": self._auto,
            "table": _table_design(self.table),
        }

    @classmethod
    def _from_design(cls, design: Design) -> OfflineRMPC:
        arguments = design.part("arguments")
        readers = {
            "Q": lambda k: arguments.array(k, 2), "R": lambda k: arguments.array(k, 2),
            "u_max": arguments.bound, "input_constraint": lambda k: arguments.optional_text(k),
            "output_matrix": lambda k: arguments.optional_array(k, 2), "y_max": arguments.bound,
            "n_ellipsoids": arguments.integer, "shrink": arguments.number, "path": arguments.text,
            "interpolate": arguments.flag, "backend": arguments.text,
            "solver": lambda k: arguments.optional_text(k),
            "solver_options": lambda k: arguments.optional_mapping(k),
            "formulation": arguments.text, "certificate_tol": arguments.number, "cost": arguments.text,
            "lyapunov": arguments.text,
        }
        values = {name: read(name) for name, read in readers.items()}
        arguments.finish()
        table = design.part("table")
        ctrl = cls.from_table(design.plant(), _table_from_design(table), **values)
        ctrl._auto = design.flag("redesign_outside")
        return ctrl

    def reset(self) -> None:
        """Forget the last step; the table is kept (see ``x_design`` for when it is redesigned)."""
        self.last = None
        self._fresh = True

    # -- on-line -----------------------------------------------------------------------------
    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Look up the gain for ``x`` and return ``u = F x``."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        z = np.asarray(x, dtype=float) if not isinstance(x, str) else None
        if z is None or z.shape != (self._n,) or not np.isfinite(z).all():
            z = as_vector(x, "x", self._n)  # raises naming the argument, or accepts a column
        if self._fresh:
            return self._first_step(z, start)
        if self._count == 0:
            return self._no_table(start)
        y = self._lookup @ z
        lev = y[: self._split]
        lev = (lev * lev).reshape(self._count, self._n).sum(axis=1)
        k = int(lev.searchsorted(_ONE, side="right"))  # how many (nested) ellipsoids hold z
        m, base = self._m, self._split
        if k == 0:
            self.last = StepInfo(status=OUTSIDE, solve_time=time.perf_counter() - start, fallback=True,
                                 extra={"index": 0, "alpha": 1.0, "level": float(lev[0])})
            return y[base : base + m]
        i = k - 1
        alpha = 1.0
        u = y[base + i * m : base + k * m]
        if k < self._count and self._interp[i]:
            a, b = lev[i], lev[k]
            alpha = min(float((b - 1.0) / (b - a)), 1.0)
            u = alpha * u + (1.0 - alpha) * y[base + k * m : base + (k + 1) * m]
        self.last = StepInfo(status=OPTIMAL, solve_time=time.perf_counter() - start, gamma=self._gammas[i],
                             extra={"index": i, "alpha": alpha})
        return u

    def _no_table(self, start: float) -> np.ndarray:
        """No certified ellipsoid: ``u = 0`` and the design's failure as the status."""
        table = self.table
        failure = (table.failed_status if table is not None else None) or INFEASIBLE
        reason = table.stop_reason if table is not None else "not designed"
        self.last = StepInfo(status=failure, solve_time=time.perf_counter() - start, fallback=True,
                             extra={"index": None, "alpha": None, "stop_reason": reason})
        return np.zeros(self._m)

    def _first_step(self, z: np.ndarray, start: float) -> np.ndarray:
        """The first step of a run: with ``x_design=None``, design from ``z`` unless the table holds it."""
        if self._auto and not np.any(z) and self.table is None:
            # Nothing to design from at the origin; u = 0 is exact there. Design at the next state.
            self.last = StepInfo(status=OPTIMAL, solve_time=time.perf_counter() - start,
                                 extra={"index": None, "alpha": None})
            return np.zeros(self._m)
        self._fresh = False
        design_time = 0.0
        inside = self._count > 0 and float(np.sum((self._lookup[: self._n] @ z) ** 2)) <= _ONE
        if self._auto and not inside:
            t0 = time.perf_counter()
            self._design_table(z)
            design_time = time.perf_counter() - t0
        u = self.step(z)
        assert self.last is not None
        self.last = StepInfo(
            status=self.last.status, solve_time=time.perf_counter() - start, gamma=self.last.gamma,
            fallback=self.last.fallback, extra={**self.last.extra, "design_time": design_time},
        )
        return u



def _table_design(table: OfflineTable) -> dict[str, Any]:
    """An :class:`~lmi.offline.OfflineTable` as JSON values (every field, each ellipsoid's too)."""
    entries = [
        {
            "status": e.status, "x": e.x, "gamma": e.gamma, "Q": e.Q, "Y": e.Y, "F": e.F,
            "certificate": None if e.certificate is None else {"margins": dict(e.certificate.margins),
                                                                "tol": e.certificate.tol},
            "nesting_margin": e.nesting_margin, "solve_time": e.solve_time,
            "solver_status": e.solver_status, "iterations": e.iterations,
        }
        for e in table.ellipsoids
    ]
    return encode({
        "ellipsoids": entries, "interpolation_margins": table.interpolation_margins,
        "interpolable": table.interpolable, "design_time": table.design_time,
        "stop_reason": table.stop_reason, "failed_status": table.failed_status,
        "skipped": [list(item) for item in table.skipped],
    }, "OfflineRMPC table")


def _table_from_design(design: Design) -> OfflineTable:
    """The :class:`~lmi.offline.OfflineTable` :func:`_table_design` wrote."""
    from lmi.certificate import Certificate
    from lmi.offline import NestedEllipsoid, OfflineTable

    entries = []
    for part in design.parts("ellipsoids"):
        cert = part.optional_part("certificate")
        certificate = None
        if cert is not None:
            margins = cert.mapping("margins")
            certificate = Certificate({str(k): float(v) for k, v in margins.items()}, cert.number("tol"))
            cert.finish()
        entries.append(NestedEllipsoid(
            status=part.text("status"), x=part.array("x", 1), gamma=part.number("gamma"),
            Q=part.array("Q", 2), Y=part.array("Y", 2), F=part.array("F", 2), certificate=certificate,
            nesting_margin=part.number("nesting_margin"), solve_time=part.number("solve_time"),
            solver_status=part.text("solver_status"), iterations=part.optional_integer("iterations"),
        ))
        part.finish()
    skipped = design.value("skipped")
    if not isinstance(skipped, list) or not all(isinstance(s, list) and len(s) == 2 for s in skipped):
        raise InvalidArgumentError("design.table.skipped", "a list of [position, level] pairs",
                                   repr(skipped)[:80])
    table = OfflineTable(
        ellipsoids=tuple(entries), interpolation_margins=design.array("interpolation_margins", 1),
        interpolable=design.booleans("interpolable"), design_time=design.number("design_time"),
        stop_reason=design.text("stop_reason"), failed_status=design.optional_text("failed_status"),
        skipped=tuple((int(i), float(level)) for i, level in skipped),
    )
    design.finish()
    return table
