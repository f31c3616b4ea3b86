"""Figures in the style of paper P: attitude in degrees, torques with the limit lines, gamma(k).

Matplotlib's object API with the Agg renderer (no pyplot, no global state, no display): each
``*_figure`` function builds and returns a :class:`matplotlib.figure.Figure` (what the tests
inspect), and each ``plot_*`` function writes that figure as a PNG. Within a figure the
colour tells the controller and saturation handling apart, the line style the plant
(solid: nonlinear, dashed: linear), so linear and nonlinear runs overlay directly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from benchmarks.reports.figure_style import PALETTE, wrapped_title

__all__ = [
    "GAMMA_LABEL",
    "SATURATION_WORDS",
    "gamma_figure",
    "plot_gamma",
    "plot_responses",
    "responses_figure",
    "run_label",
]

_AXIS_LABELS = ("roll $\\phi$", "pitch $\\theta$", "yaw $\\psi$")
_TORQUE_LABELS = ("$M_x$", "$M_y$", "$M_z$")
_COLORS = PALETTE[:8]  # paper P's figures: matplotlib's first eight
_STYLES = {"nonlinear": "-", "linear": "--"}

Run = tuple[Mapping[str, Any], Mapping[str, np.ndarray]]


#: The scenario's ``saturation`` option in words, for legends.
SATURATION_WORDS: dict[str, str] = {
    "none": "no saturation",
    "limiter": "limiter",
    "constraint": "controller's constraint",
}


def _key(rec: Mapping[str, Any]) -> str:
    sat = str(rec["saturation"])
    return f"{rec['controller']}, {SATURATION_WORDS.get(sat, sat)}"


def run_label(rec: Mapping[str, Any]) -> str:
    """A run's legend entry in words: ``"RMPC, no saturation (linear)"``."""
    return f"{_key(rec)} ({rec['plant']})"


def _colors(runs: Sequence[Run]) -> dict[str, str]:
    keys: list[str] = []
    for rec, _ in runs:
        if _key(rec) not in keys:
            keys.append(_key(rec))
    return {k: _COLORS[i % len(_COLORS)] for i, k in enumerate(keys)}


def responses_figure(runs: Sequence[Run], title: str, u_max: float) -> Figure:
    """Attitude (deg) and applied torque per axis for several runs, with the +-``u_max`` lines.

    Parameters
    ----------
    runs : sequence of (record, trace)
        ``trace`` has ``t``, ``x`` and ``u_applied`` (see :func:`benchmarks.core.runner.simulate_scenario`).
    title : str
        Figure title, wrapped at word boundaries to the figure's width (never cut).
    u_max : float
        Torque limit drawn as dotted lines (N m).

    Returns
    -------
    matplotlib.figure.Figure
        Six panels (rows: roll, pitch, yaw; columns: attitude, applied torque), one line per
        run in each, and the two limit lines in each torque panel.
    """
    fig = Figure(figsize=(11, 8), layout="constrained")
    axes = fig.subplots(3, 2, sharex=True)
    colors = _colors(runs)
    for rec, tr in runs:
        t = np.asarray(tr["t"])
        style = dict(
            color=colors[_key(rec)],
            linestyle=_STYLES.get(rec["plant"], "-"),
            linewidth=1.2,
            label=run_label(rec),
        )
        for i in range(3):
            axes[i, 0].plot(t, np.degrees(np.asarray(tr["x"])[:, i]), **style)
            axes[i, 1].plot(t[:-1], np.asarray(tr["u_applied"])[:, i], drawstyle="steps-post", **style)
        d_start = rec.get("settings", {}).get("disturbance_start")
        if rec.get("settings", {}).get("disturbance") and d_start is not None and d_start < t[-1]:
            for ax in axes.ravel():
                ax.axvline(d_start, color="0.6", linewidth=0.8, linestyle=":")
    for i in range(3):
        axes[i, 0].set_ylabel(f"{_AXIS_LABELS[i]} (deg)")
        axes[i, 1].set_ylabel(f"{_TORQUE_LABELS[i]} (N m)")
        for sign in (1.0, -1.0):
            axes[i, 1].axhline(sign * u_max, color="k", linewidth=0.8, linestyle=":")
        for ax in axes[i]:
            ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    axes[0, 0].set_title("attitude")
    axes[0, 1].set_title(f"applied torque (limit +-{u_max:g} N m dotted)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncols=min(3, len(labels)), fontsize="small")
    wrapped_title(fig, title, fontsize=11.0)
    return fig


def plot_responses(runs: Sequence[Run], path: str | Path, title: str, u_max: float) -> Path:
    """Write :func:`responses_figure` as a PNG at ``path`` (110 dpi) and return ``path``.

    Parameters
    ----------
    runs : sequence of (record, trace)
        As for :func:`responses_figure`.
    path : str or Path
        Output PNG.
    title : str
        Figure title.
    u_max : float
        Torque limit drawn as dotted lines (N m).
    """
    path = Path(path)
    responses_figure(runs, title, u_max).savefig(path, dpi=110)
    return path


#: The y label of the gamma panels: the robust MPC's bound on the infinite-horizon cost
#: ``sum x'Qx + u'Ru``, a pure number (the state and input weights make it dimensionless).
GAMMA_LABEL = "cost bound gamma(k) (dimensionless)"


def gamma_figure(groups: Mapping[str, Sequence[Run]]) -> Figure | None:
    """The cost bound gamma(k) on a log axis, one panel per experiment (steps that solved only).

    Parameters
    ----------
    groups : mapping of str to sequence of (record, trace)
        The runs of each experiment; ``trace`` has ``t`` and ``gamma`` (NaN where no bound).

    Returns
    -------
    matplotlib.figure.Figure or None
        One visible panel per experiment with a finite gamma, one line per such run; ``None``
        when no run has a gamma.
    """
    panels = {
        name: [(rec, tr) for rec, tr in runs if np.any(np.isfinite(np.asarray(tr["gamma"])))]
        for name, runs in groups.items()
    }
    panels = {name: runs for name, runs in panels.items() if runs}
    if not panels:
        return None
    cols = min(3, len(panels))
    rows = (len(panels) + cols - 1) // cols
    fig = Figure(figsize=(4.2 * cols, 3.3 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    for ax, (name, runs) in zip(axes, panels.items(), strict=False):
        colors = _colors(runs)
        for rec, tr in runs:
            t = np.asarray(tr["t"])[:-1]
            g = np.asarray(tr["gamma"])
            ok = np.isfinite(g) & (g > 0)
            ax.semilogy(
                t[ok],
                g[ok],
                drawstyle="steps-post",
                color=colors[_key(rec)],
                linestyle=_STYLES.get(rec["plant"], "-"),
                label=run_label(rec),
            )
        ax.set_title(name)
        ax.set_xlabel("time (s)")
        ax.set_ylabel(GAMMA_LABEL)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize="x-small")
    for ax in axes[len(panels) :]:
        ax.set_visible(False)
    fig.suptitle("cost bound gamma(k) of the robust MPC (at the steps that solved)")
    return fig


def plot_gamma(groups: Mapping[str, Sequence[Run]], path: str | Path) -> Path | None:
    """Write :func:`gamma_figure` as a PNG at ``path`` (110 dpi) and return ``path``.

    Returns ``None`` (and writes nothing) when no run has a gamma.
    """
    fig = gamma_figure(groups)
    if fig is None:
        return None
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path
