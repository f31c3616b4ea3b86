"""Ctrl-C inside a solver is an interrupt, never a failed solve: a ``KeyboardInterrupt`` wrapped by
compiled code (Clarabel's bindings, a numba dispatcher) in lmi's Clarabel back-end and the forms,
SCS's own SIGINT handler, and ``rmpc bench methods`` says "interrupted" once."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import clarabel
import numpy as np
import pytest

from benchmarks.cli import main
from benchmarks.suites import methods as suite
from models import PolytopicModel
from rmpc import RMPC

ROOT = Path(__file__).resolve().parent.parent
_PLANT = PolytopicModel([(np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]]))], dt=0.1)


def _wrapped_interrupt() -> SystemError:
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as interrupt:
            raise SystemError("returned a result with an exception set") from interrupt
    except SystemError as err:
        return err


class _InterruptedSolver:
    """Stands for ``clarabel.DefaultSolver``: its construction raises a wrapped interrupt."""

    def __init__(self, *args, **kwargs):
        raise _wrapped_interrupt()


@pytest.mark.parametrize("form", [{}, {"lyapunov": "vertex"}])
def test_a_wrapped_interrupt_in_a_clarabel_solve_is_raised_as_keyboard_interrupt(monkeypatch, form):
    ctrl = RMPC(_PLANT, np.eye(2), np.eye(1), u_max=[1.0], input_constraint="peak", backend="clarabel",
                **form)
    monkeypatch.setattr(clarabel, "DefaultSolver", _InterruptedSolver)  # the bindings both paths call
    with pytest.raises(KeyboardInterrupt) as info:
        ctrl.solve(np.array([0.5, 0.0]))
    assert isinstance(info.value.__cause__, SystemError)


def test_a_wrapped_interrupt_in_a_forms_cvxpy_solve_is_raised_as_keyboard_interrupt(monkeypatch):
    import cvxpy

    ctrl = RMPC(_PLANT, np.eye(2), np.eye(1), u_max=[1.0], input_constraint="peak", backend="cvxpy",
                lyapunov="vertex")

    def interrupted(self, *args, **kwargs):
        raise _wrapped_interrupt()

    monkeypatch.setattr(cvxpy.Problem, "solve", interrupted)
    with pytest.raises(KeyboardInterrupt):
        ctrl.solve(np.array([0.5, 0.0]))


def test_a_solver_error_that_is_not_an_interrupt_is_still_a_status(monkeypatch):
    ctrl = RMPC(_PLANT, np.eye(2), np.eye(1), u_max=[1.0], input_constraint="peak", backend="clarabel")

    def panicking(*args, **kwargs):
        raise SystemError("a panic of the solver")

    monkeypatch.setattr(clarabel, "DefaultSolver", panicking)
    assert ctrl.solve(np.array([0.5, 0.0])).status == "solver_error"


_SCS_DRIVER = textwrap.dedent("""
    import os, signal, sys, threading, time
    import numpy as np
    from models import RigidSatellite
    from rmpc import RMPC

    if sys.argv[1] == "ignore":
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # as in a benchmark worker process
    else:  # Python's own handler, whatever the parent left (a shell's background job ignores SIGINT)
        signal.signal(signal.SIGINT, signal.default_int_handler)
    x0 = np.array([0.3, -0.2, 0.25, 0.0, 0.0, 0.0])
    poly = RigidSatellite.paper_p().polytope(x0, 0.05, 0.3, "box")
    ctrl = RMPC(poly, np.eye(6), np.eye(3), u_max=1.0, backend="cvxpy", solver="SCS",
                solver_options={"eps_abs": 1e-12, "eps_rel": 1e-12, "max_iters": int(sys.argv[2])})
    if sys.argv[1] == "ignore":
        ctrl.solve(x0)  # cvxpy compiles the problem here: the SIGINT below lands in SCS
    threading.Timer(float(sys.argv[3]), lambda: os.kill(os.getpid(), signal.SIGINT)).start()
    start = time.perf_counter()
    try:
        solution = ctrl.solve(0.9 * x0)
    except KeyboardInterrupt:
        print(f"KeyboardInterrupt after {time.perf_counter() - start:.2f} s")
    else:
        print(f"status {solution.status} after {time.perf_counter() - start:.2f} s")
""")


def _scs(mode: str, max_iters: int, delay: float) -> str:
    done = subprocess.run([sys.executable, "-c", _SCS_DRIVER, mode, str(max_iters), str(delay)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_ctrl_c_during_an_scs_solve_raises_keyboard_interrupt():
    """SCS catches SIGINT while it solves; before the fix the solve ended 'solver_error' and the
    controller applied its fallback input, as if Ctrl-C had not been pressed."""
    out = _scs("default", 10_000_000, 2.0)
    line = out.strip().splitlines()[-1]
    assert "interrupted" in out and line.startswith("KeyboardInterrupt"), out  # SCS caught it, Python got it
    assert float(line.split()[-2]) < 10.0, line  # at once, not after the 10 million iterations


def test_an_scs_solve_interrupted_in_a_process_that_ignores_sigint_is_run_again():
    out = _scs("ignore", 4_000, 0.3)
    line = out.strip().splitlines()[-1]
    # SCS caught the SIGINT (it prints "interrupted"); ignored by the process, the solve ran again
    assert "interrupted" in out and line.startswith("status") and "solver_error" not in line, out


def test_bench_methods_says_interrupted_once(tmp_path, monkeypatch, capsys):
    real = suite.evaluate
    calls: list[str] = []

    def patched(problem, method, settings):
        calls.append(method)
        if len(calls) == 2:
            raise _wrapped_interrupt()
        return real(problem, method, settings)

    monkeypatch.setattr(suite, "evaluate", patched)
    status = main(["bench", "methods", "--short", "--problems", "kothare_ex1", "--methods",
                   "kothare,nominal,vertex", "--out", str(tmp_path), "--no-progress"])
    err = capsys.readouterr().err
    assert status == 130
    lines = [line for line in err.splitlines() if "interrupted" in line]
    assert lines == ["rmpc: interrupted; 2 cases not run; re-run the same command to resume"], err


_OFFLINE_SCS_DRIVER = textwrap.dedent("""
    import os, signal, threading, time
    import numpy as np
    from models import RigidSatellite
    from rmpc import OfflineRMPC

    signal.signal(signal.SIGINT, signal.default_int_handler)  # whatever the parent left
    x0 = np.array([0.3, -0.2, 0.25, 0.0, 0.0, 0.0])
    poly = RigidSatellite.paper_p().polytope(x0, 0.05, 0.3, "box")
    threading.Timer(4.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
    start = time.perf_counter()
    try:
        ctrl = OfflineRMPC(poly, np.eye(6), np.eye(3), u_max=1.0, backend="cvxpy", solver="SCS",
                           n_ellipsoids=3, x_design=x0,
                           solver_options={"eps_abs": 1e-12, "eps_rel": 1e-12, "max_iters": 10_000_000})
        ctrl.step(x0)
    except KeyboardInterrupt:
        print(f"KeyboardInterrupt after {time.perf_counter() - start:.2f} s")
    else:
        print(f"returned after {time.perf_counter() - start:.2f} s")
""")


def test_ctrl_c_during_an_offline_design_with_scs_raises_keyboard_interrupt():
    """The off-line table's nested problems call cvxpy themselves (lmi.offline); before the fix an
    interrupted SCS solve ended the design as a failed solve and the controller was built anyway."""
    done = subprocess.run([sys.executable, "-c", _OFFLINE_SCS_DRIVER], cwd=ROOT, capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    last = done.stdout.strip().splitlines()[-1]
    assert "interrupted" in done.stdout and last.startswith("KeyboardInterrupt"), done.stdout
