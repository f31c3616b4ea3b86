"""Compare two runs of a suite record by record, field by field: what a change to shared code changed.

A change to shared machinery (the harness, the LMI solver, the layout) must keep every suite's
records, or name what it changed on purpose. :func:`compare_runs` reads the ``results.json`` (a
suite) or ``timing.json`` (``rmpc timing``) of two output folders, pairs the records, walks every
field and lists each difference. Fields that measure time or the machine (``solve_time_p50``,
``p95_s``, ``step_time_max``, ``machine``, ...) differ from run to run and are left out.

``python -m benchmarks.compare BEFORE AFTER [--rtol R]`` prints the differences and exits 1 when
there are any, 0 when there are none, 2 on input that is not two runs (no records, items that
are not records, records without identifying fields, nesting deeper than :data:`MAX_DEPTH`, not
JSON). Records that share their identity are all compared, in order, and named in a ``note:``
line; a boolean and a number never compare equal (``true`` is not ``1``).

Examples
--------
>>> from benchmarks.compare import compare_records
>>> before = [{"experiment": "E1", "label": "RMPC", "metrics": {"iae": 1.0, "solve_time_p50": 0.1}}]
>>> after = [{"experiment": "E1", "label": "RMPC", "metrics": {"iae": 1.5, "solve_time_p50": 0.2}}]
>>> compare_records(before, after)
['E1 | RMPC: metrics.iae: 1.0 -> 1.5']
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from benchmarks.core.publish import STAGING_PREFIX
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_positive

__all__ = [
    "compare_records",
    "compare_runs",
    "duplicate_identities",
    "is_run_dependent",
    "load_run",
    "main",
    "paired_records",
    "record_identity",
]

#: Parts of a field name that mark a measurement of time or of the machine.
_RUN_DEPENDENT = ("time", "machine", "versions", "load", "wall", "elapsed")
#: Field names that contain one of those parts but are settings of the case.
_SETTINGS = frozenset({"duration", "disturbance_start", "t_on", "t_off", "time_scale"})
#: Field names without one of those parts that are still measurements of the run (a ratio of
#: two solve times; the figures of an earlier run written next to this one's, ``--baseline``).
_RUN_FIELDS = frozenset({"cvxpy_ratio", "baseline"})
#: How deep a record may nest (the suites' records nest a handful of levels).
MAX_DEPTH = 64


def is_run_dependent(name: str) -> bool:
    """Whether a field named ``name`` measures the run (time, machine) rather than the result."""
    key = str(name).lower()
    if key in _SETTINGS:
        return False
    if key in _RUN_FIELDS:
        return True
    if key.endswith(("_s", "_ms")) or "p50" in key or "p95" in key:
        return True
    return any(part in key for part in _RUN_DEPENDENT)


def record_identity(record: dict[str, Any], timing: bool) -> str:
    """What names a record across runs: ``experiment | label`` (or ``case_id``), the methods
    suite's ``problem | method``, a timing record's ``problem | formulation | backend | vertices |
    n_states`` (the fields it has); empty when the record has none of them."""
    if timing:
        parts = [record.get(k) for k in ("problem", "formulation", "backend", "vertices", "n_states")]
        return " | ".join(str(p) for p in parts if p is not None)
    label = record.get("label") or record.get("case_id")
    parts = (record.get("experiment"), label)
    if all(p is None for p in parts):  # the methods suite: one record per problem and method
        parts = (record.get("problem"), record.get("method"))
    return " | ".join(str(p) for p in parts if p is not None)


def _record_key(record: dict[str, Any], index: int, timing: bool) -> str:
    """:func:`record_identity`; a timing record's also ends with its position (``| #index``)."""
    identity = record_identity(record, timing)
    return f"{identity} | #{index}" if timing else identity


def paired_records(
    records: Sequence[dict[str, Any]], timing: bool, positional: bool = True
) -> dict[str, dict[str, Any]]:
    """The records by key; keys that repeat get their count (``#2``...) so none is dropped.

    ``positional``: a timing record's key holds its position in the run (how
    :func:`compare_records` pairs two runs of the same command); ``False`` pairs by
    :func:`record_identity` alone (two runs that timed different sets of cases).
    """
    keys = [
        _record_key(r, i, timing) if positional else record_identity(r, timing)
        for i, r in enumerate(records)
    ]
    seen: dict[str, int] = {}
    out = {}
    for key, record in zip(keys, records, strict=True):
        count = seen.get(key, 0)
        seen[key] = count + 1
        name = key if keys.count(key) == 1 else f"{key} #{count + 1}"
        while name in out:  # a key that happens to read like a numbered repeat: never merge two
            name += " (again)"
        out[name] = record
    return out


def _walk(a: Any, b: Any, path: str, rtol: float, out: list[str]) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b), key=str):
            if is_run_dependent(key):
                continue
            where = f"{path}.{key}" if path else str(key)
            if key not in a:
                out.append(f"{where}: added {json.dumps(b[key])[:120]}")
            elif key not in b:
                out.append(f"{where}: removed")
            else:
                _walk(a[key], b[key], where, rtol, out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: length {len(a)} -> {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _walk(x, y, f"{path}[{i}]", rtol, out)
    elif isinstance(a, bool) != isinstance(b, bool):  # JSON's true is not 1
        out.append(f"{path}: {json.dumps(a)[:100]} -> {json.dumps(b)[:100]}")
    elif _is_number(a) and _is_number(b):
        same = a == b or (math.isnan(a) and math.isnan(b))
        if not same and not (rtol > 0.0 and abs(a - b) <= rtol * max(abs(a), abs(b))):
            out.append(f"{path}: {a!r} -> {b!r}")
    elif a != b:
        out.append(f"{path}: {json.dumps(a)[:100]} -> {json.dumps(b)[:100]}")


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def compare_records(
    before: Sequence[dict[str, Any]], after: Sequence[dict[str, Any]], rtol: float = 0.0,
    *, timing: bool = False,
) -> list[str]:
    """Every difference between two lists of records, one line each (empty: the same records).

    Parameters
    ----------
    before, after : sequence of dict
        The records of two runs: suite records are paired by ``experiment`` and ``label`` (the
        methods suite's by ``problem`` and ``method``; a key that repeats by its position too),
        timing records (``timing=True``) by problem, formulation, back-end, vertices, size and
        position.
    rtol : float
        Numbers within this relative difference count as equal (default 0: bit for bit).
    timing : bool
        The records are ``rmpc timing``'s.
    """
    rtol = check_positive(rtol, "rtol", allow_zero=True)
    for name, records in (("before", before), ("after", after)):
        _check_records(records, name, timing)
    pairs_a = paired_records(before, timing)
    pairs_b = paired_records(after, timing)
    out: list[str] = []
    for key in sorted(set(pairs_a) | set(pairs_b)):
        if key not in pairs_a:
            out.append(f"{key}: record added")
        elif key not in pairs_b:
            out.append(f"{key}: record removed")
        else:
            found: list[str] = []
            _walk(pairs_a[key], pairs_b[key], "", rtol, found)
            out.extend(f"{key}: {line}" for line in found)
    return out


def _check_records(records: Any, name: str, timing: bool) -> None:
    """Refuse what is not the records of a run: not a list, an item that is not an object, nesting
    deeper than :data:`MAX_DEPTH`, a suite record without identifying fields."""
    if isinstance(records, str | bytes) or not isinstance(records, Sequence):
        raise InvalidArgumentError(name, "a list of records (objects)", type(records).__name__)
    for i, record in enumerate(records):
        if not isinstance(record, dict):
            raise InvalidArgumentError(
                name, "a list of records (objects)", f"item {i}: {type(record).__name__} {str(record)[:40]!r}"
            )
        depth = _depth(record)
        if depth > MAX_DEPTH:
            raise InvalidArgumentError(
                name, f"records nested at most {MAX_DEPTH} levels deep", f"record {i} nested deeper"
            )
        if not timing and not _record_key(record, i, timing):
            raise InvalidArgumentError(
                name,
                "records with identifying fields (experiment and label, case_id, or problem and method)",
                f"record {i} with none of them (keys: {', '.join(sorted(map(str, record))[:8]) or 'none'})",
            )


def _depth(value: Any) -> int:
    """How deep ``value`` nests (a number: 0), without recursion; stops counting past the limit."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        item, level = stack.pop()
        deepest = max(deepest, level)
        if level > MAX_DEPTH:
            break
        if isinstance(item, dict):
            stack.extend((v, level + 1) for v in item.values())
        elif isinstance(item, list):
            stack.extend((v, level + 1) for v in item)
    return deepest


def duplicate_identities(records: Sequence[dict[str, Any]], timing: bool = False) -> dict[str, int]:
    """The identities (the pairing keys) that more than one record shares, with their counts.

    Such records are still all compared, in their order (the first against the first).
    """
    counts: dict[str, int] = {}
    for i, record in enumerate(records):
        key = _record_key(record, i, timing)
        counts[key] = counts.get(key, 0) + 1
    return {k: n for k, n in counts.items() if n > 1}


def load_run(folder: Path, argument: str | None = None) -> tuple[list[dict[str, Any]], bool]:
    """The records of the run in ``folder`` and whether they are ``rmpc timing``'s.

    Reads ``results.json`` (a suite) or else ``timing.json``; anything else raises
    :class:`~toolkit_common.errors.InvalidArgumentError` naming ``argument`` (default: the path
    read) with what was expected and what was found.
    """
    folder = Path(folder)

    def refuse(path: Path, expected: str, found: str) -> InvalidArgumentError:
        if argument is None:
            return InvalidArgumentError(str(path), expected, found)
        return InvalidArgumentError(argument, expected, f"{found} ({path})")

    if not folder.is_dir():
        raise refuse(
            folder, "a run's output folder (with results.json or timing.json)",
            "a file" if folder.exists() else "nothing there",
        )
    if folder.resolve().name.startswith(STAGING_PREFIX):
        raise refuse(
            folder, "a run's output folder (with results.json or timing.json)",
            "the unfinished reports of a run killed while writing them (the next run into that "
            "output folder removes them)",
        )
    for name, timing in (("results.json", False), ("timing.json", True)):
        path = folder / name
        if path.exists():
            try:
                data = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, ValueError, RecursionError) as err:
                why = "nested too deeply to read" if isinstance(err, RecursionError) else str(err)[:200]
                raise refuse(path, "a readable JSON file of a run's records", why) from None
            if isinstance(data, dict) and not isinstance(data.get("records"), list):
                raise refuse(
                    path, "a list of records or an object with a list 'records'", "an object without it"
                )
            records = data["records"] if isinstance(data, dict) else data
            try:
                _check_records(records, str(path), timing)
            except InvalidArgumentError as err:
                if argument is None:
                    raise
                raise refuse(path, err.expected, err.found) from None
            if not records:
                raise refuse(path, "the records of a run (one or more)", "no records")
            return records, timing
    raise refuse(folder, "a folder with results.json or timing.json", "neither")


def compare_runs(before: str | Path, after: str | Path, rtol: float = 0.0) -> list[str]:
    """:func:`compare_records` on the records of two output folders (both suites or both timing)."""
    records_a, timing_a = load_run(Path(before))
    records_b, timing_b = load_run(Path(after))
    if timing_a != timing_b:
        raise InvalidArgumentError("after", "the same kind of output as before", "a suite and a timing run")
    return compare_records(records_a, records_b, rtol, timing=timing_a)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m benchmarks.compare BEFORE AFTER [--rtol R]``: exit 0 same, 1 different, 2 bad input."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.compare",
        description="Compare two output folders of a suite (or of rmpc timing) record by record, "
                    "field by field, leaving out the fields that measure time or the machine. Records "
                    "that share their identity (experiment and label, case_id, or problem and method) "
                    "are all compared, in order, and named in a 'note:' line; true and 1 differ. "
                    "Exit status: 0 the same, 1 different, 2 an input that is not a run (no folder, "
                    "no results.json or timing.json, not JSON, no records, items that are not records, "
                    f"records without identifying fields, nesting deeper than {MAX_DEPTH} levels).",
    )
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--rtol", type=float, default=0.0, help="relative tolerance on numbers (default 0)")
    args = parser.parse_args(argv)
    try:
        records_a, timing_a = load_run(Path(args.before))
        records_b, timing_b = load_run(Path(args.after))
        if timing_a != timing_b:
            raise InvalidArgumentError(
                "after", "the same kind of output as before", "a suite and a timing run"
            )
        lines = compare_records(records_a, records_b, args.rtol, timing=timing_a)
    except InvalidArgumentError as err:
        print(f"python -m benchmarks.compare: {err}", file=sys.stderr)
        return 2
    for folder, records, timing in ((args.before, records_a, timing_a), (args.after, records_b, timing_b)):
        for key, n in duplicate_identities(records, timing).items():
            print(f"note: {n} records of {folder} share the identity {key!r}; all are compared, in order")
    for line in lines:
        print(line)
    print(f"{len(lines)} difference{'s' if len(lines) != 1 else ''}")
    return 1 if lines else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
