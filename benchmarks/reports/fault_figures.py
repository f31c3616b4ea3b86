"""Figures of the wheel-fault suite: attitude (with the recovery band), wheel torques (commanded
and applied, with the limits) and wheel momenta per controller, with the fault windows shaded
and the rank-deficient windows hatched.

:func:`fault_case_group_figure` builds the :class:`matplotlib.figure.Figure` (matplotlib's object
API on an Agg canvas, no pyplot state); :func:`plot_fault_case_group` writes it as a PNG.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from benchmarks.families.wheel import defaults
from benchmarks.reports.figure_style import add_legend, limit_lines, wrapped_title

__all__ = ["fault_case_group_figure", "plot_fault_case_group"]


def _shade(ax: Any, windows: Sequence[tuple[float, float]], t_end: float) -> None:
    for t0, t1 in windows:
        ax.axvspan(t0, min(t1, t_end), color="tab:red", alpha=0.12, lw=0)


def _rank_windows(rec: dict) -> list[tuple[float, float]]:
    """The run's rank-deficient windows ``(t_start, t_end)`` (``metrics.faults``), if any."""
    rows = rec.get("metrics", {}).get("faults", {}).get("rank_deficient_windows") or []
    return [(float(row[0]), float(row[1])) for row in rows]


def _hatch(ax: Any, windows: Sequence[tuple[float, float]], t_end: float, label: str | None) -> None:
    for t0, t1 in windows:
        if min(t1, t_end) > t0:
            ax.axvspan(t0, min(t1, t_end), fill=False, edgecolor="0.35", hatch="//", lw=0, label=label)
            label = None


def fault_case_group_figure(
    items: Sequence[tuple[dict, dict]],
    windows: Sequence[tuple[float, float]],
    title: str,
    torque_max: float,
    momentum_max: float,
    recovery_deg: float = defaults.RECOVERY_DEG,
) -> Figure:
    """One column per run (controller): attitude (deg), wheel torques, wheel momenta.

    Parameters
    ----------
    items : sequence of (record, trace)
        The runs; traces hold ``t``, ``x`` (``[eta, w, h]``), ``u_cmd``, ``u_applied``.
    windows : sequence of (t_on, t_off)
        Fault windows, shaded in every panel.
    title : str
        The figure's title.
    torque_max, momentum_max : float
        The wheel limits, drawn as dotted lines.
    recovery_deg : float
        The recovery band (deg; the family's threshold of the recovery time), drawn as
        +-``recovery_deg`` dotted lines in the attitude panels.

    Returns
    -------
    matplotlib.figure.Figure
        A 3 x ``len(items)`` grid of panels: three attitude lines with the +-``recovery_deg``
        lines; per wheel an applied and a dashed commanded torque line with the
        +-``torque_max`` lines; per wheel a momentum line with the +-``momentum_max`` lines;
        the fault windows shaded and the run's rank-deficient windows (its record's
        ``metrics.faults.rank_deficient_windows``) hatched in every panel of its column.
    """
    n = max(len(items), 1)
    fig = Figure(figsize=(4.2 * n, 8.5), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, n, sharex="col", squeeze=False)
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:purple"]
    for col, (rec, trace) in enumerate(items):
        t, x = np.asarray(trace["t"]), np.asarray(trace["x"])
        u_cmd, u_app = np.asarray(trace["u_cmd"]), np.asarray(trace["u_applied"])
        t_u = t[: u_app.shape[0]]
        ax_a, ax_u, ax_h = axes[0, col], axes[1, col], axes[2, col]
        eta = np.degrees(x[:, :3].copy())
        eta[:, 2] = (eta[:, 2] + 180.0) % 360.0 - 180.0
        for i, name in enumerate(("roll", "pitch", "yaw")):
            ax_a.plot(t, eta[:, i], label=name, lw=1.0)
        ax_a.set_title(rec.get("label", rec.get("controller", "")), fontsize=9)
        for j in range(u_app.shape[1]):
            c = colors[j % len(colors)]
            ax_u.plot(t_u, u_app[:, j], color=c, lw=0.9, label=f"wheel {j + 1}")
            ax_u.plot(t_u, np.clip(u_cmd[:, j], -3 * torque_max, 3 * torque_max), color=c, lw=0.6, ls="--")
        for ax, lim, what in (
            (ax_a, recovery_deg, f"recovery band +-{recovery_deg:g} deg"),
            (ax_u, torque_max, "limit"),
            (ax_h, momentum_max, "limit"),
        ):
            limit_lines(ax, lim, what)
        h = x[:, 6:]
        for j in range(h.shape[1]):
            ax_h.plot(t, h[:, j], color=colors[j % len(colors)], lw=0.9)
        rank = _rank_windows(rec)
        for ax in (ax_a, ax_u, ax_h):
            _shade(ax, windows, float(t[-1]))
            _hatch(ax, rank, float(t[-1]), "rank-deficient" if ax is ax_a else None)
            ax.grid(alpha=0.3)
            ax.set_xlabel("t (s)")
            ax.xaxis.set_tick_params(labelbottom=True)
        ax_a.set_ylabel("attitude (deg)")
        ax_u.set_ylabel("wheel torque (N m)\napplied, commanded dashed")
        ax_h.set_ylabel("wheel momentum (N m s)")
        if col == 0:
            add_legend(ax_a, outside=False)
            add_legend(ax_u, outside=False)
    note = (
        " (fault windows shaded, rank-deficient windows hatched; dotted: limits and recovery band; "
        "commands clipped at 3x for display)"
    )
    wrapped_title(fig, title + note)
    return fig


def plot_fault_case_group(
    items: Sequence[tuple[dict, dict]],
    windows: Sequence[tuple[float, float]],
    path: Path,
    title: str,
    torque_max: float,
    momentum_max: float,
) -> Path:
    """Write :func:`fault_case_group_figure` as a PNG at ``path`` (90 dpi) and return ``path``.

    Parameters
    ----------
    items : sequence of (record, trace)
        The runs; traces hold ``t``, ``x`` (``[eta, w, h]``), ``u_cmd``, ``u_applied``.
    windows : sequence of (t_on, t_off)
        Fault windows, shaded in every panel.
    path : Path
        The PNG to write.
    title : str
        The figure's title.
    torque_max, momentum_max : float
        The wheel limits, drawn as dotted lines.
    """
    fault_case_group_figure(items, windows, title, torque_max, momentum_max).savefig(path, dpi=90)
    return path
