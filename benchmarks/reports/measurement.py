"""When a run measures nothing: the "no measurement" notice that replaces a verdict.

A smoke run (``--short``: every run length scaled down) checks the set-up; its runs are too short
to show what the papers' claims are about (settling, rejection of a disturbance, recovery after a
fault, steady behaviour). The reports then print :data:`NO_MEASUREMENT` with the reason, read
from the run's own records, in place of "reproduced" / "partly reproduced" / "not reproduced".

Examples
--------
>>> from benchmarks.reports.measurement import smoke_reason
>>> smoke_reason(0.075, [2.25, 2.25], "settling").split(";")[0]
'a smoke run (runs of 2.25 s, run lengths scaled by 0.075) checks the set-up'
>>> smoke_reason(1.0, [30.0], "settling") is None
True
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from typing import Any, TypeVar

__all__ = [
    "NO_MEASUREMENT",
    "VERDICT_WORDS",
    "records_reason",
    "records_scale",
    "run_durations",
    "smoke_reason",
    "withhold",
]

#: What a report says in place of a verdict when the run cannot measure the claim.
NO_MEASUREMENT = "no measurement"

#: The verdict words a smoke run's report must not print.
VERDICT_WORDS = ("reproduced", "partly", "not reproduced")

T = TypeVar("T")


def run_durations(records: Iterable[dict[str, Any]]) -> list[float]:
    """The run lengths (s) the records hold: ``settings["duration_used"]`` (what ran), else
    ``settings["duration"]`` (records with neither left out)."""
    out = []
    for rec in records:
        settings = rec.get("settings", {})
        value = settings.get("duration_used", settings.get("duration"))
        if isinstance(value, int | float) and not isinstance(value, bool):
            out.append(float(value))
    return out


def records_scale(records: Iterable[dict[str, Any]], key: str = "time_scale") -> float:
    """The smallest ``settings[key]`` of the records (the run's time scale); 1 when none has one."""
    values = [
        float(v)
        for rec in records
        if isinstance(v := rec.get("settings", {}).get(key), int | float) and not isinstance(v, bool)
    ]
    return min(values) if values else 1.0


def records_reason(records: Sequence[dict[str, Any]], what: str, key: str = "time_scale") -> str | None:
    """:func:`smoke_reason` with the scale (``settings[key]``) and run lengths read from ``records``."""
    return smoke_reason(records_scale(records, key), run_durations(records), what)


def smoke_reason(scale: float, durations: Sequence[float], what: str) -> str | None:
    """Why a run with run lengths scaled by ``scale`` cannot measure ``what``; ``None`` for a full run.

    Parameters
    ----------
    scale : float
        The run's duration or time scale (1: the suite's full runs).
    durations : sequence of float
        The run lengths the records hold (s); the reason quotes their range.
    what : str
        What the claims need to see (``"settling"``, ``"recovery after a fault"``, ...).
    """
    if scale >= 1.0:
        return None
    spans = sorted({round(float(d), 9) for d in durations})
    runs = f"run lengths scaled by {scale:g}"
    if spans:
        span = f"{spans[0]:g} s" if len(spans) == 1 else f"{spans[0]:g}-{spans[-1]:g} s"
        runs = f"runs of {span}, {runs}"
    return f"a smoke run ({runs}) checks the set-up; it cannot show {what}, so no claim is judged on it"


def withhold(claims: Sequence[T], reason: str | None) -> list[T]:
    """``claims`` with every verdict but "not run" replaced by :data:`NO_MEASUREMENT` and ``reason``.

    ``claims`` are dataclasses with ``verdict`` and ``why`` fields (the suites' ``Claim``);
    ``reason=None`` (a full run) returns them unchanged. What was measured (``evidence``) is kept.
    """
    if reason is None:
        return list(claims)
    out = []
    for claim in claims:
        if getattr(claim, "verdict", "") == "not run":
            out.append(claim)
        else:
            out.append(dataclasses.replace(claim, verdict=NO_MEASUREMENT, why=reason))  # type: ignore[type-var]
    return out
