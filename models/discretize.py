"""Zero-order-hold discretisation of continuous-time linear models (matrix exponential)."""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from toolkit_common.validation import as_matrix, check_positive

__all__ = ["zoh"]


def zoh(a: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Discretise ``x' = A x + B u`` with a zero-order hold on ``u`` over ``dt``.

    Uses the exponential of the block matrix ``[[A, B], [0, 0]] dt`` (Van Loan), which gives
    ``Ad = e^{A dt}`` and ``Bd = int_0^dt e^{A s} ds B`` exactly, also for singular ``A``.

    Parameters
    ----------
    a : (n, n) array_like
    b : (n, m) array_like
    dt : float
        Sample time in seconds, > 0.

    Returns
    -------
    ad, bd : ndarray
        The discrete-time matrices.

    Examples
    --------
    >>> import numpy as np
    >>> from models import zoh
    >>> ad, bd = zoh([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], 0.1)
    >>> np.allclose(bd.ravel(), [0.005, 0.1])
    True
    """
    a = as_matrix(a, "a")
    n = a.shape[0]
    a = as_matrix(a, "a", (n, n))
    b = as_matrix(b, "b", (n, None))
    dt = check_positive(dt, "dt")
    m = b.shape[1]
    block = np.zeros((n + m, n + m))
    block[:n, :n] = a
    block[:n, n:] = b
    phi = expm(block * dt)
    return phi[:n, :n], phi[:n, n:]
