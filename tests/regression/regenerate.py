"""Regenerate the regression values of one or more suites from today's code.

Usage, from the repository root::

    python -m tests.regression.regenerate SUITE [SUITE ...]    # rewrite tests/regression/SUITE.json
    python -m tests.regression.regenerate --all --dry-run       # only show what would change

Runs the suites' test files with pytest in record mode (see :mod:`tests.regression`): every
``check`` appends the value it measured instead of asserting. The other assertions of those tests
still hold, and a failing run writes nothing. Then, per value, the new ``measured`` is the worst of
the recorded values (the largest for a value bounded above, the smallest for one bounded below; a
value bounded on both sides must be measured once), and the thresholds move with it by the
unchanged margins. Every value of a suite must be measured by its tests, or nothing is written.
Regenerate only when a change of behaviour is intended, and read the printed differences first.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from . import DIRECTORY, RECORD_ENV, suites

__all__ = ["main", "regenerate_entry", "run_records"]

ROOT = DIRECTORY.parent.parent


def _round(x: float) -> float:
    """Six significant digits: what the files store."""
    return float(f"{x:.6g}")


def regenerate_entry(
    entry: dict[str, Any], values: Sequence[float], keep_thresholds: bool = False
) -> dict[str, Any]:
    """The entry with ``measured`` and the thresholds recomputed from the recorded ``values``.

    Parameters
    ----------
    entry : dict
        The value's current entry (``measured``, ``upper_margin`` and/or ``lower_margin``, ...).
    values : sequence of float
        What the tests recorded for it today (one per call of ``check``).
    keep_thresholds : bool
        Keep ``upper`` and ``lower`` and recompute the margins from them instead (for a value
        moved here from a test, whose threshold must not change in the move).

    Returns
    -------
    dict
        A copy of ``entry`` with the new ``measured``, and the new ``upper`` and ``lower`` (or,
        with ``keep_thresholds``, the new margins).

    Raises
    ------
    ValueError
        No value, or several different values for a value bounded on both sides.
    """
    if not values:
        raise ValueError("not measured by the suite's tests")
    has_upper, has_lower = "upper_margin" in entry, "lower_margin" in entry
    if has_upper and has_lower:
        if len(set(values)) != 1:
            raise ValueError(f"bounded on both sides but measured differently: {sorted(set(values))}")
        measured = values[0]
    elif has_upper:
        measured = max(values)
    elif has_lower:
        measured = min(values)
    else:
        raise ValueError("neither upper_margin nor lower_margin")
    new = dict(entry, measured=_round(measured))
    if keep_thresholds:
        for side, sign in (("upper", 1.0), ("lower", -1.0)):
            if f"{side}_margin" in entry:
                new[f"{side}_margin"] = _round(sign * (float(entry[side]) - new["measured"]))
        return new
    if has_upper:
        new["upper"] = _round(new["measured"] + float(entry["upper_margin"]))
    if has_lower:
        new["lower"] = _round(new["measured"] - float(entry["lower_margin"]))
    return new


def run_records(test_files: Sequence[str]) -> list[dict[str, Any]]:
    """Run ``test_files`` with pytest in record mode and return the recorded values.

    Raises
    ------
    RuntimeError
        The test run failed (its output is printed).
    """
    with tempfile.TemporaryDirectory() as tmp:
        record = Path(tmp) / "record.jsonl"
        record.touch()
        env = dict(os.environ, **{RECORD_ENV: str(record)})
        cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *test_files]
        print("running:", " ".join(cmd), flush=True)
        proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
        if proc.returncode != 0:
            print(proc.stdout[-6000:], proc.stderr[-3000:], sep="\n")
            raise RuntimeError(f"the tests failed (exit {proc.returncode}): nothing written")
        return [json.loads(line) for line in record.read_text().splitlines() if line.strip()]


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tests.regression.regenerate", description=__doc__.split("\n")[0]
    )
    parser.add_argument("suite", nargs="*", help=f"suites to regenerate (known: {', '.join(suites())})")
    parser.add_argument("--all", action="store_true", help="every suite")
    parser.add_argument("--dry-run", action="store_true", help="print the differences, write nothing")
    parser.add_argument("--keep-thresholds", action="store_true",
                        help="keep the thresholds, recompute the margins (when a value is first moved here)")
    args = parser.parse_args(argv)
    chosen = suites() if args.all else list(args.suite)
    unknown = sorted(set(chosen) - set(suites()))
    if not chosen or unknown:
        known = f"name one or more suites of {suites()} or --all"
        parser.error(known + (f"; unknown: {unknown}" if unknown else ""))
    data = {s: json.loads((DIRECTORY / f"{s}.json").read_text()) for s in chosen}
    files = sorted({f for d in data.values() for f in d["tests"]})
    records = run_records(files)
    failed_suites = []
    for suite, doc in data.items():
        failed = False
        new_values = {}
        for name, entry in doc["values"].items():
            got = [r["value"] for r in records if r["suite"] == suite and r["name"] == name]
            try:
                new_values[name] = regenerate_entry(entry, got, args.keep_thresholds)
            except ValueError as exc:
                print(f"{suite}.{name}: {exc}")
                failed = True
                continue
            old, new = entry, new_values[name]
            change = "" if old.get("measured") == new["measured"] else "  CHANGED"
            print(f"{suite}.{name}: measured {old.get('measured')} -> {new['measured']}, "
                  f"lower {old.get('lower')} -> {new.get('lower')}, "
                  f"upper {old.get('upper')} -> {new.get('upper')}{change}")
        if failed:
            failed_suites.append(suite)
            continue
        if not args.dry_run:
            doc = dict(doc, values=new_values)
            (DIRECTORY / f"{suite}.json").write_text(json.dumps(doc, indent=2, ensure_ascii=False) + "\n")
            print(f"wrote {DIRECTORY / f'{suite}.json'}")
    if failed_suites:
        print(f"not written (values missing or inconsistent): {failed_suites}")
    return 1 if failed_suites else 0


if __name__ == "__main__":
    sys.exit(main())
