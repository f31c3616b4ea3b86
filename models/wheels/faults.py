"""Reaction-wheel faults, fault schedules and the redundancy checker (paper W).

Each fault acts on one wheel in the per-wheel form ``u_j = lambda_j(t) nu_j + b_j(t)``,
``nu_j`` the command reaching the wheel and ``u_j`` its torque before the limits:

===================  ===========================  =================================================
kind                 final ``(lambda, b(t))``     paper W
===================  ===========================  =================================================
``"stuck"``          ``(0, value)``               constant torque ``c`` (0.05 N m in S1, else 0.03)
``"sinusoidal"``     ``(0, value sin(w t + p))``  ``0.03 sin(0.2 t)``, ``t`` the absolute time
``"outage"``         ``(0, 0)``                   the wheel gives nothing
``"effectiveness"``  ``(lambda, 0)``              loss of effectiveness (Remark 1)
``"bias"``           ``(1, value)``               additive fault (Remark 1, additive reading)
===================  ===========================  =================================================

A fault holds on its window ``t_on <= t < t_off``; after ``t_off`` the wheel obeys again
(**likely**: paper W gives only windows) and keeps the momentum it has. The onset is abrupt
(paper W's tests) or exponential (Remark 2): ``mu(t) = 1 - exp(-rho (t - t_on))``,
``lambda(t) = 1 - (1 - lambda) mu(t)`` and ``b(t) = mu(t) b``, with ``rho = 1`` 1/s by
default (**assumed**).

Wheels are numbered from 1, as in paper W's text ("wheel 2 stuck"): ``WheelFault(wheel=2)``
acts on ``u[1]`` and ``D[:, 1]``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from models.wheels.array import MAX_WHEELS, WheelArray, _rank, _wheel_count
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_choice, check_positive, check_real

__all__ = [
    "FAULT_KINDS",
    "FaultSchedule",
    "RankWindow",
    "WheelFault",
    "rank_deficient_windows",
]

FaultKind = Literal["stuck", "sinusoidal", "outage", "effectiveness", "bias"]
#: The fault kinds, in the order of the module table.
FAULT_KINDS: tuple[str, ...] = ("stuck", "sinusoidal", "outage", "effectiveness", "bias")
_NEEDS_VALUE = ("stuck", "sinusoidal", "bias")


class WheelFault:
    """One fault on one wheel over a time window.

    Parameters
    ----------
    wheel : int
        The wheel, numbered from 1 (paper W's numbering).
    kind : {"stuck", "sinusoidal", "outage", "effectiveness", "bias"}
        See the module table.
    t_on : float
        Onset time (s, >= 0).
    t_off : float
        End of the window (s, > ``t_on``); ``inf`` (default): until the end of the run.
    value : float, optional
        The stuck torque, the sinusoid's amplitude or the bias (N m); required for those kinds
        and rejected for the others.
    frequency : float, optional
        Angular frequency of the sinusoid (rad/s; default 0.2, paper W); sinusoidal only.
    phase : float, optional
        Phase of the sinusoid (rad; default 0); sinusoidal only.
    effectiveness : float, optional
        The remaining effectiveness ``lambda`` in [0, 1]; required for ``"effectiveness"``.
    onset : {"abrupt", "exponential"}
        Abrupt (default, paper W's tests) or exponential onset (Remark 2).
    onset_rate : float
        ``rho`` (1/s, > 0) of the exponential onset (default 1, **assumed**).

    Examples
    --------
    >>> from models import WheelFault
    >>> fault = WheelFault(wheel=2, kind="stuck", t_on=8.0, t_off=37.0, value=0.05)
    >>> fault.torque(10.0, commanded=0.1), fault.torque(40.0, commanded=0.1)
    (0.05, 0.1)
    >>> WheelFault(wheel=1, kind="effectiveness", t_on=0.0, effectiveness=0.25).torque(5.0, 1.0)
    0.25
    """

    def __init__(
        self,
        wheel: int,
        kind: FaultKind | str,
        t_on: float,
        t_off: float = math.inf,
        value: float | None = None,
        *,
        frequency: float | None = None,
        phase: float | None = None,
        effectiveness: float | None = None,
        onset: Literal["abrupt", "exponential"] = "abrupt",
        onset_rate: float = 1.0,
    ) -> None:
        if isinstance(wheel, bool) or not isinstance(wheel, int | np.integer):
            raise ArgumentTypeError(
                "wheel", "a wheel number (int, from 1)", f"{type(wheel).__name__} {wheel!r}"
            )
        if wheel < 1:
            raise InvalidArgumentError(
                "wheel", "a wheel number >= 1 (wheels are numbered from 1)", repr(wheel)
            )
        self.wheel = int(wheel)
        self.kind: str = check_choice(kind, "kind", FAULT_KINDS)
        self.t_on = check_positive(t_on, "t_on", allow_zero=True)
        t_off_val = check_real(t_off, "t_off") if t_off != math.inf else math.inf
        if not t_off_val > self.t_on:
            raise InvalidArgumentError("t_off", f"an end after t_on = {self.t_on:g} s (or inf)", repr(t_off))
        self.t_off = float(t_off_val)
        if kind in _NEEDS_VALUE:
            if value is None:
                raise InvalidArgumentError("value", f"a torque (N m) for a {kind!r} fault", "None")
            self.value = check_real(value, "value")
        else:
            if value is not None:
                raise InvalidArgumentError("value", f"None for a {kind!r} fault", repr(value))
            self.value = 0.0
        if kind != "sinusoidal":
            for name, given in (("frequency", frequency), ("phase", phase)):
                if given is not None:
                    raise InvalidArgumentError(
                        name, f"None for a {kind!r} fault (sinusoidal only)", repr(given)
                    )
        self.frequency = 0.2 if frequency is None else check_positive(frequency, "frequency")
        self.phase = 0.0 if phase is None else check_real(phase, "phase")
        if kind == "effectiveness":
            if effectiveness is None:
                raise InvalidArgumentError(
                    "effectiveness", "a value in [0, 1] for an 'effectiveness' fault", "None"
                )
            lam = check_real(effectiveness, "effectiveness")
            if not 0.0 <= lam <= 1.0:
                raise InvalidArgumentError("effectiveness", "a value in [0, 1]", repr(effectiveness))
            self.final_effectiveness = lam
        else:
            if effectiveness is not None:
                raise InvalidArgumentError("effectiveness", f"None for a {kind!r} fault", repr(effectiveness))
            self.final_effectiveness = 1.0 if kind == "bias" else 0.0
        self.onset: str = check_choice(onset, "onset", ("abrupt", "exponential"))
        self.onset_rate = check_positive(onset_rate, "onset_rate")

    # -- the fault as a function of time -----------------------------------------------------
    def is_active(self, t: float) -> bool:
        """Whether ``t_on <= t < t_off``."""
        return self.t_on <= t < self.t_off

    def onset_profile(self, t: float) -> float:
        """``mu(t)`` in [0, 1]: 0 outside the window, 1 inside for an abrupt onset."""
        if not self.is_active(t):
            return 0.0
        if self.onset == "abrupt":
            return 1.0
        return 1.0 - math.exp(-self.onset_rate * (t - self.t_on))

    def final_additive(self, t: float) -> float:
        """``b(t)`` once fully developed (N m), whether or not the window holds ``t``."""
        if self.kind == "sinusoidal":
            return self.value * math.sin(self.frequency * t + self.phase)
        return self.value

    def effectiveness_at(self, t: float) -> float:
        """``lambda(t) = 1 - (1 - lambda) mu(t)``."""
        return 1.0 - (1.0 - self.final_effectiveness) * self.onset_profile(t)

    def additive_at(self, t: float) -> float:
        """``b(t) = mu(t) b`` (N m)."""
        mu = self.onset_profile(t)
        return 0.0 if mu == 0.0 else mu * self.final_additive(t)

    def torque(self, t: float, commanded: float) -> float:
        """The wheel's torque ``lambda(t) nu + b(t)`` for the command ``nu`` (before limits)."""
        return self.effectiveness_at(t) * float(commanded) + self.additive_at(t)

    @property
    def disobeys(self) -> bool:
        """Whether the wheel stops obeying (paper W's ``sigma_j = 0``): stuck, sinusoidal, outage."""
        return self.kind in ("stuck", "sinusoidal", "outage")

    def __repr__(self) -> str:
        parts = [f"wheel={self.wheel}", f"kind={self.kind!r}", f"t_on={self.t_on:g}", f"t_off={self.t_off:g}"]
        if self.kind in _NEEDS_VALUE:
            parts.append(f"value={self.value:g}")
        if self.kind == "sinusoidal":
            parts.append(f"frequency={self.frequency:g}")
        if self.kind == "effectiveness":
            parts.append(f"effectiveness={self.final_effectiveness:g}")
        if self.onset != "abrupt":
            parts.append(f"onset={self.onset!r}, onset_rate={self.onset_rate:g}")
        return f"WheelFault({', '.join(parts)})"


@dataclass(frozen=True)
class RankWindow:
    """A time window where the healthy wheels do not span three axes.

    Attributes
    ----------
    t_start, t_end : float
        The window ``[t_start, t_end)`` (s).
    rank : int
        ``rank(D Lambda)`` in the window (its smallest value, where it changes inside).
    wheels : tuple of int
        The wheels (from 1) that have stopped obeying or lost all effectiveness.
    """

    t_start: float
    t_end: float
    rank: int
    wheels: tuple[int, ...]


class FaultSchedule:
    """The faults of one run, checked against the wheel array (and the run's length).

    Parameters
    ----------
    faults : sequence of WheelFault
        The faults; two faults on the same wheel may not overlap in time.
    n_wheels : int or WheelArray
        The number of wheels (or the array): a fault on a wheel that does not exist is an error.
    duration : float, optional
        Length of the run (s): a fault whose onset is at or after the end is an error.
    max_wheels : int
        The largest ``n_wheels`` given as an integer (default :data:`~models.wheels.array.MAX_WHEELS`,
        1000); a larger one is refused with an error naming this limit. Pass a larger value to
        lift it (an array's own count is never refused).

    Examples
    --------
    >>> from models import FaultSchedule, WheelArray, WheelFault
    >>> faults = FaultSchedule([WheelFault(4, "outage", 0.0),
    ...                         WheelFault(1, "sinusoidal", 30.0, 80.0, value=0.03)], WheelArray.paper_w())
    >>> faults.effectiveness(50.0).tolist(), round(float(faults.additive(50.0)[0]), 4)
    ([0.0, 1.0, 1.0, 0.0], -0.0163)
    >>> [(w.t_start, w.t_end, w.rank) for w in faults.rank_deficient_windows(WheelArray.paper_w(), 150.0)]
    [(30.0, 80.0, 2)]
    """

    def __init__(
        self,
        faults: Sequence[WheelFault],
        n_wheels: int | WheelArray,
        duration: float | None = None,
        *,
        max_wheels: int = MAX_WHEELS,
    ) -> None:
        if isinstance(n_wheels, WheelArray):  # an array that exists is never refused for its size
            n_wheels = n_wheels.n_wheels
            max_wheels = _lifted(max_wheels, n_wheels)
        n_wheels = _wheel_count(n_wheels, max_wheels)
        if isinstance(faults, WheelFault):
            faults = [faults]
        if isinstance(faults, str | bytes) or not isinstance(faults, Sequence):
            raise ArgumentTypeError("faults", "a sequence of WheelFault", type(faults).__name__)
        for i, fault in enumerate(faults):
            if not isinstance(fault, WheelFault):
                raise ArgumentTypeError(f"faults[{i}]", "a models.WheelFault", type(fault).__name__)
            if fault.wheel > n_wheels:
                raise InvalidArgumentError(
                    f"faults[{i}].wheel", f"a wheel that exists (1 .. {n_wheels})", repr(fault.wheel)
                )
        self.duration = None if duration is None else check_positive(duration, "duration")
        if self.duration is not None:
            for i, fault in enumerate(faults):
                if fault.t_on >= self.duration:
                    raise InvalidArgumentError(
                        f"faults[{i}].t_on",
                        f"an onset before the end of the run ({self.duration:g} s)",
                        repr(fault.t_on),
                    )
        for i, a in enumerate(faults):
            for j in range(i + 1, len(faults)):
                b = faults[j]
                if a.wheel == b.wheel and a.t_on < b.t_off and b.t_on < a.t_off:
                    raise InvalidArgumentError(
                        f"faults[{j}]",
                        f"no overlap with faults[{i}] on wheel {a.wheel}",
                        f"windows [{a.t_on:g}, {a.t_off:g}) and [{b.t_on:g}, {b.t_off:g})",
                    )
        self.faults: tuple[WheelFault, ...] = tuple(faults)
        self.n_wheels = int(n_wheels)

    def __len__(self) -> int:
        return len(self.faults)

    def __repr__(self) -> str:
        return f"FaultSchedule({list(self.faults)!r}, n_wheels={self.n_wheels})"

    # -- per-wheel form at time t --------------------------------------------------------------
    def effectiveness(self, t: float) -> np.ndarray:
        """``lambda(t)`` per wheel (1 for healthy wheels)."""
        lam = np.ones(self.n_wheels)
        for f in self.faults:
            if f.is_active(t):
                lam[f.wheel - 1] = f.effectiveness_at(t)
        return lam

    def additive(self, t: float) -> np.ndarray:
        """``b(t)`` per wheel (N m)."""
        b = np.zeros(self.n_wheels)
        for f in self.faults:
            if f.is_active(t):
                b[f.wheel - 1] = f.additive_at(t)
        return b

    def apply(self, t: float, u: ArrayLike) -> np.ndarray:
        """``lambda(t) u + b(t)``: the wheels' torques for the commands ``u`` (before limits)."""
        u = np.asarray(u, dtype=float)
        if not self.faults:
            return u.copy()
        lam = np.ones(self.n_wheels)
        b = np.zeros(self.n_wheels)
        for f in self.faults:
            if f.t_on <= t < f.t_off:
                mu = f.onset_profile(t)
                lam[f.wheel - 1] = 1.0 - (1.0 - f.final_effectiveness) * mu
                b[f.wheel - 1] = mu * f.final_additive(t)
        return lam * u + b

    def active(self, t: float) -> np.ndarray:
        """Which wheels have an active fault at ``t`` (bool per wheel)."""
        out = np.zeros(self.n_wheels, dtype=bool)
        for f in self.faults:
            if f.is_active(t):
                out[f.wheel - 1] = True
        return out

    def sigma(self, t: float) -> np.ndarray:
        """Paper W's ``sigma`` at ``t``: 0 for a wheel that disobeys, ``lambda`` (final) under loss of
        effectiveness, 1 otherwise. This is what the redundancy condition uses."""
        sig = np.ones(self.n_wheels)
        for f in self.faults:
            if f.is_active(t):
                sig[f.wheel - 1] = f.final_effectiveness
        return sig

    def events(self) -> list[float]:
        """The sorted times where a fault starts or ends (finite ones)."""
        times = {f.t_on for f in self.faults} | {f.t_off for f in self.faults if math.isfinite(f.t_off)}
        return sorted(times)

    def rank_deficient_windows(
        self, wheels: WheelArray | Any, duration: float | None = None
    ) -> list[RankWindow]:
        """See :func:`rank_deficient_windows`."""
        return rank_deficient_windows(self, wheels, duration)


def rank_deficient_windows(
    faults: FaultSchedule | Sequence[WheelFault], wheels: WheelArray | Any, duration: float | None = None
) -> list[RankWindow]:
    """The windows where ``rank(D sigma) < 3`` (paper W's condition, eq. 17, broken).

    Between fault events ``sigma`` is constant (a loss of effectiveness counts with its final
    ``lambda`` from its onset, so a gradual onset is flagged from ``t_on``); consecutive
    intervals of rank below 3 are merged.

    Parameters
    ----------
    faults : FaultSchedule or sequence of WheelFault
        The fault schedule.
    wheels : WheelArray or (3, m) array_like
        The array, or its distribution matrix ``D``.
    duration : float, optional
        End of the run (s); windows are cut there (default: the schedule's duration, else
        open windows end at ``inf``).

    Returns
    -------
    list of RankWindow
        In time order; empty when the healthy wheels always span three axes.
    """
    d = wheels.D if isinstance(wheels, WheelArray) else np.asarray(wheels, dtype=float)
    if d.ndim != 2 or d.shape[0] != 3:
        raise InvalidArgumentError(
            "wheels", "a WheelArray or a (3, m) distribution matrix", f"shape {d.shape}"
        )
    schedule = faults if isinstance(faults, FaultSchedule) else FaultSchedule(
        faults, d.shape[1], duration, max_wheels=_lifted(MAX_WHEELS, d.shape[1])
    )
    if schedule.n_wheels != d.shape[1]:
        raise InvalidArgumentError(
            "wheels", f"{schedule.n_wheels} wheels as in the schedule", f"{d.shape[1]}"
        )
    end = duration if duration is not None else schedule.duration
    end = math.inf if end is None else check_positive(end, "duration")
    cuts = sorted({0.0, *[t for t in schedule.events() if t < end], end})
    windows: list[RankWindow] = []
    for t0, t1 in pairwise(cuts):
        sig = schedule.sigma(t0)
        rank = _rank(d * sig)
        if rank >= 3:
            continue
        lost = tuple(int(j + 1) for j in np.flatnonzero(sig == 0.0))
        last = windows[-1] if windows else None
        if last is not None and last.t_end == t0:
            windows[-1] = RankWindow(
                last.t_start, t1, min(last.rank, rank), tuple(sorted(set(last.wheels) | set(lost)))
            )
        else:
            windows.append(RankWindow(t0, t1, rank, lost))
    return windows


def _lifted(max_wheels: Any, count: int) -> Any:
    """``max_wheels`` raised to ``count`` (a valid ``max_wheels`` only: a bad one is reported as given)."""
    ok = not isinstance(max_wheels, bool) and isinstance(max_wheels, int | np.integer)
    return max(int(max_wheels), count) if ok else max_wheels


def _as_schedule(faults: Any, n_wheels: int, duration: float | None = None) -> FaultSchedule:
    """Accept ``None``, a fault, a sequence of faults or a schedule."""
    if isinstance(faults, FaultSchedule):
        if faults.n_wheels != n_wheels:
            raise InvalidArgumentError(
                "faults", f"a schedule for {n_wheels} wheels", f"{faults.n_wheels} wheels"
            )
        return faults
    limit = _lifted(MAX_WHEELS, n_wheels)  # the count of an array that exists
    return FaultSchedule([] if faults is None else faults, n_wheels, duration, max_wheels=limit)
