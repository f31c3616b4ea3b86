"""Metrics of paper W's fault scenarios, computed from a :class:`~rmpc.Trajectory`.

The wheel satellite's state is ``[phi, theta, psi, p, q, r, h_1..h_m]`` and its runs carry the
input stage's per-sample log (:class:`models.WheelInputStage`, ``Trajectory.stage_log``).
The record fields are :func:`recovery_times` (``recovery_time`` per fault
event), :func:`peak_abs_error` (``peak_abs_err`` per window), :func:`saturated_fraction`
(``sat_fraction``), :func:`max_abs_momentum` (``max_abs_h``), :func:`momentum_limit_events`
(``momentum_limit_events``) and :func:`torque_summary` (commanded vs applied torque); beyond
them, :func:`null_momentum` (``null_momentum``: the wheel momentum the body does not feel, at
the last fault event and at the end) and :func:`torque_variation_rate` (``torque_tv_rate``: how
much the applied torques chatter late in the run);
:func:`fault_metrics` gathers them all (with the rank-deficient windows of the schedule).

Angles are errors from the target ``eta_d = 0``; the yaw error is wrapped to ``(-pi, pi]``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from benchmarks.core.metrics import AXES, check_trajectory, recovery_time
from models import FaultSchedule, WheelArray, rank_deficient_windows
from rmpc.sim.trajectory import Trajectory
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_positive

__all__ = [
    "RECOVERY_THRESHOLD",
    "attitude_error",
    "fault_metrics",
    "max_abs_momentum",
    "momentum_limit_events",
    "null_momentum",
    "peak_abs_error",
    "recovery_times",
    "saturated_fraction",
    "torque_summary",
    "torque_variation_rate",
]

#: Recovery threshold: ``max_i |eta_i| <= 2 deg`` (**assumed**: paper W gives none), in rad.
RECOVERY_THRESHOLD: float = math.radians(2.0)

def attitude_error(traj: Trajectory) -> np.ndarray:
    """``|eta|`` per sample and axis (rad), yaw wrapped to ``(-pi, pi]``; shape ``(N + 1, 3)``."""
    eta = np.array(check_trajectory(traj).x[:, :3], dtype=float)
    eta[:, 2] = np.remainder(eta[:, 2] + np.pi, 2.0 * np.pi) - np.pi
    return np.abs(eta)


def recovery_times(
    traj: Trajectory, faults: FaultSchedule, threshold: float = RECOVERY_THRESHOLD
) -> list[dict[str, Any]]:
    """Recovery time per fault event: from the event until ``max_i |eta_i|`` stays <= ``threshold``.

    The events are every fault's onset and (when inside the run) its end. "Stays" means up to
    the next event or the end of the run, whichever comes first; if the error is above the
    threshold at that horizon the recovery time is ``None`` (not recovered).

    Returns
    -------
    list of dict
        One per event, in time order: ``t_event`` (s), ``event`` (``"onset"`` or ``"end"``),
        ``wheel``, ``kind``, ``horizon`` (s, the next event or the run's end) and
        ``recovery_time`` (s after ``t_event``, or ``None``).
    """
    traj = check_trajectory(traj)
    if not isinstance(faults, FaultSchedule):
        raise ArgumentTypeError("faults", "a models.FaultSchedule", type(faults).__name__)
    threshold = check_positive(threshold, "threshold")
    t_end = float(traj.t[-1])
    err = attitude_error(traj).max(axis=1)
    events = []
    for f in faults.faults:
        if f.t_on < t_end:
            events.append((f.t_on, "onset", f))
        if math.isfinite(f.t_off) and f.t_off < t_end:
            events.append((f.t_off, "end", f))
    events.sort(key=lambda e: e[0])
    times = sorted({e[0] for e in events})
    out = []
    for t_ev, kind, f in events:
        later = [t for t in times if t > t_ev]
        horizon = later[0] if later else t_end
        in_window = (traj.t >= t_ev - 1e-12) & (traj.t <= horizon + 1e-12)
        rec = recovery_time(traj.t[in_window], err[in_window], t_ev, threshold)
        out.append(
            {
                "t_event": float(t_ev),
                "event": kind,
                "wheel": f.wheel,
                "kind": f.kind,
                "horizon": float(horizon),
                "recovery_time": rec,
            }
        )
    return out


def peak_abs_error(traj: Trajectory, windows: Sequence[tuple[float, float]]) -> list[dict[str, Any]]:
    """The peak ``|eta_i|`` per axis (rad) inside each window ``[t_start, t_end)``.

    Windows are cut at the end of the run; an empty window gives ``None`` peaks.
    """
    traj = check_trajectory(traj)
    err = attitude_error(traj)
    out = []
    for i, window in enumerate(windows):
        try:
            t0, t1 = (float(v) for v in window)
        except (TypeError, ValueError):
            raise InvalidArgumentError(f"windows[{i}]", "a (t_start, t_end) pair", repr(window)) from None
        if not t1 > t0:
            raise InvalidArgumentError(f"windows[{i}]", "t_end > t_start", repr(window))
        mask = (traj.t >= t0) & (traj.t < t1)
        peak = {ax: (float(err[mask, a].max()) if mask.any() else None) for a, ax in enumerate(AXES)}
        out.append({"t_start": t0, "t_end": t1, "peak": peak})
    return out


def saturated_fraction(traj: Trajectory, torque_max: Any = None) -> dict[str, Any]:
    """Fraction of samples in which a wheel's torque was clipped (overall and per wheel).

    Uses the stage log's ``torque_clipped`` when present; otherwise compares the commands
    with ``torque_max`` (required then).
    """
    traj = check_trajectory(traj)
    if "torque_clipped" in traj.stage_log:
        clipped = np.asarray(traj.stage_log["torque_clipped"], dtype=bool)
    else:
        if torque_max is None:
            raise InvalidArgumentError(
                "torque_max", "the wheels' torque limits (the run has no stage log)", "None"
            )
        clipped = np.abs(traj.u_cmd) > np.asarray(torque_max, dtype=float)
    return {"any": float(clipped.any(axis=1).mean()), "per_wheel": clipped.mean(axis=0).tolist()}


def max_abs_momentum(traj: Trajectory, momentum_index: int = 6) -> list[float]:
    """``max_k |h_j(t_k)|`` per wheel (N m s)."""
    h = check_trajectory(traj).x[:, momentum_index:]
    if h.shape[1] == 0:
        raise InvalidArgumentError(
            "traj", "a run of the wheel satellite (wheel momenta in the state)", f"{traj.x.shape[1]} states"
        )
    return np.abs(h).max(axis=0).tolist()


def momentum_limit_events(traj: Trajectory) -> dict[str, Any]:
    """Momentum-limit events from the stage log: each start of a held stretch, per wheel.

    Returns ``count`` (events), ``samples`` (samples spent held), ``events`` (a list of
    ``{"t", "wheel"}``, wheels from 1) and ``fault_altered`` (samples in which an active
    fault's torque was changed by a limit: "fault output altered by momentum limit").
    """
    traj = check_trajectory(traj)
    if "momentum_limited" not in traj.stage_log:
        raise InvalidArgumentError(
            "traj",
            "a run with a WheelInputStage log (momentum_limited)",
            f"stage_log keys {sorted(traj.stage_log)}",
        )
    held = np.asarray(traj.stage_log["momentum_limited"], dtype=bool)
    starts = held & ~np.vstack((np.zeros((1, held.shape[1]), dtype=bool), held[:-1]))
    rows, cols = np.nonzero(starts)
    events = [{"t": float(traj.t[r]), "wheel": int(c) + 1} for r, c in zip(rows, cols, strict=True)]
    altered = np.asarray(traj.stage_log.get("fault_altered", np.zeros_like(held)), dtype=bool)
    return {
        "count": len(events),
        "samples": int(held.any(axis=1).sum()),
        "events": events,
        "fault_altered": int(altered.any(axis=1).sum()),
    }


def torque_summary(traj: Trajectory) -> dict[str, Any]:
    """Commanded vs applied torque: the largest of each (N m, overall and per wheel)."""
    traj = check_trajectory(traj)
    cmd, app = np.abs(traj.u_cmd), np.abs(traj.u_applied)
    return {
        "max_abs_u_cmd": float(cmd.max()),
        "max_abs_u": float(app.max()),
        "max_abs_u_cmd_per_wheel": cmd.max(axis=0).tolist(),
        "max_abs_u_per_wheel": app.max(axis=0).tolist(),
    }


def null_momentum(traj: Trajectory, wheels: WheelArray, t_from: float) -> dict[str, Any]:
    """The wheel momentum in the null space of ``D`` (N m s), at ``t_from`` and at the end.

    ``h`` splits into ``D^+ D h`` (the momentum the body exchanges with the wheels) and its
    null-space part ``P h``, ``P = I - D^+ D``, which no body torque reveals: a controller that
    keeps a null-space torque after the faults winds the wheels up while the attitude stays put.

    Returns
    -------
    dict
        ``t_from`` (s; the sample at or after it), ``at_t_from`` and ``final`` (``|P h|``) and
        ``drift`` (``final - at_t_from``).

    For paper W's array ``P h`` is ``(n' h) n`` with ``n = (1, 1, 1, -sqrt 3)/sqrt 6``.
    """
    traj = check_trajectory(traj)
    if not isinstance(wheels, WheelArray):
        raise ArgumentTypeError("wheels", "a models.WheelArray", type(wheels).__name__)
    h = np.asarray(traj.x[:, 6:], dtype=float)
    if h.shape[1] != wheels.n_wheels:
        raise InvalidArgumentError(
            "traj", f"a run with {wheels.n_wheels} wheel momenta in the state", f"{h.shape[1]}"
        )
    d = wheels.D
    proj = np.eye(d.shape[1]) - np.linalg.pinv(d) @ d
    size = np.linalg.norm(h @ proj.T, axis=1)
    k = min(int(np.searchsorted(traj.t, t_from - 1e-12)), len(traj.t) - 1)
    return {
        "t_from": float(traj.t[k]),
        "at_t_from": float(size[k]),
        "final": float(size[-1]),
        "drift": float(size[-1] - size[k]),
    }


def torque_variation_rate(traj: Trajectory, t_from: float) -> float:
    """Total variation of the applied wheel torques per second from ``t_from`` on (N m/s).

    ``sum_j sum_k |u_j[k+1] - u_j[k]| / (t_end - t_from)`` over the held samples at or after
    ``t_from`` (as paper M's chattering metric): near zero for torques that settle, large for
    torques that chatter.
    """
    traj = check_trajectory(traj)
    t_samples = traj.t[: len(traj.u_applied)]
    mask = t_samples >= t_from - 1e-12
    u = np.asarray(traj.u_applied, dtype=float)[mask]
    span = float(traj.t[-1] - t_from)
    if len(u) < 2 or span <= 0.0:
        return 0.0
    return float(np.abs(np.diff(u, axis=0)).sum() / span)


def fault_metrics(
    traj: Trajectory,
    faults: FaultSchedule,
    wheels: WheelArray,
    threshold: float = RECOVERY_THRESHOLD,
) -> dict[str, Any]:
    """Every metric of paper W's scenarios for one run (the record fields).

    Returns a dict with ``final_abs_err`` (per axis, rad), ``max_abs_u`` (applied, N m),
    ``max_abs_u_cmd``, ``recovery_time`` (per event, :func:`recovery_times`), ``peak_abs_err``
    (per fault window and per rank-deficient window, :func:`peak_abs_error`),
    ``sat_fraction``, ``max_abs_h``, ``momentum_limit_events``, ``rank_deficient_windows``
    (``[t_start, t_end, rank, wheels]``), ``max_abs_angle_deg`` (per axis, for the +-40 deg
    range of the platform), ``status_counts``, ``final_h`` (per wheel, N m s),
    ``null_momentum`` (from the last fault event inside the run, or from the start when there
    is none; :func:`null_momentum`) and ``torque_tv_rate`` (over the second half of the run;
    :func:`torque_variation_rate`).
    """
    traj = check_trajectory(traj)
    if not isinstance(wheels, WheelArray):
        raise ArgumentTypeError("wheels", "a models.WheelArray", type(wheels).__name__)
    err = attitude_error(traj)
    t_end = float(traj.t[-1])
    fault_windows = [(f.t_on, min(f.t_off, t_end)) for f in faults.faults if f.t_on < t_end]
    rank_windows = rank_deficient_windows(faults, wheels, t_end)
    torques = torque_summary(traj)
    out: dict[str, Any] = {
        "final_abs_err": {ax: float(err[-1, a]) for a, ax in enumerate(AXES)},
        "max_abs_u": torques["max_abs_u"],
        "max_abs_u_cmd": torques["max_abs_u_cmd"],
        "recovery_time": recovery_times(traj, faults, threshold),
        "peak_abs_err": {
            "fault_windows": peak_abs_error(traj, fault_windows),
            "rank_deficient_windows": peak_abs_error(traj, [(w.t_start, w.t_end) for w in rank_windows]),
        },
        "sat_fraction": saturated_fraction(traj, wheels.torque_max),
        "max_abs_h": max_abs_momentum(traj),
        "rank_deficient_windows": [[w.t_start, w.t_end, w.rank, list(w.wheels)] for w in rank_windows],
        "max_abs_angle_deg": {ax: float(np.degrees(err[:, a].max())) for a, ax in enumerate(AXES)},
        "status_counts": traj.status_counts(),
        "final_h": np.asarray(traj.x[-1, 6:], dtype=float).tolist(),
    }
    events = [t for f in faults.faults for t in (f.t_on, f.t_off) if math.isfinite(t) and t < t_end]
    out["null_momentum"] = null_momentum(traj, wheels, max(events, default=0.0))
    out["torque_tv_rate"] = torque_variation_rate(traj, 0.5 * t_end)
    if "momentum_limited" in traj.stage_log:
        out["momentum_limit_events"] = momentum_limit_events(traj)
    return out
