"""Per-step time of the C99 export of off-line robust MPC against ``OfflineRMPC.step`` in Python.

**The stand-alone script**: ``python -m benchmarks.timing.c_export [--n-ellipsoids N] [--steps S]
[--batches B] [--calls C] [--out FILE]``. On paper P's satellite (2 vertices, inertia spread 0.3,
``||u|| <= 1``, Ts = 0.01 s, ``Q1 = diag(1, 1, 1, 0.1, 0.1, 0.1)``, ``R = I``) it designs
:class:`rmpc.OfflineRMPC` from paper P's initial state (15 ellipsoids along its ray by default),
runs one closed loop of the nominal linear model for the states to look up, exports the controller
(:func:`rmpc.export_c`), and times, with and without interpolation:

- **C**: a driver compiled with the export (``cc -std=c99 -O2``) calls ``rmpc_step`` over the
  states in ``B`` batches of ``C`` calls, each batch timed with ``clock_gettime(CLOCK_MONOTONIC)``;
  the per-step time of a batch is its time over ``C``;
- **Python**: ``OfflineRMPC.step`` at the same states, each call timed with
  ``time.perf_counter`` (the median and p95 of single calls), and in batches as the C is.

Reported: median and p95 over the batches (and the calls), the object code's size (``size`` of
the ``.o``: text, data, bss; the file size where ``size`` is missing), the static memory the export
reports (constant tables and workspace), the statuses of both and the largest difference of the
commands, with the machine and its load average. :func:`time_c_export` is the section a report
can call with its own controller and states.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.machine import machine_info, package_versions, percentiles
from benchmarks.timing.common import Q1, U_MAX, R, machine_line, tally, write_result
from models import PAPER_P_SAMPLE_TIME, RigidSatellite
from rmpc import OfflineRMPC, export_c, simulate
from toolkit_common.errors import InvalidArgumentError

__all__ = ["DRIVER", "compiler", "format_table", "main", "object_size", "run", "time_c_export"]

#: The C timing driver: reads ``count, states``; writes the per-step time of each batch (s).
DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "rmpc_controller.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    static double states[100000][RMPC_NX];
    double u[RMPC_NU];
    volatile double sink = 0.0;
    double count;
    long n, b, k, batches, calls;
    FILE *in;
    FILE *out;
    if (argc != 5 || (in = fopen(argv[1], "rb")) == NULL || (out = fopen(argv[2], "wb")) == NULL) {
        return 2;
    }
    batches = atol(argv[3]);
    calls = atol(argv[4]);
    if (fread(&count, sizeof count, 1, in) != 1 || count < 1 || count > 100000) {
        return 3;
    }
    n = (long)count;
    if (fread(states, sizeof states[0], (size_t)n, in) != (size_t)n) {
        return 4;
    }
    rmpc_init();
    for (k = 0; k < n; ++k) { /* warm the caches */
        rmpc_step(states[k], u);
        sink += u[0];
    }
    for (b = 0; b < batches; ++b) {
        const double start = now();
        double per_call;
        for (k = 0; k < calls; ++k) {
            rmpc_step(states[k % n], u);
            sink += u[0];
        }
        per_call = (now() - start) / (double)calls;
        fwrite(&per_call, sizeof per_call, 1, out);
    }
    fclose(in);
    fclose(out);
    return sink == 12345.678 ? 1 : 0;
}
"""


def compiler() -> str:
    """The C compiler on the PATH (``cc``); an error naming it when there is none."""
    cc = shutil.which("cc")
    if cc is None:
        raise InvalidArgumentError("cc", "a C compiler on PATH to build the export", "none found")
    return cc


def object_size(source: Path, folder: Path) -> dict[str, int]:
    """Compile ``source`` to an object (``cc -std=c99 -O2 -c``): ``size``'s text, data and bss, or
    the file size alone when ``size`` is missing."""
    obj = folder / "rmpc_controller.o"
    subprocess.run([compiler(), "-std=c99", "-O2", "-c", "-o", str(obj), str(source)], check=True)
    out = {"object_file_bytes": obj.stat().st_size}
    size = shutil.which("size")
    if size is not None:
        listing = subprocess.run([size, str(obj)], capture_output=True, text=True, check=True).stdout
        text, data, bss = (int(v) for v in listing.splitlines()[1].split()[:3])
        out.update(text_bytes=text, data_bytes=data, bss_bytes=bss)
    return out


def _c_batches(folder: Path, states: np.ndarray, batches: int, calls: int) -> list[float]:
    (folder / "timing_driver.c").write_text(DRIVER)
    exe = folder / "timing_driver"
    subprocess.run([compiler(), "-std=c99", "-O2", "-o", str(exe), "timing_driver.c", "rmpc_controller.c",
                    "-lm"], cwd=folder, check=True, capture_output=True, text=True)
    data = np.concatenate([[float(len(states))], np.ascontiguousarray(states, dtype=float).ravel()])
    (folder / "states.bin").write_bytes(data.tobytes())
    subprocess.run([str(exe), "states.bin", "times.bin", str(batches), str(calls)], cwd=folder, check=True)
    return np.frombuffer((folder / "times.bin").read_bytes()).tolist()


def _python_times(ctrl: OfflineRMPC, states: np.ndarray, batches: int, calls: int) -> dict[str, Any]:
    ctrl.step(states[0])  # the first step of a run is not a plain lookup
    single, statuses = [], {}
    for x in states:
        start = time.perf_counter()
        ctrl.step(x)
        single.append(time.perf_counter() - start)
        tally(statuses, ctrl.last.status)
    batch = []
    n = len(states)
    for _ in range(batches):
        start = time.perf_counter()
        for k in range(calls):
            ctrl.step(states[k % n])
        batch.append((time.perf_counter() - start) / calls)
    return {"single": percentiles(single), "batch": percentiles(batch), "status_counts": statuses}


def time_c_export(ctrl: OfflineRMPC, states: np.ndarray, *, batches: int = 200, calls: int = 1000,
                  folder: str | Path | None = None) -> dict[str, Any]:
    """Time the C export of ``ctrl`` and its Python step at ``states`` (see the module notes)."""
    with tempfile.TemporaryDirectory() as scratch:
        work = Path(folder) if folder is not None else Path(scratch)
        result = export_c(ctrl, work)
        c_batch = _c_batches(work, states, batches, calls)
        sizes = object_size(result.source, work)
        lib_u, lib_status = _c_answers(work, result.nu, states)
    py = _python_times(ctrl, states, max(1, batches // 20), calls)
    py_u, py_status = [], []
    for x in states:
        py_u.append(ctrl.step(x))
        py_status.append(str(ctrl.last.status))
    c_words = {0: "optimal", 1: "outside"}
    same_status = all(c_words.get(int(s), "error") == w for s, w in zip(lib_status, py_status, strict=True))
    c_status_counts: dict[str, int] = {}
    for code in lib_status:
        tally(c_status_counts, c_words.get(int(code), "error"))
    c = percentiles(c_batch)
    return {
        "n_ellipsoids": ctrl.table.n_ellipsoids, "interpolate": ctrl.interpolate,
        "states": len(states), "c_batches": batches, "c_calls_per_batch": calls,
        "c_p50_s": c["p50_s"], "c_p95_s": c["p95_s"], "c_max_s": c["max_s"],
        "c_status_counts": c_status_counts,
        "python_p50_s": py["single"]["p50_s"], "python_p95_s": py["single"]["p95_s"],
        "python_batch_p50_s": py["batch"]["p50_s"], "python_batch_p95_s": py["batch"]["p95_s"],
        "speedup_p50": py["single"]["p50_s"] / c["p50_s"],
        "table_bytes": result.table_bytes, "workspace_bytes": result.workspace_bytes,
        "static_bytes": result.static_bytes, **sizes,
        "python_status_counts": py["status_counts"], "same_statuses": same_status,
        "max_abs_diff_u": float(np.max(np.abs(lib_u - np.array(py_u)))),
        "max_u": float(np.max(np.abs(py_u))),
    }


_ANSWERS = r"""
#include <stdio.h>
#include "rmpc_controller.h"
int main(void)
{
    double x[RMPC_NX];
    double u[RMPC_NU];
    double status;
    while (fread(x, sizeof x, 1, stdin) == 1) {
        status = (double)rmpc_step(x, u);
        fwrite(&status, sizeof status, 1, stdout);
        fwrite(u, sizeof u, 1, stdout);
    }
    return 0;
}
"""


def _c_answers(folder: Path, nu: int, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The C export's statuses and commands at ``states`` (a driver on stdin/stdout)."""
    (folder / "answers.c").write_text(_ANSWERS)
    exe = folder / "answers"
    subprocess.run([compiler(), "-std=c99", "-O2", "-o", str(exe), "answers.c", "rmpc_controller.c", "-lm"],
                   cwd=folder, check=True, capture_output=True, text=True)
    raw = subprocess.run([str(exe)], input=np.ascontiguousarray(states, dtype=float).tobytes(),
                         capture_output=True, check=True).stdout
    rows = np.frombuffer(raw).reshape(len(states), 1 + nu)
    return rows[:, 1:], rows[:, 0].astype(int)


def run(n_ellipsoids: int = 15, steps: int = 1000, batches: int = 200, calls: int = 1000) -> dict[str, Any]:
    """Design on paper P's satellite, then time the export with and without interpolation."""
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    poly = sat.polytope(x0, PAPER_P_SAMPLE_TIME, 0.3, "scalar")
    start = time.perf_counter()
    ctrl = OfflineRMPC(poly, Q1, R, u_max=U_MAX, x_design=x0, n_ellipsoids=n_ellipsoids)
    design_time = time.perf_counter() - start
    states = simulate(ctrl, poly, x0, n_steps=steps).x[:-1]
    records = []
    for interpolate in (True, False):
        ctrl.interpolate = interpolate
        records.append({"vertices": poly.n_vertices, "design_time_s": design_time,
                        **time_c_export(ctrl, states, batches=batches, calls=calls)})
    return {"machine": machine_info(), "versions": package_versions(), "records": records}


def format_table(result: dict[str, Any]) -> str:
    """A Markdown table of the records, then the machine."""
    lines = [
        "| ellipsoids | interpolation | C p50 (us) | C p95 (us) | Python p50 (us) | Python p95 (us) "
        "| speed-up | object text/data/bss (B) | static memory (B) | same statuses | max abs diff u |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in result["records"]:
        size = (f"{r['text_bytes']}/{r['data_bytes']}/{r['bss_bytes']}" if "text_bytes" in r
                else f"{r['object_file_bytes']} (file)")
        lines.append(
            f"| {r['n_ellipsoids']} | {'on' if r['interpolate'] else 'off'} | {1e6 * r['c_p50_s']:.3f} | "
            f"{1e6 * r['c_p95_s']:.3f} | {1e6 * r['python_p50_s']:.1f} | {1e6 * r['python_p95_s']:.1f} | "
            f"{r['speedup_p50']:.0f}x | {size} | {r['static_bytes']} ({r['table_bytes']} tables + "
            f"{r['workspace_bytes']} workspace) | {r['same_statuses']} | {r['max_abs_diff_u']:.1e} |"
        )
    lines.append("")
    lines.append(machine_line(result["machine"]))
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-ellipsoids", type=int, default=15, help="ellipsoids in the table")
    parser.add_argument("--steps", type=int, default=1000, help="closed-loop states to look up")
    parser.add_argument("--batches", type=int, default=200, help="timed batches of the C driver")
    parser.add_argument("--calls", type=int, default=1000, help="calls per batch")
    parser.add_argument("--out", help="write the result as JSON to this file")
    args = parser.parse_args(argv)
    if min(args.n_ellipsoids, args.steps, args.batches, args.calls) < 1 or args.steps > 100_000:
        parser.error("--n-ellipsoids, --batches and --calls must be >= 1, --steps in 1..100000")
    result = run(args.n_ellipsoids, args.steps, args.batches, args.calls)
    write_result(result, format_table(result), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
