"""Every number a report's prose states, checked against the records of the run it reports.

Used by ``tests/test_report_numbers.py``: :func:`prose` keeps the sentences of a ``results.md``
(not its tables, figure links, code spans, the settings section, the sections on the papers'
own inconsistencies, or the papers' claims quoted in the verdict bullets: those state the
papers' numbers, not the run's; nor the machine line, whose platform string has version
numbers), :func:`numbers` and :func:`seconds` take the numbers and the times out of them, and
:func:`unexplained` lists the ones that no value of the run explains.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["SECONDS", "numbers", "prose", "record_values", "seconds", "unexplained"]

#: A number in running text (not a digit inside a name such as E1, x0, eta_1 or u(k+1)).
_NUMBER = re.compile(r"(?<![\w.^])[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?![\w.]*\w\()(?!\w)")

#: A time: a number followed by " s" (seconds) as a unit.
SECONDS = re.compile(r"(?<![\w.^])(\d+(?:\.\d+)?)(?:-(\d+(?:\.\d+)?))? s\b")

_CITATION = re.compile(r"^Paper [A-Z]: ")
_CLAIM = re.compile(r"^(- \*\*[^*]+\*\*) .*? (Measured: .*)$")


def prose(markdown: str) -> str:
    """The running text of a report (see the module's docstring for what is left out)."""
    out: list[str] = []
    skipping = False
    for line in markdown.splitlines():
        if line.startswith("## "):
            skipping = line.startswith(("## Settings", "## Inconsistencies"))
        if skipping or line.startswith(("|", "![", "Machine: ")):  # the machine's platform string
            continue
        if _CITATION.match(line):  # the papers' bibliographic data (volume, year), not the run's
            continue
        if line.startswith("Inconsistencies of paper"):  # mrp: paper M's notes, quoted
            skipping = True
            continue
        m = _CLAIM.match(line)
        if m:  # the papers' claim in words is a quotation; what was measured is the run's
            line = f"{m.group(1)} {m.group(2)}"
        line = re.sub(r"`[^`]*`", "", line)
        out.append(line)
    return "\n".join(out)


def numbers(text: str) -> list[str]:
    """The numbers of ``text`` as written."""
    return [m.group(0) for m in _NUMBER.finditer(text)]


def seconds(text: str) -> list[str]:
    """The times of ``text`` as written (each end of a range ``a-b s`` on its own)."""
    out = []
    for m in SECONDS.finditer(text):
        out += [g for g in m.groups() if g is not None]
    return out


def _walk(value: Any, key: str = "") -> Iterator[tuple[str, float]]:
    if isinstance(value, bool):
        return
    if isinstance(value, int | float):
        if math.isfinite(value):
            yield key, float(value)
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _walk(v, str(k))
    elif isinstance(value, list | tuple):
        for v in value:
            yield from _walk(v, key)


#: The record fields that hold a time (s): run lengths, starts, windows, settling and recovery times.
_TIME_KEY = re.compile(r"duration|start|_end|time|^t_|^dt$|window|onset|settling|recovery|^t$")


#: Times of the machine (wall, CPU, solve and step times): not times a report states as the run's.
_MACHINE_KEY = re.compile(r"wall|cpu|solve|step")


def record_values(out: Path, times_only: bool = False) -> np.ndarray:
    """Every number in the run's ``results.json`` and ``run.json`` (``times_only``: the fields
    that hold a time)."""
    values: list[float] = []
    for name in ("results.json", "run.json"):
        data = json.loads((out / name).read_text(encoding="utf-8"))
        if not times_only:
            values += [v for _, v in _walk(data)]
        elif name == "run.json":
            values.append(float(data["wall_time_s"]))  # the run line's wall time
        else:  # the times of the simulations, not of the machine
            values += [v for k, v in _walk(data) if _TIME_KEY.search(k) and not _MACHINE_KEY.search(k)]
    return np.asarray(values, dtype=float)


def _explained(written: str, pool: np.ndarray) -> bool:
    """Whether a value of ``pool`` printed at ``written``'s precision (its decimals, or as many
    significant digits) reads ``written``."""
    if pool.size == 0:
        return False
    target = abs(float(written))
    decimals = len(written.split(".")[1]) if "." in written and "e" not in written.lower() else 0
    if np.min(np.abs(np.abs(pool) - target)) <= 0.5 * 10.0 ** (-decimals) * (1 + 1e-9):
        return True
    digits = len(written.lstrip("+-").split("e")[0].replace(".", "").lstrip("0")) or 1
    near = pool[(np.abs(pool) > 0.5 * target) & (np.abs(pool) < 2 * target + 1)]
    return any(float(f"{abs(v):.{digits}g}") == target for v in near)


def _derived(printed: list[float]) -> np.ndarray:
    """What a sentence computes from the numbers it prints: ratios, reciprocals, products,
    differences, sums, relative gaps and changes (as fractions and percentages)."""
    a = np.asarray(printed, dtype=float)
    if a.size == 0:
        return a
    x, y = np.meshgrid(a, a)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = x / y
        gap = np.abs(x - y) / np.maximum(np.abs(x), np.abs(y))
        parts = [ratio, 100 * (ratio - 1), 100 * (1 - ratio), 100 * gap, x - y, x + y, x * y]
        out = np.concatenate(parts, axis=None)
        out = np.concatenate([out, 1 / a])
    return out[np.isfinite(out)]


def unexplained(
    text: str, values: np.ndarray, scales: Iterable[float] = (1.0,), times: bool = False
) -> list[str]:
    """The numbers (``times``: the times) of ``text`` that neither a value of the run (times one of
    ``scales``, e.g. 100 for a percentage) nor a computation on the numbers printed in the same
    line (:func:`_derived`, within 2 % of the printed result) explains, each at its printed precision."""
    pool = np.concatenate([np.asarray(values, dtype=float) * s for s in scales])
    bad: list[str] = []
    for line in text.splitlines():
        found = seconds(line) if times else numbers(line)
        direct = [w for w in found if _explained(w, pool)]
        derived = _derived([float(w) for w in numbers(line) if _explained(w, pool)])
        for w in found:
            if w in direct:
                continue
            t = float(w)
            close = np.abs(derived - t) <= 0.02 * max(abs(t), 1e-12) + 0.5 * 10.0 ** (
                -(len(w.split(".")[1]) if "." in w else 0)
            )
            if not (derived.size and close.any()):
                bad.append(w)
    return bad
