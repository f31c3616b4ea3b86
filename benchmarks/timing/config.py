"""The options of ``rmpc timing``: what one run measures (:class:`TimingConfig`) and their checks.

:func:`config_from_args` turns the parsed command line into a :class:`TimingConfig`; a bad value
raises :class:`~toolkit_common.errors.InvalidArgumentError` naming the option (the CLI turns it
into exit status 2). The defaults of a full run and of ``--quick`` are set here.

Examples
--------
>>> from argparse import Namespace
>>> from benchmarks.timing.config import config_from_args
>>> cfg = config_from_args(Namespace(out="report", quick=True, vertices=["8", "2"]))
>>> cfg.steps, cfg.vertices, cfg.cheap_steps, cfg.problems
(3, (2, 8), 75, ('RMPC', 'OfflineRMPC', 'GIPC'))
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from toolkit_common.errors import InvalidArgumentError

__all__ = [
    "CHEAP_FACTOR",
    "OPTIONAL_PROBLEMS",
    "PROBLEMS",
    "VERTEX_COUNTS",
    "TimingConfig",
    "config_from_args",
]

#: The problems a run times by default.
PROBLEMS: tuple[str, ...] = ("RMPC", "OfflineRMPC", "GIPC")
#: Problems a run may ask for: the default three, the scale section (:mod:`benchmarks.timing.scale`,
#: flexible satellite with 6-20 states; opt-in with ``--problems Scale``: Clarabel alone takes seconds
#: per solve at 14-20 states) and the per-iteration breakdown of the interior-point method on paper P
#: with the floor of its arithmetic (:mod:`benchmarks.timing.breakdown`, ``--problems Breakdown``),
#: and the exported C controllers against the anchors (:mod:`benchmarks.timing.c_exports`,
#: ``--problems C``: needs ``cc``).
OPTIONAL_PROBLEMS: tuple[str, ...] = ("Scale", "Breakdown", "C")
#: The polytope vertex counts (:func:`benchmarks.timing.common.polytope`).
VERTEX_COUNTS: tuple[int, ...] = (2, 4, 8)
#: Cheap problems (OfflineRMPC lookups, GIPC QPs: microseconds to a millisecond) follow this many
#: times more states than RMPC, so their percentiles rest on enough samples.
CHEAP_FACTOR = 25


@dataclass(frozen=True)
class TimingConfig:
    """What one run measures (see :func:`run_timing_command` for the defaults)."""

    out: Path
    steps: int = 40
    vertices: tuple[int, ...] = VERTEX_COUNTS
    problems: tuple[str, ...] = PROBLEMS
    rebuild_steps: int = 10
    scs_steps: int = 5
    n_ellipsoids: int = 15
    lookup_repeats: int = 5
    quick: bool = False
    progress: bool | None = None
    scale_steps: int = 10
    scale_sizes: tuple[int, ...] = (6, 10, 14, 20)
    scale_scs_steps: int = 1
    scale_cvxpy_steps: int = 2
    #: An earlier report's folder (``--baseline``): its times go next to this run's.
    baseline: Path | None = None

    @property
    def cheap_steps(self) -> int:
        return max(CHEAP_FACTOR * self.steps, 2)


MAX_STEPS_OPTION = 100_000
"""Bound on every ``--*-steps`` option: the report times each step, and a count above this runs
for many hours (``--steps 1e9`` used to end in a MemoryError); time in parts above it."""


def _int_option(value: Any, option: str, minimum: int, maximum: int = MAX_STEPS_OPTION) -> int:
    expected = f"an integer in [{minimum}, {maximum}] (the bound keeps a run within hours; time in parts)"
    if isinstance(value, bool):
        raise InvalidArgumentError(option, expected, repr(value))
    try:
        number = int(value)
        exact = float(value) == number if not isinstance(value, str) else True
    except (TypeError, ValueError):
        raise InvalidArgumentError(option, expected, repr(value)) from None
    if not exact or not minimum <= number <= maximum:
        raise InvalidArgumentError(option, expected, repr(value))
    return number


def _vertices_option(values: Any) -> tuple[int, ...]:
    items = [values] if isinstance(values, str | int) else list(values or [])
    if not items:
        raise InvalidArgumentError("--vertices", "one or more of 2, 4, 8", "nothing")
    out: list[int] = []
    for item in items:
        try:
            count = int(item)
        except (TypeError, ValueError):
            count = -1
        if count not in VERTEX_COUNTS or isinstance(item, bool):
            raise InvalidArgumentError("--vertices", "vertex counts among 2, 4, 8", repr(item))
        if count not in out:
            out.append(count)
    return tuple(sorted(out))


def _problems_option(values: Any) -> tuple[str, ...]:
    items = [values] if isinstance(values, str) else list(values or [])
    known = PROBLEMS + OPTIONAL_PROBLEMS
    if not items:
        raise InvalidArgumentError("--problems", f"one or more of {', '.join(known)}", "nothing")
    lookup = {p.lower(): p for p in known}
    out: list[str] = []
    for item in items:
        name = lookup.get(str(item).lower())
        if name is None:
            raise InvalidArgumentError("--problems", f"problems among {', '.join(known)}", repr(item))
        if name not in out:
            out.append(name)
    return tuple(p for p in known if p in out)


def _sizes_option(values: Any) -> tuple[int, ...]:
    from benchmarks.timing.scale import SCALE_SIZES

    items = [values] if isinstance(values, str | int) else list(values or [])
    out: list[int] = []
    for item in items:
        try:
            size = int(item)
        except (TypeError, ValueError):
            size = -1
        if size not in SCALE_SIZES or isinstance(item, bool):
            raise InvalidArgumentError("--scale-sizes", f"state dimensions among {SCALE_SIZES}", repr(item))
        if size not in out:
            out.append(size)
    if not out:
        raise InvalidArgumentError("--scale-sizes", f"one or more of {SCALE_SIZES}", "nothing")
    return tuple(sorted(out))


def config_from_args(args: argparse.Namespace) -> TimingConfig:
    """Validate the parsed options; a bad value raises :class:`InvalidArgumentError` naming it."""
    out = getattr(args, "out", None)
    if out is None or str(out).strip() == "":
        raise InvalidArgumentError("--out", "an output directory", repr(out))
    quick = bool(getattr(args, "quick", False))
    steps = getattr(args, "steps", None)
    steps = (3 if quick else 40) if steps is None else _int_option(steps, "--steps", 1)
    rebuild = getattr(args, "rebuild_steps", None)
    rebuild = (2 if quick else 10) if rebuild is None else _int_option(rebuild, "--rebuild-steps", 1)
    scs = getattr(args, "scs_steps", None)
    scs = (1 if quick else 5) if scs is None else _int_option(scs, "--scs-steps", 0)
    vertices = getattr(args, "vertices", None)
    problems = getattr(args, "problems", None)
    scale_steps = getattr(args, "scale_steps", None)
    scale_steps = ((2 if quick else 10) if scale_steps is None
                   else _int_option(scale_steps, "--scale-steps", 1))
    scale_cvxpy = getattr(args, "scale_cvxpy_steps", None)
    scale_cvxpy = ((0 if quick else 2) if scale_cvxpy is None
                   else _int_option(scale_cvxpy, "--scale-cvxpy-steps", 0))
    sizes = getattr(args, "scale_sizes", None)
    sizes = ((6,) if quick else (6, 10, 14, 20)) if sizes is None else _sizes_option(sizes)
    return TimingConfig(
        out=Path(out),
        steps=steps,
        vertices=VERTEX_COUNTS if vertices is None else _vertices_option(vertices),
        problems=PROBLEMS if problems is None else _problems_option(problems),
        rebuild_steps=min(rebuild, steps),
        scs_steps=min(scs, steps),
        n_ellipsoids=5 if quick else 15,
        lookup_repeats=2 if quick else 5,
        quick=quick,
        progress=False if getattr(args, "no_progress", False) else None,
        scale_steps=scale_steps,
        scale_sizes=sizes,
        scale_scs_steps=0 if quick else 1,
        scale_cvxpy_steps=min(scale_cvxpy, scale_steps),
        baseline=None if getattr(args, "baseline", None) is None else Path(args.baseline),
    )
