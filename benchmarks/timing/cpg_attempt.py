"""CVXPYgen on Kothare's LMIs: does its generated code (the Clarabel path for PSD cones) build here?

CVXPYgen (the ``cvxpygen`` package) generates C for a parametrised cvxpy problem; for positive
semidefinite cones only its Clarabel path applies, which compiles Clarabel's Rust core (cargo,
its crates, BLAS and LAPACK) into the generated code. The ``C``
section of ``rmpc timing`` (:mod:`benchmarks.timing.c_exports`) calls :func:`cvxpygen_attempt`
on the same LMIs it times (the cvxpy back-end's problem of :class:`lmi.KothareProblem`,
``delta_shared``) and records what happened: not installed, or the generation or build failed
(the error lines of its output), or it built. The attempt runs in a child process in a scratch
folder: CVXPYgen changes the working directory, runs pip and cargo, and imports the module it
built from the current directory.

Timing the generated code is not done here: its build has never succeeded on the machines this
was written on (crates.io cannot be reached), so a built result is recorded as built and untimed
rather than timed by untried code.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

__all__ = ["SCRIPT", "cvxpygen_attempt", "error_lines"]

_EXCEPTION = re.compile(r"^[A-Za-z_.]*(Error|Exception): ")

#: The child process: build the cvxpy problem of the section's LMIs and generate code for it.
SCRIPT = """
import sys
from cvxpygen import cpg
from benchmarks.timing.common import Q1, R, U_MAX, polytope
from lmi import KothareProblem

poly = polytope(int(sys.argv[1]))
problem = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend="cvxpy",
                         solver="CLARABEL", formulation="delta_shared")
cpg.generate_code(problem._backend.problem, code_dir="kothare_cpg", solver="CLARABEL", wrapper=True)
"""


def error_lines(output: str, limit: int = 6) -> list[str]:
    r"""The distinct lines of ``output`` that report an error, in order, at most ``limit``.

    An error line starts with ``error`` (pip, cargo, the compilers), names an exception
    (``ImportError: ...``) or says something ``could not`` be found or reached (CMake, a resolver);
    warnings are left out, even those that quote an error.

    Examples
    --------
    >>> log = "ok\n  error: failed to get `amd`\nwarning: network error\n[6] Could not resolve host: x\n"
    >>> error_lines(log + "ImportError: no module")
    ['error: failed to get `amd`', '[6] Could not resolve host: x', 'ImportError: no module']
    """
    found: list[str] = []
    for raw in output.splitlines():
        line = raw.strip()
        low = line.lower()
        if low.startswith("warning"):
            continue
        if (low.startswith("error") or "could not" in low or _EXCEPTION.match(line)) and line not in found:
            found.append(line)
    return found[:limit]


def cvxpygen_attempt(n_vertices: int, timeout_s: float = 900.0) -> dict[str, Any]:
    """Try CVXPYgen's Clarabel path on the section's LMIs at ``n_vertices``; say what happened.

    Returns
    -------
    dict
        ``outcome`` (``"not installed"``, ``"failed"``, ``"timed out"`` or ``"built"``), ``errors``
        (the error lines of the child's output, the last one the exception that ended it),
        ``attempt_s`` (the attempt's wall time) and ``version`` (CVXPYgen's, where installed).
    """
    if importlib.util.find_spec("cvxpygen") is None:
        return {"outcome": "not installed", "errors": ["the Python package cvxpygen is not installed"],
                "attempt_s": 0.0, "version": None}
    from importlib.metadata import version

    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as scratch:
        try:
            done = subprocess.run([sys.executable, "-c", SCRIPT, str(n_vertices)], cwd=scratch,
                                  capture_output=True, text=True, timeout=timeout_s, check=False)
        except subprocess.TimeoutExpired:
            return {"outcome": "timed out", "errors": [f"no answer within {timeout_s:g} s"],
                    "attempt_s": time.perf_counter() - start, "version": version("cvxpygen")}
        built = done.returncode == 0 and any(Path(scratch, "kothare_cpg").glob("cpg_module*"))
    errors = error_lines(done.stdout + "\n" + done.stderr)
    tail = [line for line in done.stderr.strip().splitlines() if line.strip()][-1:]
    if tail and tail[0].strip() not in errors:
        errors.append(tail[0].strip())
    return {"outcome": "built" if built else "failed", "errors": [] if built else errors,
            "attempt_s": time.perf_counter() - start, "version": version("cvxpygen")}
