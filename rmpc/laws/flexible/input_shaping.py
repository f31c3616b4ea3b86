"""Input shaping in front of a PD attitude loop (one of paper S's surveyed baselines).

Paper S (Fathi and Bolandi's survey of flexible satellites, in Persian) lists input shaping among
the feed-forward baselines. The
shapers are those of N. C. Singer and W. P. Seering, "Preshaping command inputs to reduce system
vibration", ASME Journal of Dynamic Systems, Measurement, and Control 112(1), 1990: for a mode of
natural frequency ``omega`` and damping ``zeta``, with ``T = 2 pi / (omega sqrt(1 - zeta^2))`` and
``K = exp(-zeta pi / sqrt(1 - zeta^2))``,

- ZV: impulses at ``0, T/2`` with amplitudes ``(1, K) / (1 + K)``;
- ZVD: impulses at ``0, T/2, T`` with amplitudes ``(1, 2K, K^2) / (1 + K)^2``.

Convolving a step with either leaves no residual vibration of that mode; ZVD also has a zero
derivative with respect to the frequency there (robust to a frequency error). The residual
vibration of a shaper on a mode ``(omega, zeta)`` is, as a fraction of an unshaped step's,
``V = exp(-zeta omega t_N) sqrt(C^2 + S^2)``, ``C, S = sum_i A_i exp(zeta omega t_i)
(cos, sin)(omega_d t_i)`` (:func:`residual_vibration`).

:class:`ShapedPD` (**assumed**, the toolkit's composition) shapes the rest-to-rest slew: at the
first sample after :meth:`ShapedPD.reset` it takes the measured attitude as the start, the rotation
``a`` about ``e`` that takes the target to it; its reference then steps towards the target by
``A_1 a``, ``A_2 a``, ... at the impulse times (the target rotated by ``(1 - sum of the amplitudes
so far) a`` about ``e``), and a PD ``u = -K_d w - K_p q_v`` acts on the error quaternion against
that reference. The shaper is designed on the plant's first flexible mode (its ``frequencies[0]``
and ``damping[0]``, the cantilever frequency of the hybrid-coordinate model) unless
``frequency`` / ``damping`` are given. Defaults: PD's gains (``K_p = 2 N m``, ``K_d = 30 N m s``),
ZVD.
"""

from __future__ import annotations

import time
from typing import Any, ClassVar, Literal

import numpy as np

from models import FlexibleSatellite
from models.attitude.quaternion import quat_error, quat_from_axis_angle, quat_multiply
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.laws.flexible.terms import FlexibleTerms, gain_matrix
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_choice, check_positive

__all__ = ["ShapedPD", "ShaperKind", "residual_vibration", "shaper"]

ShaperKind = Literal["zv", "zvd"]


def _check_mode(frequency: Any, damping: Any) -> tuple[float, float]:
    omega = check_positive(frequency, "frequency")
    zeta = check_positive(damping, "damping", allow_zero=True)
    if zeta >= 1.0:
        raise InvalidArgumentError("damping", "a damping ratio in [0, 1) (an oscillating mode)", f"{zeta:g}")
    return omega, zeta


def shaper(frequency: float, damping: float, kind: ShaperKind = "zvd") -> tuple[np.ndarray, np.ndarray]:
    """The impulse times (s) and amplitudes of a ZV or ZVD shaper for one mode.

    Parameters
    ----------
    frequency : float
        The mode's natural frequency ``omega`` (rad/s), > 0.
    damping : float
        Its damping ratio ``zeta`` in ``[0, 1)``.
    kind : {"zv", "zvd"}
        Two impulses (ZV) or three (ZVD).

    Returns
    -------
    times, amplitudes : ndarray
        ``(0, T/2)`` and ``(1, K)/(1 + K)`` (ZV) or ``(0, T/2, T)`` and ``(1, 2K, K^2)/(1 + K)^2``
        (ZVD); the amplitudes sum to 1.

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.laws.flexible.input_shaping import shaper
    >>> t, a = shaper(np.pi, 0.0)          # undamped, T = 2 s: K = 1
    >>> t.tolist(), a.tolist()
    ([0.0, 1.0, 2.0], [0.25, 0.5, 0.25])
    """
    omega, zeta = _check_mode(frequency, damping)
    kind = check_choice(kind, "kind", ("zv", "zvd"))
    root = np.sqrt(1.0 - zeta**2)
    period = 2.0 * np.pi / (omega * root)
    k = float(np.exp(-zeta * np.pi / root))
    if kind == "zv":
        return np.array([0.0, period / 2.0]), np.array([1.0, k]) / (1.0 + k)
    return np.array([0.0, period / 2.0, period]), np.array([1.0, 2.0 * k, k * k]) / (1.0 + k) ** 2


def residual_vibration(times: Any, amplitudes: Any, frequency: float, damping: float) -> float:
    """Residual vibration of a mode after a shaped step, as a fraction of an unshaped step's.

    ``V = exp(-zeta omega t_N) sqrt(C^2 + S^2)`` with ``C, S = sum_i A_i exp(zeta omega t_i)
    (cos, sin)(omega sqrt(1 - zeta^2) t_i)``, ``t_N`` the last impulse (Singer & Seering 1990).

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.laws.flexible.input_shaping import residual_vibration, shaper
    >>> t, a = shaper(1.0, 0.05)
    >>> residual_vibration(t, a, 1.0, 0.05) < 1e-12, round(residual_vibration([0.0], [1.0], 1.0, 0.05), 6)
    (True, 1.0)
    """
    omega, zeta = _check_mode(frequency, damping)
    t = np.asarray(times, dtype=float).ravel()
    a = np.asarray(amplitudes, dtype=float).ravel()
    if t.size == 0 or t.shape != a.shape or not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
        raise InvalidArgumentError(
            "times", "finite impulse times and amplitudes of one length >= 1", f"{t.size} and {a.size}"
        )
    omega_d = omega * np.sqrt(1.0 - zeta**2)
    grow = a * np.exp(zeta * omega * t)
    c, s = float(grow @ np.cos(omega_d * t)), float(grow @ np.sin(omega_d * t))
    return float(np.exp(-zeta * omega * t.max()) * np.hypot(c, s))


class ShapedPD:
    """A PD acting on a ZV- or ZVD-shaped slew reference; record name "ZVD-PD" or "ZV-PD".

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model (its first mode designs the shaper).
    dt : float
        Sample time (s); the reference steps at the first sample at or after each impulse time.
    q_ref : (4,) array_like, optional
        Target attitude (default the identity).
    K_p, K_d : float, (3,) or (3, 3) array_like
        Attitude (N m) and rate (N m s) gains of the PD.
    kind : {"zvd", "zv"}
        The shaper.
    frequency, damping : float, optional
        The mode the shaper is designed for (rad/s, ratio); default the plant's first.

    Attributes
    ----------
    times, amplitudes : ndarray
        The shaper's impulses (:func:`shaper`).

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from models.attitude.quaternion import quat_from_axis_angle
    >>> from rmpc.laws.flexible.input_shaping import ShapedPD
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> law = ShapedPD(sat)
    >>> law.name, [round(float(a), 4) for a in law.amplitudes]
    ('ZVD-PD', [0.2544, 0.5, 0.2456])
    >>> u = law.step(sat.state(quat_from_axis_angle([0, 0, 1], 0.2)))   # first step: A_1 of the slew
    >>> round(float(u[2]), 4)                                            # -K_p sin(A_1 0.1)
    -0.0509
    """

    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(
        self,
        plant: FlexibleSatellite,
        dt: float = 0.01,
        *,
        q_ref: Any = None,
        K_p: Any = 2.0,
        K_d: Any = 30.0,
        kind: ShaperKind = "zvd",
        frequency: float | None = None,
        damping: float | None = None,
    ) -> None:
        self.terms = FlexibleTerms(plant, q_ref, flex_feedforward=False)
        self.dt = check_positive(dt, "dt")
        self.K_p = gain_matrix(K_p, "K_p")
        self.K_d = gain_matrix(K_d, "K_d")
        if plant.n_modes == 0 and (frequency is None or damping is None):
            raise InvalidArgumentError("frequency", "a mode to shape for (the plant has no modes)", "None")
        omega = float(plant.frequencies[0]) if frequency is None else frequency
        zeta = float(plant.damping[0]) if damping is None else damping
        self.kind: ShaperKind = check_choice(kind, "kind", ("zv", "zvd"))
        self.times, self.amplitudes = shaper(omega, zeta, self.kind)
        self.frequency, self.damping = _check_mode(omega, zeta)
        self.name: str = f"{self.kind.upper()}-PD"
        self.last: StepInfo | None = None
        self.reset()

    def reset(self) -> None:
        """Forget the start: the next sample's attitude starts a new shaped slew."""
        self._count = 0
        self._axis: np.ndarray | None = None
        self._angle = 0.0
        self.last = None

    def fraction(self, t: float) -> float:
        """The share of the slew commanded at time ``t`` after the start (the amplitudes so far)."""
        return float(self.amplitudes[self.times <= t + 1e-9 * self.dt].sum())

    def reference(self, t: float) -> np.ndarray:
        """The shaped reference attitude at time ``t`` after the start (the target before a start)."""
        if self._axis is None:
            return self.terms.q_ref.copy()
        rest = quat_from_axis_angle(self._axis, (1.0 - self.fraction(t)) * self._angle)
        return quat_multiply(self.terms.q_ref, rest)

    def step(self, x: Any, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``[u; v]`` for the measured state (``v = inputs.pzt``, this sample's PZT command, or 0)."""
        start = time.perf_counter()
        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        q, w, _, _ = self.terms.split(x)
        q = q / np.linalg.norm(q)
        if self._count == 0:
            err0 = quat_error(q, self.terms.q_ref)
            norm = float(np.linalg.norm(err0[1:]))
            self._angle = 2.0 * float(np.arctan2(norm, err0[0]))
            self._axis = err0[1:] / norm if norm > 0.0 else None
        t = self._count * self.dt
        self._count += 1
        q_r = self.reference(t)
        qv = quat_error(q, q_r)[1:]
        u = -self.K_d @ w - self.K_p @ qv
        extra = {"fraction": self.fraction(t)}
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start, extra=extra)
        return self.terms.command(u, pzt)

    def __repr__(self) -> str:
        return f"ShapedPD(kind={self.kind!r}, frequency={self.frequency:g}, damping={self.damping:g})"
