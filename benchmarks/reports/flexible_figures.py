"""Figures of the flexible-satellite suite: the rotation error (log axis), the hub torques, the
first modal coordinate and the PZT voltages, one line per closed loop.

:func:`flexible_group_figure` builds the :class:`matplotlib.figure.Figure` (matplotlib's object
API on an Agg canvas, no pyplot state); :func:`plot_flexible_group` writes it as a PNG.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["flexible_group_figure", "plot_flexible_group"]


def flexible_group_figure(items: Sequence[tuple[str, dict]], title: str) -> Figure:
    """Four panels for the runs of one experiment.

    Parameters
    ----------
    items : sequence of (name, trace)
        The line's name and the run's trace: ``t``, ``error_deg`` (rotation error), ``u`` (applied
        hub torques, N m), ``eta`` (modal coordinates) and ``v`` (applied PZT commands).
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        Four panels sharing the time axis (rotation error on a log axis, ``max_i |u_i|``, ``eta_1``,
        ``max_j |v_j|``), one line per run in each panel where the run has that signal.
    """
    fig = Figure(figsize=(9.0, 11.0))
    FigureCanvasAgg(fig)
    ax_e, ax_u, ax_m, ax_v = fig.subplots(4, 1, sharex=True)
    for name, trace in items:
        t = np.asarray(trace["t"])
        ax_e.semilogy(t, np.maximum(np.asarray(trace["error_deg"]), 1e-6), label=name, lw=1.0)
        u = np.asarray(trace["u"])
        if u.size:
            ax_u.plot(t[: u.shape[0]], np.abs(u).max(axis=1), label=name, lw=0.8)
        eta = np.asarray(trace["eta"])
        if eta.size:
            ax_m.plot(t, eta[:, 0], label=name, lw=0.8)
        v = np.asarray(trace["v"])
        if v.size:
            ax_v.plot(t[: v.shape[0]], np.abs(v).max(axis=1), label=name, lw=0.8)
    ax_e.set_ylabel("rotation error (deg)")
    ax_u.set_ylabel("max_i |u_i| (N m)")
    ax_m.set_ylabel("eta_1 (kg^1/2 m)")
    ax_v.set_ylabel("max_j |v_j| (PZT)")
    ax_v.set_xlabel("t (s)")
    for ax in (ax_e, ax_u, ax_m, ax_v):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def plot_flexible_group(items: Sequence[tuple[str, dict]], path: Path, title: str) -> Path:
    """Write :func:`flexible_group_figure` as a PNG at ``path`` (80 dpi) and return ``path``.

    Parameters
    ----------
    items : sequence of (name, trace)
        As for :func:`flexible_group_figure`.
    path : Path
        The PNG to write.
    title : str
        The figure's title.
    """
    flexible_group_figure(items, title).savefig(path, dpi=80)
    return path
