"""Run the cases of a benchmark suite in parallel and collect records, traces and failures.

A suite (``rmpc bench paper``, ``rmpc bench faults``, ...) is a list of
:class:`SuiteCase` (an experiment name and a scenario); :func:`run_suite_cases` runs them on
local workers or Dask with a progress bar, longest first, and hands back what each produced;
the suite writes its own report from that.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.core.execute import ExecOutcome, Task, execute
from benchmarks.core.executors import make_executor_and_out
from benchmarks.core.progress import CaseProgress
from benchmarks.core.scenario import Scenario
from toolkit_common.errors import ConfigError

__all__ = [
    "SuiteCase",
    "SuiteOutcome",
    "check_time_scale",
    "chosen_experiments",
    "run_suite_cases",
    "write_records",
    "write_rows_csv",
    "write_run_info",
    "write_traces",
]


@dataclass(frozen=True)
class SuiteCase:
    """One run of a suite: the experiment it belongs to, its scenario and a short tag.

    ``key`` (file names, progress) is ``<experiment>_<tag>`` when a tag is given, else
    ``<experiment>_<controller>_<plant>_<saturation>``.
    """

    experiment: str
    scenario: Scenario
    tag: str = ""

    @property
    def key(self) -> str:
        if self.tag:
            return f"{self.experiment}_{self.tag}"
        sc = self.scenario
        return f"{self.experiment}_{sc.controller}_{sc.plant}_{sc.saturation}"


@dataclass
class SuiteOutcome:
    """What a suite run did: records, failures, files, wall time, interruption, and ``notes``
    (what the run did not take as given: a stored case it measured again, one it could not store)."""

    records: list[dict[str, Any]] = field(default_factory=list)
    failures: list[dict[str, Any]] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    wall_time_s: float = 0.0
    execution: ExecOutcome | None = None
    executor: str = ""
    notes: list[str] = field(default_factory=list)


def chosen_experiments(known: Collection[str], experiments: Sequence[str] | None) -> list[str]:
    """The experiments a run asks for (all of ``known`` by default), each checked.

    Examples
    --------
    >>> chosen_experiments(["E1", "E2"], None), chosen_experiments(["E1", "E2"], ["E2"])
    (['E1', 'E2'], ['E2'])
    """
    chosen = list(known) if experiments is None else list(experiments)
    if not chosen:
        raise ConfigError("--experiments", "one or more names among " + ", ".join(known), "none")
    for name in chosen:
        if name not in known:
            raise ConfigError("--experiments", "names among " + ", ".join(known), repr(name))
    return chosen


def check_time_scale(time_scale: float) -> float:
    """``time_scale`` if it is a factor in ``(0, 1]`` (a suite's run lengths are multiplied by it)."""
    if not 0.0 < time_scale <= 1.0:
        raise ConfigError("time_scale", "a factor in (0, 1]", repr(time_scale))
    return time_scale


def run_suite_cases(
    cases: Sequence[Any],
    out: str | Path,
    title: str,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool | None = None,
    cost: Callable[[Any], float] | None = None,
) -> tuple[SuiteOutcome, list[tuple[Any, dict, dict]]]:
    """Run ``cases`` (each with ``experiment``, ``scenario`` and ``key``) and collect the results.

    Parameters
    ----------
    cases : sequence
        The suite's cases (:class:`SuiteCase` or alike).
    out : str or Path
        The output directory, created here (before anything runs, after the executor is made,
        so a bad scheduler address fails first).
    title : str
        The progress bar's title.
    workers, scheduler, progress
        As for ``rmpc bench paper``.
    cost : callable, optional
        A relative cost per case: the long cases start first.

    Returns
    -------
    outcome : SuiteOutcome
        Records in the order of ``cases`` and failures (``experiment``, ``key``, ``error``,
        ``traceback``, ``scenario``).
    runs : list of (case, record, trace)
        The cases that finished, with their time series.
    """
    executor, out = make_executor_and_out(workers, scheduler, out)
    start = time.perf_counter()
    results: dict[str, dict[str, Any]] = {}
    ordered = sorted(cases, key=cost, reverse=True) if cost is not None else list(cases)
    tasks = [
        Task(c.key, {"scenario": c.scenario.to_dict(), "experiment": c.experiment, "trace": True})
        for c in ordered
    ]
    with CaseProgress(len(tasks), title, progress) as bar:

        def on_result(task: Task, result: dict[str, Any]) -> None:
            results[task.key] = result
            bar.advance(task.key, ok=bool(result.get("ok")))

        execution = execute(tasks, executor, on_result)
    outcome = SuiteOutcome(
        wall_time_s=time.perf_counter() - start, execution=execution, executor=executor.description
    )
    runs = []
    for case in cases:
        res = results.get(case.key)
        if res is None:
            continue
        if res["ok"]:
            outcome.records.append(res["record"])
            runs.append((case, res["record"], res["trace"]))
        else:
            outcome.failures.append(
                {
                    "experiment": case.experiment,
                    "key": case.key,
                    "error": res["error"],
                    "traceback": res.get("traceback", ""),
                    "scenario": case.scenario.to_dict(),
                }
            )
    return outcome, runs


def write_traces(out: Path, runs: Sequence[tuple[Any, dict, dict]]) -> list[Path]:
    """Create ``figures/`` and ``traces/`` in ``out``; save each run's time series as ``traces/<key>.npz``."""
    import numpy as np

    (out / "figures").mkdir(exist_ok=True)
    (out / "traces").mkdir(exist_ok=True)
    files = []
    for case, _, trace in runs:
        path = out / "traces" / f"{case.key}.npz"
        np.savez_compressed(path, **trace)
        files.append(path)
    return files


def write_records(out: Path, records: Sequence[dict[str, Any]]) -> Path:
    """``results.json``: the records (strict JSON)."""
    import json

    path = out / "results.json"
    path.write_text(json.dumps(list(records), indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return path


def write_rows_csv(path: Path, rows: Sequence[dict[str, Any]]) -> Path | None:
    """A CSV of the table rows (dicts with the same keys); nothing when there are no rows."""
    import csv

    if not rows:
        return None
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def write_run_info(
    out: Path,
    command: str,
    outcome: SuiteOutcome,
    n_cases: int,
    workers: int | None,
    scheduler: str | None,
    scale: tuple[str, float],
) -> dict[str, Any]:
    """``run.json``: the command, wall time, executor, scale, counts, machine, versions and failures."""
    import json

    from benchmarks.core.machine import machine_info, package_versions

    info = {
        "command": command,
        "wall_time_s": outcome.wall_time_s,
        "executor": outcome.executor,
        "workers": workers,
        "scheduler": scheduler,
        scale[0]: scale[1],
        "cases": n_cases,
        "done": len(outcome.records),
        "failed": len(outcome.failures),
        "interrupted": bool(outcome.execution and outcome.execution.interrupted),
        "machine": machine_info(),
        "versions": package_versions(),
        "failures": outcome.failures,
    }
    if outcome.notes:
        info["notes"] = list(outcome.notes)
    (out / "run.json").write_text(json.dumps(info, indent=1) + "\n", encoding="utf-8")
    return info
