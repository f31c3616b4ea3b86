"""Figures of paper M's suite: the error angle (log axis), the torques, and the disk's torque
next to the estimates of MAB and TF-AB."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

__all__ = ["plot_mrp_group"]


def plot_mrp_group(items: Sequence[tuple[dict, dict]], path: Path, title: str) -> Path:
    """Three panels for the runs of one experiment (one line per controller).

    Parameters
    ----------
    items : sequence of (record, trace)
        Traces hold ``t``, ``u_applied``, ``d``, ``error_angle_deg`` and, for the controllers
        with an estimator, ``torque_estimate``.
    path : Path
        The PNG to write.
    title : str
        The figure's title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_e, ax_u, ax_d) = plt.subplots(3, 1, figsize=(9.0, 9.0), sharex=True)
    for rec, trace in items:
        t = np.asarray(trace["t"])
        name = rec["controller"]
        ax_e.semilogy(t, np.maximum(np.asarray(trace["error_angle_deg"]), 1e-12), label=name, lw=1.0)
        u = np.asarray(trace["u_applied"])
        ax_u.plot(t[: u.shape[0]], np.abs(u).max(axis=1), label=name, lw=0.9)
        if "torque_estimate" in trace:
            est = np.asarray(trace["torque_estimate"])
            ax_d.plot(t[: est.shape[0]], est[:, 0], lw=0.8, ls="--", label=f"{name} estimate (x)")
    d_rec = next((tr for _, tr in items if np.asarray(tr["d"]).size), None)
    if d_rec is not None:
        d = np.asarray(d_rec["d"])
        t = np.asarray(d_rec["t"])[: d.shape[0]]
        for i, axis in enumerate("xyz"):
            ax_d.plot(t, d[:, i], color="k", lw=1.2 - 0.3 * i, label=f"true ({axis})")
    ax_e.set_ylabel("error angle (deg)")
    ax_u.set_ylabel("max_i |u_i| (N m)")
    ax_d.set_ylabel("disturbance torque (N m)")
    ax_d.set_xlabel("t (s)")
    for ax in (ax_e, ax_u, ax_d):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
