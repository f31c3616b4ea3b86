"""Sweeps: a TOML file expanded into scenarios, run in parallel, resumable through a store.

The file's format, its checks and its expansion into scenarios are
:mod:`benchmarks.core.sweep_spec`'s (its names are importable from here too); this module runs
the cases a store does not hold yet (:func:`run_sweep`, local processes or Dask) and writes the
reports from the store: ``results.json``, ``results.md``, the tables and ``errors.json``.
"""

from __future__ import annotations

import json
import shlex
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.core.execute import ExecOutcome, Task, execute
from benchmarks.core.executors import make_executor_and_out
from benchmarks.core.machine import machine_info, package_versions
from benchmarks.core.progress import CaseProgress
from benchmarks.core.publish import published_paths, staged_reports
from benchmarks.core.scenario import Scenario
from benchmarks.core.store import STORE_NAME, CaseStore
from benchmarks.core.sweep_spec import (
    SHIPPED,
    SweepSpec,
    expand,
    left_out,
    load_sweep,
    parse_sweep,
    resolve_config,
)
from benchmarks.reports.tables import metric_table, to_markdown, varying_fields, write_tables
from toolkit_common.errors import StoreError
from toolkit_common.validation import check_positive

__all__ = [
    "SHIPPED",
    "SweepOutcome",
    "SweepSpec",
    "expand",
    "left_out",
    "load_sweep",
    "parse_sweep",
    "resolve_config",
    "run_sweep",
]


@dataclass
class SweepOutcome:
    """Counts of a sweep invocation and the files it wrote."""

    name: str
    total: int
    skipped: int
    ran: int = 0
    failed: int = 0
    stored_errors: int = 0
    execution: ExecOutcome | None = None
    files: list[Path] = field(default_factory=list)
    wall_time_s: float = 0.0


def run_sweep(
    config: str | Path,
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    retry_errors: bool = False,
    progress: bool | None = None,
    argv: Sequence[str] | None = None,
    overwrite: bool = False,
    case_time_limit: float | None = None,
) -> SweepOutcome:
    """Run the cases of ``config`` not yet in ``out``'s store, then write the reports from the store.

    Parameters
    ----------
    config : str or Path
        The sweep TOML file.
    out : str or Path
        Output directory; holds the store (``sweep.sqlite``) and the reports.
    workers : int, optional
        Local worker processes (default: one per CPU; 0 runs in-process).
    scheduler : str, optional
        Address of a Dask scheduler; used instead of local workers.
    retry_errors : bool
        Run again the cases stored with an error (by default they count as finished).
    progress : bool, optional
        Force the progress bar on or off (default: on when stderr is a terminal).
    argv : sequence of str, optional
        The command line, recorded in the store's ``runs`` table.
    overwrite : bool
        Replace what ``out`` holds when it belongs to another sweep or another run (by default
        such a folder is refused with :class:`~toolkit_common.errors.StoreError`, so one sweep
        never overwrites another's results).
    case_time_limit : float, optional
        Wall-clock seconds a case may run; a case that runs longer is stopped and stored as an
        error whose message starts with ``time_limit`` (the rest runs on). Enforced in local
        worker processes and with ``workers=0``; Dask runs cases in threads, where it is not.
    """
    if case_time_limit is not None:
        case_time_limit = check_positive(case_time_limit, "case_time_limit")
    spec = load_sweep(config)
    cases = expand(spec)
    _refuse_other_results(Path(out), spec.name, overwrite)
    executor, out = make_executor_and_out(workers, scheduler, out)  # a bad --scheduler fails first
    start = time.perf_counter()
    position = {sc.case_id: i for i, sc in enumerate(cases)}
    store: CaseStore | None = None
    try:
        store = CaseStore(out / STORE_NAME)
        store.claim(spec.name, set(position), overwrite=overwrite)
    except BaseException:
        executor.close()
        if store is not None:
            store.close()
        raise
    scenarios = {sc.case_id: sc.to_dict() for sc in cases}
    with store:
        finished = store.finished_ids(include_errors=not retry_errors)
        for cid, why in store.unusable(scenarios).items():  # never trust a damaged or foreign row
            finished.discard(cid)
            print(f"sweep {spec.name}: stored case {cid} not used ({why}); measured again", file=sys.stderr)
        todo = [sc for sc in cases if sc.case_id not in finished]
        outcome = SweepOutcome(name=spec.name, total=len(cases), skipped=len(cases) - len(todo))
        if todo:
            run = store.begin_run(shlex.join(["rmpc", *(argv or sys.argv[1:])]))
            by_id = {sc.case_id: sc for sc in todo}
            tasks = [
                Task(
                    sc.case_id,
                    {"scenario": sc.to_dict(), "experiment": sc.case_id, "time_limit": case_time_limit},
                )
                for sc in todo
            ]
            with CaseProgress(len(tasks), f"sweep {spec.name}", progress) as bar:

                def on_result(task: Task, result: dict[str, Any]) -> None:
                    sc = by_id[task.key]
                    if result.get("ok"):
                        store.put_done(task.key, position[task.key], sc.to_dict(), result["record"], run)
                    else:
                        store.put_error(
                            task.key,
                            position[task.key],
                            sc.to_dict(),
                            result["error"],
                            result.get("traceback", ""),
                            run,
                        )
                        outcome.failed += 1
                    outcome.ran += 1
                    bar.advance(sc.label(), ok=bool(result.get("ok")))

                outcome.execution = execute(tasks, executor, on_result)
        outcome.wall_time_s = time.perf_counter() - start
        rows = store.rows(scenarios)
        extra = len(store.finished_ids()) - len(rows)
    if not todo:
        executor.close()
    outcome.stored_errors = sum(1 for r in rows if r["status"] == "error")
    where = executor.description if todo else "nothing to run"
    with staged_reports(out) as stage:  # every report file, or none of them, is new
        files = _write(stage, spec, cases, rows, extra, outcome, where)
    outcome.files = published_paths(files, stage, out)
    return outcome


def _refuse_other_results(out: Path, name: str, overwrite: bool) -> None:
    """Refuse a folder holding another run's results without a sweep store (a suite's, say)."""
    if overwrite or (out / STORE_NAME).exists() or not (out / "results.json").exists():
        return
    raise StoreError(
        "--out",
        f"a new folder or one of the sweep {name!r} (--overwrite replaces it)",
        f"the results of another run in {str(out)!r} (results.json without a sweep store)",
    )


def _write(
    out: Path,
    spec: SweepSpec,
    cases: list[Scenario],
    rows: list[dict[str, Any]],
    extra: int,
    outcome: SweepOutcome,
    where: str,
) -> list[Path]:
    records = [r["record"] for r in rows if r["status"] == "done"]
    errors = [r for r in rows if r["status"] == "error"]
    fields = [
        f
        for f in varying_fields([sc.to_dict() for sc in cases])
        if f not in ("controller", "plant", "saturation")
    ]
    header, table = metric_table(records, scenario_fields=fields)
    (out / "results.json").write_text(json.dumps(records, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    tables = write_tables(out, header, table, f"Sweep {spec.name}")
    failed = [
        {
            "case_id": r["case_id"],
            "error": r["error"],
            "scenario": r["scenario"],
            "traceback": (r["record"] or {}).get("traceback", ""),
        }
        for r in errors
    ]
    (out / "errors.json").write_text(json.dumps(failed, indent=1) + "\n", encoding="utf-8")
    ex = outcome.execution
    status = (
        "interrupted"
        if ex is not None and ex.interrupted
        else "complete"
        if len(rows) == len(cases)
        else "partial"
    )
    lines = [f"# Sweep `{spec.name}`", ""]
    if spec.description:
        lines += [spec.description, ""]
    lines += [
        f"{len(cases)} cases: {len(records)} done, {len(errors)} failed, "
        f"{len(cases) - len(rows)} not run yet ({status}). This invocation ran {outcome.ran} on {where} "
        f"in {outcome.wall_time_s:.1f} s and skipped "
        f"{outcome.skipped} finished earlier."
        + (
            f" The store also holds {extra} cases of earlier versions of the sweep file, left out here."
            if extra
            else ""
        ),
        _machine_line(),
        "",
        "`experiment` is the case id; varying fields are shown; metrics as in `rmpc bench paper` "
        "(errors in rad, worst axis for settling and overshoot).",
        "",
        to_markdown(header, table),
        "",
    ]
    dropped = left_out(spec)
    if dropped:
        lines += [
            f"Left out of the grid ({len(dropped)} combinations a controller cannot run): "
            + "; ".join(sorted(set(dropped)))
            + ".",
            "",
        ]
    if errors:
        lines += ["## Failed cases", ""] + [f"- `{r['case_id']}`: {r['error']}" for r in errors] + [""]
    lines += [
        "## Base scenario",
        "",
        "```json",
        json.dumps(Scenario.from_dict(spec.base, lenient_settings=True).to_dict(), indent=1),
        "```",
        "",
    ]
    (out / "results.md").write_text("\n".join(lines), encoding="utf-8")
    return [out / n for n in ("results.json", "results.md", "errors.json", STORE_NAME)] + tables


def _machine_line() -> str:
    m = machine_info()
    versions = ", ".join(f"{k} {v}" for k, v in package_versions().items())
    return (
        f"Machine: {m['platform']}, {m['cpu_count']} CPUs, Python {m['python']}, load average "
        f"{m['load_average']} at the end; {versions}."
    )
