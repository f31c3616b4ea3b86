"""What a matplotlib figure draws, for the tests of the suites' figures.

A figure is read back through its artists: the lines drawn in data coordinates (the curves), the
horizontal and vertical lines spanning an axis (``axhline`` / ``axvline``: limits and event
markers) and the shaded spans (``axvspan``). The tests of ``tests/test_report_figures.py`` and of
the suites (``tests/test_bench_*.py``) assert on these, not on the PNG files.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

__all__ = ["capture", "curves", "hline_values", "hlines", "spans", "visible_axes", "vlines"]


def visible_axes(fig: Figure) -> list[Axes]:
    """The figure's visible axes, in creation order."""
    return [ax for ax in fig.axes if ax.get_visible()]


def curves(ax: Axes) -> list[Line2D]:
    """The lines drawn in data coordinates (not ``axhline``/``axvline``)."""
    return [line for line in ax.lines if line.get_transform() is ax.transData]


def hlines(ax: Axes) -> list[Line2D]:
    """The ``axhline`` lines of ``ax`` (they span the axis width; the y value is data)."""
    return [line for line in ax.lines if line.get_transform() is ax.get_yaxis_transform(which="grid")]


def vlines(ax: Axes) -> list[Line2D]:
    """The ``axvline`` lines of ``ax`` (they span the axis height; the x value is data)."""
    return [line for line in ax.lines if line.get_transform() is ax.get_xaxis_transform(which="grid")]


def spans(ax: Axes) -> list[tuple[float, float]]:
    """The ``(x0, x1)`` of every ``axvspan`` of ``ax`` (shaded intervals of the time axis)."""
    out = []
    for patch in ax.patches:
        if isinstance(patch, Rectangle) and patch.get_transform() is not ax.transData:
            x0 = float(patch.get_x())
            out.append((x0, x0 + float(patch.get_width())))
    return out


def hline_values(ax: Axes) -> list[float]:
    """The y values of the ``axhline`` lines, sorted."""
    return sorted(float(np.asarray(line.get_ydata())[0]) for line in hlines(ax))


def capture(monkeypatch: Any, module: Any, name: str) -> list[tuple[tuple[Any, ...], Any]]:
    """Wrap ``module.name`` (a figure builder) to record ``(args, figure)`` of every call."""
    built: list[tuple[tuple[Any, ...], Any]] = []
    original: Callable[..., Any] = getattr(module, name)

    def recording(*args: Any, **kwargs: Any) -> Any:
        fig = original(*args, **kwargs)
        built.append((args, fig))
        return fig

    monkeypatch.setattr(module, name, recording)
    return built
