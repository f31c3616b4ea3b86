"""What the suites' figures share: one colour and one line style per run, titles that fit, limit
lines, shaded windows and a torque panel zoomed on the steady window.

Within a figure every run keeps one colour in every panel, no two runs share a colour
(:data:`PALETTE`, then evenly spaced hues past it), and the line style cycles through
:data:`LINE_STYLES`, so runs that lie on top of each other still show as distinct dash patterns
(and in the legend, whose handles are long enough to show them).
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
    "LIMIT_STYLE",
    "LINE_STYLES",
    "PALETTE",
    "add_legend",
    "limit_lines",
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


def add_legend(ax: Axes, **kw: Any) -> None:
    """A legend with handles long enough to show the dash patterns (only if ``ax`` has labels)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, handlelength=3.5, **{"loc": "upper right", **kw})
