"""Figures of the flexible-satellite suite: the rotation error (log axis), the hub torques, the
first modal coordinate and the PZT voltages, one line per closed loop."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

__all__ = ["plot_flexible_group"]


def plot_flexible_group(items: Sequence[tuple[str, dict]], path: Path, title: str) -> Path:
    """Four panels for the runs of one experiment.

    Parameters
    ----------
    items : sequence of (name, trace)
        The line's name and the run's trace: ``t``, ``error_deg`` (rotation error), ``u`` (applied
        hub torques, N m), ``eta`` (modal coordinates) and ``v`` (applied PZT commands).
    path : Path
        The PNG to write.
    title : str
        The figure's title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_e, ax_u, ax_m, ax_v) = plt.subplots(4, 1, figsize=(9.0, 11.0), sharex=True)
    for name, trace in items:
        t = np.asarray(trace["t"])
        ax_e.semilogy(t, np.maximum(np.asarray(trace["error_deg"]), 1e-6), label=name, lw=1.0)
        u = np.asarray(trace["u"])
        if u.size:
            ax_u.plot(t[: u.shape[0]], np.abs(u).max(axis=1), label=name, lw=0.8)
        eta = np.asarray(trace["eta"])
        if eta.size:
            ax_m.plot(t, eta[:, 0], label=name, lw=0.8)
        v = np.asarray(trace["v"])
        if v.size:
            ax_v.plot(t[: v.shape[0]], np.abs(v).max(axis=1), label=name, lw=0.8)
    ax_e.set_ylabel("rotation error (deg)")
    ax_u.set_ylabel("max_i |u_i| (N m)")
    ax_m.set_ylabel("eta_1 (kg^1/2 m)")
    ax_v.set_ylabel("max_j |v_j| (PZT)")
    ax_v.set_xlabel("t (s)")
    for ax in (ax_e, ax_u, ax_m, ax_v):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path
