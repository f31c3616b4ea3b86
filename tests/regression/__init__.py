"""Regression values: thresholds that are the toolkit's own earlier outputs, one JSON file per suite.

A *regression value* is a number the toolkit itself produced on an earlier run (a settling time,
an error at a given time, a count of LMI solves, a peak), with no reference outside the toolkit
to compare it with. A test asserts that today's value is still on the good side of a threshold
placed a stated margin away from the measured one. The outside references (published values,
python-control, SciPy, an independent solver, an exact identity or conservation law) are not
regression values: they stay in the tests, next to the comparison, and are never regenerated.

Each suite's file ``tests/regression/<suite>.json`` holds::

    {"suite": ..., "tests": [the test files that measure its values],
     "values": {name: {"what": ..., "unit": ..., "measured": ...,
                       "upper_margin" and "upper" and/or "lower_margin" and "lower",
                       "reason": why the margin is what it is}}}

``upper = measured + upper_margin`` and ``lower = measured - lower_margin``; a test calls
:func:`check` with the value it measured, which must lie within ``[lower, upper]`` (inclusive;
a missing side is unbounded). ``python -m tests.regression.regenerate <suite>`` reruns the
suite's tests in record mode (environment variable :data:`RECORD_ENV` naming a file: every
:func:`check` appends its value there instead of asserting), then rewrites ``measured`` and the
thresholds from the unchanged margins.
"""

from __future__ import annotations

import json
import math
import os
from functools import cache
from pathlib import Path
from typing import Any

__all__ = ["DIRECTORY", "RECORD_ENV", "check", "load", "suites", "thresholds"]

#: Where the suites' JSON files live.
DIRECTORY = Path(__file__).resolve().parent

#: When set, the path of a JSON-lines file that :func:`check` appends ``{suite, name, value}`` to.
RECORD_ENV = "RMPC_REGRESSION_RECORD"


def suites() -> list[str]:
    """The names of the suites that have a regression file, sorted."""
    return sorted(p.stem for p in DIRECTORY.glob("*.json"))


@cache
def load(suite: str) -> dict[str, Any]:
    """The parsed ``<suite>.json`` (cached; the files do not change during a test run).

    Parameters
    ----------
    suite : str
        The suite's name, the file's stem.

    Returns
    -------
    dict
        ``suite``, ``tests`` and ``values`` as described in the module docstring.
    """
    path = DIRECTORY / f"{suite}.json"
    if not path.is_file():
        raise FileNotFoundError(f"no regression file for suite {suite!r}: {path} (known: {suites()})")
    return json.loads(path.read_text())


def thresholds(entry: dict[str, Any]) -> tuple[float, float]:
    """``(lower, upper)`` of one value's entry; ``-inf`` / ``inf`` where the side is unbounded."""
    lower = float(entry["lower"]) if "lower" in entry else -math.inf
    upper = float(entry["upper"]) if "upper" in entry else math.inf
    return lower, upper


def check(suite: str, name: str, value: float) -> None:
    """Assert that ``value`` is within the thresholds of ``suite``'s regression value ``name``.

    In record mode (:data:`RECORD_ENV` set) the value is appended to the record file instead
    and nothing is asserted.

    Parameters
    ----------
    suite : str
        The suite, the stem of its JSON file.
    name : str
        The value's key in the file's ``values``.
    value : float
        What the test measured today.

    Raises
    ------
    AssertionError
        Outside ``[lower, upper]``; the message gives the earlier measurement and the command
        that regenerates the file.
    KeyError
        ``name`` is not one of the suite's values.
    """
    entry = load(suite)["values"][name]
    value = float(value)
    record = os.environ.get(RECORD_ENV)
    if record:
        with open(record, "a", encoding="utf-8") as fh:
            fh.write(json.dumps({"suite": suite, "name": name, "value": value}) + "\n")
        return
    lower, upper = thresholds(entry)
    assert lower <= value <= upper, (
        f"regression value {suite}.{name} ({entry['what']}) = {value:.6g} {entry.get('unit', '')} is outside "
        f"[{lower:.6g}, {upper:.6g}] (measured {entry['measured']:.6g} earlier); if the change is intended, "
        f"regenerate with: python -m tests.regression.regenerate {suite}"
    )
