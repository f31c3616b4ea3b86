"""The common base of the QP back-ends: ``setup(qp) -> update(...) -> solve()``.

A back-end is built with its settings, ``setup`` once with a :class:`~rmpc.qp.problem.QP`
(the matrices are factorised or stored then), ``update`` with new vectors only
(``g, l, u, lb, ub``) and ``solve``d as often as needed. Each back-end maps its solver's
statuses into :data:`~rmpc.qp.problem.STATUSES` through its ``STATUS_MAP`` and rejects
unknown settings with an error naming the setting.

Every back-end is bounded in iterations (``max_iter``) and in wall time per ``solve`` call
(``time_limit``, :data:`DEFAULT_TIME_LIMIT` seconds by default, ``inf`` for none): a solve
stopped by the first reports ``"max_iterations"``, by the second ``"time_limit"``.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from collections.abc import Mapping
from numbers import Integral, Real
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from rmpc.qp.problem import QP, QPResult, SolverResiduals
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, SolverError
from toolkit_common.status import Status
from toolkit_common.validation import check_bool

__all__ = ["DEFAULT_TIME_LIMIT", "BackendSettings", "QPBackend"]

#: Default bound in seconds on the wall time of one ``solve`` call of every back-end (the
#: ``time_limit`` setting; ``inf`` switches it off). Measured on GIPC's QPs (paper P's and
#: paper W's suites, short and at full length, and the GIPC cases of the shipped sweeps): of
#: 298631 ProxQP solves, 298620 took under 20 ms (a warm-started one about 10
#: microseconds) and the slowest 104 ms, a warm solve of 2 iterations that the loaded shared
#: 2-core machine had descheduled; the first cvxpy step, with its modelling, took 0.24 s. 5 s
#: is 50 times that slowest solve, so load does not bring a normal solve near it, and it keeps
#: a hopeless step far from a minute: one ``GIPC.step`` with ProxQP at a state of 1e8 ran
#: 54-76 s before (10000 outer iterations of about 1450 inner ones each). A larger QP (a long
#: control horizon ``Nc``) may need a larger value.
DEFAULT_TIME_LIMIT = 5.0


@dataclasses.dataclass(frozen=True)
class BackendSettings:
    """Base of the typed settings of a back-end (a frozen dataclass).

    Subclasses declare their fields with defaults and list which fields are tolerances
    (``_POSITIVE``), counts (``_COUNTS``), flags (``_FLAGS``), choices (``_CHOICES``) and
    time limits in seconds (``_SECONDS``: a number > 0, ``inf`` for none); ``__post_init__``
    checks them.
    """

    _POSITIVE: ClassVar[tuple[str, ...]] = ()
    _SECONDS: ClassVar[tuple[str, ...]] = ()
    _NONNEGATIVE: ClassVar[tuple[str, ...]] = ()
    _COUNTS: ClassVar[tuple[str, ...]] = ()
    _FLAGS: ClassVar[tuple[str, ...]] = ()
    _CHOICES: ClassVar[dict[str, tuple[str, ...]]] = {}

    def __post_init__(self) -> None:
        label = type(self).__name__
        for name in self._POSITIVE + self._NONNEGATIVE:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, Real) or not np.isfinite(value):
                raise ArgumentTypeError(f"{label}.{name}", "a finite real number", repr(value))
            if value < 0 or (value == 0 and name in self._POSITIVE):
                expected = "a number > 0" if name in self._POSITIVE else "a number >= 0"
                raise InvalidArgumentError(f"{label}.{name}", expected, repr(value))
        for name in self._SECONDS:
            value, expected = getattr(self, name), "a number of seconds > 0 (inf: none)"
            if isinstance(value, bool) or not isinstance(value, Real):
                raise ArgumentTypeError(f"{label}.{name}", expected, repr(value))
            if not value > 0:  # NaN fails too
                raise InvalidArgumentError(f"{label}.{name}", expected, repr(value))
        for name in self._COUNTS:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, Integral) or value < 1:
                raise InvalidArgumentError(f"{label}.{name}", "a positive integer", repr(value))
        for name in self._FLAGS:
            value = getattr(self, name)
            check_bool(value, f"{label}.{name}")
        for name, options in self._CHOICES.items():
            value = getattr(self, name)
            if value not in options:
                listed = ", ".join(repr(o) for o in options)
                raise InvalidArgumentError(f"{label}.{name}", f"one of {listed}", repr(value))

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The accepted setting names."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def from_kwargs(cls, settings: Mapping[str, Any] | None = None, **kwargs: Any) -> BackendSettings:
        """Build settings from keywords; an unknown name raises, naming it and the options."""
        merged = dict(settings or {})
        merged.update(kwargs)
        known = cls.names()
        for key in merged:
            if key not in known:
                raise InvalidArgumentError(
                    f"settings {key!r}", f"a setting of {cls.__name__} ({', '.join(known)})",
                    f"the unknown setting {key!r}",
                )
        return cls(**merged)


class QPBackend(ABC):
    """A QP solver behind the ``setup -> update -> solve`` verbs.

    Parameters
    ----------
    settings : BackendSettings or mapping, optional
        The back-end's settings object, or a mapping of setting names.
    **kwargs
        Individual settings (override ``settings``). Unknown names raise
        :class:`~toolkit_common.errors.InvalidArgumentError`.
    """

    #: Name used by :func:`rmpc.qp.make_backend`.
    name: ClassVar[str] = ""
    #: The settings dataclass.
    settings_class: ClassVar[type[BackendSettings]] = BackendSettings
    #: Solver status -> word of :data:`rmpc.qp.problem.STATUSES`.
    STATUS_MAP: ClassVar[dict[Any, Status]] = {}

    def __init__(self, settings: BackendSettings | Mapping[str, Any] | None = None, **kwargs: Any) -> None:
        if isinstance(settings, self.settings_class):
            self.settings = self.settings_class.from_kwargs(dataclasses.asdict(settings), **kwargs)
        elif settings is None or isinstance(settings, Mapping):
            self.settings = self.settings_class.from_kwargs(settings, **kwargs)
        else:
            raise ArgumentTypeError(
                "settings", f"a {self.settings_class.__name__} or a mapping", type(settings).__name__
            )
        self._qp: QP | None = None
        self._setup_error = None
        self._size = (0, 0)
        self._vec: dict[str, np.ndarray] = {}

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles hold the settings and the current problem, not the solver (OSQP's,
        Clarabel's and cvxpy's do not pickle): :meth:`__setstate__` builds it again, so a
        restored back-end answers as one set up afresh with the same data (no warm start)."""
        return {"settings": self.settings, "qp": None if self._qp is None else self.problem}

    def __setstate__(self, state: dict[str, Any]) -> None:
        type(self).__init__(self, state["settings"])
        if state["qp"] is not None:
            self.setup(state["qp"])

    # -- the verbs -------------------------------------------------------------------
    def setup(self, qp: QP) -> None:
        """Store ``qp`` and build the solver (matrices are fixed from here on)."""
        if not isinstance(qp, QP):
            raise ArgumentTypeError("qp", "an rmpc.qp.QP", type(qp).__name__)
        self._qp = qp
        self._size = (qp.n_vars, qp.n_cons)
        self._vec = {k: np.array(getattr(qp, k), dtype=float) for k in ("g", "l", "u", "lb", "ub")}
        self._build()

    def _build(self) -> None:
        """Run ``_setup``; a solver that refuses the data is recorded, reported by ``solve``."""
        self._setup_error: str | None = None
        try:
            self._setup()
        except Exception as err:  # the bindings raise their own types (OSQPException, ...)
            self._setup_error = f"{type(err).__name__}: {err}"

    def update(
        self,
        *,
        g: ArrayLike | None = None,
        l: ArrayLike | None = None,  # noqa: E741 - the solvers' own name for the lower bound
        u: ArrayLike | None = None,
        lb: ArrayLike | None = None,
        ub: ArrayLike | None = None,
    ) -> None:
        """Replace some of the vectors ``g, l, u, lb, ub`` (``None`` keeps the current one).

        The checks are cheap (shape, NaN, ``l <= u``), so this is safe to call every step.
        If the pattern of infinite bounds changes and the solver cannot represent that in
        place, the solver is rebuilt (documented per back-end).
        """
        if self._qp is None:
            raise SolverError(f"{type(self).__name__}.update: call setup(qp) first")
        n, m = self._size
        changed: dict[str, np.ndarray] = {}
        for key, value, size in (("g", g, n), ("l", l, m), ("u", u, m), ("lb", lb, n), ("ub", ub, n)):
            if value is None:
                continue
            arr = np.array(value, dtype=float)  # a copy: later changes by the caller do not leak in
            if arr.shape != (size,):
                raise InvalidArgumentError(key, f"a vector of length {size}", f"shape {arr.shape}")
            # one vectorised test per vector (this runs every control step); details on failure
            if key == "g":
                ok = np.isfinite(arr).all()
            elif key in ("l", "lb"):
                ok = (arr < np.inf).all()  # no NaN, no +inf lower bound
            else:
                ok = (arr > -np.inf).all()  # no NaN, no -inf upper bound
            if not ok:
                self._reject(key, arr)
            changed[key] = arr
        if not changed:
            return
        for lo_key, up_key in (("l", "u"), ("lb", "ub")):
            if lo_key in changed or up_key in changed:
                lo = changed.get(lo_key, self._vec[lo_key])
                up = changed.get(up_key, self._vec[up_key])
                if not (lo <= up).all():
                    i = int(np.argmax(lo > up))
                    raise InvalidArgumentError(
                        f"{lo_key}, {up_key}", f"{lo_key} <= {up_key} element-wise",
                        f"{lo_key}[{i}] = {lo[i]:.6g} > {up_key}[{i}] = {up[i]:.6g}",
                    )
        self._vec.update(changed)
        if self._setup_error is not None:
            self._build()  # the solver was never built: try again with the new data
        else:
            self._update(changed)

    @staticmethod
    def _reject(key: str, arr: np.ndarray) -> None:
        if key == "g":
            bad, expected = ~np.isfinite(arr), "finite values"
        elif key in ("l", "lb"):
            bad, expected = ~(arr < np.inf), "numbers or -inf (no NaN, no +inf lower bound)"
        else:
            bad, expected = ~(arr > -np.inf), "numbers or +inf (no NaN, no -inf upper bound)"
        i = int(np.argmax(bad))
        raise InvalidArgumentError(key, expected, f"{arr[i]} at index {i}")

    def solve(self) -> QPResult:
        """Solve the current problem; failures come back as a status, never as an exception."""
        if self._qp is None:
            raise SolverError(f"{type(self).__name__}.solve: call setup(qp) first")
        if self._setup_error is not None:
            return self._result(
                Status.NUMERICAL_ERROR, f"setup failed: {self._setup_error}", None, None, None, -1, 0.0,
                SolverResiduals(),
            )
        return self._solve()

    # -- helpers for subclasses and tests -----------------------------------------------
    @property
    def problem(self) -> QP:
        """The current problem as a validated :class:`QP` (the setup data plus updates)."""
        if self._qp is None:
            raise SolverError(f"{type(self).__name__}.problem: call setup(qp) first")
        return QP(H=self._qp.H, C=self._qp.C, **self._vec)

    def _result(
        self,
        status: Status,
        raw_status: str,
        x: ArrayLike,
        y_c: ArrayLike,
        y_box: ArrayLike,
        iterations: int,
        solve_time: float,
        residuals: SolverResiduals,
        info: dict[str, Any] | None = None,
    ) -> QPResult:
        assert self._qp is not None
        n, m = self._size
        xv = None
        if status in (Status.OPTIMAL, Status.INACCURATE) and x is not None:
            # copies: some bindings (proxsuite) return views of the solver's own memory,
            # which the next solve would overwrite
            xv = np.array(x, dtype=float).reshape(n)
            if not np.isfinite(xv).all():
                status, xv = Status.NUMERICAL_ERROR, None
        if xv is not None:
            objective = float(0.5 * (xv @ self._qp.H @ xv) + self._vec["g"] @ xv)
            yc = np.zeros(m) if y_c is None else np.array(y_c, dtype=float).reshape(m)
            yb = np.zeros(n) if y_box is None else np.array(y_box, dtype=float).reshape(n)
        else:
            xv, objective = np.full(n, np.nan), float("nan")
            yc, yb = np.full(m, np.nan), np.full(n, np.nan)
        return QPResult(
            x=xv, objective=objective, status=status, iterations=int(iterations),
            solve_time=float(solve_time), residuals=residuals, y_C=yc, y_box=yb,
            raw_status=raw_status, backend=self.name, info=info or {},
        )

    @classmethod
    def map_status(cls, raw: Any) -> Status:
        """The shared status word for a solver status (unknown ones: ``"numerical_error"``)."""
        return cls.STATUS_MAP.get(raw, Status.NUMERICAL_ERROR)

    # -- what a back-end implements ---------------------------------------------------
    @abstractmethod
    def _setup(self) -> None:
        """Build the solver from ``self._qp`` and ``self._vec``."""

    @abstractmethod
    def _update(self, changed: dict[str, np.ndarray]) -> None:
        """Push changed vectors (already in ``self._vec``) to the solver."""

    @abstractmethod
    def _solve(self) -> QPResult:
        """Solve and build the result with :meth:`_result`."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.settings!r})"
