"""``python -m benchmarks.mutation``: the command line of the mutation check."""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from benchmarks.mutation.operators import OPERATORS
from benchmarks.mutation.runner import CheckConfig, list_mutants, run_check

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The options of ``python -m benchmarks.mutation``."""
    p = argparse.ArgumentParser(
        prog="python -m benchmarks.mutation",
        description="Mutate a seeded sample of the modules one change at a time, run the tests that run the "
        "changed line, and report which mutants the tests catch.",
    )
    p.add_argument("--modules", nargs="+", default=["lmi", "rmpc.mpc"], help="packages or modules to mutate")
    p.add_argument("--tests", nargs="+", default=["tests"], help="test files or folders of the map run")
    p.add_argument("--max-mutants", type=int, default=100, help="size of the sample (0: every mutant)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sample")
    p.add_argument("--operators", nargs="+", choices=OPERATORS, default=list(OPERATORS))
    p.add_argument("--mutant", action="append", default=[], metavar="ID", help="run this mutant (repeatable)")
    p.add_argument("--out", type=Path, default=Path("mutation-out"), help="output folder")
    p.add_argument("--root", type=Path, default=Path.cwd(), help="the project (default: the current folder)")
    p.add_argument("--timeout-base", type=float, default=60.0, help="seconds every mutant's run is allowed")
    p.add_argument("--timeout-factor", type=float, default=3.0, help="times its tests' map-run durations")
    p.add_argument("--max-test-seconds", type=float, default=120.0,
                   help="cut a mutant's tests where their durations reach this (0: no cut)")
    p.add_argument("--budget-minutes", type=float, default=None, help="start no mutant after this long")
    p.add_argument("--list", action="store_true",
                   help="count the mutants per module and operator; run nothing")
    p.add_argument("--keep-sandbox", action="store_true", help="leave the temporary copy on disk")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the check; exit 0 when it finished, 2 on bad input, 130 when interrupted."""
    args = build_parser().parse_args(argv)
    if args.max_mutants < 0:
        print("error: --max-mutants must be >= 0", file=sys.stderr)
        return 2
    try:
        if args.list:
            mutants = list_mutants(args.root.resolve(), args.modules, tuple(args.operators))
            for (module, operator), n in sorted(Counter((m.module, m.operator) for m in mutants).items()):
                print(f"{module:40s} {operator:10s} {n:5d}")
            print(f"{'total':40s} {'':10s} {len(mutants):5d}")
            return 0
        config = CheckConfig(
            root=args.root, modules=args.modules, tests=args.tests, out=args.out,
            max_mutants=args.max_mutants or None, seed=args.seed, operators=tuple(args.operators),
            mutant_ids=args.mutant, timeout_base=args.timeout_base, timeout_factor=args.timeout_factor,
            max_test_seconds=args.max_test_seconds or None, budget_minutes=args.budget_minutes,
            python=sys.executable, keep_sandbox=args.keep_sandbox,
        )
        summary = run_check(config, log=lambda line: print(line, flush=True))
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"interrupted; the mutants that finished are in {args.out}", file=sys.stderr)
        return 130
    c = summary["counts"]
    print(f"{summary['tried']} mutants: {c['caught']} caught, {c['survived']} survived "
          f"({summary['no_test']} run by no test), {c['timeout']} timed out, {c['error']} errors, "
          f"{c['not run']} not run; {summary['wall_seconds']:.0f} s; report in {args.out / 'report.md'}")
    return 0
