"""Running the probes: API calls in forked children with time and memory limits, CLI calls as processes."""

from __future__ import annotations

import multiprocessing as mp
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from dev.robustness.probe import Probe
from dev.robustness.verdicts import Outcome, classify_cli, classify_exception

MEMORY_LIMIT_BYTES = 4 * 2**30
"""Address-space limit of an API probe's child (a size without a bound ends in MemoryError, not swap)."""


def _child(probe: Probe, conn: Any) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, MEMORY_LIMIT_BYTES))
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            assert probe.call is not None
            result = probe.call()
        except BaseException as error:
            verdict = classify_exception(error, probe.names, probe.found)
            detail = f"{type(error).__name__}: {str(error)[:400]}"
        else:
            if probe.expect == "either" and _finite(result):
                verdict, detail = "clear", f"accepted: {_describe(result)}"
            else:
                verdict = "silent"
                warned = "; ".join(sorted({f"{w.category.__name__}: {str(w.message)[:120]}" for w in caught}))
                detail = f"accepted: {_describe(result)}" + (f" (warnings: {warned})" if warned else "")
    conn.send((verdict, detail, time.perf_counter() - start))
    conn.close()


def _finite(result: Any) -> bool:
    try:
        values = np.asarray(result, dtype=float)
    except (TypeError, ValueError):
        return True
    return bool(np.all(np.isfinite(values)))


def _describe(result: Any) -> str:
    text = repr(result)
    return text if len(text) < 160 else text[:157] + "..."


def run_api_probe(probe: Probe, timeout: float) -> Outcome:
    """Run ``probe.call`` in a forked child; a child that does not answer within ``timeout`` s is a hang."""
    context = mp.get_context("fork")
    parent, child = context.Pipe(duplex=False)
    process = context.Process(target=_child, args=(probe, child), daemon=True)
    start = time.perf_counter()
    process.start()
    child.close()
    if parent.poll(timeout):
        try:
            verdict, detail, elapsed = parent.recv()
        except EOFError:
            verdict, detail, elapsed = (
                "crash",
                "the child died without an answer",
                time.perf_counter() - start,
            )
        process.join(5)
    else:
        verdict, detail, elapsed = "hang", f"no answer within {timeout:g} s", timeout
    if process.is_alive():
        process.kill()
        process.join()
    if process.exitcode not in (0, None) and verdict != "hang" and detail.startswith("the child died"):
        detail += f" (exit code {process.exitcode})"
    return Outcome(verdict, detail, float(elapsed))


def rmpc_command() -> list[str]:
    """The command that runs the CLI: the installed ``rmpc`` next to this Python, else ``python -m``."""
    candidate = os.path.join(os.path.dirname(sys.executable), "rmpc")
    if os.path.exists(candidate):
        return [candidate]
    return [sys.executable, "-c", "import sys; from benchmarks.cli import main; sys.exit(main())"]


def run_cli_probe(probe: Probe, timeout: float) -> Outcome:
    """Run ``rmpc <probe.argv>`` in a scratch folder prepared by ``probe.setup``."""
    scratch = tempfile.mkdtemp(prefix="rmpc-probe-")
    try:
        if probe.setup is not None:
            probe.setup(scratch)
        argv = [arg.replace("{tmp}", scratch) for arg in probe.argv]
        env = dict(os.environ, OMP_NUM_THREADS="1", NO_COLOR="1")
        start = time.perf_counter()
        returncode, stderr = _run_in_own_group(rmpc_command() + argv, scratch, env, timeout)
        elapsed = time.perf_counter() - start
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    verdict = classify_cli(returncode, stderr, probe.names)
    if probe.expect == "either" and verdict == "silent":
        verdict = "clear"  # an edge input accepted, as it may be
    tail = stderr.strip().splitlines()[-3:] if stderr.strip() else []
    detail = (
        f"exit {returncode}: " + " | ".join(tail)[:400]
        if returncode is not None
        else (f"no answer within {timeout:g} s")
    )
    return Outcome(verdict, detail, elapsed if returncode is not None else timeout)


def _run_in_own_group(
    command: list[str], cwd: str, env: dict[str, str], timeout: float
) -> tuple[int | None, str]:
    """Run ``command`` in a new process group; on timeout kill the whole group (workers it started too).

    Returns the exit status (None after a timeout) and the standard error.
    """
    process = subprocess.Popen(
        command,
        cwd=cwd,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=_limit_memory,
    )
    try:
        _, stderr = process.communicate(timeout=timeout)
        returncode: int | None = process.returncode
    except subprocess.TimeoutExpired:
        returncode = None
        stderr = ""
    finally:
        try:
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    if returncode is None:
        try:
            _, stderr = process.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            stderr = ""
    return returncode, stderr or ""


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, MEMORY_LIMIT_BYTES))


def preload() -> None:
    """Import the toolkit once in the parent, so that each forked child starts with it loaded."""
    import clarabel  # noqa: F401
    import cvxpy  # noqa: F401

    import benchmarks.cli  # noqa: F401
    import lmi  # noqa: F401
    import models  # noqa: F401
    import rmpc  # noqa: F401


def run_probes(
    probes: Iterable[Probe], timeout: float, report: Callable[[Probe, Outcome], None] | None = None
) -> list[tuple[Probe, Outcome]]:
    """Run every probe in order; ``report(probe, outcome)`` is called after each one."""
    preload()
    results = []
    for probe in probes:
        own = getattr(probe, "run", None)  # a probe that drives its command itself (interrupts)
        if callable(own):
            outcome = own(timeout)
        elif probe.group == "api":
            outcome = run_api_probe(probe, timeout)
        else:
            outcome = run_cli_probe(probe, timeout)
        results.append((probe, outcome))
        if report is not None:
            report(probe, outcome)
    return results
