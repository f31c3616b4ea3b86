"""Figures of paper M's suite: the error angle (log axis), the torques, and the disk's torque
next to the estimates of MAB and TF-AB.

:func:`mrp_group_figure` builds the :class:`matplotlib.figure.Figure` (matplotlib's object API on
an Agg canvas, no pyplot state); :func:`plot_mrp_group` writes it as a PNG.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["mrp_group_figure", "plot_mrp_group"]


def mrp_group_figure(items: Sequence[tuple[dict, dict]], title: str) -> Figure:
    """Three panels for the runs of one experiment (one line per controller).

    Parameters
    ----------
    items : sequence of (record, trace)
        Traces hold ``t``, ``u_applied``, ``d``, ``error_angle_deg`` and, for the controllers
        with an estimator, ``torque_estimate``.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        Three panels sharing the time axis: the error angle (log axis) and ``max_i |u_i|``, one
        line per run; the disturbance torque, one dashed line per estimating run and the three
        axes of the true torque.
    """
    fig = Figure(figsize=(9.0, 9.0))
    FigureCanvasAgg(fig)
    ax_e, ax_u, ax_d = fig.subplots(3, 1, sharex=True)
    for rec, trace in items:
        t = np.asarray(trace["t"])
        name = rec["controller"]
        ax_e.semilogy(t, np.maximum(np.asarray(trace["error_angle_deg"]), 1e-12), label=name, lw=1.0)
        u = np.asarray(trace["u_applied"])
        ax_u.plot(t[: u.shape[0]], np.abs(u).max(axis=1), label=name, lw=0.9)
        if "torque_estimate" in trace:
            est = np.asarray(trace["torque_estimate"])
            ax_d.plot(t[: est.shape[0]], est[:, 0], lw=0.8, ls="--", label=f"{name} estimate (x)")
    d_rec = next((tr for _, tr in items if np.asarray(tr["d"]).size), None)
    if d_rec is not None:
        d = np.asarray(d_rec["d"])
        t = np.asarray(d_rec["t"])[: d.shape[0]]
        for i, axis in enumerate("xyz"):
            ax_d.plot(t, d[:, i], color="k", lw=1.2 - 0.3 * i, label=f"true ({axis})")
    ax_e.set_ylabel("error angle (deg)")
    ax_u.set_ylabel("max_i |u_i| (N m)")
    ax_d.set_ylabel("disturbance torque (N m)")
    ax_d.set_xlabel("t (s)")
    for ax in (ax_e, ax_u, ax_d):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def plot_mrp_group(items: Sequence[tuple[dict, dict]], path: Path, title: str) -> Path:
    """Write :func:`mrp_group_figure` as a PNG at ``path`` (90 dpi) and return ``path``.

    Parameters
    ----------
    items : sequence of (record, trace)
        As for :func:`mrp_group_figure`.
    path : Path
        The PNG to write.
    title : str
        The figure's title.
    """
    mrp_group_figure(items, title).savefig(path, dpi=90)
    return path
