"""The validated data of a Kothare (1996) min-max problem, shared by every back-end."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import (
    as_matrix,
    as_real_array,
    as_vector,
    check_choice,
    check_pd,
    check_positive,
    check_psd,
)

__all__ = ["InputConstraint", "KothareData", "build_kothare_data", "input_bound_vector", "psd_factor"]

InputConstraint = Literal["ellipsoid", "peak"] | None
Formulation = Literal["delta", "delta_shared", "standard"]
FORMULATIONS: tuple[str, ...] = ("delta", "delta_shared", "standard")
#: The kinds of input constraint.
INPUT_CONSTRAINTS: tuple[str | None, ...] = ("ellipsoid", "peak", None)


def psd_factor(mat: np.ndarray, tol: float = 1e-12) -> np.ndarray:
    """Return ``L`` (``p x n``, ``p = rank``) with ``L' L = mat`` for a PSD matrix."""
    lam, vec = np.linalg.eigh(mat)
    keep = lam > tol * max(1.0, float(np.max(np.abs(lam))))
    return (vec[:, keep] * np.sqrt(lam[keep])).T


@dataclass(frozen=True)
class KothareData:
    """Validated problem data (read-only arrays).

    Attributes
    ----------
    A, B : ndarray
        Vertices, shapes ``(N, n, n)`` and ``(N, n, m)``.
    Q1, R : ndarray
        Weights; ``Q1h`` (``p x n``) and ``Rh`` (``m x m``) with ``Q1h' Q1h = Q1``, ``Rh' Rh = R``.
    dt : float
        Sample time used by the delta (``(A - I)/dt``) formulation.
    input_constraint : {"ellipsoid", "peak", None}
    u_max : ndarray
        ``(1,)`` for the ellipsoid, ``(m,)`` for the peak bound, empty for none.
    C_out : ndarray or None
        Output matrix of the output constraints ``|(C x(k+i))_r| <= y_max_r``, ``i >= 1``.
    y_max : ndarray
        Output bounds (empty without output constraints).
    formulation : {"delta", "delta_shared", "standard"}
    """

    A: np.ndarray
    B: np.ndarray
    Q1: np.ndarray
    R: np.ndarray
    Q1h: np.ndarray
    Rh: np.ndarray
    dt: float
    input_constraint: InputConstraint
    u_max: np.ndarray
    C_out: np.ndarray | None
    y_max: np.ndarray
    formulation: Formulation

    @property
    def n(self) -> int:
        return int(self.A.shape[1])

    @property
    def m(self) -> int:
        return int(self.B.shape[2])

    @property
    def n_vertices(self) -> int:
        return int(self.A.shape[0])


def _bound_vector(value: Any, name: str, size: int) -> np.ndarray:
    if np.ndim(value) == 0:
        vec = np.full(size, check_positive(value, name))
    else:
        vec = as_vector(value, name, size)
        if np.any(vec <= 0):
            raise InvalidArgumentError(name, "bounds > 0", repr(vec.tolist()))
    return vec


def input_bound_vector(input_constraint: InputConstraint, u_max: ArrayLike, m: int) -> np.ndarray:
    """The input bound of a problem as :class:`KothareData` holds it, checked against its kind.

    ``(1,)`` for ``"ellipsoid"`` (``u_max`` a scalar), ``(m,)`` for ``"peak"`` (a scalar for
    every input or one bound per input), empty for ``None`` (``u_max`` must be ``None``). Every
    error names ``input_constraint`` or ``u_max``. A controller built around a Kothare problem
    (:class:`rmpc.CRMPC`) uses it to know the bound before it builds the problem.

    Examples
    --------
    >>> from lmi.data import input_bound_vector
    >>> input_bound_vector("ellipsoid", 2.0, 3).tolist(), input_bound_vector("peak", 2.0, 3).tolist()
    ([2.0], [2.0, 2.0, 2.0])
    """
    check_choice(input_constraint, "input_constraint", INPUT_CONSTRAINTS)
    if input_constraint is None:
        if u_max is not None:
            raise InvalidArgumentError(
                "u_max", "None when input_constraint is None", repr(u_max)
            )
        return np.zeros(0)
    if u_max is None:
        raise InvalidArgumentError(
            "u_max", f"a bound > 0 for input_constraint={input_constraint!r}", "None"
        )
    if input_constraint == "ellipsoid":
        if np.ndim(u_max) != 0:
            raise InvalidArgumentError(
                "u_max", "a scalar for input_constraint='ellipsoid'", repr(u_max)
            )
        return np.array([check_positive(u_max, "u_max")])
    return _bound_vector(u_max, "u_max", m)


def build_kothare_data(
    A: ArrayLike,
    B: ArrayLike,
    Q: ArrayLike,
    R: ArrayLike,
    *,
    dt: float = 1.0,
    input_constraint: InputConstraint = "ellipsoid",
    u_max: ArrayLike | None = None,
    output_matrix: ArrayLike | None = None,
    y_max: ArrayLike | None = None,
    formulation: Formulation = "delta_shared",
) -> KothareData:
    """Validate the problem data; every error names the argument.

    ``A`` is ``(N, n, n)`` (or one ``(n, n)``), ``B`` is ``(N, n, m)`` (or ``(n, m)``).
    """
    a = as_real_array(A, "A", "an (N, n, n) stack or one (n, n) matrix") if not isinstance(A, str) else None
    b = as_real_array(B, "B", "an (N, n, m) stack or one (n, m) matrix") if not isinstance(B, str) else None
    if a is None or a.ndim not in (2, 3):
        raise InvalidArgumentError("A", "an (N, n, n) stack or one (n, n) matrix", repr(A))
    if b is None or b.ndim not in (2, 3):
        raise InvalidArgumentError("B", "an (N, n, m) stack or one (n, m) matrix", repr(B))
    a = a[None] if a.ndim == 2 else a
    b = b[None] if b.ndim == 2 else b
    if a.shape[0] == 0:
        raise InvalidArgumentError("A", "at least one vertex", "an empty stack")
    n = a.shape[1]
    if a.shape[2] != n:
        raise InvalidArgumentError("A", "square vertices (n, n)", f"shape {a.shape[1:]}")
    if b.shape[0] != a.shape[0] or b.shape[1] != n:
        raise InvalidArgumentError(
            "B", f"shape ({a.shape[0]}, {n}, m) matching A", f"shape {b.shape}"
        )
    for name, arr in (("A", a), ("B", b)):
        if not np.all(np.isfinite(arr)):
            raise InvalidArgumentError(name, "finite values", "NaN or inf")
    m = b.shape[2]
    q1 = check_psd(as_matrix(Q, "Q", (n, n)), "Q")
    r = check_pd(as_matrix(R, "R", (m, m)), "R")
    dt = check_positive(dt, "dt")
    check_choice(input_constraint, "input_constraint", INPUT_CONSTRAINTS)
    check_choice(formulation, "formulation", FORMULATIONS)
    umax = input_bound_vector(input_constraint, u_max, m)
    if (output_matrix is None) != (y_max is None):
        raise InvalidArgumentError(
            "output_matrix", "output_matrix and y_max given together", "only one of them"
        )
    if output_matrix is not None:
        c_out = as_matrix(output_matrix, "output_matrix", (None, n))
        ymax = _bound_vector(y_max, "y_max", c_out.shape[0])
    else:
        c_out, ymax = None, np.zeros(0)
    arrays = [a, b, q1, r, umax, ymax] + ([c_out] if c_out is not None else [])
    for arr in arrays:
        arr.setflags(write=False)
    rh = np.linalg.cholesky(r).T
    return KothareData(
        A=a, B=b, Q1=q1, R=r, Q1h=psd_factor(q1), Rh=rh, dt=dt,
        input_constraint=input_constraint, u_max=umax, C_out=c_out, y_max=ymax,
        formulation=formulation,
    )
