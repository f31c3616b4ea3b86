"""The metrics of paper V's study, computed from a closed-loop run on the flexible satellite.

Definitions where paper V gives none are the toolkit's (**assumed**):

- ``t_s``: the last time the rotation error exceeds ``threshold`` (default 1 deg; 0 if it never
  does, ``inf`` if the final error exceeds it): :func:`benchmarks.core.metrics.last_time_above`,
  an absolute threshold, unlike the core's relative-band ``settling_time``;
- ``final_error``: the rotation error at the end (rad);
- ``rms_error_tail``: RMS rotation error over the last ``tail`` seconds (paper V's "accuracy");
- ``peak_u``: largest applied hub torque component (N m); ``saturated_fraction``: share of
  samples where the limiter changed the hub torque;
- ``ci``: chattering index ``(1/T) sum_k ||u(k+1) - u(k)||_1`` of the applied hub torque (N m/s,
  :func:`benchmarks.core.metrics.total_variation_rate` over the run);
- ``effort``: ``int ||u||_1 dt`` of the applied hub torque (N m s);
- ``hf_power_fraction``: the share of the applied hub torque's power (mean removed, all axes)
  at frequencies above the first modal frequency ``Lambda_1`` (0 without modes or
  torque variation);
- ``eta_peak`` / ``eta_residual``: per mode, the largest ``|eta_i|`` over the run / over the tail;
- ``modal_energy_residual``: the largest modal energy ``eta'' M eta'/2 + eta' K eta/2`` over the tail;
- ``v_peak``: largest applied PZT command;
- ``regime``: paper S's label of ``bandwidth`` (when given) against ``Lambda_1``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from benchmarks.core.metrics import check_trajectory, last_time_above, total_variation_rate
from models import FlexibleSatellite
from models.attitude.quaternion import rotation_angle
from rmpc.sim.trajectory import Trajectory
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_positive

__all__ = ["flexible_metrics", "power_fraction_above"]


def power_fraction_above(u: np.ndarray, dt: float, frequency: float) -> float:
    """Share of the power of ``u`` (samples along axis 0, mean removed) above ``frequency`` (rad/s).

    Examples
    --------
    >>> import numpy as np
    >>> from benchmarks.families.flexible.metrics import power_fraction_above
    >>> t = np.arange(1000) * 0.01
    >>> u = np.sin(0.5 * 2 * np.pi * t) + 0.1 * np.sin(5.0 * 2 * np.pi * t)   # 0.5 Hz and 5 Hz
    >>> round(power_fraction_above(u[:, None], 0.01, 2 * np.pi * 2.0), 4)   # above 2 Hz
    0.0099
    """
    arr = np.asarray(u, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.shape[0] < 2:
        return 0.0
    spectrum = np.abs(np.fft.rfft(arr - arr.mean(axis=0), axis=0)) ** 2
    total = float(spectrum.sum())
    if total == 0.0:
        return 0.0
    omega = 2.0 * np.pi * np.fft.rfftfreq(arr.shape[0], dt)
    return float(spectrum[omega > frequency].sum()) / total


def flexible_metrics(
    traj: Trajectory,
    satellite: FlexibleSatellite,
    *,
    q_ref: ArrayLike | None = None,
    threshold: float = np.deg2rad(1.0),
    tail: float = 10.0,
    bandwidth: float | None = None,
) -> dict[str, Any]:
    """Paper V's metrics of one run (see the module docstring).

    Parameters
    ----------
    traj : Trajectory
        A run of :func:`rmpc.sim.simulate` on ``satellite`` (states ``[q, w, eta, eta']``, inputs
        ``[u; v]``).
    satellite : FlexibleSatellite
        The simulated plant.
    q_ref : (4,) array_like, optional
        Target attitude (default the identity).
    threshold : float
        Settling threshold on the rotation error (rad).
    tail : float
        Length (s) of the final window of the residual metrics.
    bandwidth : float, optional
        The closed loop's attitude bandwidth (rad/s) for the regime label.

    Returns
    -------
    dict
        The metrics by name.
    """
    check_trajectory(traj)
    if not isinstance(satellite, FlexibleSatellite):
        raise ArgumentTypeError("satellite", "a models.FlexibleSatellite", type(satellite).__name__)
    if traj.x.shape[1] != satellite.n_states:
        raise InvalidArgumentError(
            "traj", f"states of length {satellite.n_states}", f"length {traj.x.shape[1]}"
        )
    threshold = check_positive(threshold, "threshold")
    tail = check_positive(tail, "tail")
    n = satellite.n_modes
    error = np.array([rotation_angle(x[:4], q_ref) for x in traj.x])
    duration = float(traj.t[-1] - traj.t[0])
    in_tail = traj.t >= traj.t[-1] - tail
    u = traj.u_applied[:, :3]
    v = traj.u_applied[:, 3:]
    eta = np.abs(traj.x[:, 7:7 + n])
    out: dict[str, Any] = {
        "t_s": last_time_above(traj.t, error, threshold),
        "final_error": float(error[-1]),
        "rms_error_tail": float(np.sqrt(np.mean(error[in_tail] ** 2))),
        "peak_u": float(np.abs(u).max()) if u.size else 0.0,
        "saturated_fraction": float(np.mean(np.any(traj.u_cmd[:, :3] != u, axis=1))) if u.size else 0.0,
        "ci": total_variation_rate(u, duration),
        "effort": float(np.sum(np.abs(u)) * traj.dt),
        "eta_peak": eta.max(axis=0) if n else np.zeros(0),
        "eta_residual": eta[in_tail].max(axis=0) if n else np.zeros(0),
        "modal_energy_residual": max(satellite.modal_energy(x) for x in traj.x[in_tail]),
        "v_peak": float(np.abs(v).max()) if v.size else 0.0,
        "hf_power_fraction": power_fraction_above(u, traj.dt, float(satellite.frequencies[0]))
        if n else 0.0,
    }
    if bandwidth is not None:
        out["regime"] = satellite.regime(bandwidth)
    return out
