"""Where a robust MPC has a certified answer: its feasible region along chosen directions.

The LMI problem of Kothare's robust MPC (and of its forms) is feasible on a star-shaped set of
states: the variables that meet the LMIs at ``x`` meet them at ``t x`` for every ``t < 1``. So
along a direction ``d`` the certified states form a segment ``[0, t* d]``, and
:func:`boundary_along` finds ``t*`` by doubling (or halving) from ``t = 1`` and bisecting to a
relative tolerance; :func:`feasible_region` does it for every row of ``directions``. A multiple
that reaches ``t_max`` is reported as the cap (the region extends at least that far), never as
a boundary.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rmpc.mpc.fallback import is_certified
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_positive

__all__ = ["RegionResult", "TimeBudgetExceeded", "boundary_along", "feasible_region"]


class TimeBudgetExceeded(Exception):
    """A region search ran past its deadline (:func:`boundary_along`); the caller keeps what finished."""


def _certified(ctrl: Any, x: np.ndarray, counts: dict[str, int], deadline: float, last: list[str]) -> bool:
    if time.perf_counter() > deadline:
        raise TimeBudgetExceeded
    sol = ctrl.solve(x)
    counts[sol.status] = counts.get(sol.status, 0) + 1
    certified = is_certified(sol)  # "optimal", or "inaccurate" with its certificate: a gain exists
    if not certified:
        last[0] = sol.status
    return certified


def boundary_along(
    ctrl: Any, d: np.ndarray, *, t_max: float = 1024.0, rel_tol: float = 1e-3,
    counts: dict[str, int] | None = None, deadline: float = np.inf,
) -> tuple[float, str]:
    """The largest multiple ``t`` (to ``rel_tol``) with ``t d`` certified, and what stopped it.

    Parameters
    ----------
    ctrl : object with ``solve(x)``
        A robust MPC (:class:`rmpc.RMPC`, ...) whose ``solve`` returns an
        :class:`lmi.LMISolution`; an answer whose gain the controller would apply counts as
        certified (``"optimal"``, or ``"inaccurate"`` with its certificate holding).
    d : (n,) ndarray
        The direction (its length sets the unit of ``t``).
    t_max : float
        The cap: the search stops there, ``(t_max, "cap")``.
    rel_tol : float
        The bisection's relative width.
    counts : dict, optional
        Updated with the number of solves per status.
    deadline : float
        A ``time.perf_counter()`` value past which :class:`TimeBudgetExceeded` is raised.

    Returns
    -------
    (float, str)
        ``t`` and the status of the last failed solve above it (``"infeasible"``, a solver
        failure word), or ``"cap"``; ``(0.0, status)`` when even ``d / t_max`` fails.
    """
    counts = {} if counts is None else counts
    last = ["cap"]
    lo, hi = 0.0, 1.0
    if _certified(ctrl, d, counts, deadline, last):
        lo = 1.0
        while True:
            hi = 2.0 * lo
            if hi > t_max:
                return t_max, "cap"
            if not _certified(ctrl, hi * d, counts, deadline, last):
                break
            lo = hi
    else:
        t = 1.0
        while True:
            t /= 2.0
            if t < 1.0 / t_max:
                return 0.0, last[0]
            if _certified(ctrl, t * d, counts, deadline, last):
                lo, hi = t, 2.0 * t
                break
    while hi - lo > rel_tol * lo:
        mid = 0.5 * (lo + hi)
        if _certified(ctrl, mid * d, counts, deadline, last):
            lo = mid
        else:
            hi = mid
    return lo, last[0]


@dataclass(frozen=True)
class RegionResult:
    """The certified region of a controller along directions.

    Attributes
    ----------
    directions : (k, n) ndarray
        The directions searched (rows).
    t : (k,) ndarray
        The largest certified multiple along each (``t_max`` where capped).
    limits : tuple of str
        What ended each: ``"infeasible"``, a solver failure word, or ``"cap"``.
    t_max : float
        The cap of the search.
    status_counts : dict
        Solves per status over the whole search.
    """

    directions: np.ndarray
    t: np.ndarray
    limits: tuple[str, ...]
    t_max: float
    status_counts: dict[str, int] = field(default_factory=dict)

    @property
    def points(self) -> np.ndarray:
        """The boundary points ``t_i d_i`` (rows); capped ones are lower bounds of the region."""
        return self.t[:, None] * self.directions

    @property
    def capped(self) -> np.ndarray:
        """Which directions reached the cap (the region extends at least that far)."""
        return np.array([why == "cap" for why in self.limits], dtype=bool)


def feasible_region(
    ctrl: Any, directions: ArrayLike, *, t_max: float = 1024.0, rel_tol: float = 1e-3,
    budget_s: float = np.inf,
) -> RegionResult:
    """The states along ``directions`` at which ``ctrl`` has a certified answer.

    Parameters
    ----------
    ctrl : object with ``solve(x)``
        :class:`rmpc.RMPC` (any form) or another robust MPC with ``solve``.
    directions : (k, n) array_like
        One direction per row, in the state's units (e.g. ``x0`` and its rotations).
    t_max, rel_tol
        The cap and the relative tolerance of :func:`boundary_along`.
    budget_s : float
        Wall time for the whole search; past it :class:`TimeBudgetExceeded` is raised.

    Examples
    --------
    >>> import numpy as np
    >>> from models import PolytopicModel
    >>> from rmpc import RMPC
    >>> from rmpc.analysis import feasible_region
    >>> plant = PolytopicModel([(np.array([[2.0]]), np.array([[1.0]]))], dt=1.0)
    >>> ctrl = RMPC(plant, Q=np.eye(1), R=np.eye(1), u_max=1.0)
    >>> region = feasible_region(ctrl, [[1.0], [-1.0]], rel_tol=1e-4)
    >>> np.round(region.t, 3)   # |2 + F| < 1 needs |F| > 1, and |F x| <= 1: the boundary is |x| = 1
    array([1., 1.])
    """
    if not callable(getattr(ctrl, "solve", None)):
        raise ArgumentTypeError("ctrl", "a robust MPC with solve(x) (rmpc.RMPC)", type(ctrl).__name__)
    try:
        dirs = np.atleast_2d(np.asarray(directions, dtype=float))
    except (TypeError, ValueError) as err:
        raise InvalidArgumentError("directions", "a (k, n) array of directions", str(err)) from None
    n = getattr(getattr(ctrl, "plant", None), "n_states", dirs.shape[1])
    if dirs.ndim != 2 or dirs.shape[1] != n or not np.all(np.isfinite(dirs)):
        raise InvalidArgumentError("directions", f"a finite (k, {n}) array", f"shape {dirs.shape}")
    if np.any(np.linalg.norm(dirs, axis=1) == 0.0):
        raise InvalidArgumentError("directions", "non-zero rows", "a zero direction")
    t_max = check_positive(t_max, "t_max")
    if t_max <= 1.0:
        raise InvalidArgumentError("t_max", "a cap > 1", repr(t_max))
    rel_tol = check_positive(rel_tol, "rel_tol")
    try:
        budget = float(budget_s)
    except (TypeError, ValueError):
        budget = float("nan")
    if isinstance(budget_s, bool) or not budget > 0:  # inf: no budget
        raise InvalidArgumentError("budget_s", "seconds > 0 (inf for no budget)", repr(budget_s))
    deadline = time.perf_counter() + budget
    counts: dict[str, int] = {}
    ts, limits = [], []
    for d in dirs:
        t, why = boundary_along(ctrl, d, t_max=t_max, rel_tol=rel_tol, counts=counts, deadline=deadline)
        ts.append(t)
        limits.append(why)
    return RegionResult(dirs, np.array(ts), tuple(limits), t_max, counts)
