"""The rest of round two: sweep reachability, interrupts in solvers, form solver options, stale
staging folders, NumPy integers.

- Sweep files (``cli:reach ...``): each controller option a scenario builds is reachable with a
  good value (the tiny sweep must run: ``either`` with names no refusal contains) and refused with
  a bad one, the message naming the key path, before any case runs; keywords a sweep cannot set
  are refused saying why.
- Interrupts (``interrupt ...``): Ctrl-C inside SCS (which catches SIGINT itself while it solves),
  an interrupt wrapped by compiled code in lmi's Clarabel back-end and in the forms, and
  ``rmpc bench methods`` saying "interrupted" once. Each runs a script in a process of its own
  (:class:`ScriptProbe`) or sends SIGINT into a running sweep
  (:class:`dev.robustness.interrupt_cases.InterruptProbe`).
- A form's ``solver_options = {max_iter = 0}`` (API and sweep): refused as Kothare's is.
- A hidden ``.staging-*`` folder a killed run left in ``--out`` (:class:`ScriptProbe`): removed by
  the next run, which says so; refused by ``benchmarks.compare`` as a run.
- NumPy integers (``np.int64(10)``) where Python's ``10`` is accepted: accepted.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from dev.robustness.interrupt_cases import InterruptProbe
from dev.robustness.probe import Expect, Probe
from dev.robustness.runner import rmpc_command
from dev.robustness.sweep_cases import FORM_SWEEP, SWEEP_ARGV
from dev.robustness.verdicts import VERDICTS, Outcome

__all__ = ["ScriptProbe", "close_probes"]

_MUST_RUN = ("(a good value: the sweep must run)",)
"""Names no refusal contains: a refusal of a good value is not ``clear``, only a run that exits 0 is."""
_MUST_ACCEPT = ("(a NumPy integer is an integer)",)
"""The same for an API call that must accept its input."""
_ROLL = "[[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]]"
"""An output matrix that bounds the roll angle of the 6-state satellite."""
_SCS_LOOSE = 'backend = "cvxpy"\nsolver = "SCS"\nsolver_options = {eps_abs = 1e-5, eps_rel = 1e-5}'

#: (label, controller, settings lines, names a clear refusal contains, expect, family)
_REACH: tuple[tuple[str, str, str, tuple[str, ...], Expect, str], ...] = (
    ("RMPC solver SCS", "RMPC", _SCS_LOOSE, _MUST_RUN, "either", "rigid"),
    ("RMPC solver with the ipm", "RMPC", 'solver = "SCS"', ("settings.solver: expected",), "error", "rigid"),
    ("RMPC solver number", "RMPC", "solver = 5", ("settings.solver: expected",), "error", "rigid"),
    ("RMPC output bound", "RMPC", f"output_matrix = {_ROLL}\ny_max = 1.0", _MUST_RUN, "either", "rigid"),
    (
        "RMPC output bound soft y",
        "RMPC",
        f"output_matrix = {_ROLL}\ny_max = 1.0\nsoft = {{y = 10.0}}",
        _MUST_RUN,
        "either",
        "rigid",
    ),
    (
        "RMPC output_matrix alone",
        "RMPC",
        f"output_matrix = {_ROLL}",
        ("settings.output_matrix: expected",),
        "error",
        "rigid",
    ),
    (
        "RMPC output_matrix shape",
        "RMPC",
        "output_matrix = [[1.0, 0.0]]\ny_max = 1.0",
        ("settings.output_matrix: expected",),
        "error",
        "rigid",
    ),
    (
        "RMPC y_max negative",
        "RMPC",
        f"output_matrix = {_ROLL}\ny_max = -1.0",
        ("settings.y_max: expected",),
        "error",
        "rigid",
    ),
    (
        "RMPC output bound wheel",
        "RMPC",
        f"output_matrix = {_ROLL}\ny_max = 1.0",
        _MUST_RUN,
        "either",
        "wheel",
    ),
    (
        "RMPC output_matrix flexible",
        "RMPC",
        f"output_matrix = {_ROLL}\ny_max = 1.0",
        ("modal_bound",),
        "error",
        "flexible",
    ),
    (
        "RMPC x_ref",
        "RMPC",
        "x_ref = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
        ("settings.x_ref: expected no x_ref",),
        "error",
        "rigid",
    ),
    ("RMPC backend proxqp", "RMPC", 'backend = "proxqp"', ("settings.backend: expected",), "error", "rigid"),
    (
        "RMPC form max_iter 0",
        "RMPC",
        'lyapunov = "vertex"\nsolver_options = {max_iter = 0}',
        ("settings.solver_options.max_iter: expected an integer >= 1",),
        "error",
        "rigid",
    ),
    (
        "OfflineRMPC path trajectory",
        "OfflineRMPC",
        'path = "trajectory"\nn_ellipsoids = 3',
        _MUST_RUN,
        "either",
        "rigid",
    ),
    (
        "OfflineRMPC path file",
        "OfflineRMPC",
        'path = "design.txt"',
        ("settings.path: expected one of",),
        "error",
        "rigid",
    ),
    (
        "OfflineRMPC solver SCS with the ipm",
        "OfflineRMPC",
        'solver = "SCS"',
        ("settings.solver: expected",),
        "error",
        "rigid",
    ),
    (
        "OfflineRMPC x_design",
        "OfflineRMPC",
        "x_design = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0]",
        ("settings.x_design: expected no x_design",),
        "error",
        "rigid",
    ),
    (
        "CRMPC rmpc_options",
        "CRMPC",
        'rmpc_options = {hold_radius = 1e-6, lyapunov = "vertex"}',
        _MUST_RUN,
        "either",
        "rigid",
    ),
    ("CRMPC rmpc_options soft", "CRMPC", "rmpc_options = {soft = {u = 100.0}}", _MUST_RUN, "either", "mrp"),
    (
        "CRMPC rmpc_options x_ref",
        "CRMPC",
        "rmpc_options = {x_ref = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]}",
        ("settings.rmpc_options.x_ref",),
        "error",
        "rigid",
    ),
    (
        "CRMPC rmpc_options own key",
        "CRMPC",
        "rmpc_options = {resolve_threshold = 0.5}",
        ("settings.rmpc_options.resolve_threshold",),
        "error",
        "rigid",
    ),
    (
        "CRMPC rmpc_options soft negative",
        "CRMPC",
        "rmpc_options = {soft = {u = -1.0}}",
        ("settings.rmpc_options.soft.u",),
        "error",
        "rigid",
    ),
    (
        "CRMPC rmpc_options unknown",
        "CRMPC",
        "rmpc_options = {bogus = 1}",
        ("settings.rmpc_options: expected keys",),
        "error",
        "rigid",
    ),
    (
        "CRMPC rmpc_options number",
        "CRMPC",
        "rmpc_options = 5",
        ("settings.rmpc_options: expected a table",),
        "error",
        "rigid",
    ),
    (
        "CRMPC backend proxqp",
        "CRMPC",
        'backend = "proxqp"',
        ("settings.backend: expected",),
        "error",
        "wheel",
    ),
    (
        "CRMPC adaptation",
        "CRMPC",
        'adaptation = "mit"',
        ("settings.adaptation: expected no adaptation",),
        "error",
        "rigid",
    ),
    ("GIPC backend ipm", "GIPC", 'backend = "ipm"', ("settings.backend: expected",), "error", "rigid"),
)


def _sweep_text(controller: str, family: str, settings: str) -> str:
    text = FORM_SWEEP.replace('controller = "RMPC"', f'controller = "{controller}"').format(settings=settings)
    if family != "rigid":  # the other families' own plant; the wheel's without a fault (whose onset is 8 s)
        extra = 'fault_kind = "none"\nduration = 0.3' if family == "wheel" else "duration = 0.03"
        text = text.replace('plant = "linear"\n', f'family = "{family}"\n')
        text = text.replace("duration = 0.03", extra)
    return text


def _write(text: str) -> Callable[[str], None]:
    def setup(tmp: str) -> None:
        with open(os.path.join(tmp, "sweep.toml"), "w", encoding="utf-8") as handle:
            handle.write(text)

    return setup


@dataclass(frozen=True)
class ScriptProbe(Probe):
    """A probe that runs a Python script in a process of its own; the script prints its verdict.

    The script's last line of standard output is ``<verdict> <detail>`` with a verdict of
    :data:`dev.robustness.verdicts.VERDICTS`; ``{tmp}`` in the script is a scratch folder.

    Attributes
    ----------
    script : str
        The Python source.
    """

    script: str = ""

    def run(self, timeout: float) -> Outcome:
        """Run the script; no verdict line, or a traceback, is a ``crash``."""
        scratch = tempfile.mkdtemp(prefix="rmpc-close-")
        start = time.perf_counter()
        env = dict(
            os.environ,
            OMP_NUM_THREADS="1",
            NO_COLOR="1",
            PYTHONUNBUFFERED="1",
            RMPC_COMMAND=" ".join(rmpc_command()),
        )
        try:
            done = subprocess.run(
                [sys.executable, "-c", self.script.replace("{tmp}", scratch)],
                cwd=scratch,
                env=env,
                capture_output=True,
                text=True,
                timeout=timeout,
                check=False,
            )
        except subprocess.TimeoutExpired:
            return Outcome("hang", f"no answer within {timeout:g} s", timeout)
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
        elapsed = time.perf_counter() - start
        lines = done.stdout.strip().splitlines()
        verdict, _, detail = (lines[-1] if lines else "").partition(" ")
        if verdict not in VERDICTS:
            tail = " | ".join(done.stderr.strip().splitlines()[-3:])[:400]
            return Outcome("crash", f"exit {done.returncode}, no verdict: {tail}", elapsed)
        return Outcome(verdict, detail[:400], elapsed)


_PRELUDE = textwrap.dedent("""
    import numpy as np
    from models import PolytopicModel
    from rmpc import RMPC
    PLANT = PolytopicModel([(np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]]))], dt=0.1)

    def wrapped():
        try:
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt as ki:
                raise SystemError("returned a result with an exception set") from ki
        except SystemError as err:
            return err
""")

_CLARABEL_WRAPPED = _PRELUDE + textwrap.dedent("""
    import clarabel
    form = FORM_ARGS
    ctrl = RMPC(PLANT, np.eye(2), np.eye(1), u_max=[1.0], input_constraint="peak", backend="clarabel", **form)
    def interrupted(*args, **kwargs):
        raise wrapped()
    clarabel.DefaultSolver = interrupted
    try:
        sol = ctrl.solve(np.array([0.5, 0.0]))
    except KeyboardInterrupt:
        print("clear the wrapped interrupt came back as KeyboardInterrupt")
    else:
        print(f"silent the interrupt became the status {sol.status!r}")
""")

_SCS_SIGINT = textwrap.dedent("""
    import os, signal, threading, time
    import numpy as np
    from models import RigidSatellite
    from rmpc import RMPC
    x0 = np.array([0.3, -0.2, 0.25, 0.0, 0.0, 0.0])
    poly = RigidSatellite.paper_p().polytope(x0, 0.05, 0.3, "box")
    ctrl = RMPC(poly, np.eye(6), np.eye(3), u_max=1.0, backend="cvxpy", solver="SCS",
                solver_options={"eps_abs": 1e-12, "eps_rel": 1e-12, "max_iters": 10_000_000})
    threading.Timer(2.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
    start = time.perf_counter()
    try:
        sol = ctrl.solve(x0)
    except KeyboardInterrupt:
        print(f"clear KeyboardInterrupt {time.perf_counter() - start:.1f} s into the solve")
    else:
        print(f"silent the solve ended {sol.status!r} after {time.perf_counter() - start:.1f} s; Ctrl-C lost")
""")

_METHODS_ONE_LINE = textwrap.dedent("""
    import contextlib, io
    from benchmarks.cli import main
    from benchmarks.suites import methods as suite
    real, calls = suite.evaluate, []
    def patched(problem, method, settings):
        calls.append(method)
        if len(calls) == 2:
            try:
                try:
                    raise KeyboardInterrupt
                except KeyboardInterrupt as ki:
                    raise SystemError("returned a result with an exception set") from ki
            except SystemError as err:
                raise err
        return real(problem, method, settings)
    suite.evaluate = patched
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        status = main(["bench", "methods", "--short", "--problems", "kothare_ex1", "--methods",
                       "kothare,nominal,vertex", "--out", "{tmp}/out", "--no-progress"])
    lines = [line for line in err.getvalue().splitlines() if "interrupted" in line]
    if status != 130:
        print(f"crash exit {status}, not 130")
    elif len(lines) != 1:
        print(f"unclear {len(lines)} 'interrupted' lines: {' | '.join(lines)}")
    else:
        print(f"clear one line: {lines[0]}")
""")

_STALE_STAGE = textwrap.dedent("""
    import os, subprocess, sys
    from pathlib import Path
    tmp = Path("{tmp}")
    (tmp / "sweep.toml").write_text('name = "s"\\n[base]\\ncontroller = "LQR"\\nsaturation = "limiter"\\n'
                                    'plant = "linear"\\nduration = 0.03\\n')
    stale = tmp / "out" / ".staging-999999999-abc"
    stale.mkdir(parents=True)
    (stale / "results.json").write_text('[{"case_id": "from a killed run"}]')
    cmd = os.environ["RMPC_COMMAND"].split() + ["bench", "sweep", "--config", str(tmp / "sweep.toml"),
                                                 "--out", str(tmp / "out"), "--workers", "0", "--no-progress"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        print(f"crash exit {done.returncode}: {done.stderr.strip()[-200:]}")
    elif stale.exists():
        print("silent the staging folder of the killed run is still there")
    elif stale.name not in done.stderr:
        print("unclear removed without saying so")
    else:
        said = [line for line in done.stderr.splitlines() if stale.name in line][0]
        print("clear removed, and said so: " + said[:160])
""")


def _compare_staging() -> object:
    """``benchmarks.compare`` given a staging folder a killed run left (it holds a results.json)."""
    from benchmarks.compare import compare_runs

    tmp = tempfile.mkdtemp(prefix="rmpc-close-")
    stage = os.path.join(tmp, ".staging-999999999-abc")
    os.makedirs(stage)
    for folder in (stage, tmp):
        with open(os.path.join(folder, "results.json"), "w", encoding="utf-8") as handle:
            handle.write('[{"case_id": "a", "x": 1}]')
    return compare_runs(stage, tmp)


def _form_max_iter_zero() -> object:
    from models import PolytopicModel
    from rmpc import RMPC

    plant = PolytopicModel([(np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]]))], dt=0.1)
    return RMPC(
        plant,
        np.eye(2),
        np.eye(1),
        u_max=[1.0],
        input_constraint="peak",
        lyapunov="vertex",
        solver_options={"max_iter": 0},
    )


def _numpy_integer_calls() -> list[tuple[str, Callable[[], object]]]:
    from benchmarks.core.sweep_spec import expand, parse_sweep

    def sweep(data: dict) -> Callable[[], object]:
        return lambda: len(expand(parse_sweep(data)))

    def osqp() -> object:
        from rmpc.qp.osqp_backend import OSQPSettings

        return OSQPSettings(scaling=np.int64(10)).scaling

    def design() -> object:
        from rmpc.io.design import Design

        return Design({"N": np.int64(10)}).integer("N")

    return [
        ("sweep max_cases", sweep({"max_cases": np.int64(10), "base": {"controller": "GIPC"}})),
        ("sweep montecarlo.n", sweep({"base": {"controller": "GIPC"}, "montecarlo": {"n": np.int64(2)}})),
        (
            "sweep montecarlo.seed",
            sweep({"base": {"controller": "GIPC"}, "montecarlo": {"n": 2, "seed": np.int64(3)}}),
        ),
        ("sweep settings.Np", sweep({"base": {"controller": "GIPC", "settings": {"Np": np.int64(100)}}})),
        ("sweep settings.R_du", sweep({"base": {"controller": "GIPC", "settings": {"R_du": np.int64(1)}}})),
        ("wheel fault_wheel", sweep({"base": {"family": "wheel", "fault_wheel": np.int64(3)}})),
        ("wheel seed", sweep({"base": {"family": "wheel", "seed": np.int64(4)}})),
        ("OSQPSettings.scaling", osqp),
        ("Design.integer", design),
    ]


def close_probes() -> list[Probe]:
    """Every probe of this module."""
    probes: list[Probe] = [
        Probe(
            f"cli:reach {label} ({family})",
            "cli",
            names,
            argv=SWEEP_ARGV,
            setup=_write(_sweep_text(controller, family, body)),
            expect=expect,
            kind="sweep reach",
        )
        for label, controller, body, names, expect, family in _REACH
    ]
    probes += [
        ScriptProbe(
            "interrupt: wrapped in lmi's Clarabel back-end",
            "api",
            ("interrupt",),
            script=_CLARABEL_WRAPPED.replace("FORM_ARGS", "{}"),
            kind="interrupt",
        ),
        ScriptProbe(
            "interrupt: wrapped in the forms' Clarabel solve",
            "api",
            ("interrupt",),
            script=_CLARABEL_WRAPPED.replace("FORM_ARGS", '{"lyapunov": "vertex"}'),
            kind="interrupt",
        ),
        ScriptProbe(
            "interrupt: SIGINT during an SCS solve",
            "api",
            ("interrupt",),
            script=_SCS_SIGINT,
            kind="interrupt",
        ),
        ScriptProbe(
            "cli:interrupt methods says interrupted once",
            "cli",
            ("interrupted",),
            script=_METHODS_ONE_LINE,
            kind="interrupt",
        ),
        InterruptProbe(
            "cli:interrupt sweep (SCS, --workers 0), SIGINT to the process 0.5 s after the first case",
            "cli",
            ("interrupted",),
            argv=SWEEP_ARGV,
            kind="interrupt",
            delay=0.5,
            sweep=_SCS_SWEEP,
            running=1,
        ),
        ScriptProbe(
            "cli:sweep over a staging folder a killed run left",
            "cli",
            ("staging",),
            script=_STALE_STAGE,
            kind="store",
        ),
        Probe(
            "benchmarks.compare:a staging folder as a run",
            "api",
            ("killed while writing",),
            call=_compare_staging,
            kind="store",
        ),
        Probe(
            "RMPC.solver_options:{'max_iter': 0} with lyapunov='vertex'",
            "api",
            ("solver_options['max_iter']",),
            found=(">= 1",),
            call=_form_max_iter_zero,
            kind="value",
        ),
    ]
    probes += [
        Probe(
            f"numpy integer: {label}", "api", _MUST_ACCEPT, call=call, expect="either", kind="numpy integer"
        )
        for label, call in _numpy_integer_calls()
    ]
    return probes


_SCS_SWEEP = """name = "interrupt_scs"
[base]
controller = "RMPC"
plant = "linear"
saturation = "constraint"
duration = 0.03
[base.settings]
backend = "cvxpy"
solver = "SCS"
solver_options = {eps_abs = 1e-12, eps_rel = 1e-12, max_iters = 3000}
[grid]
u_max = [0.5, 0.7, 0.9, 1.0]
"""
"""Four RMPC cases of three samples solved by SCS (about a second a solve, most of it inside SCS,
which takes SIGINT itself while it solves)."""
