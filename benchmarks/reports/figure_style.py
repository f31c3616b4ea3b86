"""What the suites' figures share: one colour and one line style per run, titles that fit, limit
lines, shaded windows and a torque panel zoomed on the steady window.

Within a figure every run keeps one colour in every panel, no two runs share a colour
(:data:`PALETTE`, then evenly spaced hues past it), and the line style cycles through
:data:`LINE_STYLES`, so runs that lie on top of each other still show as distinct dash patterns
(and in the legend, whose handles are long enough to show them). Where three or more runs
coincide no dash pattern keeps them apart: :func:`note_coincident` names the runs that a panel
draws on top of each other, at the head of its legend.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.figure import Figure

__all__ = [
    "COINCIDENT_GID",
    "COINCIDE_FRACTION",
    "LIMIT_STYLE",
    "LINE_STYLES",
    "PALETTE",
    "add_legend",
    "coincident_groups",
    "limit_lines",
    "note_coincident",
    "run_styles",
    "shade_window",
    "steady_zoom",
    "title_width",
    "wrapped_title",
]

#: Distinct colours, in the order runs take them (matplotlib's ten, then ten more far from them).
PALETTE: tuple[str, ...] = (
    "tab:blue",
    "tab:orange",
    "tab:green",
    "tab:red",
    "tab:purple",
    "tab:brown",
    "tab:pink",
    "tab:gray",
    "tab:olive",
    "tab:cyan",
    "black",
    "navy",
    "gold",
    "teal",
    "magenta",
    "lime",
    "maroon",
    "slateblue",
    "darkorange",
    "darkseagreen",
)
#: Line styles, cycled over the runs of a figure (solid, dashed, dash-dot; dotted is the limits').
LINE_STYLES: tuple[str, ...] = ("-", "--", "-.")
#: Two curves closer than this fraction of their panel's data range (of its log10 on a log axis)
#: everywhere are drawn on top of each other (0.2 %: under a pixel of a 300-pixel panel).
COINCIDE_FRACTION: float = 0.002
#: The ``gid`` of the legend title that names the coincident runs of a panel.
COINCIDENT_GID = "coincident-runs"
#: Style of a limit line (a bound of the case: torque limit, modal bound, recovery band).
LIMIT_STYLE: dict[str, Any] = {"color": "k", "linestyle": ":", "linewidth": 1.1}


def run_styles(n: int) -> list[dict[str, Any]]:
    """``color``, ``linestyle`` and ``linewidth`` of the ``n`` runs of one figure.

    No two runs share a colour (the palette first, evenly spaced hues of a cyclic colour map
    past it); the line styles cycle through :data:`LINE_STYLES` (dotted is kept for the limit
    lines); solid lines are drawn wider so
    that a dashed run on top of a solid one shows both.

    Examples
    --------
    >>> [s["linestyle"] for s in run_styles(4)]
    ['-', '--', '-.', '-']
    >>> len({s["color"] for s in run_styles(25)})
    25
    """
    if n <= len(PALETTE):
        colors: list[Any] = list(PALETTE[:n])
    else:
        hsv = colormaps["hsv"]
        colors = [hsv(i / n) for i in range(n)]
    out = []
    for i, color in enumerate(colors):
        style = LINE_STYLES[i % len(LINE_STYLES)]
        out.append({"color": color, "linestyle": style, "linewidth": 1.6 if style == "-" else 1.1})
    return out


def title_width(fig: Figure, fontsize: float) -> int:
    """How many characters of a ``fontsize`` title fit across ``fig`` (a wide glyph's measure)."""
    width_pt = fig.get_figwidth() * 72.0
    return max(20, int(0.9 * width_pt / (0.6 * fontsize)))


def wrapped_title(fig: Figure, title: str, fontsize: float = 10.0) -> None:
    """Set ``title`` as the figure's title, wrapped at word boundaries to fit the figure's width."""
    text = "\n".join(textwrap.wrap(title, title_width(fig, fontsize), break_long_words=False))
    fig.suptitle(text, fontsize=fontsize)


def limit_lines(ax: Axes, value: float, label: str | None = None, both: bool = True) -> None:
    """Horizontal lines at ``+value`` (and ``-value`` when ``both``) in :data:`LIMIT_STYLE`."""
    ax.axhline(value, label=label, **LIMIT_STYLE)
    if both:
        ax.axhline(-value, **LIMIT_STYLE)


def shade_window(
    ax: Axes, window: Sequence[float], t_end: float, label: str | None = None, **kw: Any
) -> None:
    """Shade the part of the time interval ``window`` that lies inside the run (ending at ``t_end``)."""
    t0, t1 = float(window[0]), min(float(window[1]), t_end)
    if t1 > t0:
        style = {"color": "0.5", "alpha": 0.12, "lw": 0, **kw}
        ax.axvspan(t0, t1, label=label, **style)


def steady_zoom(ax: Axes, window: Sequence[float], series: Sequence[tuple[np.ndarray, np.ndarray]]) -> None:
    """Limit ``ax`` to the time ``window`` and to the range the ``(t, y)`` series take inside it.

    The y range is the series' range inside the window with a 10 % margin (a flat series gets
    a margin of its own magnitude, or 1 when zero), so the initial transient is left out.
    """
    t0, t1 = float(window[0]), float(window[1])
    inside = [np.asarray(y)[(np.asarray(t) >= t0) & (np.asarray(t) <= t1)] for t, y in series]
    values = np.concatenate([v[np.isfinite(v)] for v in inside]) if inside else np.zeros(0)
    ax.set_xlim(t0, t1)
    if values.size:
        lo, hi = float(values.min()), float(values.max())
        pad = 0.1 * (hi - lo) if hi > lo else (abs(hi) or 1.0)
        ax.set_ylim(lo - pad, hi + pad)


def add_legend(ax: Axes, outside: bool = True, note: str | None = None, **kw: Any) -> None:
    """A legend with handles long enough to show the dash patterns (only if ``ax`` has labels),
    to the right of the panel (``outside``, where it hides no data) or in its upper right corner;
    a ``note`` (:func:`note_coincident`) heads it, wrapped, its text's ``gid``
    :data:`COINCIDENT_GID`."""
    if ax.get_legend_handles_labels()[0]:
        where = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0} if outside else {}
        title = None if note is None else "\n".join(textwrap.wrap(note, 34))
        legend = ax.legend(
            fontsize=7,
            handlelength=3.5,
            title=title,
            title_fontsize=7,
            alignment="left",
            **{"loc": "upper right", **where, **kw},
        )
        legend.get_title().set_gid(COINCIDENT_GID if note is not None else None)


def _plotted(ax: Axes, line: Any) -> np.ndarray:
    y = np.asarray(line.get_ydata(), dtype=float)
    return np.log10(np.maximum(y, 1e-300)) if ax.get_yscale() == "log" else y


def coincident_groups(
    ax: Axes, names: Sequence[str], window: Sequence[float] | None = None, fraction: float = COINCIDE_FRACTION
) -> list[list[str]]:
    """The groups (two runs or more) of ``names`` whose curves in ``ax`` coincide.

    Two curves coincide when they share their time samples and their values (log10 values on a
    log axis) differ nowhere (inside the time ``window``, when given) by more than ``fraction``
    of the range the runs' curves of ``ax`` span there; a group joins the runs that coincide
    with its first one.
    """
    lines = [line for line in ax.get_lines() if line.get_label() in names and len(line.get_xdata())]
    if len(lines) < 2:
        return []
    values = []
    for line in lines:
        t, y = np.asarray(line.get_xdata(), dtype=float), _plotted(ax, line)
        values.append(y if window is None else y[(t >= window[0]) & (t <= window[1])])
    finite = np.concatenate([v[np.isfinite(v)] for v in values])
    tol = fraction * (float(finite.max() - finite.min()) if finite.size else 0.0)
    groups: list[list[str]] = []
    taken: set[int] = set()
    for i, (line, y) in enumerate(zip(lines, values, strict=True)):
        if i in taken:
            continue
        group = [str(line.get_label())]
        for j in range(i + 1, len(lines)):
            other, y_other = lines[j], values[j]
            same_t = np.array_equal(np.asarray(line.get_xdata()), np.asarray(other.get_xdata()))
            if j not in taken and same_t and y.shape == y_other.shape and np.all(np.abs(y - y_other) <= tol):
                group.append(str(other.get_label()))
                taken.add(j)
        if len(group) > 1:
            groups.append(group)
    return groups


def note_coincident(ax: Axes, names: Sequence[str], window: Sequence[float] | None = None) -> str | None:
    """The note naming the runs that ``ax`` draws on top of each other (:func:`coincident_groups`),
    for :func:`add_legend`'s ``note``; ``None`` when no runs coincide."""
    groups = coincident_groups(ax, names, window)
    if not groups:
        return None
    return "on top of each other: " + "; ".join(" = ".join(group) for group in groups)
