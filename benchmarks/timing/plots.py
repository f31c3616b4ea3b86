"""The figure of the timing report: per-step time distributions, one panel per problem (the C
section's exported controllers with the paths they were timed against included).

Box plots on a log axis (the paths span microseconds to seconds): the box is the interquartile
range, the line the median, the whiskers reach the 5th and 95th percentiles, and the dots beyond
them are single steps. Drawn with matplotlib's Agg canvas directly, so no global backend is set:
:func:`distributions_figure` returns the :class:`matplotlib.figure.Figure`, :func:`plot_distributions`
writes it as a PNG.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

__all__ = ["distributions_figure", "plot_distributions"]

_PROBLEMS = ("RMPC", "OfflineRMPC", "GIPC", "C")


_COLOURS = {1: "#bbbbbb", 2: "#8fb8de", 4: "#f2b880", 8: "#9bd39b"}


def _label(rec: dict[str, Any]) -> str:
    if rec["problem"] == "GIPC":
        return rec["backend"]
    return f"{rec['backend']} / {rec['formulation']} / {rec['vertices']}v"


def distributions_figure(report: dict[str, Any], samples: dict[str, np.ndarray]) -> Figure:
    """The per-step times of every record of ``report`` (``samples`` by record key), as a Figure.

    Parameters
    ----------
    report : dict
        The timing report: ``records`` (each with ``problem``, ``backend``, ``formulation`` and
        ``vertices``) and ``machine``.
    samples : dict of str to ndarray
        The per-step times (s) by record key ``"problem|backend|formulation|vertices"``.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per problem with samples (RMPC, OfflineRMPC, GIPC, and C: the exported
        controllers against the Python paths at the same states), one box per record on a log
        time axis; a single "no timing samples" panel when there is none.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    groups = []
    for problem in _PROBLEMS:
        recs = [r for r in report["records"] if r["problem"] == problem]
        data, labels, colours = [], [], []
        for rec in recs:
            key = f"{rec['problem']}|{rec['backend']}|{rec['formulation']}|{rec['vertices']}"
            times = np.asarray(samples.get(key, []), dtype=float)
            times = times[np.isfinite(times) & (times > 0)]
            if times.size:
                data.append(times)
                labels.append(_label(rec))
                colours.append(_COLOURS.get(rec["vertices"], "#dddddd"))
        if data:
            groups.append((problem, data, labels, colours))
    width = max(8.0, 0.55 * max((len(g[1]) for g in groups), default=1) + 2.0)
    fig = Figure(figsize=(width, 3.6 * max(len(groups), 1)), layout="constrained")
    FigureCanvasAgg(fig)
    if not groups:
        ax = fig.add_subplot()
        ax.text(0.5, 0.5, "no timing samples", ha="center", va="center")
        ax.set_axis_off()
    for i, (problem, data, labels, colours) in enumerate(groups):
        ax = fig.add_subplot(len(groups), 1, i + 1)
        boxes = ax.boxplot(data, whis=(5, 95), widths=0.6, patch_artist=True,
                           flierprops={"markersize": 2, "alpha": 0.5}, medianprops={"color": "black"})
        for patch, colour in zip(boxes["boxes"], colours, strict=True):
            patch.set_facecolor(colour)
        ax.set_xticks(range(1, len(labels) + 1), labels, rotation=40, ha="right", fontsize=7,
                      rotation_mode="anchor")
        ax.set_yscale("log")
        ax.set_ylabel("time per step (s)")
        note = {"GIPC": "nominal model",
                "C": "the C export against the Python paths at the same states; colour: vertex count"
                }.get(problem, "colour: vertex count (blue 2, orange 4, green 8)")
        ax.set_title(f"{problem}: per-step time (box: quartiles, whiskers: p5-p95; {note})", fontsize=10)
        ax.grid(True, which="both", axis="y", alpha=0.3)
    m = report.get("machine", {})
    fig.suptitle(
        f"{m.get('platform', '')}, {m.get('cpu_count', '?')} CPUs, load {m.get('load_average_start')} "
        f"-> {m.get('load_average_end')}", fontsize=8,
    )
    return fig


def plot_distributions(report: dict[str, Any], samples: dict[str, np.ndarray], path: Path) -> Path:
    """Write :func:`distributions_figure` as a PNG at ``path`` (110 dpi) and return ``path``."""
    distributions_figure(report, samples).savefig(path, dpi=110)
    return Path(path)
