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
- ``regime``: paper S's label of ``bandwidth`` (when given) against ``Lambda_1``;
- ``eta1_rms_early`` / ``eta1_rms_late``: RMS of ``eta_1`` over the windows :data:`EARLY_WINDOW` and
  :data:`LATE_WINDOW` (fractions of the run: [30, 60] s and [120, 150] s of the 150 s V-slew);
  ``eta1_decay_rate``: ``ln(early / late)`` over the time between the windows' centres (1/s, ``None``
  when either is 0); ``mode1_open_loop_decay_rate``: ``-Re`` of the plant's first free-free mode
  without control (1/s, the rate at which ``eta_1`` decays when nothing feeds or damps it);
- ``modal_work_peak`` / ``modal_work_after``: the work ``-int eta'^T delta w' dt`` of the hub's motion on
  the modes (J, :func:`hub_work_on_modes`): its largest running value, and what it adds from the start
  of :data:`EARLY_WINDOW` to the end (the excitation after "about 30 s" of paper V);
- ``rate_hf_rms_late`` / ``attitude_hf_rms_late_deg``: RMS over :data:`LATE_WINDOW` of the part of
  the body rate (rad/s) and of the attitude error's rotation vector ``2 q_v`` (deg) above
  ``Lambda_1 / 2`` (:func:`highpass` over the whole run); ``rate_hf_share_late`` /
  ``attitude_hf_share_late``: each over the RMS of its whole signal on that window (``None`` for
  runs too short to filter). The late window, because early in a slew the part above
  ``Lambda_1 / 2`` is also the loop's own fast transient (it is the same with the modes damped by
  AVC), while at the end it is the modes';
- ``modal_energy_ratio``: the largest modal energy over the largest rigid kinetic energy ``w' J w / 2``
  (0 for a run that never moves).
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

__all__ = [
    "EARLY_WINDOW",
    "LATE_WINDOW",
    "flexible_metrics",
    "highpass",
    "hub_work_on_modes",
    "open_loop_decay_rate",
    "power_fraction_above",
]

#: The early window of the modal decay metrics, as fractions of the run length ([30, 60] s of the
#: 150 s V-slew: paper V's "after about 30 s").
EARLY_WINDOW: tuple[float, float] = (0.2, 0.4)
#: The late window, as fractions of the run length ([120, 150] s of the V-slew).
LATE_WINDOW: tuple[float, float] = (0.8, 1.0)
#: Order of the zero-phase Butterworth high-pass of :func:`highpass`.
HIGHPASS_ORDER = 4


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


def highpass(signal: np.ndarray, dt: float, cutoff: float) -> np.ndarray | None:
    """The part of ``signal`` (samples along axis 0) above ``cutoff`` (rad/s).

    A zero-phase Butterworth high-pass of order :data:`HIGHPASS_ORDER` (``scipy.signal.sosfiltfilt``),
    so a slow slew leaves little trace while a modal oscillation passes; near either end the
    filter's edge transient remains.
    ``None`` when the run is too short to filter or ``cutoff`` is at or above the Nyquist frequency.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0.0, 200.0, 0.01)
    >>> slow, fast = np.sin(0.02 * t), 0.01 * np.sin(0.8 * t)   # a slew-like and a modal part
    >>> hf = highpass(slow + fast, 0.01, 0.4)
    >>> bool(np.abs(hf - fast)[2000:-2000].max() < 1e-3)   # 4.4e-4 measured, 20 s from the ends
    True
    """
    from scipy.signal import butter, sosfiltfilt

    arr = np.asarray(signal, dtype=float)
    nyquist = np.pi / dt
    if not 0.0 < cutoff < nyquist:
        return None
    sos = butter(HIGHPASS_ORDER, cutoff / nyquist, btype="highpass", output="sos")
    if arr.shape[0] <= 3 * (2 * sos.shape[0] + 1):  # sosfiltfilt's default padding
        return None
    # sosfiltfilt's default padding (15 samples, initial conditions at steady state): on the V-slew's
    # last fifth it leaves 7e-8 rad/s of the body rate when AVC damps the modes, against 1.5e-6 without
    # AVC; an odd padding over one period of ``cutoff`` raised the former to 2.4e-6 (measured)
    return sosfiltfilt(sos, arr, axis=0)


def hub_work_on_modes(traj: Trajectory, satellite: FlexibleSatellite) -> np.ndarray:
    """The running work (J) of the hub's motion on the modes, ``-int eta'^T delta w' dt``, at ``traj.t``.

    From the modal energy balance ``E_m' = -eta'^T C eta' - eta'^T delta w' + eta'^T Gamma_a v``
    (``M = I``, no panel disturbance): the change of the modal energy plus what the damping took out
    minus what the PZT forces put in (trapezoidal rule between samples, the PZT command held).
    """
    n = satellite.n_modes
    eta_dot = traj.x[:, 7 + n : 7 + 2 * n]
    energy = np.array([satellite.modal_energy(x) for x in traj.x])
    damping = np.einsum("ti,ij,tj->t", eta_dot, np.asarray(satellite.damping_matrix), eta_dot)
    lost = np.concatenate(([0.0], np.cumsum(0.5 * (damping[1:] + damping[:-1]) * np.diff(traj.t))))
    v = traj.u_applied[:, 3:]
    if v.size:
        force = v @ np.asarray(satellite.pzt_matrix).T
        power = 0.5 * ((eta_dot[:-1] + eta_dot[1:]) * force).sum(axis=1)
        pzt = np.concatenate(([0.0], np.cumsum(power * np.diff(traj.t))))
    else:
        pzt = np.zeros_like(lost)
    return energy - energy[0] + lost - pzt


def open_loop_decay_rate(satellite: FlexibleSatellite) -> float:
    """``-Re`` (1/s) of the uncontrolled plant's slowest oscillatory eigenvalue (its first free-free mode).

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> round(open_loop_decay_rate(FlexibleSatellite.di_gennaro()), 4)
    0.005
    """
    a = np.asarray(satellite.linearize(attitude="quaternion")[0])
    ev = np.linalg.eigvals(a)
    ev = ev[np.abs(ev.imag) > 1e-9]
    return float(-ev[np.argmin(np.abs(ev.imag))].real)


def _window(t: np.ndarray, fractions: tuple[float, float]) -> np.ndarray:
    t0, t1 = float(t[0]), float(t[-1])
    lo, hi = (t0 + f * (t1 - t0) for f in fractions)
    return (t >= lo - 1e-9) & (t <= hi + 1e-9)


def _rms(values: np.ndarray) -> float:
    """RMS over the samples (axis 0) of a scalar signal or of a vector signal's norm (0 when empty)."""
    arr = np.asarray(values, dtype=float)
    if arr.shape[0] == 0:
        return 0.0
    arr = arr.reshape(arr.shape[0], -1)
    return float(np.sqrt(np.mean(np.sum(arr**2, axis=1))))


def _modal_metrics(traj: Trajectory, satellite: FlexibleSatellite) -> dict[str, Any]:
    """The decay, excitation, rate and energy-ratio metrics (see the module docstring)."""
    n = satellite.n_modes
    t = traj.t
    out: dict[str, Any] = {}
    early, late = _window(t, EARLY_WINDOW), _window(t, LATE_WINDOW)
    if n:
        eta1 = traj.x[:, 7]
        rms_e, rms_l = _rms(eta1[early]), _rms(eta1[late])
        gap = float(np.mean(t[late]) - np.mean(t[early])) if early.any() and late.any() else 0.0
        out["eta1_rms_early"], out["eta1_rms_late"] = rms_e, rms_l
        decays = rms_e > 0 and rms_l > 0 and gap > 0
        out["eta1_decay_rate"] = float(np.log(rms_e / rms_l) / gap) if decays else None
        out["mode1_open_loop_decay_rate"] = open_loop_decay_rate(satellite)
        work = hub_work_on_modes(traj, satellite)
        start = int(np.argmax(early))
        out["modal_work_peak"] = float(work.max())
        out["modal_work_after"] = float(work[-1] - work[start])
    w = traj.x[:, 4:7]
    q = traj.x[:, :4]
    rotvec = 2.0 * q[:, 1:4] * np.where(q[:, :1] < 0.0, -1.0, 1.0)  # error rotation vector, q0 >= 0
    cutoff = float(satellite.frequencies[0]) / 2.0 if n else np.inf
    hw = highpass(w, traj.dt, cutoff) if n else None
    hq = highpass(rotvec, traj.dt, cutoff) if n else None
    out["rate_hf_rms_late"] = None if hw is None else _rms(hw[late])
    out["attitude_hf_rms_late_deg"] = None if hq is None else float(np.degrees(_rms(hq[late])))
    rms_w, rms_q = _rms(w[late]), _rms(rotvec[late])
    out["rate_hf_share_late"] = None if hw is None or rms_w == 0 else _rms(hw[late]) / rms_w
    out["attitude_hf_share_late"] = None if hq is None or rms_q == 0 else _rms(hq[late]) / rms_q
    inertia = np.asarray(satellite.inertia)
    kinetic = 0.5 * np.einsum("ti,ij,tj->t", w, inertia, w).max()
    modal = max(satellite.modal_energy(x) for x in traj.x)
    out["modal_energy_ratio"] = float(modal / kinetic) if kinetic > 0 else 0.0
    return out


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
    out.update(_modal_metrics(traj, satellite))
    if bandwidth is not None:
        out["regime"] = satellite.regime(bandwidth)
    return out
