"""The ``rmpc`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from toolkit_common.errors import InvalidArgumentError, ToolkitError

__all__ = ["main"]


def _cmd_demo(args: argparse.Namespace) -> int:
    from models import PAPER_P_SAMPLE_TIME, RigidSatellite, TorqueLimiter
    from rmpc import LQR, simulate

    if not 0 < args.duration <= MAX_DEMO_DURATION:  # NaN fails too
        expected = f"a number of seconds in (0, {MAX_DEMO_DURATION:g}]"
        raise InvalidArgumentError("--duration", expected, repr(args.duration))
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    plant = sat.linear_model(x0, PAPER_P_SAMPLE_TIME)
    q = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
    ctrl = LQR(plant, Q=q, R=np.eye(3))
    traj = simulate(ctrl, sat, x0, duration=args.duration, dt=PAPER_P_SAMPLE_TIME, limiter=TorqueLimiter(1.0))
    err = np.abs(traj.x[-1, :3])
    print("LQR on the nonlinear satellite of paper P (limiter +-1 N m)")
    print(f"  initial attitude (deg): {np.round(np.degrees(x0[:3]), 3).tolist()}")
    print(
        f"  final attitude after {args.duration:g} s (deg): "
        f"{np.round(np.degrees(traj.x[-1, :3]), 5).tolist()}"
    )
    print(f"  max |u| applied (N m): {np.abs(traj.u_applied).max():.4f}")
    print(f"  sum |e(k)| per axis (rad): {np.round(np.abs(traj.x[:, :3]).sum(axis=0), 3).tolist()}")
    return 0 if np.all(err < 1e-2) else 1


def max_workers() -> int:
    """The most local worker processes ``--workers`` accepts: 4 per CPU, at least 64."""
    from benchmarks.core.executors import default_workers

    return max(64, 4 * default_workers())


def _workers(text: str) -> int:
    limit = max_workers()
    expected = f"expected an integer in [0, {limit}] (4 per CPU; --scheduler runs on more machines)"
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{expected}, found {text!r}") from None
    if not 0 <= value <= limit:
        raise argparse.ArgumentTypeError(f"{expected}, found {text!r}")
    return value


def _bounded_positive(limit: float) -> Any:
    """An argparse type: a finite number in ``(0, limit]``."""

    def parse(text: str) -> float:
        expected = f"expected a number in (0, {limit:g}]"
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{expected}, found {text!r}") from None
        if not 0 < value <= limit:
            raise argparse.ArgumentTypeError(f"{expected}, found {text!r}")
        return value

    return parse


MAX_DEMO_DURATION = 3600.0
"""Bound on ``rmpc demo --duration`` (s): an hour of simulated time at 10 ms."""

MAX_CASE_TIME_LIMIT = 7 * 24 * 3600.0
"""Bound on ``--case-time-limit`` (s): a week."""

MAX_DURATION_SCALE = 100.0
"""Bound on ``--duration-scale``: paper P's 30 s runs become 50 min of simulated time."""


def _experiments(text: str) -> list[str]:
    parts = [part.strip() for part in text.split(",")]
    if not text.strip() or any(not part for part in parts):
        raise argparse.ArgumentTypeError(f"expected experiment names separated by commas, found {text!r}")
    return parts


def _out_dir(text: str) -> str:
    """An argparse type for ``--out``: a folder name, not empty, not an existing file, writable.

    The folder (or, when it does not exist yet, the nearest folder above it that does) must take
    a new file: a read-only folder is refused here, naming ``--out``, instead of failing later in
    the store or the report writer with a message about a file.
    """
    import os

    if not text.strip():
        raise argparse.ArgumentTypeError(f"expected a folder name, found {text!r}")
    if os.path.exists(text) and not os.path.isdir(text):
        raise argparse.ArgumentTypeError(f"expected a folder, found the file {text!r}")
    from benchmarks.core.folders import not_writable

    problem = not_writable(text)
    if problem is not None:
        raise argparse.ArgumentTypeError(f"expected a folder that can be written, found {text!r} ({problem})")
    return text


def _cmd_bench_paper(args: argparse.Namespace) -> int:
    from benchmarks.families.rigid.defaults import SHORT_DURATION_SCALE
    from benchmarks.suites.paper import run_paper

    scale = SHORT_DURATION_SCALE if args.short else args.duration_scale
    outcome = run_paper(
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        duration_scale=scale,
        experiments=args.experiments,
        progress=None if not args.no_progress else False,
    )
    return _report_suite("paper", outcome, args.out)


def _report_suite(name: str, outcome: Any, out: str, resumable: bool = False) -> int:
    """Print a suite's summary and failures; one line when it was interrupted. Returns the exit status.

    ``resumable``: the suite keeps its finished cases and a re-run resumes (``bench methods``), so
    the interrupted line says how many cases did not run and how to resume.
    """
    ex = outcome.execution
    done, failed = len(outcome.records), len(outcome.failures)
    print(
        f"rmpc bench {name}: {done} cases done, {failed} failed in {outcome.wall_time_s:.1f} s; "
        f"results in {out}/results.md"
    )
    for failure in outcome.failures:
        print(f"  failed: {failure['key']}: {failure['error']}", file=sys.stderr)
    if ex is not None and ex.interrupted:
        if resumable:
            line = f"{len(ex.unfinished)} cases not run; re-run the same command to resume"
        else:
            line = "the files hold the cases that finished"
        print(f"rmpc: interrupted; {line}", file=sys.stderr)
        return 130
    return 1 if failed or (ex is not None and ex.unfinished) else 0


def _cmd_bench_suite(args: argparse.Namespace) -> int:
    """``rmpc bench faults | mrp | flexible``: the suites of the later papers share one command shape."""
    import importlib

    module = importlib.import_module(f"benchmarks.suites.{args.suite_module}")
    outcome = getattr(module, args.suite_runner)(
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        time_scale=module.SHORT_TIME_SCALE if args.short else 1.0,
        experiments=args.experiments,
        progress=None if not args.no_progress else False,
    )
    return _report_suite(args.bench_command, outcome, args.out)


#: The later papers' suites: command -> (module in benchmarks.suites, runner, help, what it runs,
#: --short help, experiment names for --experiments).
_SUITES: dict[str, tuple[str, str, str, str, str, str]] = {
    "faults": (
        "faults",
        "run_faults",
        "paper W's wheel-fault scenarios S1-S4 (W1-W4)",
        "Run W1-W4 (paper W's S1-S4 on the four-wheel satellite: ABFTC, RMPC, CRMPC, GIPC) and write "
        "results.json, results.md (tables, paper W's reported results next to the measured ones, its "
        "inconsistencies, every setting chosen), results.csv, run.json, figures/W*.png and traces/*.npz "
        "into DIR.",
        "a smoke run (run lengths and fault windows x 0.1) to check the set-up; no measurement",
        "W1,...",
    ),
    "mrp": (
        "mrp",
        "run_mrp",
        "paper M's MRP satellite scenarios M1-M3",
        "Run M1-M3 (paper M's MRP satellite with the spinning disk: BS, MAB, TFAB, RMPC, CRMPC) and write "
        "results.json, results.md (tables, paper M's reported results next to the measured ones, its "
        "inconsistencies, every setting chosen), results.csv, run.json, figures/M*.png and traces/*.npz "
        "into DIR.",
        "a smoke run (run lengths x 0.05); no measurement",
        "M1,...",
    ),
    "flexible": (
        "flexible",
        "run_flexible",
        "paper V's flexible satellite study F1-F4 and paper S's baselines F5",
        "Run F1-F4 (paper V's flexible satellite: MTSMC and CSMC with and without PZT vibration control on "
        "the V-slew, the boundary-layer sweep, steady error with the integral term, OfflineRMPC and RMPC on "
        "the 14-state model on a small slew; F5: paper S's baselines on the V-slew) and write results.json, "
        "results.md (tables, paper V's reported "
        "results next to the measured ones, the papers' inconsistencies, every setting chosen), results.csv, "
        "run.json, figures/F*.png and traces/*.npz into DIR.",
        "a smoke run (run lengths x 0.02); no measurement",
        "F1,...",
    ),
}


def _names(text: str) -> list[str]:
    parts = [part.strip() for part in text.split(",")]
    if not text.strip() or any(not part for part in parts):
        raise argparse.ArgumentTypeError(f"expected names separated by commas, found {text!r}")
    return parts


def _cmd_bench_methods(args: argparse.Namespace) -> int:
    from benchmarks.suites.methods import run_methods

    outcome = run_methods(
        args.out,
        short=args.short,
        problems=args.problems,
        methods=args.methods,
        progress=None if not args.no_progress else False,
        fresh=args.fresh,
        baseline=args.baseline,
    )
    return _report_suite("methods", outcome, args.out, resumable=True)


def _add_methods(bsub: Any) -> None:
    from benchmarks.suites.methods import METHODS
    from benchmarks.suites.methods_problems import PROBLEMS, SHORT_PROBLEMS

    methods = bsub.add_parser(
        "methods",
        help="the robust MPC forms head to head on the field's test problems",
        description="Solve every test problem (Kothare's examples 1 and 2, MUP's demo system, paper P's "
        "satellite at 2 and 8 vertices and holding attitude under a gravity-gradient torque, paper W's wheel "
        "satellite, the 14-state flexible model, the double integrator of the tube literature) with every "
        "method (" + ", ".join(METHODS) + "): gamma at the start state, the feasible region along "
        "fixed directions, the closed-loop cost, bound violations over seeded switching runs, solve times "
        "next to cvxpy + Clarabel, statuses. Writes "
        "results.json, results.md, results.csv, run.json, figures/*.png and cases/*.json (each finished "
        "case; re-running the same command resumes). Exit status: 0 all done, 1 some cases failed, "
        "2 bad input, 130 interrupted.",
    )
    methods.add_argument("--out", required=True, type=_out_dir, metavar="DIR", help="output directory")
    methods.add_argument(
        "--short", action="store_true",
        help=f"a smoke run ({len(SHORT_PROBLEMS)} small problems, few directions, short loops)",
    )
    methods.add_argument(
        "--problems", type=_names, default=None, metavar=",".join(list(PROBLEMS)[:2]) + ",...",
        help="run only these problems (" + ", ".join(PROBLEMS) + ")",
    )
    methods.add_argument(
        "--methods", type=_names, default=None, metavar="kothare,vertex,...", help="run only these methods"
    )
    methods.add_argument("--fresh", action="store_true", help="ignore the cases stored by an earlier run")
    methods.add_argument(
        "--baseline", default=None, metavar="OLD_DIR",
        help="an earlier methods run's output directory: the report puts its solve times, iterations "
        "and time ratios next to this run's, with new/old per problem and method, and flags a "
        "baseline measured on another machine",
    )
    methods.add_argument("--no-progress", action="store_true", help="no progress output at all")
    methods.set_defaults(func=_cmd_bench_methods)


def _add_suite(bsub: Any, name: str, workers_help: str) -> None:
    module, runner, help_text, description, short_help, metavar = _SUITES[name]
    status = "Exit status: 0 all done, 1 some cases failed, 2 bad input, 130 interrupted."
    parser = bsub.add_parser(name, help=help_text, description=f"{description} {status}")
    parser.add_argument("--out", required=True, type=_out_dir, metavar="DIR", help="output directory")
    parser.add_argument("--workers", type=_workers, default=None, metavar="N", help=workers_help)
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS", help="a Dask scheduler instead")
    parser.add_argument("--short", action="store_true", help=short_help)
    parser.add_argument(
        "--experiments", type=_experiments, default=None, metavar=metavar, help="run only these experiments"
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress output at all")
    parser.set_defaults(func=_cmd_bench_suite, suite_module=module, suite_runner=runner)


def _cmd_bench_sweep(args: argparse.Namespace, argv: Sequence[str]) -> int:
    from benchmarks.core.sweep import run_sweep

    outcome = run_sweep(
        args.config,
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        retry_errors=args.retry_errors,
        progress=None if not args.no_progress else False,
        argv=argv,
        overwrite=args.overwrite,
        case_time_limit=args.case_time_limit,
    )
    ex = outcome.execution
    print(
        f"rmpc bench sweep {outcome.name}: {outcome.total} cases, {outcome.skipped} finished before, "
        f"{outcome.ran} run now ({outcome.failed} failed) in {outcome.wall_time_s:.1f} s; "
        f"results in {args.out}/results.md"
    )
    if ex is not None and ex.interrupted:
        print(
            f"rmpc: interrupted; {len(ex.unfinished)} cases not run; re-run the same command to resume",
            file=sys.stderr,
        )
        return 130
    if ex is not None and ex.unfinished:
        print(
            f"rmpc: {ex.lost_reason}; {len(ex.unfinished)} cases not run; re-run the same command to resume",
            file=sys.stderr,
        )
        return 1
    if outcome.stored_errors:
        print(
            f"rmpc: {outcome.stored_errors} cases failed (listed in {args.out}/results.md and errors.json)",
            file=sys.stderr,
        )
        return 1
    return 0


def _add_bench(sub: argparse._SubParsersAction) -> None:
    bench = sub.add_parser(
        "bench",
        help="benchmark suites and sweeps",
        description="Run a benchmark suite (paper P's experiments, paper W's fault scenarios) or a sweep "
        "of scenarios.",
    )
    bsub = bench.add_subparsers(
        dest="bench_command", required=True, metavar="{paper,faults,mrp,flexible,methods,sweep}"
    )
    workers_help = "worker processes on this machine (default: one per CPU; 0: run in this process)"
    paper = bsub.add_parser(
        "paper",
        help="experiments E1-E6 of paper P",
        description="Run E1-E6 of paper P (RMPC, GIPC, CRMPC; linear and nonlinear satellite) and write "
        "results.json, results.md (tables and every setting chosen), results.csv, results.tex, "
        "results_table.json, run.json, figures/*.png and traces/*.npz into DIR. Exit status: 0 all done, "
        "1 some cases failed, 2 bad input, 130 interrupted.",
    )
    paper.add_argument("--out", required=True, type=_out_dir, metavar="DIR", help="output directory")
    paper.add_argument("--workers", type=_workers, default=None, metavar="N", help=workers_help)
    paper.add_argument("--scheduler", default=None, metavar="ADDRESS", help="run on a Dask scheduler instead")
    length = paper.add_mutually_exclusive_group()
    length.add_argument(
        "--duration-scale",
        type=_bounded_positive(MAX_DURATION_SCALE),
        default=1.0,
        metavar="F",
        help="multiply every duration and the disturbance time by F (default 1)",
    )
    length.add_argument(
        "--short",
        action="store_true",
        help="short runs (duration scale 0.075: 2.25 s instead of 30 s) to check the set-up",
    )
    paper.add_argument(
        "--experiments",
        type=_experiments,
        default=None,
        metavar="E1,E2,...",
        help="run only these experiments",
    )
    paper.add_argument("--no-progress", action="store_true", help="no progress output at all")
    paper.set_defaults(func=_cmd_bench_paper)

    for name in _SUITES:
        _add_suite(bsub, name, workers_help)
    _add_methods(bsub)

    sweep = bsub.add_parser(
        "sweep",
        help="a sweep of scenarios from a TOML file (resumable)",
        description="Run the cases of a sweep file (see benchmarks/sweeps/) and store each one in "
        "DIR/sweep.sqlite as it finishes; re-running skips the stored cases. Writes results.json, "
        "results.md, results.csv, results.tex, results_table.json and errors.json from the store. "
        "Exit status: 0 all done, 1 some cases failed or did not run, 2 bad input, 130 interrupted. "
        "With --scheduler the Dask workers need this toolkit installed.",
    )
    sweep.add_argument(
        "--config",
        required=True,
        metavar="FILE",
        help="the sweep TOML file, or the name of a shipped one (smoke, uncertainty, ...)",
    )
    sweep.add_argument(
        "--out", required=True, type=_out_dir, metavar="DIR", help="output directory (holds the store)"
    )
    sweep.add_argument("--workers", type=_workers, default=None, metavar="N", help=workers_help)
    sweep.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="a Dask scheduler (tcp://host:port) to run the cases on instead of local workers",
    )
    sweep.add_argument("--retry-errors", action="store_true", help="run again the cases stored with an error")
    sweep.add_argument(
        "--case-time-limit",
        type=_bounded_positive(MAX_CASE_TIME_LIMIT),
        default=None,
        metavar="S",
        help="stop a case after S seconds of wall time and store it as a time_limit error (not on Dask)",
    )
    sweep.add_argument(
        "--overwrite",
        action="store_true",
        help="replace what DIR holds when it belongs to another sweep or run (refused by default)",
    )
    sweep.add_argument("--no-progress", action="store_true", help="no progress output at all")
    sweep.set_defaults(func=_cmd_bench_sweep)


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``rmpc`` command.

    ``argv`` (the arguments to be parsed) lets the parser skip importing the heavy timing module
    unless the command is ``timing``.
    """
    parser = argparse.ArgumentParser(
        prog="rmpc", description="Robust MPC for satellite attitude control: runs and benchmarks."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="a closed-loop LQR run on the nonlinear satellite")
    demo.add_argument("--duration", type=float, default=30.0, help="simulated time in s")
    demo.set_defaults(func=_cmd_demo)
    _add_bench(sub)
    from benchmarks.export_command import add_export_parser

    add_export_parser(sub, _out_dir)
    command = next((a for a in (argv or []) if not a.startswith("-")), None)
    if argv is None or command == "timing":
        _add_timing(sub)
    else:  # listed in `rmpc --help` without importing the solvers it times
        sub.add_parser("timing", help="the solver timing report (timing.json, timing.md, timing.png)")
    return parser


def _add_timing(sub: argparse._SubParsersAction) -> None:
    """``rmpc timing --out DIR`` (the solver timing report), owned by :mod:`benchmarks.timing`."""
    try:
        from benchmarks.timing import add_timing_parser
    except ModuleNotFoundError as err:
        if err.name != "benchmarks.timing":
            raise
        return  # a checkout without the timing report: the other commands still work
    add_timing_parser(sub)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status (2 on bad usage or bad input, 130 on interrupt)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    try:
        if args.func is _cmd_bench_sweep:
            return int(_cmd_bench_sweep(args, argv))
        return int(args.func(args))
    except ToolkitError as err:
        print(f"rmpc: error: {err}".replace("\n", " "), file=sys.stderr)
        return 2
    except OSError as err:
        where = err.filename if err.filename else "output"
        print(f"rmpc: error: {where}: {err.strerror or err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rmpc: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
