"""Run one scenario through its plant family (build, simulate, measure) and make its record.

:func:`run_scenario` gives the record of one scenario; :func:`simulate_scenario` also the time
series. :func:`run_case` is the function worker processes (or Dask workers) execute; it never
raises for a failing case but returns the error, so a sweep can record it and go on. The
runner uses :mod:`benchmarks.core.scenario`, which does not import it back.
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
import traceback
from collections.abc import Iterator
from typing import Any

import numpy as np

from benchmarks.core.interrupts import is_interrupt
from benchmarks.core.jsonable import json_safe
from benchmarks.core.scenario import Scenario

__all__ = ["run_case", "run_scenario", "simulate_scenario"]


def simulate_scenario(
    scenario: Scenario, experiment: str | None = None, keep_trace: bool = False
) -> tuple[dict[str, Any], dict[str, np.ndarray] | None]:
    """Simulate ``scenario``; return its record and (with ``keep_trace``) the time series.

    Parameters
    ----------
    scenario : Scenario
        The validated case.
    experiment : str, optional
        The record's ``experiment`` (default: the case id).
    keep_trace : bool
        Also return ``t, x, u_cmd, u_applied, d, gamma`` as arrays (for figures).

    Returns
    -------
    record : dict
        ``experiment, case_id, label, controller, plant, saturation, status, settings, metrics,
        wall_time_s, cpu_time_s`` (the process's CPU time, which shows how much a loaded machine
        slowed the case down).
    trace : dict of ndarray or None
    """
    start, cpu_start = time.perf_counter(), time.process_time()
    family = scenario.plant_family
    settings = family.effective_settings(scenario.controller, scenario.settings)
    result = family.simulate(scenario, settings, keep_trace)
    record_settings = scenario.to_dict()
    record_settings.update(result.settings)
    record = {
        "experiment": experiment if experiment is not None else scenario.case_id,
        "case_id": scenario.case_id,
        "label": scenario.label(),
        "controller": scenario.controller,
        "plant": scenario.plant,
        "saturation": scenario.saturation,
        "status": "done",
        "settings": record_settings,
        "metrics": result.metrics,
        "wall_time_s": time.perf_counter() - start,
        "cpu_time_s": time.process_time() - cpu_start,
    }
    trace = result.trace if keep_trace else None
    return json_safe(record), trace


def run_scenario(scenario: Scenario, experiment: str | None = None) -> dict[str, Any]:
    """Simulate ``scenario`` and return its record (see :func:`simulate_scenario`)."""
    record, _ = simulate_scenario(scenario, experiment=experiment)
    return record


class CaseTimeLimit(BaseException):
    """A case ran longer than its wall-clock limit (raised inside the case by a timer).

    A ``BaseException``, like ``KeyboardInterrupt``, so that a fallback that catches a failing
    solver's ``Exception`` does not swallow it and run on.
    """


class _Timer:
    """Whether the case's time limit was armed and whether it has expired."""

    def __init__(self) -> None:
        self.armed = False
        self.expired = False


@contextlib.contextmanager
def _time_limit(seconds: float | None) -> Iterator[_Timer]:
    """Raise :class:`CaseTimeLimit` in this thread after ``seconds`` of wall time.

    A POSIX interval timer (``SIGALRM``) needs the main thread of a process: local worker
    processes and ``--workers 0`` have it; a Dask worker runs cases in threads, where the limit
    cannot be armed (the case then runs unbounded). The timer is checked between Python
    bytecodes, so one long call into compiled code (a QP solve) finishes before the case stops;
    raised inside a compiled function the error may reach the caller wrapped (a numba kernel
    turns it into ``SystemError``), so the yielded timer says whether the limit expired.
    """
    timer = _Timer()
    usable = (
        seconds is not None
        and hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
    )
    if not usable:
        yield timer
        return

    def expire(signum: int, frame: Any) -> None:
        timer.expired = True
        raise CaseTimeLimit(f"the case ran longer than its limit of {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, float(seconds))
    timer.armed = True
    try:
        yield timer
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def run_case(payload: dict[str, Any]) -> dict[str, Any]:
    """Worker entry point: ``payload = {"scenario": dict, "experiment": str|None, "trace": bool,
    "time_limit": seconds|None}``.

    Returns ``{"ok": True, "record": ..., "trace": ...}`` or, when the case raised or ran past
    ``time_limit``, ``{"ok": False, "error": "<type>: <message>", "traceback": ...}`` (the type
    ``time_limit`` for a case stopped by its limit). An interrupt is not a failing case: a
    ``KeyboardInterrupt``, or an error that compiled code raised because of one
    (:func:`benchmarks.core.interrupts.is_interrupt`), propagates as ``KeyboardInterrupt``.
    """
    limit = payload.get("time_limit")
    timer = _Timer()
    try:
        scenario = Scenario.from_dict(payload["scenario"])
        with _time_limit(limit) as timer:
            record, trace = simulate_scenario(
                scenario, experiment=payload.get("experiment"), keep_trace=bool(payload.get("trace"))
            )
        return {"ok": True, "record": record, "trace": trace}
    except CaseTimeLimit as err:
        return {"ok": False, "error": f"time_limit: {err}", "traceback": traceback.format_exc()}
    except Exception as err:  # a failing case is data, not a crash of the sweep
        if is_interrupt(err):  # Ctrl-C wrapped by compiled code on its way (numba: SystemError)
            raise KeyboardInterrupt from err
        if timer.expired:  # the limit's error, wrapped by compiled code it passed through
            message = f"the case ran longer than its limit of {limit:g} s"
            return {"ok": False, "error": f"time_limit: {message}", "traceback": traceback.format_exc()}
        return {
            "ok": False,
            "error": f"{type(err).__name__}: {err}".replace("\n", " "),
            "traceback": traceback.format_exc(),
        }
