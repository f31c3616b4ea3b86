"""Figures of the flexible-satellite suite: the rotation error (log axis), the hub torques (with
the torque limit and a panel zoomed on the residual window), the first modal coordinate (with
the modal bound of the runs that have one), the body rate's part above ``Lambda_1 / 2`` (where
the modes show) and, when a run drives them, the PZT commands; one colour and line style per
closed loop.

:func:`flexible_group_figure` builds the :class:`matplotlib.figure.Figure` (matplotlib's object
API on an Agg canvas, no pyplot state); :func:`plot_flexible_group` writes it as a PNG.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from benchmarks.families.flexible.metrics import flexible_metrics, highpass
from benchmarks.reports.figure_style import (
    add_legend,
    limit_lines,
    note_coincident,
    run_styles,
    shade_window,
    steady_zoom,
    wrapped_title,
)

__all__ = ["PZT_UNIT", "RESIDUAL_TAIL", "flexible_group_figure", "plot_flexible_group"]

#: Length (s) of the residual window at the end of a run: the ``tail`` of the residual metrics
#: (``rms_error_tail``, ``eta_residual``) of :func:`benchmarks.families.flexible.metrics.flexible_metrics`.
RESIDUAL_TAIL: float = float(inspect.signature(flexible_metrics).parameters["tail"].default)

_TIME = "t (s)"
#: The PZT commands enter the modal equations as forces ``Gamma_a v`` (``Gamma_a = I``, ``M = I``).
PZT_UNIT = "kg^1/2 m/s^2"


def _settings(rec: Mapping[str, Any]) -> Mapping[str, Any]:
    return rec.get("settings", {})


#: Floor of the log axis of the rate panel (rad/s).
_RATE_FLOOR = 1e-9


def _rate_hf(rec: Mapping[str, Any], trace: Mapping[str, Any]) -> np.ndarray | None:
    """``||w_hf||`` per sample (rad/s), or ``None`` without rates, modes or enough samples."""
    lam1 = _settings(rec).get("first_mode_frequency")
    if "w" not in trace or lam1 is None:
        return None
    t = np.asarray(trace["t"])
    if t.size < 2:
        return None
    hf = highpass(np.asarray(trace["w"]), float(t[1] - t[0]), float(lam1) / 2.0)
    return None if hf is None else np.linalg.norm(hf, axis=1)


def flexible_group_figure(items: Sequence[tuple[str, Mapping[str, Any], dict]], title: str) -> Figure:
    """The panels of one experiment's runs.

    Parameters
    ----------
    items : sequence of (name, record, trace)
        The line's name, the run's record (``saturation``; ``settings`` with ``u_max`` and
        ``modal_bound``) and its trace: ``t``, ``error_deg`` (rotation error), ``u`` (applied hub
        torques, N m), ``eta`` (modal coordinates) and ``v`` (applied PZT commands).
    title : str
        The figure's title (wrapped to the figure's width).

    Returns
    -------
    matplotlib.figure.Figure
        Panels sharing the time axis, one line per run in each, each run in its own colour and
        line style: the rotation error on a log axis and ``max_i |u_i|`` with the residual
        window (the last :data:`RESIDUAL_TAIL` s) shaded and the torque limits dotted;
        ``max_i |u_i|`` again on the residual window alone; ``eta_1`` with the +-modal bounds
        dotted (labelled with the runs that have them); ``||w_hf||``, the body rate's part above
        ``Lambda_1 / 2`` (:func:`benchmarks.families.flexible.metrics.highpass`, the record's
        ``settings.first_mode_frequency``) on a log axis, for the runs whose trace has ``w``; runs
        drawn on top of each other named in a note; ``max_j |v_j|`` of the runs whose PZT
        commands are not all zero (the panel is left out when no run drives them).
    """
    styles = run_styles(len(items))
    pzt = [bool(np.any(np.asarray(trace["v"]) != 0.0)) for _, _, trace in items]
    has_eta = any(np.asarray(trace["eta"]).size for _, _, trace in items)
    rates = [_rate_hf(rec, trace) for _, rec, trace in items]
    has_rate = any(r is not None for r in rates)
    rows = 3 + int(has_eta) + int(has_rate) + int(any(pzt))
    fig = Figure(figsize=(9.0, 2.7 * rows + 0.8), layout="constrained")
    FigureCanvasAgg(fig)
    ax_e = fig.add_subplot(rows, 1, 1)
    ax_u = fig.add_subplot(rows, 1, 2, sharex=ax_e)
    ax_z = fig.add_subplot(rows, 1, 3)
    ax_m = fig.add_subplot(rows, 1, 4, sharex=ax_e) if has_eta else None
    ax_r = fig.add_subplot(rows, 1, 4 + int(has_eta), sharex=ax_e) if has_rate else None
    ax_v = fig.add_subplot(rows, 1, rows, sharex=ax_e) if any(pzt) else None
    t_end = 0.0
    torque_series = []
    for (name, _rec, trace), style, drives_pzt, rate in zip(items, styles, pzt, rates, strict=True):
        t = np.asarray(trace["t"])
        t_end = max(t_end, float(t[-1]))
        ax_e.semilogy(t, np.maximum(np.asarray(trace["error_deg"]), 1e-6), label=name, **style)
        u = np.asarray(trace["u"])
        if u.size:
            u_max = np.abs(u).max(axis=1)
            ax_u.plot(t[: u.shape[0]], u_max, label=name, **style)
            ax_z.plot(t[: u.shape[0]], u_max, label=name, **style)
            torque_series.append((t[: u.shape[0]], u_max))
        eta = np.asarray(trace["eta"])
        if ax_m is not None and eta.size:
            ax_m.plot(t, eta[:, 0], label=name, **style)
        if ax_r is not None and rate is not None:
            ax_r.semilogy(t, np.maximum(rate, _RATE_FLOOR), label=name, **style)
        if ax_v is not None and drives_pzt:
            v = np.asarray(trace["v"])
            ax_v.plot(t[: v.shape[0]], np.abs(v).max(axis=1), label=name, **style)
    limited = [rec for _, rec, _ in items if rec.get("saturation") != "none"]
    limits = sorted({float(_settings(rec)["u_max"]) for rec in limited})
    for u_limit in limits:
        limit_lines(ax_u, u_limit, f"limit {u_limit:g} N m", both=False)
        ax_u.set_ylim(top=max(ax_u.get_ylim()[1], 1.08 * u_limit))
    if ax_m is not None:
        bounds: dict[float, list[str]] = {}
        for name, rec, _ in items:
            if _settings(rec).get("modal_bound") is not None:
                bounds.setdefault(float(_settings(rec)["modal_bound"]), []).append(name)
        for bound, names_bounded in sorted(bounds.items()):
            limit_lines(ax_m, bound, f"|eta_i| <= {bound:g} ({', '.join(names_bounded)})")
    residual = (max(0.0, t_end - RESIDUAL_TAIL), t_end)
    for ax in (ax_e, ax_u):
        shade_window(ax, residual, t_end, f"residual window (last {RESIDUAL_TAIL:g} s)")
    steady_zoom(ax_z, residual, torque_series)
    ax_z.set_title(f"max_i |u_i| on the residual window [{residual[0]:g}, {residual[1]:g}] s", fontsize=9)
    ax_e.set_ylabel("rotation error (deg)")
    ax_u.set_ylabel("max_i |u_i| (N m)")
    ax_z.set_ylabel("max_i |u_i| (N m)")
    if ax_m is not None:
        ax_m.set_ylabel("eta_1 (kg^1/2 m)")
    if ax_r is not None:
        ax_r.set_ylabel("||w_hf|| (rad/s)")
        ax_r.set_title(
            "body rate above Lambda_1/2 (V7 of the report measures it on the run's last fifth)",
            fontsize=9,
        )
    if ax_v is not None:
        ax_v.set_ylabel(f"max_j |v_j| ({PZT_UNIT})")
    names = [name for name, _, _ in items]
    panels = [a for a in (ax_e, ax_u, ax_z, ax_m, ax_r, ax_v) if a is not None]
    for ax in panels:
        ax.set_xlabel(_TIME)
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.grid(alpha=0.3)
        add_legend(ax, note=note_coincident(ax, names, residual if ax is ax_z else None))
    wrapped_title(fig, title)
    return fig


def plot_flexible_group(items: Sequence[tuple[str, Mapping[str, Any], dict]], path: Path, title: str) -> Path:
    """Write :func:`flexible_group_figure` as a PNG at ``path`` (80 dpi) and return ``path``.

    Parameters
    ----------
    items : sequence of (name, record, trace)
        As for :func:`flexible_group_figure`.
    path : Path
        The PNG to write.
    title : str
        The figure's title.
    """
    flexible_group_figure(items, title).savefig(path, dpi=80)
    return path
