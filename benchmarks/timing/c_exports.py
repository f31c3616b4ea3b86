"""The ``C`` section of ``rmpc timing``: the exported C controllers timed against the anchors, one run.

For paper P's satellite at each vertex count of the run (``rmpc timing --problems C``):

- **on-line RMPC**: :class:`rmpc.RMPC` of Kothare's form (the problem of the RMPC section:
  ``delta_shared``, ``||u|| <= u_max``) is exported (:func:`rmpc.export_c`), compiled with
  ``cc -std=c99 -O2`` as a shared library together with :data:`TIMED_STEP` (``rmpc_step`` between
  two ``clock_gettime`` calls, wall and thread CPU time) and loaded with ctypes. At the states of
  the RMPC section's closed loop (its own states when it ran in the same run, else
  :func:`benchmarks.timing.rmpc.section_states`) four paths solve, interleaved state by state
  (the order rotated): the export's ``rmpc_step``, the Python ipm (``KothareProblem.solve``,
  warm-started, as the RMPC section times it; its iterations in the C core where it carries the
  problem, :mod:`lmi.ccore.runtime`), the same with the numba kernels (``ipm-numba``,
  ``solver_options={"core": "numba"}``: the Python implementation, against which the export's
  speed-up target is judged) and Clarabel (``backend="clarabel"``). Every path
  first solves once, untimed, at ``1.3 x0``, so every timed solve is warm. Reported per path:
  p50/p95/max of the wall time and of the thread CPU time, iterations, statuses; for the export
  its gamma and ``u`` against the Python ipm's, the object code (``size`` of the ``.o`` compiled
  with ``-O2``: text, data, bss) and its static memory (``ExportResult.static_bytes`` +
  ``rmpc_solver_workspace_bytes()``).
- **CVXPYgen** on the same LMIs (its Clarabel path for PSD cones): what happened
  (:mod:`benchmarks.timing.cpg_attempt`; not tried in a quick run).
- **off-line RMPC**: :class:`rmpc.OfflineRMPC` (the OfflineRMPC section's design) exported and
  its lookup timed in C against ``OfflineRMPC.step``, with and without interpolation
  (:func:`benchmarks.timing.c_export.time_c_export`, the stand-alone script's code).

The targets of :data:`TARGETS` are judged on the thread CPU time's p50 (the machine is shared;
the wall times are reported beside them). Without a C compiler the section records ``no C
compiler`` and the run goes on.
"""

from __future__ import annotations

import ctypes
import math
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from benchmarks.core.machine import percentiles
from benchmarks.timing.common import POLYTOPE_NAMES, Q1, U_MAX, R, finite, median_int, tally

if TYPE_CHECKING:
    from benchmarks.core.progress import CaseProgress
    from benchmarks.timing.config import TimingConfig
    from models import PolytopicModel

__all__ = ["NO_COMPILER", "TARGETS", "TIMED_STEP", "c_markdown", "judge_targets", "time_c"]

#: What the section records when there is no ``cc`` on the PATH.
NO_COMPILER = "no C compiler"

#: ``rmpc_step`` between two clock readings: wall (CLOCK_MONOTONIC) and thread CPU time, in s.
TIMED_STEP = r"""
#define _POSIX_C_SOURCE 199309L
#include <time.h>
#include "rmpc_controller.h"

int rmpc_timed_step(const double *x, double *u, double *wall_s, double *cpu_s);

static double seconds(const struct timespec *a, const struct timespec *b)
{
    return (double)(b->tv_sec - a->tv_sec) + 1e-9 * (double)(b->tv_nsec - a->tv_nsec);
}

int rmpc_timed_step(const double *x, double *u, double *wall_s, double *cpu_s)
{
    struct timespec w0, w1, c0, c1;
    int code;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    clock_gettime(CLOCK_MONOTONIC, &w0);
    code = rmpc_step(x, u);
    clock_gettime(CLOCK_MONOTONIC, &w1);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    *wall_s = seconds(&w0, &w1);
    *cpu_s = seconds(&c0, &c1);
    return code;
}
"""

#: The targets (2-core machine, same run): (name, vertices, what is measured, limit, unit).
TARGETS: tuple[tuple[str, int, str, float, str], ...] = (
    ("on-line export p50 warm per solve", 2, "c_cpu_p50_s", 1e-3, "s, at most"),
    ("on-line export faster than the Python ipm (numba kernels, p50)", 2, "ipm_over_c", 4.0, "x, at least"),
    ("on-line export faster than CVXPYgen's code (p50)", 2, "cvxpygen_over_c", 10.0, "x, at least"),
    ("on-line export p50 warm per solve", 8, "c_cpu_p50_s", 3e-3, "s, at most"),
    ("off-line lookup of 15 ellipsoids per step (p50)", 2, "lookup_p50_s", 2e-6, "s, at most"),
    ("object code of the on-line export (text + data)", 2, "object_bytes", 200e3, "B, under"),
)

_D = ctypes.POINTER(ctypes.c_double)


def _c_word(code: int) -> str:
    """The on-line export's status code as a word: ``optimal`` for 0, the Python word of
    :data:`rmpc.export.c_writer.STATUS_CODES` where there is one, else the C name's tail."""
    from rmpc.export.c_writer import STATUS_CODES

    if code == 0:
        return "optimal"
    for status in STATUS_CODES:
        if status.value == code:
            plain = status.word.replace("_", "").isalpha()
            return status.word if plain else status.name.removeprefix("RMPC_STATUS_").lower()
    return f"code {code}"


@dataclass
class _Times:
    """What one path measured at the states."""

    wall: list[float] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)
    iterations: list[int | None] = field(default_factory=list)
    gammas: list[float] = field(default_factory=list)
    inputs: list[np.ndarray] = field(default_factory=list)
    statuses: dict[str, int] = field(default_factory=dict)


class _Export:
    """The on-line export compiled as a shared library with :data:`TIMED_STEP`, loaded by ctypes."""

    def __init__(self, ctrl: Any, folder: Path) -> None:
        from benchmarks.timing.c_export import compiler, object_size
        from rmpc import export_c

        self.result = export_c(ctrl, folder)
        (folder / "timed_step.c").write_text(TIMED_STEP)
        lib = folder / "librmpc_timed.so"
        subprocess.run([compiler(), "-std=c99", "-O2", "-shared", "-fPIC", "-o", str(lib),
                        "rmpc_controller.c", "timed_step.c", "-lm"], cwd=folder, check=True,
                       capture_output=True, text=True)
        self.sizes = object_size(self.result.source, folder)
        self.lib = ctypes.CDLL(str(lib))
        self.lib.rmpc_last_gamma.restype = ctypes.c_double
        self.lib.rmpc_solver_workspace_bytes.restype = ctypes.c_ulong
        self.lib.rmpc_init()
        self.solver_workspace_bytes = int(self.lib.rmpc_solver_workspace_bytes())
        self.nu = self.result.nu

    def step(self, x: np.ndarray, times: _Times | None) -> None:
        xc = np.ascontiguousarray(x, dtype=float)
        u = np.zeros(self.nu)
        wall, cpu = ctypes.c_double(), ctypes.c_double()
        code = self.lib.rmpc_timed_step(xc.ctypes.data_as(_D), u.ctypes.data_as(_D), ctypes.byref(wall),
                                        ctypes.byref(cpu))
        if times is None:
            return
        times.wall.append(wall.value)
        times.cpu.append(cpu.value)
        times.iterations.append(int(self.lib.rmpc_last_iterations()))
        times.gammas.append(float(self.lib.rmpc_last_gamma()))
        times.inputs.append(u)
        tally(times.statuses, _c_word(int(code)))


def _python_step(problem: Any, x: np.ndarray, times: _Times | None) -> None:
    w0, c0 = time.perf_counter(), time.thread_time()
    sol = problem.solve(x)
    c1, w1 = time.thread_time(), time.perf_counter()
    if times is None:
        return
    times.wall.append(w1 - w0)
    times.cpu.append(c1 - c0)
    times.iterations.append(sol.iterations)
    times.gammas.append(sol.gamma)
    times.inputs.append(sol.F @ x if sol.F is not None else np.full(problem.data.m, np.nan))
    tally(times.statuses, str(sol.status))


def _record(backend: str, poly: PolytopicModel, times: _Times, settings: str) -> dict[str, Any]:
    wall, cpu = percentiles(times.wall), percentiles(times.cpu)
    return {
        "problem": "C", "formulation": "delta_shared", "backend": backend, "vertices": poly.n_vertices,
        "polytope": POLYTOPE_NAMES[poly.n_vertices], "steps": len(times.wall), **wall,
        "cpu_p50_s": cpu["p50_s"], "cpu_p95_s": cpu["p95_s"], "cpu_max_s": cpu["max_s"],
        "iterations_p50": median_int(times.iterations), "status_counts": dict(times.statuses),
        "max_rel_err": None, "settings": settings,
    }


def _online(poly: PolytopicModel, states: list[np.ndarray], folder: Path) -> dict[str, Any]:
    """The export, the Python ipm and Clarabel at ``states``, interleaved; their records."""
    from lmi import KothareProblem
    from models import RigidSatellite
    from rmpc import RMPC

    ctrl = RMPC(poly, Q1, R, u_max=U_MAX, input_constraint="ellipsoid", formulation="delta_shared")
    export = _Export(ctrl, folder)

    def problem(backend: str, options: dict[str, Any] | None = None) -> Any:
        return KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend=backend,
                              formulation="delta_shared", solver_options=options)

    ipm, numba, clarabel = problem("ipm"), problem("ipm", {"core": "numba"}), problem("clarabel")
    paths = [("c-export", lambda x, t: export.step(x, t)), ("ipm", lambda x, t: _python_step(ipm, x, t)),
             ("ipm-numba", lambda x, t: _python_step(numba, x, t)),
             ("clarabel", lambda x, t: _python_step(clarabel, x, t))]
    warm_up = 1.3 * RigidSatellite.initial_state()
    times = {name: _Times() for name, _ in paths}
    for _, run in paths:
        run(warm_up, None)
    for k, x in enumerate(states):
        shift = k % len(paths)
        for name, run in paths[shift:] + paths[:shift]:
            run(x, times[name])
    c, py = times["c-export"], times["ipm"]
    rec_c = _record("c-export", poly, c, "rmpc_step of rmpc.export_c(RMPC), cc -std=c99 -O2 -fPIC, "
                    "loaded with ctypes; timed inside C (clock_gettime around rmpc_step)")
    both = np.isfinite(c.gammas) & np.isfinite(py.gammas)
    rec_c.update(
        max_rel_err=finite(np.max(np.abs(np.array(c.gammas)[both] / np.array(py.gammas)[both] - 1.0)))
        if np.any(both) else None,
        compared_steps=int(np.sum(both)),
        max_abs_err_u=finite(np.nanmax(np.abs(np.array(c.inputs) - np.array(py.inputs)))),
        **export.sizes,
        object_bytes=export.sizes.get("text_bytes", 0) + export.sizes.get("data_bytes", 0)
        if "text_bytes" in export.sizes else export.sizes["object_file_bytes"],
        export_static_bytes=export.result.static_bytes,
        solver_workspace_bytes=export.solver_workspace_bytes,
        static_memory_bytes=export.result.static_bytes + export.solver_workspace_bytes,
    )
    return {"records": [
        rec_c,
        _record("ipm", poly, py, "KothareProblem.solve, the toolkit's ipm warm-started (the RMPC "
                f"section's fast path; its iterations in {ipm._backend.core}: lmi.ccore.runtime)"),
        _record("ipm-numba", poly, times["ipm-numba"], "KothareProblem.solve, the toolkit's ipm "
                "warm-started, its iterations in the numba kernels (solver_options core='numba')"),
        _record("clarabel", poly, times["clarabel"], "KothareProblem.solve with backend='clarabel' "
                "(Clarabel's own API, defaults)"),
    ], "samples": {f"C|{name}|delta_shared|{poly.n_vertices}": np.asarray(t.wall)
                    for name, t in times.items()}}


def _offline(poly: PolytopicModel, cfg: TimingConfig, folder: Path) -> list[dict[str, Any]]:
    """The off-line export's lookup against ``OfflineRMPC.step`` (with and without interpolation)."""
    from benchmarks.timing.c_export import time_c_export
    from models import RigidSatellite
    from rmpc import OfflineRMPC, simulate

    x0 = RigidSatellite.initial_state()
    ctrl = OfflineRMPC(poly, Q1, R, u_max=U_MAX, x_design=x0, n_ellipsoids=cfg.n_ellipsoids)
    states = simulate(ctrl, poly, x0, n_steps=cfg.cheap_steps).x[:-1]
    batches, calls = (10, 100) if cfg.quick else (200, 1000)
    records = []
    for interpolate in (True, False):
        ctrl.interpolate = interpolate
        res = time_c_export(ctrl, states, batches=batches, calls=calls,
                            folder=folder / f"offline_{interpolate}")
        records.append({
            "problem": "C", "formulation": "lookup" + ("+interpolation" if interpolate else ""),
            "backend": "c-export", "vertices": poly.n_vertices, "polytope": POLYTOPE_NAMES[poly.n_vertices],
            "steps": len(states), "p50_s": res["c_p50_s"], "p95_s": res["c_p95_s"], "max_s": res["c_max_s"],
            "status_counts": res["c_status_counts"], "max_rel_err": None,
            "max_abs_err_u": finite(res["max_abs_diff_u"]),
            "same_statuses": res["same_statuses"], "n_ellipsoids": res["n_ellipsoids"],
            "python_p50_s": res["python_p50_s"], "python_p95_s": res["python_p95_s"],
            "python_over_c_p50": res["speedup_p50"], "calls_per_batch": calls, "lookup_states": len(states),
            **{k: res[k] for k in ("object_file_bytes", "text_bytes", "data_bytes", "bss_bytes") if k in res},
            "static_memory_bytes": res["static_bytes"], "table_bytes": res["table_bytes"],
            "workspace_bytes": res["workspace_bytes"],
            "settings": f"rmpc.export_c(OfflineRMPC), {res['n_ellipsoids']} ellipsoids; C: {batches} batches "
                        f"of {calls} calls over the states of its closed loop, per-call time of each batch; "
                        "Python: OfflineRMPC.step, single calls",
        })
    return records


def time_c(poly: PolytopicModel, cfg: TimingConfig, states: list[np.ndarray] | None = None,
           bar: CaseProgress | None = None) -> dict[str, Any]:
    """The section at one vertex count: records, samples and CVXPYgen's outcome.

    ``states`` are the RMPC section's states when it ran in this run; otherwise the same closed
    loop is followed here (:func:`benchmarks.timing.rmpc.section_states`). Without ``cc`` on the
    PATH nothing is timed: ``{"records": [], "samples": {}, "compiler": None, "note": NO_COMPILER}``.
    """
    from benchmarks.timing.cpg_attempt import cvxpygen_attempt
    from benchmarks.timing.rmpc import section_states

    if shutil.which("cc") is None:
        if bar is not None:
            bar.advance(f"C {poly.n_vertices} vertices: {NO_COMPILER}")
        return {"records": [], "samples": {}, "compiler": None, "note": NO_COMPILER, "cvxpygen": None}
    if states is None:
        states = section_states(poly, cfg.steps)
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        online = _online(poly, states, folder / "online")
        offline = _offline(poly, cfg, folder)
    if cfg.quick:
        cpg = {"outcome": "not tried", "errors": ["a quick run does not try CVXPYgen"], "attempt_s": 0.0,
               "version": None}
    else:
        cpg = cvxpygen_attempt(poly.n_vertices)
    cpg["vertices"] = poly.n_vertices
    if bar is not None:
        bar.advance(f"C {poly.n_vertices} vertices")
    return {"records": online["records"] + offline, "samples": online["samples"],
            "compiler": shutil.which("cc"), "note": "", "cvxpygen": cpg}


def _find(records: list[dict[str, Any]], backend: str, vertices: int,
          formulation: str) -> dict[str, Any] | None:
    for rec in records:
        if (rec["problem"], rec["backend"], rec["vertices"], rec["formulation"]) == (
                "C", backend, vertices, formulation):
            return rec
    return None


def _measure(what: str, vertices: int, records: list[dict[str, Any]],
             cvxpygen: dict[int, dict[str, Any]]) -> tuple[float | None, str]:
    """The measured value of one target and a note (why there is none, what it is)."""
    c = _find(records, "c-export", vertices, "delta_shared")
    if what == "lookup_p50_s":
        rec = _find(records, "c-export", vertices, "lookup+interpolation")
        if rec is None:
            return None, "not in this run"
        plain = _find(records, "c-export", vertices, "lookup")
        note = (f"with interpolation (OfflineRMPC's default); without: {1e6 * plain['p50_s']:.3f} us"
                if plain else "")
        if rec["n_ellipsoids"] != 15:
            return rec["p50_s"], f"{rec['n_ellipsoids']} ellipsoids in this run, not 15: not judged"
        return rec["p50_s"], note
    if c is None:
        return None, "not in this run"
    if what == "c_cpu_p50_s":
        return c["cpu_p50_s"], f"thread CPU time; wall p50 {1e3 * c['p50_s']:.3f} ms"
    if what == "object_bytes":
        return float(c["object_bytes"]), (f"static memory {c['static_memory_bytes']} B (export "
                                          f"{c['export_static_bytes']} + solver workspace "
                                          f"{c['solver_workspace_bytes']})")
    if what == "ipm_over_c":
        py = _find(records, "ipm-numba", vertices, "delta_shared")
        if py is None:
            return None, "not in this run"
        wall = py["p50_s"] / c["p50_s"]
        return py["cpu_p50_s"] / c["cpu_p50_s"], (f"thread CPU time p50 {1e3 * py['cpu_p50_s']:.3f} ms / "
                                                  f"{1e3 * c['cpu_p50_s']:.3f} ms; wall {wall:.2f}x")
    attempt = cvxpygen.get(vertices)
    if attempt is None:
        return None, "not in this run"
    if attempt["outcome"] == "built":
        return None, "CVXPYgen's code built, but this section does not time it (never built where written)"
    return None, f"CVXPYgen {attempt['outcome']}: " + "; ".join(attempt["errors"])


def judge_targets(records: list[dict[str, Any]], cvxpygen: dict[int, dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per target of :data:`TARGETS`: measured, target, met (``None``: not judged) and a note."""
    rows = []
    for name, vertices, what, limit, unit in TARGETS:
        value, note = _measure(what, vertices, records, cvxpygen)
        met = None
        if value is not None and math.isfinite(value) and "not judged" not in note:
            met = bool(value >= limit) if "at least" in unit else bool(value < limit) if "under" in unit \
                else bool(value <= limit)
        rows.append({"target": name, "vertices": vertices, "measured": finite(value), "limit": limit,
                     "unit": unit, "met": met, "note": note})
    return rows


def _value(value: float | None, unit: str) -> str:
    if value is None:
        return "n/a"
    if unit.startswith("s"):
        return f"{1e3 * value:.3f} ms" if value >= 1e-4 else f"{1e6 * value:.3f} us"
    if unit.startswith("x"):
        return f"{value:.2f}x"
    return f"{value / 1e3:.1f} kB"


def c_markdown(report: dict[str, Any]) -> list[str]:
    """The ``C`` section of ``timing.md`` (empty when the run did not ask for it)."""
    from benchmarks.timing.common import ms, us

    summary = report.get("c")
    if summary is None:
        return []
    lines = ["## C: the exported controllers against the anchors", ""]
    if summary["compiler"] is None:
        return [*lines, f"{NO_COMPILER} (``cc`` not on the PATH): nothing was timed.", ""]
    recs = [r for r in report["records"] if r["problem"] == "C"]
    online = [r for r in recs if r["formulation"] == "delta_shared"]
    lines += [
        f"Compiler: `{summary['compiler']}`. On-line: `rmpc.export_c` of the RMPC of the RMPC section "
        "(delta_shared, ||u|| <= u_max), compiled `cc -std=c99 -O2 -fPIC` with a timing wrapper and "
        "loaded with ctypes, against the Python ipm (`KothareProblem.solve`, warm-started; `ipm`: the "
        "package's default, its iterations in the C core `pip install .` builds where it carries the "
        "problem; `ipm-numba`: the numba kernels) and Clarabel "
        "(`backend='clarabel'`) at the states of the RMPC section's closed loop, interleaved state by "
        "state; each path solved once first, untimed, at 1.3 x0, so every timed solve is warm. Thread CPU "
        "time is the time the solve's thread ran (the machine is shared); wall time beside it. Errors "
        "are the export's against the Python ipm at the same state.", "",
        "| vertices | path | steps | wall p50 / p95 (ms) | thread CPU p50 / p95 (ms) | iterations p50 "
        "| statuses | max rel err gamma | max abs err u |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in online:
        it = "n/a" if r["iterations_p50"] is None else f"{r['iterations_p50']:g}"
        err = f"{r['max_rel_err']:.1e}" if r.get("max_rel_err") is not None else ""
        du = f"{r['max_abs_err_u']:.1e}" if r.get("max_abs_err_u") is not None else ""
        lines.append(
            f"| {r['vertices']} | {r['backend']} | {r['steps']} | {ms(r['p50_s'], 3)} / {ms(r['p95_s'], 3)} "
            f"| {ms(r['cpu_p50_s'], 3)} / {ms(r['cpu_p95_s'], 3)} | {it} | {_words(r['status_counts'])} "
            f"| {err} | {du} |")
    lines += ["", "| vertices | ipm / export (CPU p50) | ipm-numba / export (CPU p50) | Clarabel / export "
              "(CPU p50) | ipm / export (wall p50) | Clarabel / export (wall p50) |",
              "| --- | --- | --- | --- | --- | --- |"]
    for c in (r for r in online if r["backend"] == "c-export"):
        py = _find(recs, "ipm", c["vertices"], "delta_shared")
        nb = _find(recs, "ipm-numba", c["vertices"], "delta_shared")
        cl = _find(recs, "clarabel", c["vertices"], "delta_shared")
        if py is not None and cl is not None:
            numba_ratio = f"{nb['cpu_p50_s'] / c['cpu_p50_s']:.2f}x" if nb is not None else "not run"
            lines.append(f"| {c['vertices']} | {py['cpu_p50_s'] / c['cpu_p50_s']:.2f}x | {numba_ratio} "
                         f"| {cl['cpu_p50_s'] / c['cpu_p50_s']:.2f}x | {py['p50_s'] / c['p50_s']:.2f}x "
                         f"| {cl['p50_s'] / c['p50_s']:.2f}x |")
    lines += ["", "Object code: `size` of the `.o` compiled `cc -std=c99 -O2 -c`; static memory: "
              "`ExportResult.static_bytes` (constant tables and the controller's workspace) + "
              "`rmpc_solver_workspace_bytes()` (the solver's, on-line only).", "",
              "| export | vertices | text (B) | data (B) | bss (B) | static memory (B) |",
              "| --- | --- | --- | --- | --- | --- |"]
    for r in recs:
        if r["backend"] == "c-export" and r["formulation"] != "lookup":
            kind = "on-line RMPC" if r["formulation"] == "delta_shared" else "OfflineRMPC"
            lines.append(f"| {kind} | {r['vertices']} | {r.get('text_bytes', 'n/a')} "
                         f"| {r.get('data_bytes', 'n/a')} | {r.get('bss_bytes', 'n/a')} "
                         f"| {r['static_memory_bytes']} |")
    lines += ["", "Off-line lookup: C in batches of calls over the states of the controller's closed loop "
              "(per-call time of each batch), Python `OfflineRMPC.step` in single calls, same states.", "",
              "| vertices | lookup | ellipsoids | C p50 / p95 (us) | Python p50 / p95 (us) | Python / C "
              "| same statuses | max abs diff u |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in recs:
        if r["formulation"].startswith("lookup"):
            lines.append(f"| {r['vertices']} | {r['formulation']} | {r['n_ellipsoids']} "
                         f"| {us(r['p50_s'])} / {us(r['p95_s'])} | {us(r['python_p50_s'])} / "
                         f"{us(r['python_p95_s'])} | {r['python_over_c_p50']:.0f}x | {r['same_statuses']} "
                         f"| {r['max_abs_err_u']:.1e} |")
    lines += ["", "CVXPYgen on the same LMIs (its Clarabel path, the only one for PSD cones):", ""]
    for att in summary["cvxpygen"]:
        what = "; ".join(f"`` {e} ``" for e in att["errors"]) or "built"
        lines.append(f"- {att['vertices']} vertices: {att['outcome']} ({att['attempt_s']:.1f} s): {what}")
    lines += ["", "### Targets", "", "| target | vertices | measured | target | met | note |",
              "| --- | --- | --- | --- | --- | --- |"]
    for t in summary["targets"]:
        met = "not judged" if t["met"] is None else "met" if t["met"] else "not met"
        lines.append(f"| {t['target']} | {t['vertices']} | {_value(t['measured'], t['unit'])} "
                     f"| {t['unit'].split(', ')[1]} {_value(t['limit'], t['unit'])} | {met} | {t['note']} |")
    return [*lines, ""]


def _words(counts: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in counts.items())
