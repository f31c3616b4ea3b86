"""The architecture diagram of docs/architecture.rst: packages, protocols and one closed-loop run.

Run by docs/conf.py at build time (``write(path)``); also runnable on its own:
``python docs/figures/architecture.py out.png``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

PACKAGE = "#dce8f5"
PROTOCOL = "#fbe7c6"
SIGNAL = "#e3f1df"


def _box(ax, x, y, w, h, title, lines=(), color=PACKAGE, size=9):
    ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.02,rounding_size=0.08",
                                fc=color, ec="#333333", lw=1.0))
    ax.text(x + w / 2, y + h - 0.13, title, ha="center", va="top", fontsize=size + 1, weight="bold")
    for i, line in enumerate(lines):
        ax.text(x + 0.1, y + h - 0.45 - 0.24 * i, line, ha="left", va="top", fontsize=size,
                family="monospace")


def _arrow(ax, start, end, text="", offset=(0.0, 0.08), color="#333333", style="-|>", ls="-"):
    ax.add_patch(FancyArrowPatch(start, end, arrowstyle=style, mutation_scale=12, color=color,
                                 lw=1.2, linestyle=ls, shrinkA=2, shrinkB=2))
    if text:
        mx, my = (start[0] + end[0]) / 2 + offset[0], (start[1] + end[1]) / 2 + offset[1]
        ax.text(mx, my, text, ha="center", va="bottom", fontsize=8, family="monospace")


def draw() -> plt.Figure:
    """The figure: the four packages with their dependency arrows, and one sample of the loop."""
    fig, ax = plt.subplots(figsize=(11.0, 7.2))
    ax.set_xlim(0, 11)
    ax.set_ylim(0, 7.2)
    ax.axis("off")

    # top: the packages and the one direction of their imports
    ax.text(0.1, 7.05, "Packages (imports point one way)", fontsize=11, weight="bold", va="top")
    _box(ax, 0.2, 4.6, 2.4, 2.1, "benchmarks", ["families/<family>/", "suites/  timing/", "core/  reports/",
                                                 "cli.py  (rmpc)"])
    _box(ax, 3.3, 4.6, 2.6, 2.1, "rmpc", ["controller.py", "mpc/   qp/", "laws/<family>/", "sim/"])
    _box(ax, 6.6, 5.75, 2.0, 0.95, "lmi", ["problems, solver", "backends/"], size=8)
    _box(ax, 6.6, 4.6, 2.0, 0.95, "models", ["protocols, linear", "attitude/ <family>/"], size=8)
    _box(ax, 9.05, 4.6, 1.85, 2.1, "toolkit_common", ["errors", "validation", "status"], size=7)
    _arrow(ax, (2.6, 5.65), (3.3, 5.65))
    _arrow(ax, (5.9, 6.1), (6.6, 6.2))
    _arrow(ax, (5.9, 5.2), (6.6, 5.07))
    _arrow(ax, (8.6, 6.2), (9.05, 6.0), color="#777777")
    _arrow(ax, (8.6, 5.07), (9.05, 5.2), color="#777777")

    # bottom: one sample of a closed-loop run
    ax.text(0.1, 4.2, "One sample of simulate(controller, plant, x0, ...)", fontsize=11, weight="bold",
            va="top")
    _box(ax, 0.3, 1.6, 2.5, 1.9, "Controller", ["reset()", "step(x, inputs)", "last: StepInfo", "name"],
         color=PROTOCOL)
    _box(ax, 3.6, 2.35, 1.7, 0.8, "limiter", ["u_max"], color=SIGNAL, size=8)
    _box(ax, 5.7, 2.35, 1.7, 0.8, "actuator", ["wheel lag"], color=SIGNAL, size=8)
    _box(ax, 7.9, 1.6, 2.8, 1.9, "Plant", ["dynamics(x, u, d)", "attitude_euler(x)",
                                          "input stage, d(t)", "integrator by name"], color=PROTOCOL)
    _arrow(ax, (2.8, 2.75), (3.6, 2.75), "u_cmd")
    _arrow(ax, (5.3, 2.75), (5.7, 2.75))
    _arrow(ax, (7.4, 2.75), (7.9, 2.75), "u")
    _arrow(ax, (9.3, 1.6), (9.3, 0.75), style="-")
    _arrow(ax, (9.3, 0.75), (1.55, 0.75), "x(k+1), sampled (optional sensor)", offset=(0, 0.05), style="-")
    _arrow(ax, (1.55, 0.75), (1.55, 1.6))
    ax.text(5.5, 0.3, "Trajectory: t, x, u_cmd, u_applied, status (one vocabulary), solve_time, gamma, "
            "attitude (roll, pitch, yaw)", ha="center", fontsize=8, family="monospace")
    fig.tight_layout()
    return fig


def write(path: str | Path) -> Path:
    """Draw the figure and save it as a PNG at ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = draw()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


if __name__ == "__main__":
    write(sys.argv[1] if len(sys.argv) > 1 else "architecture.png")
