"""Interrupts: SIGINT sent to a running ``rmpc bench methods`` or ``rmpc bench sweep`` at chosen moments.

Each probe starts the command in a scratch folder (in a process group of its own, as a shell
starts a job), waits until the run has written its first finished case (a file in
``out/cases/`` or the sweep store), waits ``delay`` seconds more and sends SIGINT: to the
command's process, or to its whole process group as Ctrl-C in a terminal does (then the worker
processes receive it too). The delays put the signal into the compiled code of the LMI solver
(numba kernels), of the QP solvers (OSQP, which catches SIGINT itself while it solves) and into
the toolkit's Python code.

A good answer (``clear``): exit status 130, no traceback, a message on standard error that says
``interrupted``, every case file that existed when the signal was sent still there, and no case
reported or stored as failed. ``silent``: the run ignored the interrupt and exited 0. ``crash``:
any other exit status, a traceback, a case reported or stored as failed, a finished case lost.
``hang``: no exit within the time limit. ``unclear``: exit 130 without a message saying so, or
the run ended before the signal could be sent (the probe then tested nothing).

:func:`interrupt_probes` is the catalogue; :meth:`InterruptProbe.run` runs one (the probe
runner calls a probe's own ``run`` when it has one).
"""

from __future__ import annotations

import glob
import json
import os
import resource
import shutil
import signal
import sqlite3
import subprocess
import tempfile
import time
from dataclasses import dataclass

from dev.robustness.probe import Probe
from dev.robustness.runner import MEMORY_LIMIT_BYTES, rmpc_command
from dev.robustness.verdicts import Outcome

__all__ = ["InterruptProbe", "interrupt_probes"]

METHODS_ARGV = (
    "bench",
    "methods",
    "--short",
    "--out",
    "{tmp}/out",
    "--no-progress",
    "--problems",
    "kothare_ex1",
    "--methods",
    "kothare,disturbance,soft",
)
"""A methods run of about 12 s: one short case, then ``disturbance`` (about 9 s in the numba
kernels and cvxpy), then ``soft``."""

OSQP_SWEEP = """name = "interrupt_osqp"
[base]
controller = "GIPC"
plant = "nonlinear"
saturation = "constraint"
duration = 0.3
settings = {backend = "osqp", Nc = 40}
[montecarlo]
n = 6
seed = 1
"""
"""Six GIPC cases of 30 steps, about 2 s each at a light load, nine tenths of it in OSQP's solves
(a control horizon of 40 moves); OSQP takes SIGINT itself while it solves."""


def _sweep_argv(workers: int) -> tuple[str, ...]:
    return (
        "bench", "sweep", "--config", "{tmp}/sweep.toml", "--out", "{tmp}/out",
        "--workers", str(workers), "--no-progress",
    )


def _stored_cases(tmp: str) -> dict[str, str]:
    """The finished cases in the scratch folder: case id -> status (files of methods, rows of a store).

    A stored sweep case with a solve whose status is ``"interrupted"`` (OSQP took the signal and
    the controller went on with a fallback) has the status ``"interrupted solve"``: an interrupted
    case stored as a result.
    """
    found = {os.path.basename(p)[:-5]: "done" for p in glob.glob(os.path.join(tmp, "out", "cases", "*.json"))}
    store = os.path.join(tmp, "out", "sweep.sqlite")
    if os.path.isfile(store):
        try:
            with sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=1.0) as db:
                rows = list(db.execute("SELECT case_id, status, record FROM cases"))
        except sqlite3.Error:
            rows = []  # not created yet, or locked for a moment: read again on the next poll
        for cid, status, record in rows:
            try:
                metrics = json.loads(record).get("metrics", {}) if record else {}
            except (ValueError, AttributeError):
                metrics = {}
            counts = metrics.get("status_counts") if isinstance(metrics, dict) else None
            hit = isinstance(counts, dict) and bool(counts.get("interrupted"))
            found[cid] = "interrupted solve" if status == "done" and hit else status
    return found


def _write_sweep(tmp: str, text: str) -> None:
    with open(os.path.join(tmp, "sweep.toml"), "w", encoding="utf-8") as handle:
        handle.write(text)


def _prepare_child() -> None:
    """The command's memory limit, and SIGINT handled as in a terminal's foreground job (a shell
    starts background jobs with SIGINT ignored, and an ignored signal stays ignored in children)."""
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, MEMORY_LIMIT_BYTES))
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@dataclass(frozen=True)
class InterruptProbe(Probe):
    """A probe that sends SIGINT into a running command.

    Attributes
    ----------
    delay : float
        Seconds after the first finished case (``-1``: after the command started, before any
        case) at which SIGINT is sent.
    to_group : bool
        Send it to the command's process group (Ctrl-C in a terminal), not only to its process.
    sweep : str
        The sweep file written to ``{tmp}/sweep.toml`` (sweep probes).
    running : int
        How many cases may still finish after the signal (those running then: none for the
        methods suite, which drops the case it interrupts; one for a sweep run in-process;
        the cases in flight on workers).
    """

    delay: float = 0.0
    to_group: bool = False
    sweep: str = ""
    running: int = 0

    def run(self, timeout: float) -> Outcome:
        """Run the command, interrupt it, and classify what it did."""
        scratch = tempfile.mkdtemp(prefix="rmpc-interrupt-")
        try:
            if self.sweep:
                _write_sweep(scratch, self.sweep)
            argv = [arg.replace("{tmp}", scratch) for arg in self.argv]
            env = dict(os.environ, OMP_NUM_THREADS="1", NO_COLOR="1", PYTHONUNBUFFERED="1")
            start = time.perf_counter()
            process = subprocess.Popen(
                rmpc_command() + argv, cwd=scratch, env=env, stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE, text=True, start_new_session=True, preexec_fn=_prepare_child,
            )
            try:
                sent, before = self._interrupt(process, scratch, start, timeout)
                left = max(1.0, timeout - (time.perf_counter() - start))
                try:
                    _, stderr = process.communicate(timeout=left)
                    returncode: int | None = process.returncode
                except subprocess.TimeoutExpired:
                    returncode, stderr = None, ""
            finally:
                try:
                    os.killpg(process.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                process.wait()
            elapsed = time.perf_counter() - start
            after = _stored_cases(scratch)
            failed_files = self._failed_in_results(scratch)
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
        verdict, why = _classify(returncode, stderr or "", sent, before, after, failed_files, self.running)
        tail = (stderr or "").strip().splitlines()[-3:]
        detail = f"{why}; exit {returncode}: " + " | ".join(tail)[:400]
        return Outcome(verdict, detail, elapsed if returncode is not None else timeout)

    def _interrupt(
        self, process: subprocess.Popen, scratch: str, start: float, timeout: float
    ) -> tuple[bool, dict[str, str]]:
        """Wait for the moment, send SIGINT; return whether it was sent and the cases stored then."""
        while self.delay >= 0 and not _stored_cases(scratch):
            if process.poll() is not None or time.perf_counter() - start > timeout:
                return False, {}
            time.sleep(0.02)
        time.sleep(abs(self.delay))
        if process.poll() is not None:
            return False, {}
        before = _stored_cases(scratch)
        if self.to_group:
            os.killpg(process.pid, signal.SIGINT)
        else:
            process.send_signal(signal.SIGINT)
        return True, before

    @staticmethod
    def _failed_in_results(scratch: str) -> list[str]:
        """Cases the run's ``run.json`` lists as failed (the methods suite)."""
        try:
            with open(os.path.join(scratch, "out", "run.json"), encoding="utf-8") as handle:
                info = json.load(handle)
        except (OSError, ValueError):
            return []
        failures = info.get("failures", []) if isinstance(info, dict) else []
        return [str(f.get("key")) for f in failures if isinstance(f, dict)]


def _classify(
    returncode: int | None,
    stderr: str,
    sent: bool,
    before: dict[str, str],
    after: dict[str, str],
    failed_files: list[str],
    running: int,
) -> tuple[str, str]:
    if returncode is None:
        return "hang", "no exit after the interrupt"
    if not sent:
        return "unclear", "the run ended before the signal was sent (nothing tested)"
    lost = sorted(set(before) - set(after))
    errors = sorted(cid for cid, status in after.items() if status != "done")
    failed = [line.strip() for line in stderr.splitlines() if line.strip().startswith("failed:")]
    if "Traceback (most recent call last)" in stderr:
        return "crash", "a traceback"
    if lost:
        return "crash", f"finished cases lost: {', '.join(lost)}"
    if failed or errors or failed_files:
        first = (failed or errors or failed_files)[0]
        return "crash", f"a case recorded as failed or with an interrupted solve: {first}"
    if len(after) - len(before) > running:
        return "crash", f"{len(after) - len(before)} cases finished after the signal; {running} were running"
    if returncode == 0:
        return "silent", "the interrupt was ignored; the run completed"
    if returncode != 130:
        return "crash", f"exit status {returncode}, not 130"
    if "interrupted" not in stderr.lower():
        return "unclear", "exit 130 without a message saying so"
    return "clear", f"{len(before)} cases finished before the signal, {len(after)} kept"


def _methods(delay: float, to_group: bool = False) -> InterruptProbe:
    where = "group" if to_group else "process"
    moment = f"{-delay:g} s after the start" if delay < 0 else f"{delay:g} s after the first case"
    return InterruptProbe(
        f"cli:interrupt methods, SIGINT to the {where} {moment}",
        "cli",
        ("interrupted",),
        argv=METHODS_ARGV,
        kind="interrupt",
        delay=delay,
        to_group=to_group,
    )


def _sweep(workers: int, delay: float, to_group: bool) -> InterruptProbe:
    where = "group" if to_group else "process"
    return InterruptProbe(
        f"cli:interrupt sweep (OSQP, --workers {workers}), SIGINT to the {where} "
        f"{delay:g} s after the first case",
        "cli",
        ("interrupted",),
        argv=_sweep_argv(workers),
        kind="interrupt",
        delay=delay,
        to_group=to_group,
        sweep=OSQP_SWEEP,
        running=max(1, 2 * workers),  # at most two cases per worker are in flight
    )


def interrupt_probes() -> list[Probe]:
    """Every interrupt probe: the methods suite in-process, sweeps in-process and on workers."""
    probes: list[Probe] = [_methods(-2.0)]
    probes += [_methods(delay) for delay in (0.0, 0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5)]
    probes += [_methods(delay, to_group=True) for delay in (1.0, 4.0)]
    probes += [_sweep(0, delay, to_group=False) for delay in (0.5, 1.5, 2.5)]
    probes += [_sweep(2, delay, to_group=True) for delay in (0.5, 2.0)]
    return probes
