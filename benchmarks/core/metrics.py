"""Metrics of one closed-loop run: attitude error, torque use, saturation, solver effort.

The attitude error is the attitude itself (every experiment regulates it to zero), per axis
``roll, pitch, yaw`` = ``phi, theta, psi`` in rad; for a plant without an attitude the errors
are its states, keyed by the plant's own state names (:func:`error_signals`). Definitions (``e_k = e(t_k)``,
``k = 0 .. N`` the recorded samples):

- ``sum_abs_err``: ``sum_k |e_k|`` over all ``N + 1`` samples (paper P's table metric).
- ``final_abs_err``: ``|e_N|``.
- ``iae`` and ``ise``: ``int |e| dt`` and ``int e^2 dt`` by the trapezoidal rule over the
  samples (exact for a piecewise-linear signal).
- ``settling_time``: the first sample time after which ``|e|`` stays within a band of 2 %
  of ``|e_0|`` (of ``max |e|`` when ``e_0 = 0``) until the end of the run; ``None`` when the
  last sample is outside the band (not settled within the run).
  :func:`last_time_above` is the other reading some families record (paper V's ``t_s``): the
  last sample time at which ``|e|`` exceeds an absolute threshold. Both, and the recovery
  times, rest on :func:`settle_index`.
- ``overshoot``: how far ``e`` crosses zero to the side opposite to ``e_0``, in % of
  ``|e_0|``; ``None`` when ``e_0 = 0``.

Torques (N m, per axis limit ``u_max``): ``max_abs_u`` (largest applied component),
``max_abs_u_cmd`` (largest commanded), ``saturated_fraction`` (share of steps whose command
reaches the limit on some axis), ``constraint_violation`` (largest excess of an applied
component over ``u_max``, 0 if none) and ``violation_steps``. Solver effort: the
controller-reported ``solve_time_p50/p95/max`` over all steps (a step that keeps its gain
costs 0), the same over the steps that solved (``solve_time_solves_*``), the wall time of
``step`` (``step_time_*``), ``n_solves``, ``fallback_count``, ``failure_count`` and
``status_counts``. ``gamma``: first, last, smallest and largest cost bound, their count, and
the series gamma(k) at the steps that solved (``t``, ``values``; at most 200 points, evenly
thinned).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import ArgumentTypeError
from toolkit_common.status import USABLE_STATUSES, Status

__all__ = [
    "AXES",
    "FAILURE_FREE_STATUSES",
    "check_trajectory",
    "compute_metrics",
    "error_signals",
    "iae",
    "ise",
    "last_time_above",
    "overshoot",
    "recovery",
    "recovery_time",
    "settle_index",
    "settling_time",
    "step_timing",
    "total_variation_rate",
]

#: Names of the attitude axes, in state order.
AXES: tuple[str, str, str] = ("roll", "pitch", "yaw")
#: Largest number of (t, gamma) points kept in ``metrics["gamma"]`` (evenly thinned).
GAMMA_POINTS = 200
#: Step statuses that are not failures: the usable words of the status vocabulary
#: (:data:`toolkit_common.status.USABLE_STATUSES`): solved, solved less accurately, a kept gain,
#: or a control law without an optimiser that computed its output (``"ok"``).
FAILURE_FREE_STATUSES: frozenset[Status] = USABLE_STATUSES
#: Step statuses of a step that solved nothing: a kept gain or a law evaluated in closed form.
_NO_SOLVE: tuple[Status, ...] = (Status.OK, Status.REUSED)


def _trapezoid(y: np.ndarray, t: np.ndarray) -> float:
    if y.size < 2:
        return 0.0
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


def iae(t: ArrayLike, e: ArrayLike) -> float:
    """Integral of ``|e|`` over ``t`` (trapezoidal rule).

    Examples
    --------
    >>> iae([0.0, 1.0, 2.0], [1.0, -1.0, 0.0])
    1.5
    """
    return _trapezoid(np.abs(np.asarray(e, dtype=float)), np.asarray(t, dtype=float))


def ise(t: ArrayLike, e: ArrayLike) -> float:
    """Integral of ``e^2`` over ``t`` (trapezoidal rule on the squared samples).

    Examples
    --------
    >>> ise([0.0, 1.0, 2.0], [1.0, -1.0, 0.0])
    1.5
    """
    e = np.asarray(e, dtype=float)
    return _trapezoid(e * e, np.asarray(t, dtype=float))


def settle_index(e: ArrayLike, limit: float) -> int:
    """The first sample index from which ``|e| <= limit`` holds to the end.

    ``0`` when ``|e|`` never exceeds ``limit``; ``len(e)`` when even the last sample does (not
    settled). With several columns the largest ``|e_i|`` of a sample counts.

    Examples
    --------
    >>> settle_index([3.0, 2.0, 0.5, 1.5, 0.2], 1.0)
    4
    >>> settle_index([0.5, 0.2], 1.0), settle_index([0.5, 2.0], 1.0)
    (0, 2)
    """
    mag = np.abs(np.asarray(e, dtype=float))
    if mag.ndim == 2:
        mag = mag.max(axis=1)
    outside = np.flatnonzero(mag > limit)
    return 0 if outside.size == 0 else int(outside[-1]) + 1


def settling_time(t: ArrayLike, e: ArrayLike, band: float = 0.02) -> float | None:
    """First time after which ``|e|`` stays within ``band * |e(0)|`` (``None`` if never).

    A band relative to the start: the reference is ``|e(0)|``, or ``max |e|`` when
    ``e(0) = 0``; a signal that is zero throughout settles at ``t[0]``. The time is that of the
    first sample inside the band after the last one outside it. For an absolute threshold and
    the time of the last sample outside, see :func:`last_time_above`.

    Examples
    --------
    >>> settling_time([0.0, 1.0, 2.0, 3.0], [1.0, 0.5, 0.01, 0.0])
    2.0
    >>> settling_time([0.0, 1.0], [1.0, 0.5]) is None
    True
    """
    t = np.asarray(t, dtype=float)
    mag = np.abs(np.asarray(e, dtype=float))
    ref = mag[0] if mag[0] > 0 else float(np.max(mag))
    if ref == 0.0:
        return float(t[0])
    k = settle_index(mag, band * ref)
    return None if k == mag.size else float(t[k])


def last_time_above(t: ArrayLike, e: ArrayLike, threshold: float) -> float:
    """The last sample time at which ``|e|`` exceeds the absolute ``threshold``.

    ``0.0`` when it never does; ``inf`` when the last sample still does (not settled within the
    run). Paper V's settling time ``t_s`` (:mod:`benchmarks.families.flexible.metrics`). Unlike
    :func:`settling_time`, the threshold is absolute and the time is that of the last sample
    outside it, not of the first inside.

    Examples
    --------
    >>> last_time_above([0.0, 1.0, 2.0, 3.0, 4.0], [3.0, 2.0, 0.5, 1.5, 0.2], 1.0)
    3.0
    >>> last_time_above([0.0, 1.0], [0.5, 2.0], 1.0)
    inf
    """
    k = settle_index(e, threshold)
    if k == 0:
        return 0.0
    if k == len(e):
        return float("inf")
    return float(np.asarray(t, dtype=float)[k - 1])


def recovery(
    t: ArrayLike,
    e: ArrayLike,
    t_on: float,
    band: float,
    t_off: float | None = None,
) -> dict[str, Any]:
    """How a run recovers from an event at ``t_on`` (a disturbance step, a fault).

    Parameters
    ----------
    t : (N,) array_like
        Sample times (s).
    e : (N,) or (N, k) array_like
        The error; with several columns the largest ``|e_i|`` counts.
    t_on : float
        Time of the event (s).
    band : float
        Absolute error band of "recovered" (same unit as ``e``).
    t_off : float, optional
        End of the window (default: the end of the run).

    Returns
    -------
    dict
        ``peak_error`` (largest error in the window), ``recovery_time`` (time from ``t_on``
        after which the error stays within ``band`` until the window's end; ``None`` if it is
        outside the band at the end), ``band``.

    Examples
    --------
    >>> out = recovery([0, 1, 2, 3, 4], [0.0, 0.5, 0.2, 0.01, 0.0], t_on=1.0, band=0.05)
    >>> out["peak_error"], out["recovery_time"]
    (0.5, 2.0)
    """
    t = np.asarray(t, dtype=float)
    mag = np.abs(np.asarray(e, dtype=float))
    if mag.ndim == 2:
        mag = mag.max(axis=1)
    end = t[-1] if t_off is None else float(t_off)
    inside = (t >= t_on) & (t <= end)
    if not np.any(inside):
        return {"peak_error": None, "recovery_time": None, "band": float(band)}
    idx = np.flatnonzero(inside)
    window = mag[idx]
    return {
        "peak_error": float(window.max()),
        "recovery_time": recovery_time(t[idx], window, t_on, band),
        "band": float(band),
    }


def recovery_time(t: ArrayLike, e: ArrayLike, t_on: float, band: float) -> float | None:
    """Time from ``t_on`` after which ``|e|`` stays within the absolute ``band`` until the last sample.

    ``t`` and ``e`` are the samples of the window after the event; ``0.0`` when ``|e|`` never
    leaves the band in it, ``None`` when the last sample is outside (not recovered).

    Examples
    --------
    >>> recovery_time([1.0, 2.0, 3.0, 4.0], [0.5, 0.2, 0.01, 0.0], t_on=1.0, band=0.05)
    2.0
    """
    k = settle_index(e, band)
    if k == 0:
        return 0.0
    if k == len(e):
        return None
    return float(np.asarray(t, dtype=float)[k] - t_on)


def check_trajectory(traj: Any, name: str = "traj") -> Any:
    """``traj`` if it is an :class:`rmpc.Trajectory`; an ``ArgumentTypeError`` naming ``name`` otherwise."""
    from rmpc.sim.trajectory import Trajectory  # here: the metrics above load without the controllers

    if not isinstance(traj, Trajectory):
        raise ArgumentTypeError(name, "an rmpc.Trajectory", type(traj).__name__)
    return traj


def step_timing(traj: Any) -> dict[str, Any]:
    """Per-step wall time and solve time of a run (percentiles) and its status counts.

    ``solve_time_solves_*`` are over the steps that solved an optimisation problem (status not
    ``"ok"``, the word of control laws without one, nor ``"reused"``); ``None`` when none did.
    """
    step = np.asarray(traj.step_time, dtype=float)
    solve = np.asarray(traj.solve_time, dtype=float)
    statuses = [getattr(info, "status", Status.OK) if info is not None else Status.OK for info in traj.info]
    solved = np.array([s for s, st in zip(solve, statuses, strict=False) if st not in _NO_SOLVE])
    return {
        "step_time_p50": float(np.percentile(step, 50)),
        "step_time_p95": float(np.percentile(step, 95)),
        "solve_time_p50": float(np.percentile(solve, 50)),
        "solve_time_p95": float(np.percentile(solve, 95)),
        "solve_time_solves_p50": float(np.percentile(solved, 50)) if solved.size else None,
        "solve_time_solves_p95": float(np.percentile(solved, 95)) if solved.size else None,
        "status_counts": traj.status_counts(),
    }


def total_variation_rate(u: ArrayLike, length: float) -> float:
    """Total variation of a sampled signal per second: ``(1/L) sum_k ||u_(k+1) - u_k||_1``.

    The chattering measure of the suites: a torque that switches sign from sample to sample
    scores ``2 |u| / dt`` per axis, a smooth torque the mean slope of ``|u|``.

    Parameters
    ----------
    u : (N, m) array_like
        The samples ``u_0 .. u_(N-1)`` of one window, in time order (zero-order hold).
    length : float
        The window's length ``L`` (s); ``0`` gives ``0.0``.

    Returns
    -------
    float
        Units of ``u`` per second.

    Examples
    --------
    >>> total_variation_rate([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]], 2.0)
    2.0
    """
    arr = np.asarray(u, dtype=float)
    return float(np.sum(np.abs(np.diff(arr, axis=0)))) / length if length > 0 else 0.0


def overshoot(e: ArrayLike) -> float | None:
    """Largest excursion past zero, opposite to ``e(0)``, in % of ``|e(0)|`` (``None`` if ``e(0) = 0``).

    Examples
    --------
    >>> overshoot([2.0, 0.5, -0.2, 0.0])
    10.0
    >>> overshoot([2.0, 1.0, 0.0])
    0.0
    """
    e = np.asarray(e, dtype=float)
    if e[0] == 0.0:
        return None
    beyond = float(np.max(-np.sign(e[0]) * e))
    return 100.0 * max(0.0, beyond) / abs(float(e[0]))


def _finite_or_none(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def _pcts(values: np.ndarray, prefix: str) -> dict[str, float | None]:
    if values.size == 0:
        return {f"{prefix}_p50": None, f"{prefix}_p95": None, f"{prefix}_max": None}
    return {
        f"{prefix}_p50": float(np.percentile(values, 50)),
        f"{prefix}_p95": float(np.percentile(values, 95)),
        f"{prefix}_max": float(np.max(values)),
    }


def _per_axis(values: list[Any], names: tuple[str, ...] = AXES) -> dict[str, Any]:
    return dict(zip(names, values, strict=True))


def error_signals(traj: Any) -> tuple[np.ndarray, tuple[str, ...]]:
    """The regulated errors of a run and their names.

    For a plant with an attitude (``traj.attitude_euler`` not ``None``: the satellites) the
    first three states, named ``roll, pitch, yaw``; for any other plant every state, by the
    plant's own names (``Trajectory.names()``: python-control's signal names for a polytope
    from :meth:`models.PolytopicModel.from_statespace`, ``x[i]`` where it gives none).
    """
    x = np.asarray(traj.x, dtype=float)
    if getattr(traj, "attitude_euler", None) is not None and x.shape[1] >= 3:
        return x[:, :3], AXES
    names = traj.names("state") if callable(getattr(traj, "names", None)) else ()
    if len(names) != x.shape[1]:
        names = tuple(f"x[{i}]" for i in range(x.shape[1]))
    return x, tuple(names)


def compute_metrics(traj: Any, u_max: float, band: float = 0.02) -> dict[str, Any]:
    """All metrics of a :class:`rmpc.Trajectory` (see the module notes for definitions).

    Parameters
    ----------
    traj : rmpc.Trajectory
        The run; the errors are :func:`error_signals` (the attitude of a satellite, every state
        by its name for any other plant).
    u_max : float
        Per-axis torque limit (N m) that saturation and violation are measured against.
    band : float
        Settling band as a fraction of the initial error (default 2 %).

    Returns
    -------
    dict
        JSON-ready values; ``None`` where a value does not exist.
    """
    t = np.asarray(traj.t, dtype=float)
    err, names = error_signals(traj)
    k = err.shape[1]
    u_app = np.abs(np.asarray(traj.u_applied, dtype=float))
    u_cmd = np.abs(np.asarray(traj.u_cmd, dtype=float))
    status = list(traj.status)
    solve = np.asarray(traj.solve_time, dtype=float)
    solved = np.array([s != Status.REUSED for s in status], dtype=bool)
    excess = np.max(u_app, axis=1) - u_max if u_app.size else np.zeros(0)
    gamma_all = np.asarray(traj.gamma, dtype=float)
    solved_at = np.flatnonzero(np.isfinite(gamma_all))
    gamma = gamma_all[solved_at]
    picks = np.linspace(0, solved_at.size - 1, min(solved_at.size, GAMMA_POINTS)).astype(int)
    keep = solved_at[np.unique(picks)]
    fallbacks = sum(bool(getattr(info, "fallback", False)) for info in traj.info)
    counts: dict[str, int] = {}
    for s in status:
        counts[s] = counts.get(s, 0) + 1
    metrics: dict[str, Any] = {
        "sum_abs_err": _per_axis([float(v) for v in np.sum(np.abs(err), axis=0)], names),
        "final_abs_err": _per_axis([float(v) for v in np.abs(err[-1])], names),
        "iae": _per_axis([iae(t, err[:, i]) for i in range(k)], names),
        "ise": _per_axis([ise(t, err[:, i]) for i in range(k)], names),
        "settling_time": _per_axis([settling_time(t, err[:, i], band) for i in range(k)], names),
        "overshoot": _per_axis([overshoot(err[:, i]) for i in range(k)], names),
        "max_abs_u": float(np.max(u_app)) if u_app.size else 0.0,
        "max_abs_u_cmd": float(np.max(u_cmd)) if u_cmd.size else 0.0,
        "saturated_fraction": float(np.mean(np.any(u_cmd >= u_max * (1.0 - 1e-6), axis=1)))
        if u_cmd.size
        else 0.0,
        "constraint_violation": float(max(0.0, np.max(excess))) if excess.size else 0.0,
        "violation_steps": int(np.sum(excess > 1e-9)),
        **_pcts(solve, "solve_time"),
        **_pcts(solve[solved], "solve_time_solves"),
        **_pcts(np.asarray(traj.step_time, dtype=float), "step_time"),
        "n_steps": len(status),
        "n_solves": int(np.sum(solved)),
        "fallback_count": int(fallbacks),
        "failure_count": int(sum(1 for s in status if s not in FAILURE_FREE_STATUSES)),
        "status_counts": counts,
        "gamma": {
            "first": _finite_or_none(gamma[0]) if gamma.size else None,
            "last": _finite_or_none(gamma[-1]) if gamma.size else None,
            "min": float(np.min(gamma)) if gamma.size else None,
            "max": float(np.max(gamma)) if gamma.size else None,
            "count": int(gamma.size),
            "t": [float(t[k]) for k in keep],
            "values": [float(gamma_all[k]) for k in keep],
        },
    }
    return metrics
