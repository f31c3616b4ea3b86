"""Figures of ``rmpc bench methods``: the feasible regions of the 2-state problems and a summary.

Drawn with matplotlib's object API on an Agg canvas (no pyplot state), like the other suites.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from benchmarks.reports.figure_style import add_legend, run_styles, wrapped_title

__all__ = ["plot_regions", "plot_summary"]


def plot_regions(
    problem: str,
    points: Mapping[str, Sequence[Sequence[float]] | None],
    trajectories: Mapping[str, Sequence[Sequence[float]] | None],
    x0: Sequence[float],
    path: Path,
    capped: Mapping[str, bool] | None = None,
    t_max: float | None = None,
) -> Path | None:
    """The region boundary of every method (a polygon through ``t_i d_i``) and its closed loop.

    A method whose region reached the search cap (``capped[method]``) is drawn dashed and named
    "at least", and the axes' extent is set by the other methods' regions and the closed loops;
    where every method reached the cap, no polygon is drawn and the panel says so (the cap's
    polygon is the search's limit, not a region). Returns the path written, or ``None`` when no
    method has a region.
    """
    drawn = {m: np.asarray(p) for m, p in points.items() if p}
    if not drawn:
        return None
    capped = capped or {}
    all_capped = all(capped.get(m, False) for m in drawn)
    fig = Figure(figsize=(8.5, 6.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    styles = run_styles(len(drawn))
    extent: list[np.ndarray] = [np.asarray([x0], dtype=float)]
    for (method, pts), style in zip(drawn.items(), styles, strict=True):
        at_cap = capped.get(method, False)
        if not all_capped:
            closed = np.vstack([pts, pts[:1]])
            label = f"{method} (at least: the search cap)" if at_cap else method
            look = {**style, "linestyle": "--"} if at_cap else style
            ax.plot(closed[:, 0], closed[:, 1], label=label, **look)
            if not at_cap:
                extent.append(pts)
        traj = trajectories.get(method)
        if traj:
            tr = np.asarray(traj)
            ax.plot(tr[:, 0], tr[:, 1], color=style["color"], lw=0.6, ls=":", marker=".", ms=2,
                    label=f"{method} closed loop" if all_capped else None)
            extent.append(tr)
    ax.plot([x0[0]], [x0[1]], "k*", ms=10, label="x0")
    every = np.vstack(extent)
    lo, hi = every.min(axis=0), every.max(axis=0)
    pad = 0.08 * np.maximum(hi - lo, 1e-9)
    ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])
    ax.set_ylim(lo[1] - pad[1], hi[1] + pad[1])
    ax.set_xlabel("x1")
    ax.set_ylabel("x2")
    ax.grid(True, lw=0.3)
    add_legend(ax)
    if all_capped:
        cap = f" t = {t_max:g}" if t_max is not None else ""
        title = (
            f"{problem}: every method's region reaches the search cap{cap} (regions at least that large, "
            "not drawn); closed loop on the nominal plant (dotted)"
        )
    else:
        title = (
            f"{problem}: largest certified multiple along each direction (boundary), closed loop on the "
            "nominal plant (dotted)"
        )
    wrapped_title(fig, title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path


def plot_summary(problems: Sequence[str], methods: Sequence[str], region: np.ndarray, cost: np.ndarray,
                 path: Path, capped: np.ndarray | None = None) -> Path | None:
    """Two heat maps, problem x method: region and closed-loop cost, each over Kothare's
    (``region`` and ``cost`` of shape ``(len(problems), len(methods))``, NaN where unknown).

    ``capped`` (same shape) marks region ratios that rest on a region at the search cap: written
    "at least"/"cap" in grey and kept off the colour scale, which the measured ratios set.
    """
    if not problems or not methods:
        return None
    capped = np.zeros(region.shape, dtype=bool) if capped is None else np.asarray(capped, dtype=bool)
    fig = Figure(figsize=(11.0, 1.2 + 0.55 * len(problems) * 2), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1)
    for ax, data, what in (
        (axes[0], region, "region / Kothare's (geometric mean over directions; > 1: larger; "
         "cap: a region at the search cap, a bound, uncoloured)"),
        (axes[1], cost, "closed-loop cost on the nominal plant / Kothare's (< 1: cheaper; "
         "-: no certified gain or no cost)"),
    ):
        is_region = ax is axes[0]
        shown = np.log2(data)
        if is_region:
            shown = np.where(capped, np.nan, shown)
        lim = max(1.0, float(np.nanmax(np.abs(shown)))) if np.isfinite(shown).any() else 1.0
        im = ax.imshow(
            shown, cmap="coolwarm_r" if ax is axes[0] else "coolwarm", vmin=-lim, vmax=lim, aspect="auto"
        )
        ax.set_xticks(range(len(methods)), methods, rotation=20, fontsize=8)
        ax.set_yticks(range(len(problems)), problems, fontsize=8)
        for i in range(len(problems)):
            for j in range(len(methods)):
                text = "-" if not np.isfinite(data[i, j]) else f"{data[i, j]:.3g}"
                if is_region and capped[i, j] and np.isfinite(data[i, j]):
                    text = f"cap ({data[i, j]:.3g})"
                ax.text(j, i, text, ha="center", va="center", fontsize=7)
        ax.set_title(what, fontsize=9)
        fig.colorbar(im, ax=ax, label="log2 of the ratio")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path
