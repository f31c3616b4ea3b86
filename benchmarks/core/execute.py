"""The one loop that runs cases on an executor and hands each result over as it arrives.

Used by the paper suite and by sweeps alike:

- at most ``2 x workers`` cases are in flight; the rest wait here (so an interrupt has
  little to cancel and a huge sweep costs no memory);
- each result goes to ``on_result`` as soon as its case finishes (the sweep commits it to
  its store there);
- the first SIGINT stops submitting, cancels what has not started and waits for the
  running cases (their results are kept); a second SIGINT abandons them (the handler is
  :class:`benchmarks.core.interrupts.Interrupts`; a case run in this process, ``--workers 0``,
  that an interrupt reached is not kept, whatever it returned);
- a dead worker process (``kill -9``, out of memory) breaks the pool: the pool is restarted
  and the unfinished cases are submitted again, up to ``max_restarts`` times.
"""

from __future__ import annotations

import sys
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from benchmarks.core.executors import CaseExecutor, WorkerLost
from benchmarks.core.interrupts import Interrupts
from benchmarks.core.runner import run_case

__all__ = ["ExecOutcome", "Task", "execute"]


@dataclass(frozen=True)
class Task:
    """A case to run: its key (case id) and the payload of :func:`benchmarks.core.runner.run_case`."""

    key: str
    payload: dict[str, Any]


@dataclass
class ExecOutcome:
    """What happened: finished keys, interruption, crashes, and the keys that did not run."""

    finished: list[str] = field(default_factory=list)
    interrupted: bool = False
    restarts: int = 0
    unfinished: list[str] = field(default_factory=list)
    lost_reason: str | None = None


def _stderr(msg: str) -> None:
    print(f"rmpc: {msg}", file=sys.stderr, flush=True)


def execute(
    tasks: Sequence[Task],
    executor: CaseExecutor,
    on_result: Callable[[Task, dict[str, Any]], None],
    max_restarts: int = 3,
    notice: Callable[[str], None] = _stderr,
    poll: float = 0.25,
) -> ExecOutcome:
    """Run ``tasks`` on ``executor``; call ``on_result(task, result)`` as each one finishes.

    Parameters
    ----------
    tasks : sequence of Task
        The cases, in submission order.
    executor : CaseExecutor
        Where they run.
    on_result : callable
        Receives the task and the dict returned by :func:`benchmarks.core.runner.run_case`.
    max_restarts : int
        How many times a broken worker pool is replaced before giving up.
    notice : callable
        Receives one-line messages for the user (interrupts, restarts).
    poll : float
        Longest wait (s) between checks of the interrupt flag.

    Returns
    -------
    ExecOutcome
    """
    queue: deque[Task] = deque(tasks)
    inflight: dict[Any, Task] = {}
    outcome = ExecOutcome()
    # two cases per worker keep a pool busy; an executor may ask for fewer (InlineExecutor: one)
    limit = getattr(executor, "in_flight", 2 * max(1, executor.workers))
    current: Task | None = None  # submitted, not yet in flight (an in-process case runs here)
    with Interrupts(notice) as interrupts:
        try:
            while queue or inflight:
                if interrupts.count and not outcome.interrupted:
                    outcome.interrupted = True
                    outcome.unfinished.extend(t.key for t in queue)
                    queue.clear()
                    for fut in list(inflight):
                        if executor.cancel(fut):
                            outcome.unfinished.append(inflight.pop(fut).key)
                while queue and len(inflight) < limit and not interrupts.count:
                    current = queue.popleft()
                    future = executor.submit(run_case, current.payload)
                    if interrupts.interrupted():  # an interrupt reached a case run in this process
                        raise KeyboardInterrupt
                    inflight[future] = current
                    current = None
                if not inflight:
                    break
                lost: list[Task] = []
                for fut in executor.wait_any(set(inflight), poll):
                    task = inflight.pop(fut)
                    try:
                        result = executor.result(fut)
                    except WorkerLost as err:
                        outcome.lost_reason = str(err)
                        lost.append(task)
                        continue
                    on_result(task, result)
                    outcome.finished.append(task.key)
                if lost:
                    # a broken pool fails every case in it: collect them all, then restart once
                    while inflight:
                        for fut in executor.wait_any(set(inflight), poll):
                            task = inflight.pop(fut)
                            try:
                                result = executor.result(fut)
                            except WorkerLost:
                                lost.append(task)
                                continue
                            on_result(task, result)
                            outcome.finished.append(task.key)
                    if interrupts.count or outcome.restarts >= max_restarts or not executor.restart():
                        outcome.unfinished.extend(t.key for t in lost)
                        break
                    outcome.restarts += 1
                    notice(
                        f"{outcome.lost_reason}; restarted the workers; "
                        f"re-running {len(lost)} unfinished cases"
                    )
                    queue.extendleft(reversed(lost))
            if interrupts.count:
                outcome.interrupted = True
        except KeyboardInterrupt:
            interrupts.settle()
            outcome.interrupted = True
            if current is not None:
                outcome.unfinished.append(current.key)
            outcome.unfinished.extend(t.key for t in inflight.values())
            inflight.clear()
            executor.close(abandon=True)
            outcome.unfinished.extend(t.key for t in queue)
            return outcome
    outcome.unfinished.extend(t.key for t in queue)
    outcome.unfinished.extend(t.key for t in inflight.values())
    executor.close()
    return outcome
