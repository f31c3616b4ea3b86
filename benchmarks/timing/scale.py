"""The scale section of ``rmpc timing``: how an online robust MPC solve grows with the state.

Plants: the flexible satellite of :class:`models.FlexibleSatellite` (Di Gennaro's modes, the hub
inertia **assumed**) linearised at zero attitude, ZOH at ``Ts = 0.05`` s, with
0, 2, 4 and 7 modes: 6, 10, 14 and 20 states (0 modes is the rigid hub). The published set has
4 modes; modes 5-7 are **assumed** here, for the size only: frequencies 3.3, 4.2 and 5.1 rad/s,
damping 0.03, and the coupling rows of modes 2-4 halved (the mass matrix stays positive
definite; the constructor checks it). Polytope of the hub-torque effectiveness: 2 vertices
``B`` x 0.8 and x 1.2; 8 vertices each axis' torque column x 0.8 or x 1.2 independently.
``Q1 = diag(100 I6, I_2N)``, ``R = I3``, peak bound 2 N m per axis, initial attitude 10 deg
off (the flexible satellite's problem at 4 modes).

At the states of one closed loop driven by the default path (the toolkit's IPM, warm-started,
on vertex 0), every path solves the same states, interleaved state by state: the IPM warm
(default) and cold, Clarabel's own API (``delta_shared``), cvxpy + SCS at SCS's default
tolerances for a few states (up to 10 states: :data:`SCS_MAX_STATES`), and cvxpy + Clarabel
(built once, Clarabel's defaults) on the textbook LMIs (``standard``) and on the delta form for
the first ``cvxpy_steps`` states (up to 14 states: :data:`CVXPY_MAX_STATES`). Records: p50 / p95 /
max time per solve, median iterations, statuses, and ``gamma`` against Clarabel's (relative).
Not a controller benchmark: the loop only supplies realistic states.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from benchmarks.core.machine import percentiles
from benchmarks.reports.sections import statuses
from benchmarks.timing.common import SCS_OPTIONS

__all__ = ["SCALE_SIZES", "SCALE_VERTICES", "plot_scale", "scale_figure", "scale_problem", "time_scale"]

SCALE_SIZES: tuple[int, ...] = (6, 10, 14, 20)
SCALE_VERTICES: tuple[int, ...] = (2, 8)
SCALE_DT = 0.05
U_PEAK = 2.0
#: Modes 5-7 (**assumed**, for the 20-state size only): frequency (rad/s), damping, coupling row
#: of the published mode it halves.
EXTRA_MODES: tuple[tuple[float, float, int], ...] = ((3.3, 0.03, 1), (4.2, 0.03, 2), (5.1, 0.03, 3))
#: SCS only up to this size: one solve took 4.4 s at 6 states and 29 s at 14 (2 vertices, load ~7).
SCS_MAX_STATES = 10
#: cvxpy + Clarabel only up to this size: one solve took 250-270 s at 20 states, 8 vertices (load ~1).
CVXPY_MAX_STATES = 14


def _satellite(n_modes: int) -> Any:
    from models import FlexibleSatellite
    from models.flexible.parameters import (
        DI_GENNARO_COUPLING,
        DI_GENNARO_DAMPING,
        DI_GENNARO_FREQUENCIES,
        DI_GENNARO_INERTIA,
    )

    if n_modes <= len(DI_GENNARO_FREQUENCIES):
        return FlexibleSatellite.di_gennaro(n_modes)
    extra = EXTRA_MODES[: n_modes - len(DI_GENNARO_FREQUENCIES)]
    freq = list(DI_GENNARO_FREQUENCIES) + [e[0] for e in extra]
    damp = list(DI_GENNARO_DAMPING) + [e[1] for e in extra]
    coupling = [list(r) for r in DI_GENNARO_COUPLING] + [
        [0.5 * c for c in DI_GENNARO_COUPLING[e[2]]] for e in extra]
    return FlexibleSatellite(DI_GENNARO_INERTIA, freq, damp, coupling)


def scale_problem(n_states: int, n_vertices: int) -> dict[str, Any]:
    """The keyword arguments of :class:`lmi.KothareProblem` (without the back-end) and ``x0``."""
    if n_states not in SCALE_SIZES:
        raise ValueError(f"n_states must be one of {SCALE_SIZES}, got {n_states!r}")
    if n_vertices not in SCALE_VERTICES:
        raise ValueError(f"n_vertices must be one of {SCALE_VERTICES}, got {n_vertices!r}")
    n_modes = (n_states - 6) // 2
    a, b = _satellite(n_modes).discretize(dt=SCALE_DT)
    if n_vertices == 2:
        gains = [np.full(3, 0.8), np.full(3, 1.2)]
    else:
        gains = [np.array([gx, gy, gz]) for gx in (0.8, 1.2) for gy in (0.8, 1.2) for gz in (0.8, 1.2)]
    x0 = np.zeros(n_states)
    x0[:3] = np.deg2rad(10.0) / np.sqrt(3.0)
    return {
        "A": np.array([a] * len(gains)), "B": np.array([b * g[None, :] for g in gains]),
        "Q": np.diag([100.0] * 6 + [1.0] * (n_states - 6)), "R": np.eye(3), "dt": SCALE_DT,
        "input_constraint": "peak", "u_max": U_PEAK, "x0": x0,
    }


def _states(kwargs: dict[str, Any], x0: np.ndarray, steps: int) -> list[np.ndarray]:
    from lmi import KothareProblem

    prob = KothareProblem(**kwargs)
    a, b = kwargs["A"][0], kwargs["B"][0]
    gain = np.zeros((b.shape[1], a.shape[0]))
    x, out = x0.copy(), []
    for _ in range(steps):
        out.append(x.copy())
        sol = prob.solve(x)
        if sol.ok:
            gain = sol.F
        x = a @ x + b @ (gain @ x)
    return out


def time_scale(steps: int, sizes: Sequence[int] = SCALE_SIZES, vertices: Sequence[int] = SCALE_VERTICES,
               scs_steps: int = 2, progress: Any = None, cvxpy_steps: int = 0) -> dict[str, Any]:
    """Time every path at every size and vertex count; returns ``{"records", "samples"}``."""
    from lmi import KothareProblem

    records: list[dict[str, Any]] = []
    samples: dict[str, np.ndarray] = {}
    for n_states in sizes:
        for count in vertices:
            spec = scale_problem(n_states, count)
            x0 = spec.pop("x0")
            states = _states(spec, x0, steps)
            paths = [
                ("ipm", "delta_shared", {"backend": "ipm"}, steps,
                 "defaults, warm-started (fallback to Clarabel on)"),
                ("ipm-cold", "delta_shared", {"backend": "ipm", "solver_options": {"warm_start": False}},
                 steps, "defaults, every solve cold"),
                ("clarabel", "delta_shared", {"backend": "clarabel"}, steps,
                 "Clarabel's own API, defaults (1e-8)"),
            ]
            if scs_steps and n_states <= SCS_MAX_STATES:
                scs = {"backend": "cvxpy", "solver": "SCS", "solver_options": SCS_OPTIONS}
                paths.append(("cvxpy:SCS", "delta", scs, min(scs_steps, steps),
                              f"cvxpy built once; SCS {SCS_OPTIONS}"))
            if cvxpy_steps and n_states <= CVXPY_MAX_STATES:
                cvx = {"backend": "cvxpy", "solver": "CLARABEL"}
                for formulation, what in (("standard", "the textbook LMIs"), ("delta", "the delta form")):
                    paths.append(("cvxpy:CLARABEL", formulation, cvx, min(cvxpy_steps, steps),
                                  f"cvxpy built once, {what}; Clarabel's defaults"))
            built = []
            for name, formulation, opts, limit, settings in paths:
                start = time.perf_counter()
                prob = KothareProblem(**spec, formulation=formulation, **opts)
                built.append({"name": name, "formulation": formulation, "prob": prob, "limit": limit,
                              "settings": settings,
                              "setup_s": time.perf_counter() - start, "times": [], "its": [],
                              "gammas": [], "statuses": {}})
            for k, x in enumerate(states):  # interleaved: load changes hit every path alike
                for path in built:
                    if k >= path["limit"]:
                        continue
                    start = time.perf_counter()
                    sol = path["prob"].solve(x)
                    path["times"].append(time.perf_counter() - start)
                    path["its"].append(sol.iterations)
                    path["gammas"].append(sol.gamma if sol.ok else np.nan)
                    path["statuses"][sol.status] = path["statuses"].get(sol.status, 0) + 1
            ref = np.asarray(built[2]["gammas"], dtype=float)
            for path in built:
                vals = np.asarray(path["gammas"], dtype=float)
                both = np.isfinite(vals) & np.isfinite(ref[: vals.size])
                err = (float(np.max(np.abs(vals[both] / ref[: vals.size][both] - 1.0)))
                       if np.any(both) else None)
                its = [i for i in path["its"] if i is not None]
                key = f"Scale|{path['name']}|{path['formulation']}|{count}|{n_states}"
                samples[key] = np.asarray(path["times"])
                records.append({
                    "problem": "Scale", "backend": path["name"], "formulation": path["formulation"],
                    "n_states": n_states, "vertices": count, "steps": len(path["times"]),
                    **percentiles(path["times"]), "setup_s": path["setup_s"],
                    "iterations_p50": float(np.median(its)) if its else None,
                    "status_counts": path["statuses"], "max_rel_err": err,
                    "error_reference": "Clarabel (defaults) at the same states", "settings": path["settings"],
                })
            if progress is not None:
                progress.advance(f"scale {n_states} states {count} vertices")
    return {"records": records, "samples": samples}


def format_scale_markdown(records: Sequence[dict[str, Any]], plot_name: str | None) -> list[str]:
    """The report's scale section (Markdown lines)."""
    if not records:
        return []
    lines = [
        "## Scale (flexible satellite, 6-20 states; see benchmarks.timing.scale)", "",
        "The flexible satellite's problem (ZOH 0.05 s, Q1 = diag(100 I6, I), R = I3, peak 2 N m, 10 deg "
        "off) with 0, 2, 4, 7 modes (modes 5-7 assumed); hub-torque effectiveness 0.8/1.2 (2 vertices: "
        "all axes together, 8: per axis). Error = max |gamma / gamma_clarabel - 1|.", "",
        "| states | vertices | path | formulation | steps | p50 (ms) | p95 (ms) | max (ms) | iterations p50 "
        "| statuses "
        "| max rel err gamma | path p50 / ipm p50 |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    fast = {(r["n_states"], r["vertices"]): r["p50_s"] for r in records if r["backend"] == "ipm"}
    for r in records:
        it = "n/a" if r["iterations_p50"] is None else f"{r['iterations_p50']:g}"
        err = "n/a" if r["max_rel_err"] is None else f"{r['max_rel_err']:.1e}"
        ratio = r["p50_s"] / fast[(r["n_states"], r["vertices"])]
        counts = statuses(r["status_counts"])
        lines.append(
            f"| {r['n_states']} | {r['vertices']} | {r['backend']} | {r['formulation']} | {r['steps']} "
            f"| {1e3 * r['p50_s']:.1f} "
            f"| {1e3 * r['p95_s']:.1f} | {1e3 * r['max_s']:.1f} | {it} | {counts} | {err} | {ratio:.1f}x |")
    lines.append("")
    if plot_name:
        lines += [f"![time per solve against state dimension]({plot_name})", ""]
    return lines


def scale_figure(records: Sequence[dict[str, Any]]) -> Figure:
    """p50 (markers and lines) and p95 (bars) of each path against the state dimension, log axis.

    Parameters
    ----------
    records : sequence of dict
        The scale records: ``backend``, ``formulation``, ``vertices``, ``n_states``, ``p50_s``
        and ``p95_s``.

    Returns
    -------
    matplotlib.figure.Figure
        One panel, one error-bar line per (backend, formulation, vertex count) that has records.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    styles = {2: "-", 8: "--"}
    for backend, formulation in dict.fromkeys((r["backend"], r["formulation"]) for r in records):
        for count in sorted({r["vertices"] for r in records}):
            recs = sorted((r for r in records if r["backend"] == backend and r["formulation"] == formulation
                           and r["vertices"] == count),
                          key=lambda r: r["n_states"])
            if not recs:
                continue
            xs = [r["n_states"] for r in recs]
            p50 = np.array([r["p50_s"] for r in recs])
            p95 = np.array([r["p95_s"] for r in recs])
            ax.errorbar(xs, p50, yerr=[np.zeros_like(p50), np.maximum(p95 - p50, 0.0)], marker="o",
                        linestyle=styles.get(count, ":"), capsize=3,
                        label=f"{backend} {formulation}, {count} vertices")
    ax.set_yscale("log")
    ax.set_xlabel("state dimension")
    ax.set_ylabel("time per solve (s): p50, bar to p95")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return fig


def plot_scale(records: Sequence[dict[str, Any]], path: Path) -> Path:
    """Write :func:`scale_figure` as a PNG at ``path`` (110 dpi) and return ``path``."""
    scale_figure(records).savefig(path, dpi=110)
    return Path(path)
