"""Figures of paper M's suite: the error angle (log axis), the torques (with the torque limit and
a panel zoomed on the steady window), and each axis of the disk's torque next to the estimates
of MAB and TF-AB.

:func:`mrp_group_figure` builds the :class:`matplotlib.figure.Figure` (matplotlib's object API on
an Agg canvas, no pyplot state); :func:`plot_mrp_group` writes it as a PNG.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from benchmarks.reports.figure_style import (
    add_legend,
    limit_lines,
    note_coincident,
    run_styles,
    shade_window,
    steady_zoom,
    wrapped_title,
)

__all__ = ["mrp_group_figure", "plot_mrp_group"]

_TIME = "t (s)"


def _window(items: Sequence[tuple[dict, dict]], key: str) -> list[float] | None:
    """The first record's ``settings[key]`` window (the runs of a group share it), or ``None``."""
    for rec, _ in items:
        window = rec.get("settings", {}).get(key)
        if window is not None:
            return [float(window[0]), float(window[1])]
    return None


def _limits(items: Sequence[tuple[dict, dict]]) -> list[float]:
    """The torque limits ``u_max`` of the runs that have one (saturation other than ``none``)."""
    return sorted(
        {float(rec["settings"]["u_max"]) for rec, _ in items if rec.get("saturation", "none") != "none"}
    )


def mrp_group_figure(items: Sequence[tuple[dict, dict]], title: str) -> Figure:
    """The runs of one experiment, one colour and line style per controller in every panel.

    Parameters
    ----------
    items : sequence of (record, trace)
        Records hold ``controller``, ``saturation`` and ``settings`` (``u_max``, ``steady_window``,
        ``late_window``); traces hold ``t``, ``u_applied``, ``d``, ``error_angle_deg`` and, for
        the controllers with an estimator, ``torque_estimate``.
    title : str
        The figure's title (wrapped to the figure's width).

    Returns
    -------
    matplotlib.figure.Figure
        Left column: the error angle (log axis) and ``max_i |u_i|`` over the run, one line per
        run, with the steady window shaded and the torque limit of the runs that have one
        dotted; ``max_i |u_i|`` again, limited to the steady window (the initial transient left
        out). Right column, when the experiment has a disturbance torque or an estimate: one
        panel per axis with the true torque (black) and each estimating run's estimate, the
        late window (where the estimate's error is measured) shaded. Runs drawn on top of each
        other are named in a note of the panel.
    """
    fig = Figure(figsize=(13.0, 9.5), layout="constrained")
    FigureCanvasAgg(fig)
    has_d = any(np.asarray(tr["d"]).size or "torque_estimate" in tr for _, tr in items)
    grid = fig.add_gridspec(3, 2 if has_d else 1)
    ax_e = fig.add_subplot(grid[0, 0])
    ax_u = fig.add_subplot(grid[1, 0], sharex=ax_e)
    ax_z = fig.add_subplot(grid[2, 0])
    ax_d = [fig.add_subplot(grid[i, 1], sharex=ax_e) for i in range(3)] if has_d else []
    styles = run_styles(len(items))
    t_end = 0.0
    torque_series = []
    for (rec, trace), style in zip(items, styles, strict=True):
        t = np.asarray(trace["t"])
        t_end = max(t_end, float(t[-1]))
        name = rec["controller"]
        ax_e.semilogy(t, np.maximum(np.asarray(trace["error_angle_deg"]), 1e-12), label=name, **style)
        u = np.asarray(trace["u_applied"])
        u_max = np.abs(u).max(axis=1)
        ax_u.plot(t[: u.shape[0]], u_max, label=name, **style)
        ax_z.plot(t[: u.shape[0]], u_max, label=name, **style)
        torque_series.append((t[: u.shape[0]], u_max))
        if "torque_estimate" in trace:
            est = np.asarray(trace["torque_estimate"])
            for i, ax in enumerate(ax_d):
                ax.plot(t[: est.shape[0]], est[:, i], label=f"{name} estimate", **style)
    d_rec = next((tr for _, tr in items if np.asarray(tr["d"]).size), None)
    if d_rec is not None:
        d = np.asarray(d_rec["d"])
        t = np.asarray(d_rec["t"])[: d.shape[0]]
        for i, ax in enumerate(ax_d):
            ax.plot(t, d[:, i], color="k", lw=2.0, label="true", zorder=1)
    for u_limit in _limits(items):
        limit_lines(ax_u, u_limit, f"limit {u_limit:g} N m", both=False)
        ax_u.set_ylim(top=max(ax_u.get_ylim()[1], 1.08 * u_limit))
    steady = _window(items, "steady_window")
    if steady is not None:
        for ax in (ax_e, ax_u):
            shade_window(ax, steady, t_end, "steady window")
        steady_zoom(ax_z, steady, torque_series)
        ax_z.set_title(f"max_i |u_i| on the steady window [{steady[0]:g}, {steady[1]:g}] s", fontsize=9)
    else:
        ax_z.set_visible(False)
    late = _window(items, "late_window")
    for ax in ax_d:
        if late is not None:
            shade_window(ax, late, t_end, "estimate error window", color="tab:blue", alpha=0.08)
    ax_e.set_ylabel("error angle (deg)")
    ax_u.set_ylabel("max_i |u_i| (N m)")
    ax_z.set_ylabel("max_i |u_i| (N m)")
    for i, ax in enumerate(ax_d):
        ax.set_ylabel(f"disturbance torque, {'xyz'[i]} (N m)")
    names = [rec["controller"] for rec, _ in items]
    notes = {ax: note_coincident(ax, names) for ax in (ax_e, ax_u)}
    notes[ax_z] = note_coincident(ax_z, names, steady)
    notes.update({ax: note_coincident(ax, [f"{name} estimate" for name in names]) for ax in ax_d})
    for ax in (ax_e, ax_u, ax_z, *ax_d):
        ax.set_xlabel(_TIME)
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.grid(alpha=0.3)
        add_legend(ax, note=notes[ax])
    wrapped_title(fig, title)
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
