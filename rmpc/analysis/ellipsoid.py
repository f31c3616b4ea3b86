"""Drawing an invariant ellipsoid ``{x : x' Q^-1 x <= 1}`` projected on two states."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError

__all__ = ["ellipse_points", "plot_ellipsoid"]


def ellipse_points(Q: ArrayLike, dims: tuple[int, int] = (0, 1), n_points: int = 200,
                   center: ArrayLike | None = None) -> np.ndarray:
    """Boundary points ``(n_points, 2)`` of the projection of ``{x' Q^-1 x <= 1}`` on ``dims``.

    The projection of the ellipsoid on a coordinate plane is the ellipse of the matching 2 x 2
    block of ``Q`` (not of ``Q^-1``): its points are ``center + L [cos s, sin s]`` with
    ``L L' = Q[dims][:, dims]``.
    """
    q = np.asarray(Q, dtype=float)
    if q.ndim != 2 or q.shape[0] != q.shape[1] or not np.all(np.isfinite(q)):
        raise InvalidArgumentError("Q", "a finite square matrix", f"shape {q.shape}")
    i, j = (int(k) for k in dims)
    if i == j or not (0 <= i < q.shape[0] and 0 <= j < q.shape[0]):
        raise InvalidArgumentError("dims", f"two different state indices in [0, {q.shape[0]})", repr(dims))
    block = q[np.ix_([i, j], [i, j])]
    block = 0.5 * (block + block.T)
    w, v = np.linalg.eigh(block)
    if w[0] <= 0.0:
        raise InvalidArgumentError("Q", "a positive definite matrix (an ellipsoid)",
                                   f"the block of dims {dims} has eigenvalue {w[0]:.3g}")
    s = np.linspace(0.0, 2.0 * np.pi, int(n_points))
    pts = (v * np.sqrt(w)) @ np.vstack([np.cos(s), np.sin(s)])
    c = np.zeros(2) if center is None else np.asarray(center, dtype=float).reshape(-1)[[i, j]]
    return pts.T + c


def plot_ellipsoid(Q: Any, dims: tuple[int, int] = (0, 1), ax: Any = None, center: ArrayLike | None = None,
                   names: tuple[str, str] | None = None, **line: Any) -> Any:
    """Draw the projection of ``{x' Q^-1 x <= 1}`` on ``dims``; returns the matplotlib axes.

    ``Q`` is a matrix or anything with a ``Q`` attribute (an :class:`lmi.LMISolution`, the
    invariant ellipsoid of the gain it certifies). ``center`` shifts it (a set-point ``x_ref``);
    ``names`` label the axes; ``line`` goes to ``ax.plot``.
    """
    import matplotlib.pyplot as plt

    q = getattr(Q, "Q", Q)
    if q is None:
        raise InvalidArgumentError("Q", "an ellipsoid matrix or a solution that has one",
                                   "None (no certified answer)")
    pts = ellipse_points(q, dims, center=center)
    if ax is None:
        _, ax = plt.subplots()
    ax.plot(pts[:, 0], pts[:, 1], **line)
    if names is not None:
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
    return ax
