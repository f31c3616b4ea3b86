"""Per-solve time of MUP's method keys on the toolkit's solver against the same LMIs through cvxpy.

Run as ``python -m dev.mup_keys_timing [KEY,KEY,...]`` (default: ``ding`` and the four
``*_soft_con`` keys, with ``wan``, ``mao`` and ``cao`` beside them). On Kothare's example 2 and
MUP's demo system (:func:`benchmarks.suites.methods_problems.build_problem`), each key's RMPC is
built twice, ``backend="ipm"`` (the toolkit's interior-point method) and ``backend="cvxpy"``
(cvxpy + Clarabel on the same LMIs), and both solve the same 26 states alternately, state by
state, so that both see the same machine load: the closed loop of the ipm's law (clipped to the
bound) on the nominal plant from ``x0``, restarted from ``0.9^k x0`` when ``||x|| < 0.05
||x0||``. Printed per key: the median wall time of the 25 warm solves (the first, cold, solve
left out) per back-end, how many of the 26 were ``"optimal"`` and certified, and the ratio. The
soft-constrained keys take MUP's demo soft limits (``u_sl = 0.4``, ``y_sl = [1; 0.5]``, ``Wsu =
1e4``, ``Wsy = 1e2 I``) on MUP's demo and ``u_sl = 0.2``, ``Wsu = 1e3`` on example 2.
"""

from __future__ import annotations

import os
import sys
import time
import warnings

import numpy as np

from benchmarks.suites.methods_problems import build_problem
from rmpc import RMPC

MUP_SOFT = {"u": [1e4], "u_limit": [0.4], "y": [1e2, 1e2], "y_limit": [1.0, 0.5]}
EX2_SOFT = {"u": [1e3], "u_limit": [0.2]}
DEFAULT_KEYS = ("ding", "kothare_soft_con", "wan_soft_con", "cao_soft_con", "wan_cao_soft_con",
                "wan", "mao", "cao")
STATES = 26


def time_key(name: str, key: str) -> str:
    """One line: the median warm solve time per back-end on problem ``name``."""
    p = build_problem(name)
    a_true, b_true = p.true_plant
    kw: dict = {"Q": p.Q, "R": p.R, "u_max": p.u_max}
    if p.output_matrix is not None:
        kw.update(output_matrix=p.output_matrix, y_max=p.y_max)
    if key.endswith("_soft_con"):
        kw["soft"] = MUP_SOFT if name == "mup_demo" else EX2_SOFT
    ctrls = {b: RMPC.from_method(key, p.plant, backend=b, **kw) for b in ("ipm", "cvxpy")}
    times: dict[str, list[float]] = {b: [] for b in ctrls}
    ok = dict.fromkeys(ctrls, 0)
    x = p.x0.copy()
    for j in range(STATES):
        sols = {}
        for b, ctrl in ctrls.items():
            start = time.perf_counter()
            sols[b] = ctrl.problem.solve(x)
            if j:
                times[b].append(time.perf_counter() - start)
            cert = sols[b].certificate
            ok[b] += sols[b].status == "optimal" and cert is not None and cert.ok
        x = a_true @ x + b_true @ np.clip(sols["ipm"].F @ x, -p.u_max, p.u_max)
        if np.linalg.norm(x) < 0.05 * np.linalg.norm(p.x0):
            x = p.x0 * 0.9 ** (j + 1)
    med = {b: float(np.median(v)) for b, v in times.items()}
    return (f"{name:12s} {key:18s} ipm {1e3 * med['ipm']:6.2f} ms "
            f"({ok['ipm']}/{STATES} optimal+certified)  cvxpy {1e3 * med['cvxpy']:6.2f} ms "
            f"({ok['cvxpy']}/{STATES})  ratio {med['cvxpy'] / med['ipm']:4.1f}x")


def main(argv: list[str]) -> None:
    keys = argv[0].split(",") if argv else list(DEFAULT_KEYS)
    warnings.simplefilter("ignore")
    print(f"load average {os.getloadavg()}, {os.cpu_count()} cpus", flush=True)
    for name in ("kothare_ex2", "mup_demo"):
        for key in keys:
            print(time_key(name, key), flush=True)
    print(f"load average {os.getloadavg()}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
