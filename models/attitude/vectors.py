"""The cross product of 3-vectors and its skew-symmetric matrix: one copy for every package.

Both are unchecked: they sit in the hot paths of the plants and the controllers (``np.cross``
costs about ten times more on 3-vectors).
"""

from __future__ import annotations

import numpy as np

__all__ = ["cross3", "skew"]


def skew(v: np.ndarray) -> np.ndarray:
    """The cross-product matrix ``[v]x``, with ``[v]x w = v x w``.

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.vectors import skew
    >>> skew(np.array([1.0, 2.0, 3.0])) @ np.array([0.0, 0.0, 1.0])
    array([ 2., -1.,  0.])
    """
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` for two 3-vectors.

    Examples
    --------
    >>> import numpy as np
    >>> from models.attitude.vectors import cross3
    >>> cross3(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])).tolist()
    [0.0, 0.0, 1.0]
    """
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
