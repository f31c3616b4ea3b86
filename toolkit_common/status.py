"""The one status vocabulary of the toolkit: LMI solves, QP solves and controller steps.

Every solver back-end maps its own statuses into :class:`Status` (Clarabel's ``SolverStatus``,
cvxpy's strings, OSQP's and ProxQP's codes), and every controller reports one word of it in
``last.status`` (:class:`rmpc.StepInfo`). A :class:`Status` is a ``str``: it compares equal to
its word (``Status.OPTIMAL == "optimal"``) and is written to JSON records as the word.

:data:`STATUS_TABLE` says what each word means and whether the answer that comes with it may be
applied (:func:`is_usable`); the documentation's status table is generated from it.

Examples
--------
>>> from toolkit_common.status import Status, is_usable
>>> Status("optimal") is Status.OPTIMAL, Status.OPTIMAL == "optimal"
(True, True)
>>> is_usable("reused"), is_usable("infeasible")
(True, False)
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = [
    "FAILURE_STATUSES",
    "SOLVER_STATUSES",
    "STATUS_TABLE",
    "USABLE_STATUSES",
    "Status",
    "StatusInfo",
    "as_status",
    "is_usable",
]


class Status(StrEnum):
    """A word of the status vocabulary (see :data:`STATUS_TABLE` for the meanings).

    Its ``repr`` is its word's (``'optimal'``), so a status prints as the string it stands for.
    """

    OPTIMAL = "optimal"
    INACCURATE = "inaccurate"
    UNCERTIFIED = "uncertified"
    INFEASIBLE = "infeasible"
    UNBOUNDED = "unbounded"
    MAX_ITERATIONS = "max_iterations"
    TIME_LIMIT = "time_limit"
    NUMERICAL_ERROR = "numerical_error"
    SOLVER_ERROR = "solver_error"
    INTERRUPTED = "interrupted"
    NOT_SOLVED = "not_solved"
    REUSED = "reused"
    OK = "ok"
    OUTSIDE = "outside"
    BOUND_VIOLATION = "bound_violation"
    SINGULAR = "singular"
    DIVERGED = "diverged"
    UNKNOWN = "unknown"

    def __repr__(self) -> str:
        return repr(self.value)


@dataclass(frozen=True)
class StatusInfo:
    """What a status word means.

    Attributes
    ----------
    status : Status
        The word.
    usable : bool
        Whether the answer that comes with it may be applied as it is.
    source : str
        Who reports it: ``"solver"`` (an LMI or QP back-end, and the controller that passes its
        word on), or ``"controller"`` (a controller's own step).
    meaning : str
        One sentence.
    """

    status: Status
    usable: bool
    source: str
    meaning: str


#: Every word with its meaning, in the order the documentation's table lists them.
STATUS_TABLE: tuple[StatusInfo, ...] = (
    StatusInfo(Status.OPTIMAL, True, "solver",
               "The solver converged to its tolerances; for an LMI problem its certificate (every "
               "LMI recomputed in numpy) holds too."),
    StatusInfo(Status.INACCURATE, True, "solver",
               "The solver met only reduced tolerances. An LMI answer is applied only when its "
               "certificate holds; a QP answer is applied, flagged."),
    StatusInfo(Status.UNCERTIFIED, False, "solver",
               "The LMI solver converged, but a recomputed LMI margin is below the certificate's "
               "tolerance: the answer is not applied."),
    StatusInfo(Status.INFEASIBLE, False, "solver",
               "The problem has no solution (for the toolkit's LMI solver: proved by a checked "
               "Farkas certificate)."),
    StatusInfo(Status.UNBOUNDED, False, "solver", "The objective is unbounded below."),
    StatusInfo(Status.MAX_ITERATIONS, False, "solver", "The iteration limit was reached first."),
    StatusInfo(Status.TIME_LIMIT, False, "solver", "The time limit was reached first."),
    StatusInfo(Status.NUMERICAL_ERROR, False, "solver",
               "The solver stopped on a numerical difficulty (a failed factorisation, no progress)."),
    StatusInfo(Status.SOLVER_ERROR, False, "solver", "The solver failed in another way or raised."),
    StatusInfo(Status.INTERRUPTED, False, "solver", "The QP solver was interrupted (a signal, a callback)."),
    StatusInfo(Status.NOT_SOLVED, False, "solver", "The QP solver returned without solving."),
    StatusInfo(Status.REUSED, True, "controller",
               "No solve at this step: the controller kept a gain certified earlier (near the "
               "origin, or inside the invariant ellipsoid of that gain)."),
    StatusInfo(Status.OK, True, "controller",
               "A control law evaluated in closed form (a fixed gain, a sliding-mode or "
               "backstepping law): there is nothing to converge."),
    StatusInfo(Status.OUTSIDE, False, "controller",
               "Off-line robust MPC: the state lies outside the largest precomputed ellipsoid; "
               "the outermost gain is applied as a fallback."),
    StatusInfo(Status.BOUND_VIOLATION, False, "controller",
               "GIPC: the QP answer violates the input bounds by more than the tolerance; the "
               "previous input is held as a fallback."),
    StatusInfo(Status.SINGULAR, False, "controller",
               "A law met the singularity of its attitude coordinates (Euler pitch near "
               "+-90 deg): zero command, adaptation frozen."),
    StatusInfo(Status.DIVERGED, False, "controller",
               "A law's adaptive states are no longer finite or exceed their bound: zero command."),
    StatusInfo(Status.UNKNOWN, False, "controller", "The controller reported nothing for this step."),
)

_INFO: dict[Status, StatusInfo] = {row.status: row for row in STATUS_TABLE}

#: The words whose answer may be applied as it is.
USABLE_STATUSES: frozenset[Status] = frozenset(row.status for row in STATUS_TABLE if row.usable)
#: The words an LMI or QP back-end reports.
SOLVER_STATUSES: frozenset[Status] = frozenset(row.status for row in STATUS_TABLE if row.source == "solver")
#: The words that are not usable.
FAILURE_STATUSES: frozenset[Status] = frozenset(Status) - USABLE_STATUSES


def as_status(value: Any, name: str = "status") -> Status:
    """Return ``value`` as a :class:`Status`, raising an error that names ``name`` otherwise."""
    if isinstance(value, Status):
        return value
    if not isinstance(value, str):
        raise ArgumentTypeError(name, "a status word (str)", f"{type(value).__name__} {value!r}")
    try:
        return Status(value)
    except ValueError:
        words = ", ".join(repr(s.value) for s in Status)
        raise InvalidArgumentError(name, f"one of {words}", repr(value)) from None


def is_usable(status: Any) -> bool:
    """Whether the answer that comes with ``status`` may be applied as it is (see :data:`STATUS_TABLE`)."""
    return _INFO[as_status(status)].usable


def describe(status: Any) -> StatusInfo:
    """The :class:`StatusInfo` of a word."""
    return _INFO[as_status(status)]
