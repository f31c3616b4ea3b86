"""What a matplotlib figure draws, for the tests of the suites' figures.

A figure is read back through its artists: the lines drawn in data coordinates (the curves), the
horizontal and vertical lines spanning an axis (``axhline`` / ``axvline``: limits and event
markers) and the shaded spans (``axvspan``). The tests of ``tests/test_report_figures.py`` and of
the suites (``tests/test_bench_*.py``) assert on these, not on the PNG files.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

__all__ = [
    "UNIT",
    "assert_readable",
    "capture",
    "coincident_note",
    "curves",
    "hatched_spans",
    "hline_values",
    "hlines",
    "run_curves",
    "spans",
    "title_inside",
    "visible_axes",
    "vlines",
]

#: A unit in parentheses or brackets, e.g. "(N m)", "[deg]", "(kg^1/2 m/s^2)".
UNIT = re.compile(r"[(\[][^()\[\]]*[A-Za-z][^()\[\]]*[)\]]")


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
    """The ``(x0, x1)`` of every filled ``axvspan`` of ``ax`` (shaded intervals of the time axis)."""
    return [_x_range(p) for p in _vspans(ax) if p.get_fill()]


def hatched_spans(ax: Axes) -> list[tuple[float, float]]:
    """The ``(x0, x1)`` of every hatched, unfilled ``axvspan`` of ``ax``."""
    return [_x_range(p) for p in _vspans(ax) if not p.get_fill() and p.get_hatch()]


def _vspans(ax: Axes) -> list[Rectangle]:
    return [p for p in ax.patches if isinstance(p, Rectangle) and p.get_transform() is not ax.transData]


def _x_range(patch: Rectangle) -> tuple[float, float]:
    x0 = float(patch.get_x())
    return (x0, x0 + float(patch.get_width()))


def run_curves(ax: Axes, names: list[str]) -> list[Line2D]:
    """The curves of ``ax`` whose label is one of the runs' ``names`` (in drawing order)."""
    return [line for line in curves(ax) if line.get_label() in names]


def title_inside(fig: Figure) -> bool:
    """Whether the rendered suptitle lies inside the figure (drawn on the figure's canvas)."""
    fig.canvas.draw()
    box = fig._suptitle.get_window_extent(fig.canvas.get_renderer())
    whole = fig.bbox
    return bool(box.x0 >= whole.x0 and box.x1 <= whole.x1 and box.y0 >= whole.y0 and box.y1 <= whole.y1)


def _on_top(ax: Axes, a: Line2D, b: Line2D, height: float) -> bool:
    """Whether ``a`` and ``b`` lie within 0.2 % of ``height`` (the panel's data range) everywhere
    inside the panel's time range."""
    xa, xb = np.asarray(a.get_xdata(), float), np.asarray(b.get_xdata(), float)
    if xa.shape != xb.shape or not np.allclose(xa, xb):
        return False
    return bool(np.all(np.abs(_shown(ax, a) - _shown(ax, b)) <= 0.002 * height))


def _shown(ax: Axes, line: Line2D) -> np.ndarray:
    """The values of ``line`` inside the x range of ``ax`` (log10 on a log axis)."""
    x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
    lo, hi = sorted(ax.get_xlim())
    y = y[(x >= lo) & (x <= hi)]
    return np.log10(y) if ax.get_yscale() == "log" else y


def coincident_note(ax: Axes) -> list[set[str]]:
    """The groups of runs the note of ``ax`` names as drawn on top of each other."""
    legend = ax.get_legend()
    notes = [] if legend is None else [legend.get_title().get_text()]
    notes = [text for text in notes if legend.get_title().get_gid() == "coincident-runs"]
    if not notes:
        return []
    body = " ".join(notes[0].split("\n")).split(": ", 1)[1]
    return [set(group.split(" = ")) for group in body.split("; ")]


def assert_readable(fig: Figure, names: list[str]) -> None:
    """The properties every suite figure has, for runs named ``names``.

    Every visible axes has data (a curve) and an x and a y label that carry a unit; the title
    lies inside the figure; in every axes, the runs' curves have pairwise different colours and
    two runs drawn on top of each other (closer than 0.2 % of the panel's range everywhere)
    differ in line style or are named together in the panel's note; each run keeps one
    (colour, line style) in the whole figure, and no two runs share it.
    """
    assert title_inside(fig), fig.get_suptitle()
    style_of: dict[str, tuple[Any, Any]] = {}
    for ax in visible_axes(fig):
        where = f"axes {ax.get_ylabel()!r}"
        assert curves(ax), f"{where} has no curve"
        assert UNIT.search(ax.get_xlabel()), f"{where}: x label {ax.get_xlabel()!r} has no unit"
        assert UNIT.search(ax.get_ylabel()), f"{where}: y label {ax.get_ylabel()!r} has no unit"
        runs = [line for line in curves(ax) if line.get_label() in names]
        colours = [str(line.get_color()) for line in runs]
        assert len(set(colours)) == len(colours), f"{where}: a colour repeats: {colours}"
        if runs:
            shown = np.concatenate([_shown(ax, line) for line in runs])
            height = float(np.ptp(shown[np.isfinite(shown)])) if np.isfinite(shown).any() else 0.0
            groups = coincident_note(ax)
            for i, line in enumerate(runs):  # runs on top of each other: another style, or named
                for other in runs[i + 1 :]:
                    if _on_top(ax, line, other, height):
                        named = any({line.get_label(), other.get_label()} <= g for g in groups)
                        assert named or line.get_linestyle() != other.get_linestyle(), (
                            f"{where}: {line.get_label()} and {other.get_label()} on top of each other"
                        )
        for line in runs:
            style = (str(line.get_color()), str(line.get_linestyle()))
            assert style_of.setdefault(line.get_label(), style) == style, f"{line.get_label()} changes style"
    styles = list(style_of.values())
    assert len(set(styles)) == len(styles)


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
