"""Run the test suite under several of OpenBLAS's kernel choices and report what each found.

numpy and scipy ship OpenBLAS built for every x86-64 core type (``DYNAMIC_ARCH``); at import it
picks the kernels of the processor it runs on, and ``OPENBLAS_CORETYPE`` overrides the pick. A
machine with another CPU (an AMD EPYC picks the Haswell kernels, an older Xeon Sandybridge's)
rounds differently: the same code and data give other last digits, other iteration counts, and
a reference solver at the edge of its accuracy may end with another status. This script shows
those differences before a newcomer's machine does: one full ``pytest`` run per choice, each in
a subprocess with the choice in its environment, a JUnit file per run, and a report
(``report.md`` and ``report.json``) with the kernel each run really used (as ``threadpoolctl``
reads it; a core type the CPU cannot run falls back to another) and every failing test.

Usage, from a checkout with the test extras installed::

    python dev/blas_kernels.py --out dev/reports/blas_kernels
    python dev/blas_kernels.py --choice Haswell:1 --choice Sandybridge:2 -- tests/test_qp_backends.py

A choice is ``CORETYPE:THREADS`` (``default`` for the machine's own pick). Runs go one after the
other unless ``--jobs 2``; give a run one thread per job on a 2-core machine. A run's result is
kept in ``OUT/<choice>.json`` as soon as it ends, and a rerun skips the choices already there
(``--fresh`` to run them again), so an interrupted matrix loses no finished run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: The kernel families OpenBLAS's x86-64 build distinguishes that a current x86-64 server runs;
#: Zen (AMD EPYC) maps to Haswell's kernels in OpenBLAS 0.3.x. Threads alternate 1 / 2.
DEFAULT_CHOICES = ("default:2", "Haswell:1", "Haswell:2", "Sandybridge:1", "Nehalem:2", "Prescott:1")

_PROBE = (
    "import json, numpy, scipy.linalg, threadpoolctl\n"
    "print(json.dumps(sorted({(i.get('architecture') or '?') for i in threadpoolctl.threadpool_info()"
    " if i['internal_api'] == 'openblas'})))"
)


@dataclass
class RunResult:
    """One run of the suite under one kernel choice."""

    choice: str
    coretype: str
    threads: int
    kernels: list[str]
    passed: int = 0
    failed: int = 0
    errors: int = 0
    skipped: int = 0
    seconds: float = 0.0
    exit_code: int | None = None
    failures: list[str] = field(default_factory=list)


def parse_choice(text: str) -> tuple[str, int]:
    """``"Haswell:1"`` -> ``("Haswell", 1)``; a clear error for anything else."""
    core, sep, threads = text.partition(":")
    if not core or not sep or not threads.isdigit() or int(threads) < 1:
        raise argparse.ArgumentTypeError(
            f"--choice: expected CORETYPE:THREADS such as 'Haswell:1' or 'default:2', found {text!r}"
        )
    return core, int(threads)


def environment(coretype: str, threads: int) -> dict[str, str]:
    """The environment of one run: the core type (none for ``default``) and the thread count."""
    env = dict(os.environ)
    env.pop("OPENBLAS_CORETYPE", None)
    if coretype != "default":
        env["OPENBLAS_CORETYPE"] = coretype
    env["OPENBLAS_NUM_THREADS"] = str(threads)
    return env


def kernels_used(env: dict[str, str]) -> list[str]:
    """The OpenBLAS kernel names ``threadpoolctl`` reports under ``env``."""
    out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True,
                         check=False)
    try:
        return list(json.loads(out.stdout.strip().splitlines()[-1]))
    except (IndexError, json.JSONDecodeError):
        return [f"unknown ({out.stderr.strip()[-200:]})"]


def read_junit(path: Path, result: RunResult) -> None:
    """Counts and failing test ids from a JUnit XML file into ``result``."""
    root = ET.parse(path).getroot()
    for case in root.iter("testcase"):
        name = f"{case.get('classname', '')}::{case.get('name', '')}"
        if case.find("failure") is not None:
            result.failed += 1
            result.failures.append(name)
        elif case.find("error") is not None:
            result.errors += 1
            result.failures.append(f"{name} (error)")
        elif case.find("skipped") is not None:
            result.skipped += 1
        else:
            result.passed += 1


def run_one(choice: str, out: Path, pytest_args: list[str]) -> RunResult:
    """Run the suite under ``choice`` and store its result in ``OUT/<choice>.json``."""
    coretype, threads = parse_choice(choice)
    env = environment(coretype, threads)
    result = RunResult(choice, coretype, threads, kernels_used(env))
    tag = choice.replace(":", "-t")
    junit = out / f"{tag}.xml"
    log = out / f"{tag}.log"
    start = time.perf_counter()
    with log.open("w") as fh:
        proc = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--junitxml={junit}",
             *pytest_args],
            cwd=ROOT, env=env, stdout=fh, stderr=subprocess.STDOUT, check=False,
        )
    result.seconds = round(time.perf_counter() - start, 1)
    result.exit_code = proc.returncode
    if junit.exists():
        read_junit(junit, result)
    (out / f"{tag}.json").write_text(json.dumps(asdict(result), indent=2) + "\n")
    print(f"{choice}: {result.passed} passed, {result.failed} failed, {result.errors} errors "
          f"in {result.seconds:.0f} s (kernels {', '.join(result.kernels)})", file=sys.stderr, flush=True)
    return result


def stored_result(choice: str, out: Path) -> RunResult | None:
    """A finished run of ``choice`` in ``out``: its JSON, or else its complete JUnit file (a run
    whose pytest finished after this script was stopped), or ``None``."""
    tag = choice.replace(":", "-t")
    path, junit = out / f"{tag}.json", out / f"{tag}.xml"
    if path.exists():
        return RunResult(**json.loads(path.read_text()))
    if not junit.exists():
        return None
    try:
        coretype, threads = parse_choice(choice)
        result = RunResult(choice, coretype, threads, kernels_used(environment(coretype, threads)))
        read_junit(junit, result)
    except ET.ParseError:  # pytest still writing, or stopped mid-file
        return None
    suite = ET.parse(junit).getroot()
    suite = suite if suite.tag == "testsuite" else suite.find("testsuite")
    result.seconds = float(suite.get("time", "0")) if suite is not None else 0.0
    result.exit_code = 1 if result.failed or result.errors else 0
    path.write_text(json.dumps(asdict(result), indent=2) + "\n")
    return result


def write_report(results: list[RunResult], out: Path, pytest_args: list[str]) -> None:
    """``report.json`` and ``report.md`` from the runs' results."""
    (out / "report.json").write_text(json.dumps([asdict(r) for r in results], indent=2) + "\n")
    lines = [
        "# The test suite under OpenBLAS's kernel choices",
        "",
        f"Command per run: `python -m pytest {' '.join(pytest_args) or '(the whole suite)'}` with "
        "`OPENBLAS_CORETYPE` and `OPENBLAS_NUM_THREADS` set as below (`dev/blas_kernels.py`).",
        "",
        "| choice | kernels used | threads | passed | failed | errors | skipped | time (s) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in results:
        lines.append(f"| {r.choice} | {', '.join(r.kernels)} | {r.threads} | {r.passed} | {r.failed} | "
                     f"{r.errors} | {r.skipped} | {r.seconds:.0f} |")
    failing = sorted({f for r in results for f in r.failures})
    lines += ["", "## Failures", ""]
    if not failing:
        lines.append("None.")
    for name in failing:
        where = ", ".join(r.choice for r in results if name in r.failures)
        lines.append(f"- `{name}`: {where}")
    (out / "report.md").write_text("\n".join(lines) + "\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--choice", action="append", type=str, default=None,
                        help=f"CORETYPE:THREADS, repeatable (default: {', '.join(DEFAULT_CHOICES)})")
    parser.add_argument("--out", type=Path, default=ROOT / "dev" / "reports" / "blas_kernels")
    parser.add_argument("--jobs", type=int, default=1, help="runs at once (default 1)")
    parser.add_argument("--fresh", action="store_true", help="run again the choices already stored")
    parser.add_argument("pytest_args", nargs="*", help="after --: passed to pytest")
    args = parser.parse_args(argv)
    choices = args.choice or list(DEFAULT_CHOICES)
    for c in choices:
        parse_choice(c)
    if args.jobs < 1:
        parser.error(f"--jobs: expected an integer >= 1, found {args.jobs}")
    args.out.mkdir(parents=True, exist_ok=True)
    stored: dict[str, RunResult] = {}
    for c in choices:
        if not args.fresh and (kept := stored_result(c, args.out)) is not None:
            stored[c] = kept
            print(f"{c}: kept from {args.out}", file=sys.stderr)
    todo = [c for c in choices if c not in stored]
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for result in pool.map(lambda c: run_one(c, args.out, args.pytest_args), todo):
            stored[result.choice] = result
    results = [stored[c] for c in choices]
    write_report(results, args.out, args.pytest_args)
    print(f"report: {args.out / 'report.md'}", file=sys.stderr)
    return 0 if all(r.failed == r.errors == 0 and r.exit_code == 0 for r in results) else 1


if __name__ == "__main__":
    raise SystemExit(main())
