"""Warm per-solve time of the C core (:mod:`lmi.ccore`) against the Python ipm, same states, one run.

For paper P's satellite at 2 and 8 vertices (:func:`benchmarks.timing.common.polytope`), without
and with the input ellipsoid (``u_max`` = paper P's torque limit): the Python controller
(:class:`rmpc.RMPC`, back-end ``"ipm"``, its iterations in the numba kernels) runs a closed loop on
the nominal model and its states are written to a file; the same controller with the package's
default ``core="auto"`` (the C core :mod:`lmi.ccore.runtime` calls, where built) solves at the same
states in the same process; the C driver (``lmi/ccore/driver.c``, compiled with each set of flags)
solves at the same states in a fresh process and times each call with ``clock_gettime`` (wall and
thread CPU time). The first (cold) solve is left out of both. Reported: p50/p95 per solve, the
largest gamma and ``u`` differences, the object-code size (``size`` of ``ipm.o`` + ``dense.o``)
and the static workspace, the machine and its load before and after.

With ``--phases``, one more build (``-O2 -DKOTHARE_PHASE_TIMES``, see ``lmi/ccore/ipm.h``) at the
same states reports where a warm solve's time goes: the NT scaling with ``P`` formed, ``H = P'P``,
the Cholesky factor and its pivot test, the QR of ``P``, the predictor-corrector step (its Newton
solves and step lengths) and the rest (stopping tests, data, certificate), per solve and per entry.

Run: ``python -m benchmarks.timing.ccore [--steps N] [--phases] [--out FILE.json]``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import tempfile
import time
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.machine import machine_info
from toolkit_common.errors import ConfigError

__all__ = ["FLAG_SETS", "PHASES", "main", "time_case"]

#: Compiler flags timed: the tests' flags, and the same with the host's vector instructions.
FLAG_SETS = {"O2": ["-O2"], "O3-native": ["-O3", "-march=native"]}
_WARN = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]

#: The phases of a ``-DKOTHARE_PHASE_TIMES`` build, in the order of ``KOTHARE_PHASE_*`` (ipm.h).
PHASES = ("scaling_and_p", "schur_h", "cholesky", "qr", "newton_step", "newton_solves", "step_lengths",
          "solve")


def _stats(values: list[float]) -> dict[str, float]:
    arr = np.asarray(values, dtype=float)
    return {"p50_ms": float(np.percentile(arr, 50)) * 1e3, "p95_ms": float(np.percentile(arr, 95)) * 1e3}


def _controller(n_vertices: int, bound: bool, core: str = "numba") -> Any:
    from benchmarks.families.rigid import defaults
    from benchmarks.timing.common import polytope
    from rmpc import RMPC

    plant = polytope(n_vertices)
    q = np.diag(defaults.CONTROLLER_DEFAULTS["RMPC"]["Q_diag"])
    r = np.diag(defaults.CONTROLLER_DEFAULTS["RMPC"]["R_diag"])
    kw = {"u_max": defaults.U_MAX, "input_constraint": "ellipsoid"} if bound else {}
    return RMPC(plant, q, r, solver_options={"core": core}, **kw), plant


def _phases(folder: Path, solves: int) -> dict[str, Any]:
    """Per-phase thread CPU time of the driver built with ``-O2 -DKOTHARE_PHASE_TIMES`` at the
    states in ``folder`` (the first, cold, solve left out): per warm solve (ms) and per entry to
    the phase (us), the entries, and the rest of a solve outside the iteration's phases."""
    exe = folder / "driver_phases"
    srcs = [str(folder / f) for f in ("ipm.c", "dense.c", "driver.c")]
    subprocess.run(["cc", *_WARN, "-O2", "-DKOTHARE_PHASE_TIMES", "-o", str(exe), *srcs, "-lm"], check=True)
    out = subprocess.run([str(exe), str(folder / "states.txt")], check=True, capture_output=True, text=True)
    line = [row for row in out.stderr.splitlines() if row.startswith("phases ")][-1].split()[1:]
    sec = dict(zip(PHASES, (float(v) for v in line[:len(PHASES)]), strict=True))
    count = dict(zip(PHASES, (int(v) for v in line[len(PHASES):]), strict=True))
    outside = ("scaling_and_p", "schur_h", "cholesky", "qr", "newton_step")
    rest = sec["solve"] - sum(sec[name] for name in outside)
    return {
        "flags": "-O2 -DKOTHARE_PHASE_TIMES", "warm_solves": solves,
        "per_solve_ms": {**{name: sec[name] / solves * 1e3 for name in PHASES}, "rest": rest / solves * 1e3},
        "per_entry_us": {name: (sec[name] / count[name] * 1e6 if count[name] else 0.0) for name in PHASES},
        "entries": count,
    }


def time_case(n_vertices: int, bound: bool, steps: int, folder: Path, phases: bool = False) -> dict[str, Any]:
    """Time one problem: the Python closed loop, then the C driver at its states per flag set
    (and, with ``phases``, the per-phase times of a ``-DKOTHARE_PHASE_TIMES`` build)."""
    from lmi.ccore.generate import write_solver
    from models import RigidSatellite

    ctrl, plant = _controller(n_vertices, bound)
    x = RigidSatellite.paper_p().initial_state()
    a, b = plant.nominal
    states, gammas, inputs, wall, cpu, iters = [], [], [], [], [], []
    for _ in range(steps):
        w0, c0 = time.perf_counter(), time.thread_time()
        sol = ctrl.solve(x)
        c1, w1 = time.thread_time(), time.perf_counter()
        if sol.status != "optimal":
            raise ConfigError("--steps", "a closed loop of optimal solves",
                              f"{sol.status} at step {len(states)}")
        u = sol.F @ x
        states.append(x.copy())
        gammas.append(sol.gamma)
        inputs.append(u)
        wall.append(w1 - w0)
        cpu.append(c1 - c0)
        iters.append(sol.iterations)
        x = a @ x + b @ u
    # the C core the package calls (lmi.ccore.runtime) at the same states, when it is built
    core_ctrl, _ = _controller(n_vertices, bound, "auto")
    core_wall, core_cpu, core_gap = [], [], 0.0
    for x_k, g_k in zip(states, gammas, strict=True):
        w0, c0 = time.perf_counter(), time.thread_time()
        sol = core_ctrl.solve(x_k)
        c1, w1 = time.thread_time(), time.perf_counter()
        core_wall.append(w1 - w0)
        core_cpu.append(c1 - c0)
        core_gap = max(core_gap, abs(sol.gamma / g_k - 1.0))
    write_solver(ctrl, folder)
    with resources.as_file(resources.files("lmi.ccore") / "driver.c") as src:
        shutil.copyfile(src, folder / "driver.c")
    np.savetxt(folder / "states.txt", np.array(states))
    record: dict[str, Any] = {
        "vertices": n_vertices, "input_bound": "ellipsoid" if bound else "none",
        "variables": ctrl.problem._backend._solver.n, "steps": steps,
        "python": {"wall": _stats(wall[1:]), "cpu": _stats(cpu[1:]),
                   "iterations_p50": float(np.median(iters[1:]))},
        "python_core": {"core": core_ctrl.problem._backend.core, "wall": _stats(core_wall[1:]),
                        "cpu": _stats(core_cpu[1:]), "max_gamma_rel": core_gap},
        "c": {},
    }
    for label, flags in FLAG_SETS.items():
        exe = folder / f"driver_{label}"
        srcs = [str(folder / f) for f in ("ipm.c", "dense.c", "driver.c")]
        subprocess.run(["cc", *_WARN, *flags, "-o", str(exe), *srcs, "-lm"], check=True)
        out = subprocess.run([str(exe), str(folder / "states.txt")], check=True, capture_output=True,
                             text=True)
        rows = [line.split() for line in out.stdout.splitlines()]
        m = inputs[0].size
        status = [int(r[0]) for r in rows]
        gamma_c = np.array([float(r[1]) for r in rows])
        u_c = np.array([[float(v) for v in r[3:3 + m]] for r in rows])
        c_wall = [int(r[-2]) * 1e-9 for r in rows]
        c_cpu = [int(r[-1]) * 1e-9 for r in rows]
        objs = []
        for name in ("ipm", "dense"):
            obj = folder / f"{name}_{label}.o"
            subprocess.run(["cc", *_WARN, *flags, "-c", "-o", str(obj), str(folder / f"{name}.c")],
                           check=True)
            objs.append(str(obj))
        size = subprocess.run(["size", *objs], check=True, capture_output=True, text=True).stdout.splitlines()
        text_data = sum(int(line.split()[0]) + int(line.split()[1]) for line in size[1:])
        bss = sum(int(line.split()[2]) for line in size[1:])
        record["c"][label] = {
            "flags": " ".join(flags), "statuses_nonzero": int(sum(s != 0 for s in status)),
            "wall": _stats(c_wall[1:]), "cpu": _stats(c_cpu[1:]),
            "iterations_p50": float(np.median([int(r[2]) for r in rows][1:])),
            "max_gamma_rel": float(np.max(np.abs(gamma_c - gammas) / np.abs(gammas))),
            "max_u_abs": float(np.max(np.abs(u_c - np.array(inputs)))),
            "object_text_data_bytes": text_data, "static_bss_bytes": bss,
        }
    if phases:
        record["phases"] = _phases(folder, steps - 1)
    return record


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run every case and print a table; ``--out`` writes the records as JSON."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.timing.ccore",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=40, help="closed-loop states per case (default 40)")
    parser.add_argument("--out", type=Path, default=None, help="write the records here (JSON)")
    parser.add_argument("--phases", action="store_true",
                        help="also time the phases of a warm solve (a -DKOTHARE_PHASE_TIMES build)")
    args = parser.parse_args(argv)
    if args.steps < 3:
        raise ConfigError("--steps", "an integer >= 3", repr(args.steps))
    if shutil.which("cc") is None:
        raise ConfigError("cc", "a C compiler on the PATH", "none")
    report: dict[str, Any] = {"machine_before": machine_info(), "cases": []}
    with tempfile.TemporaryDirectory() as tmp:
        for n_vertices in (2, 8):
            for bound in (False, True):
                folder = Path(tmp) / f"v{n_vertices}_{int(bound)}"
                report["cases"].append(time_case(n_vertices, bound, args.steps, folder, phases=args.phases))
    report["machine_after"] = machine_info()
    print(f"machine: {report['machine_before']['platform']}, {report['machine_before']['cpu_count']} CPUs, "
          f"load {report['machine_before']['load_average']} -> {report['machine_after']['load_average']}")
    print("| vertices | bound | vars | path | wall p50 / p95 ms | cpu p50 / p95 ms | iters p50 | "
          "max gamma rel | max u abs | .o text+data B | bss B |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for case in report["cases"]:
        py = case["python"]
        print(f"| {case['vertices']} | {case['input_bound']} | {case['variables']} | python ipm | "
              f"{py['wall']['p50_ms']:.2f} / {py['wall']['p95_ms']:.2f} | {py['cpu']['p50_ms']:.2f} / "
              f"{py['cpu']['p95_ms']:.2f} | {py['iterations_p50']:.0f} | | | | |")
        pc = case["python_core"]
        print(f"| {case['vertices']} | {case['input_bound']} | {case['variables']} | "
              f"python, core {pc['core']} | "
              f"{pc['wall']['p50_ms']:.2f} / {pc['wall']['p95_ms']:.2f} | {pc['cpu']['p50_ms']:.2f} / "
              f"{pc['cpu']['p95_ms']:.2f} | | {pc['max_gamma_rel']:.1e} | | | |")
        for label, c in case["c"].items():
            print(f"| {case['vertices']} | {case['input_bound']} | {case['variables']} | C {label} | "
                  f"{c['wall']['p50_ms']:.2f} / {c['wall']['p95_ms']:.2f} | {c['cpu']['p50_ms']:.2f} / "
                  f"{c['cpu']['p95_ms']:.2f} | {c['iterations_p50']:.0f} | {c['max_gamma_rel']:.1e} | "
                  f"{c['max_u_abs']:.1e} | {c['object_text_data_bytes']} | {c['static_bss_bytes']} |")
    if args.phases:
        _print_phases(report["cases"])
    if args.out is not None:
        args.out.write_text(json.dumps(report, indent=2))
    return report


def _print_phases(cases: list[dict[str, Any]]) -> None:
    names = ("scaling_and_p", "schur_h", "cholesky", "qr", "newton_step", "newton_solves", "step_lengths",
             "rest", "solve")
    print("\nphases of a warm solve (-O2 -DKOTHARE_PHASE_TIMES, thread CPU time): ms per solve "
          "(us per entry; entries per solve); newton_solves and step_lengths are part of newton_step")
    print("| vertices | bound | " + " | ".join(names) + " |")
    print("|---|---|" + "---|" * len(names))
    for case in cases:
        ph = case["phases"]
        cells = []
        for name in names:
            ms = ph["per_solve_ms"][name]
            if name == "rest":
                cells.append(f"{ms:.2f}")
            else:
                per = ph["entries"][name] / ph["warm_solves"]
                cells.append(f"{ms:.2f} ({ph['per_entry_us'][name]:.0f}; {per:.1f})")
        print(f"| {case['vertices']} | {case['input_bound']} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
