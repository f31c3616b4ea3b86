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
) -> Path | None:
    """The region boundary of every method (a polygon through ``t_i d_i``) and its closed loop.

    Returns the path written, or ``None`` when no method has a region.
    """
    drawn = {m: np.asarray(p) for m, p in points.items() if p}
    if not drawn:
        return None
    fig = Figure(figsize=(8.5, 6.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    styles = run_styles(len(drawn))
    for (method, pts), style in zip(drawn.items(), styles, strict=True):
        closed = np.vstack([pts, pts[:1]])
        ax.plot(closed[:, 0], closed[:, 1], label=method, **style)
        traj = trajectories.get(method)
        if traj:
            tr = np.asarray(traj)
            ax.plot(tr[:, 0], tr[:, 1], color=style["color"], lw=0.6, ls=":", marker=".", ms=2)
    ax.plot([x0[0]], [x0[1]], "k*", ms=10, label="x0")
    ax.set_xlabel("x1")
    ax.set_ylabel("x2")
    ax.grid(True, lw=0.3)
    add_legend(ax)
    wrapped_title(
        fig,
        f"{problem}: largest certified multiple along each direction (boundary), closed loop on the "
        "nominal plant (dotted)",
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path


def plot_summary(problems: Sequence[str], methods: Sequence[str], region: np.ndarray, cost: np.ndarray,
                 path: Path) -> Path | None:
    """Two heat maps, problem x method: region and closed-loop cost, each over Kothare's
    (``region`` and ``cost`` of shape ``(len(problems), len(methods))``, NaN where unknown)."""
    if not problems or not methods:
        return None
    fig = Figure(figsize=(11.0, 1.2 + 0.55 * len(problems) * 2), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1)
    for ax, data, what in (
        (axes[0], region, "region / Kothare's (geometric mean over directions; > 1: larger)"),
        (axes[1], cost, "closed-loop cost on the nominal plant / Kothare's (< 1: cheaper)"),
    ):
        shown = np.log2(data)
        lim = max(1.0, float(np.nanmax(np.abs(shown)))) if np.isfinite(shown).any() else 1.0
        im = ax.imshow(
            shown, cmap="coolwarm_r" if ax is axes[0] else "coolwarm", vmin=-lim, vmax=lim, aspect="auto"
        )
        ax.set_xticks(range(len(methods)), methods, rotation=20, fontsize=8)
        ax.set_yticks(range(len(problems)), problems, fontsize=8)
        for i in range(len(problems)):
            for j in range(len(methods)):
                text = "-" if not np.isfinite(data[i, j]) else f"{data[i, j]:.3g}"
                ax.text(j, i, text, ha="center", va="center", fontsize=7)
        ax.set_title(what, fontsize=9)
        fig.colorbar(im, ax=ax, label="log2 of the ratio")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path
