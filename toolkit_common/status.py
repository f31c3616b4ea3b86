"""The one status vocabulary of the toolkit: LMI solves, QP solves and controller steps.

Every solver back-end maps its own statuses into :class:`Status` (Clarabel's ``SolverStatus``,
cvxpy's strings, OSQP's and ProxQP's codes), and every controller reports one word of it in
``last.status`` (:class:`rmpc.StepInfo`). A :class:`Status` is a ``str``: it compares equal to
its word (``Status.OPTIMAL == "optimal"``) and is written to JSON records as the word.

:data:`STATUS_TABLE` says what each word means, whether the answer that comes with it may be
applied (:func:`is_usable`) and what the controllers do with it (:func:`describe`); the
documentation's status table is generated from it.

Examples
--------
>>> from toolkit_common.status import Status, describe, is_usable
>>> Status("optimal") is Status.OPTIMAL, Status.OPTIMAL == "optimal"
(True, True)
>>> is_usable("reused"), is_usable("infeasible")
(True, False)
>>> describe("outside").source, Status.OUTSIDE      # the repr is the word
('controller', 'outside')
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
    "describe",
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
    """What a status word means and what a controller does with it.

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
        What happened, in one or two sentences.
    action : str
        What the controllers of :mod:`rmpc` do when they get or report it.
    """

    status: Status
    usable: bool
    source: str
    meaning: str
    action: str


_SOLVER_FAILURE = (
    "Robust MPC keeps its last certified gain (zero before the first; ``on_failure=\"raise\"`` "
    "raises instead), GIPC holds the previous input; both flag the step as a fallback."
)

#: Every word with its meaning, in the order the documentation's table lists them.
STATUS_TABLE: tuple[StatusInfo, ...] = (
    StatusInfo(Status.OPTIMAL, True, "solver",
               "The solver converged to its tolerances; for an LMI problem its certificate (every "
               "LMI recomputed in numpy) holds too. Off-line robust MPC reports it for a state "
               "inside its table of certified ellipsoids.",
               "Applies the answer: robust MPC the gain ``F = Y Q^-1``, GIPC the first input "
               "increment, off-line robust MPC the (interpolated) gain of the ellipsoid."),
    StatusInfo(Status.INACCURATE, True, "solver",
               "The solver met only reduced tolerances. An LMI answer comes with its certificate; "
               "a QP answer with its ``x``, flagged.",
               "Robust MPC applies the gain when its certificate holds (a fallback otherwise); "
               "GIPC holds the previous input."),
    StatusInfo(Status.UNCERTIFIED, False, "solver",
               "The LMI solver converged, but a recomputed LMI margin is below the certificate's "
               "tolerance (or ``F`` could not be formed).",
               _SOLVER_FAILURE),
    StatusInfo(Status.INFEASIBLE, False, "solver",
               "The problem has no solution (for the toolkit's LMI solver: proved by a checked "
               "Farkas certificate), e.g. an input bound too tight for the state.",
               _SOLVER_FAILURE + " Off-line robust MPC reports the design's failure word when no "
               "ellipsoid could be designed, and applies zero."),
    StatusInfo(Status.UNBOUNDED, False, "solver",
               "The objective is unbounded below (dual infeasible).", _SOLVER_FAILURE),
    StatusInfo(Status.MAX_ITERATIONS, False, "solver", "The iteration limit was reached first.",
               _SOLVER_FAILURE),
    StatusInfo(Status.TIME_LIMIT, False, "solver",
               "The time limit was reached first: for a QP back-end its ``time_limit`` setting "
               "(seconds per solve call, retries included; 5 s by default), for an LMI solver a "
               "limit passed to it.", _SOLVER_FAILURE),
    StatusInfo(Status.NUMERICAL_ERROR, False, "solver",
               "The solver stopped on a numerical difficulty (a failed factorisation, no progress, "
               "a non-finite answer).", _SOLVER_FAILURE),
    StatusInfo(Status.SOLVER_ERROR, False, "solver",
               "The LMI solver failed in another way: it raised, or returned a status outside the "
               "vocabulary.", _SOLVER_FAILURE),
    StatusInfo(Status.INTERRUPTED, False, "solver",
               "The QP solver was interrupted (a signal, a callback).", _SOLVER_FAILURE),
    StatusInfo(Status.NOT_SOLVED, False, "solver", "The QP solver returned without solving.",
               _SOLVER_FAILURE),
    StatusInfo(Status.REUSED, True, "controller",
               "No solve at this step: the controller kept a gain certified earlier (near the "
               "origin, or inside the invariant ellipsoid of that gain).",
               "Applies the kept gain; its guarantees hold inside its ellipsoid."),
    StatusInfo(Status.OK, True, "controller",
               "A control law evaluated in closed form (a fixed gain such as LQR, a sliding-mode "
               "or backstepping law): there is nothing to converge.",
               "Applies the law's output."),
    StatusInfo(Status.OUTSIDE, False, "controller",
               "Off-line robust MPC: the state lies outside the largest precomputed ellipsoid.",
               "Applies the outermost gain ``F_1`` without a guarantee, flagged as a fallback."),
    StatusInfo(Status.BOUND_VIOLATION, False, "controller",
               "GIPC: the QP answer violates the input bounds by more than the tolerance.",
               "Holds the previous input (``du = 0``), flagged as a fallback."),
    StatusInfo(Status.SINGULAR, False, "controller",
               "A law met the singularity of its attitude coordinates (Euler pitch near "
               "+-90 deg).",
               "Zero command; the adaptation is frozen."),
    StatusInfo(Status.DIVERGED, False, "controller",
               "A law's adaptive states are no longer finite or exceed their bound.",
               "Zero command from then on."),
    StatusInfo(Status.UNKNOWN, False, "controller",
               "The controller reported nothing for this step (no ``last``).",
               "Whatever it returned is applied; the simulator records the word."),
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
