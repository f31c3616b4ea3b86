"""Interrupts (Ctrl-C, SIGINT) stop every runner at once, keep the finished cases and exit 130.

A SIGINT that lands in a numba kernel released from the GIL comes back as ``SystemError:
CPUDispatcher(...) returned a result with an exception set`` (the interrupt is its cause); one
that lands in a finaliser is swallowed; OSQP catches SIGINT itself while it solves. None of
them may be recorded as a failed case, nor let the run go on.
"""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from benchmarks.cli import main
from benchmarks.core import runner
from benchmarks.core.interrupts import is_interrupt
from benchmarks.core.store import STORE_NAME
from benchmarks.suites import methods as suite
from benchmarks.suites.methods import run_methods

ROOT = Path(__file__).resolve().parent.parent

#: Two LQR cases of 0.3 s on the linear satellite, run in this process by the sweep tests.
_TWO_CASES = """
name = "two"
[base]
controller = "LQR"
saturation = "limiter"
plant = "linear"
duration = 0.3
[grid]
u_max = [0.5, 1.0]
"""


def _wrapped_interrupt() -> SystemError:
    """What numba's dispatcher raises when SIGINT lands in a kernel that released the GIL."""
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as interrupt:
            message = "CPUDispatcher(<function k>) returned a result with an exception set"
            raise SystemError(message) from interrupt
    except SystemError as err:
        return err


def test_is_interrupt_follows_the_cause_and_the_context():
    assert is_interrupt(KeyboardInterrupt())
    assert is_interrupt(_wrapped_interrupt())
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise ValueError("raised while handling it")  # noqa: B904 - the context is the point
    except ValueError as err:
        assert is_interrupt(err)
    assert not is_interrupt(SystemError("a real one")) and not is_interrupt(None)


# -- the methods suite (cases in this process) ----------------------------------------------------

_ARGS = dict(short=True, problems=["kothare_ex1"], methods=["kothare", "nominal", "vertex"], progress=False)


def _first_real_then(monkeypatch, second):
    """Patch the suite: its first case is measured, the second is ``second`` (which gets the first
    case's result as ``first``), the others are measured."""
    real = suite.evaluate
    calls: list[str] = []
    first: list = []

    def patched(problem, method, settings):
        calls.append(method)
        if len(calls) == 2:
            return second(problem, method, settings, first[0])
        first.append(real(problem, method, settings))
        return first[-1]

    monkeypatch.setattr(suite, "evaluate", patched)
    return calls


def _assert_stopped_after_first(tmp_path, outcome, calls):
    assert outcome.execution.interrupted
    assert outcome.failures == []  # the interrupted case is not a failure
    assert calls == ["kothare", "nominal"]  # nothing ran after it
    assert outcome.execution.unfinished == ["kothare_ex1__nominal", "kothare_ex1__vertex"]
    assert sorted(p.name for p in (tmp_path / "cases").glob("*.json")) == ["kothare_ex1__kothare.json"]
    assert json.loads((tmp_path / "run.json").read_text())["failures"] == []


def test_methods_an_interrupt_wrapped_by_compiled_code_stops_the_run(tmp_path, monkeypatch):
    def wrapped(problem, method, settings, first):
        raise _wrapped_interrupt()

    calls = _first_real_then(monkeypatch, wrapped)
    outcome = run_methods(tmp_path, **_ARGS)
    _assert_stopped_after_first(tmp_path, outcome, calls)


def test_methods_an_interrupt_swallowed_inside_a_case_stops_it_at_once(tmp_path, monkeypatch):
    spent: list[float] = []

    def swallowing(problem, method, settings, first):
        start = time.perf_counter()
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)
        except KeyboardInterrupt:
            pass  # a finaliser or a library's broad except: the case goes on
        try:
            for _ in range(100):  # 10 s of "solving" unless the interrupt comes back
                time.sleep(0.1)
            return first
        finally:
            spent.append(time.perf_counter() - start)

    calls = _first_real_then(monkeypatch, swallowing)
    outcome = run_methods(tmp_path, **_ARGS)
    _assert_stopped_after_first(tmp_path, outcome, calls)
    assert spent[0] < 4.0, spent  # raised again within a second, not 10 s later


def test_methods_a_case_that_returns_after_an_interrupt_is_not_kept(tmp_path, monkeypatch):
    def returns_anyway(problem, method, settings, first):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)
        except KeyboardInterrupt:
            pass
        rec, extra = first
        return {**rec, "method": method}, extra  # at once, before the interrupt is raised again

    calls = _first_real_then(monkeypatch, returns_anyway)
    outcome = run_methods(tmp_path, **_ARGS)
    _assert_stopped_after_first(tmp_path, outcome, calls)


# -- sweeps run in this process (--workers 0) -----------------------------------------------------


def _sweep(tmp_path: Path, monkeypatch, second) -> tuple[int, list[tuple]]:
    config = tmp_path / "sweep.toml"
    config.write_text(_TWO_CASES, encoding="utf-8")
    original = runner.simulate_scenario
    calls: list[float] = []

    def patched(scenario, *args, **kwargs):
        calls.append(scenario.u_max)
        if len(calls) == 1:
            return second(original, scenario, *args, **kwargs)
        return original(scenario, *args, **kwargs)

    monkeypatch.setattr(runner, "simulate_scenario", patched)
    out = tmp_path / "out"
    code = main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0",
                 "--no-progress"])
    with sqlite3.connect(out / STORE_NAME) as db:
        rows = list(db.execute("SELECT case_id, status FROM cases"))
    return code, rows, calls


def test_sweep_in_process_a_wrapped_interrupt_is_not_stored_as_an_error(tmp_path, monkeypatch, capsys):
    def wrapped(original, scenario, *args, **kwargs):
        raise _wrapped_interrupt()

    code, rows, calls = _sweep(tmp_path, monkeypatch, wrapped)
    assert code == 130, capsys.readouterr().err
    assert rows == [] and len(calls) == 1  # not stored as failed, and the next case did not start
    assert "interrupted" in capsys.readouterr().err


def test_sweep_in_process_the_first_interrupt_lets_the_running_case_finish_and_no_other(
    tmp_path, monkeypatch, capsys
):
    def interrupted_once(original, scenario, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C once: this case finishes and is stored
        time.sleep(0.2)
        return original(scenario, *args, **kwargs)

    code, rows, calls = _sweep(tmp_path, monkeypatch, interrupted_once)
    assert code == 130, capsys.readouterr().err
    assert [status for _, status in rows] == ["done"] and len(calls) == 1


# -- OSQP catches SIGINT itself while it solves ----------------------------------------------------


def _slow_qp():
    from rmpc.qp import QP

    rng = np.random.default_rng(0)
    n = 400
    m = rng.standard_normal((n, n))
    return QP(H=m @ m.T + 1e-6 * np.eye(n), g=rng.standard_normal(n), C=rng.standard_normal((n, n)),
              l=-np.ones(n), u=np.ones(n))


def _osqp_solve_with_sigint(handler) -> object:
    """Solve a QP that takes seconds with OSQP and send SIGINT 0.3 s into the solve."""
    import threading

    from rmpc.qp import OSQPBackend

    backend = OSQPBackend(eps_abs=1e-12, eps_rel=1e-12, max_iter=10**7, time_limit=2.0, polishing=False)
    backend.setup(_slow_qp())
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    previous = signal.signal(signal.SIGINT, handler)
    try:
        timer.start()
        return backend.solve()
    finally:
        timer.join()
        signal.signal(signal.SIGINT, previous)


def test_osqp_hands_a_sigint_it_caught_to_python():
    with pytest.raises(KeyboardInterrupt):
        _osqp_solve_with_sigint(signal.default_int_handler)


def test_osqp_solves_again_when_the_process_ignores_sigint():
    result = _osqp_solve_with_sigint(signal.SIG_IGN)
    assert result.status != "interrupted", result.status  # a worker process ignores SIGINT


# -- a real SIGINT to the command ------------------------------------------------------------------


def _start(argv: list[str], out: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(
        argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # as a foreground job
    )


def _interrupt_after_first_case(proc: subprocess.Popen, out: Path, delay: float) -> list[str]:
    deadline = time.monotonic() + 240
    while not list((out / "cases").glob("*.json")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no case finished"
        time.sleep(0.02)
    time.sleep(delay)
    before = sorted(p.name for p in (out / "cases").glob("*.json"))
    proc.send_signal(signal.SIGINT)
    return before


def _assert_interrupted(proc: subprocess.Popen, out: Path, before: list[str]) -> None:
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "failed:" not in stderr, stderr
    assert "rmpc: interrupted" in stderr
    assert sorted(p.name for p in (out / "cases").glob("*.json")) == before  # kept, none added
    assert json.loads((out / "run.json").read_text())["failures"] == []


def test_sigint_in_a_numba_kernel_stops_bench_methods(tmp_path):
    """The second case spins in a numba kernel that releases the GIL, where a SIGINT becomes a
    ``SystemError`` whose cause is the interrupt (before the fix: "failed: ...: SystemError", exit 1)."""
    driver = textwrap.dedent("""
        import sys
        import numpy as np
        from numba import njit
        from benchmarks.cli import main
        from benchmarks.suites import methods

        @njit(nogil=True)
        def spin(a, n):
            s = 0.0
            for i in range(n):
                s += np.sqrt(i * 1.0)
            a[0] = s
            return 1, a, s

        spin(np.zeros(1), 10)  # compiled now, not when the signal comes
        real, calls = methods.evaluate, []

        def evaluate(problem, method, settings):
            calls.append(method)
            if len(calls) == 2:
                a = np.zeros(1)
                while True:
                    spin(a, 200_000)
            return real(problem, method, settings)

        methods.evaluate = evaluate
        sys.exit(main(sys.argv[1:]))
    """)
    out = tmp_path / "out"
    proc = _start([sys.executable, "-c", driver, "bench", "methods", "--short", "--out", str(out),
                   "--problems", "kothare_ex1", "--methods", "kothare,nominal,vertex", "--no-progress"], out)
    before = _interrupt_after_first_case(proc, out, 1.0)
    assert before == ["kothare_ex1__kothare.json"]
    _assert_interrupted(proc, out, before)


def test_sigint_stops_rmpc_bench_methods(tmp_path):
    out = tmp_path / "out"
    rmpc = [sys.executable, "-c", "import sys; from benchmarks.cli import main; sys.exit(main())"]
    argv = ["bench", "methods", "--short", "--out", str(out), "--problems", "kothare_ex1",
            "--methods", "kothare,disturbance,soft", "--no-progress"]
    proc = _start([*rmpc, *argv], out)
    before = _interrupt_after_first_case(proc, out, 2.0)  # in the disturbance case (about 9 s)
    _assert_interrupted(proc, out, before)


def test_in_process_each_result_is_taken_before_the_next_case_runs(monkeypatch):
    """``--workers 0``: a case's result reaches ``on_result`` (and so the store) before the next case
    starts; with two cases submitted at once, an interrupt during the second would lose the first."""
    from benchmarks.core import execute as execute_module
    from benchmarks.core.executors import InlineExecutor

    log: list[str] = []

    def fake_run_case(payload):
        log.append(f"run {payload['key']}")
        return {"ok": True}

    monkeypatch.setattr(execute_module, "run_case", fake_run_case)
    tasks = [execute_module.Task(k, {"key": k}) for k in ("a", "b", "c")]
    outcome = execute_module.execute(
        tasks, InlineExecutor(), lambda task, _: log.append(f"stored {task.key}"), notice=lambda _: None)
    assert outcome.finished == ["a", "b", "c"]
    assert log == ["run a", "stored a", "run b", "stored b", "run c", "stored c"]
