"""Argument checks that raise :mod:`toolkit_common.errors` with messages naming the argument."""

from __future__ import annotations

from collections.abc import Iterable
from numbers import Real
from typing import Any

import numpy as np

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = [
    "as_matrix",
    "as_vector",
    "check_choice",
    "check_pd",
    "check_positive",
    "check_psd",
    "check_real",
    "check_symmetric",
]


def _describe_shape(arr: np.ndarray) -> str:
    return f"shape {arr.shape}"


def _to_float_array(value: Any, name: str) -> np.ndarray:
    if isinstance(value, str | bytes):
        raise ArgumentTypeError(name, "a numeric array", f"{type(value).__name__} {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ArgumentTypeError(
            name, "a numeric array", f"{type(value).__name__} ({err})"
        ) from None
    return arr


def _check_finite(arr: np.ndarray, name: str) -> None:
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        where = tuple(int(i) for i in bad)
        raise InvalidArgumentError(
            name, "finite values", f"{arr[tuple(bad)]} at index {where}"
        )


def as_vector(value: Any, name: str, size: int | None = None) -> np.ndarray:
    """Return ``value`` as a finite 1-D float array, checking its length.

    Parameters
    ----------
    value : array_like
        The vector. A column or row matrix of the right length is accepted and flattened.
    name : str
        Argument name for error messages.
    size : int, optional
        The required length.

    Raises
    ------
    InvalidArgumentError
        On a wrong length, more than one non-singleton dimension, NaN or inf.
    ArgumentTypeError
        When ``value`` is not numeric.
    """
    arr = _to_float_array(value, name)
    if arr.ndim > 1 and sum(d > 1 for d in arr.shape) <= 1:
        arr = arr.reshape(-1)
    if arr.ndim != 1:
        expected = f"a vector of length {size}" if size is not None else "a vector"
        raise InvalidArgumentError(name, expected, _describe_shape(arr))
    if size is not None and arr.shape[0] != size:
        raise InvalidArgumentError(name, f"a vector of length {size}", f"length {arr.shape[0]}")
    _check_finite(arr, name)
    return arr


def as_matrix(
    value: Any,
    name: str,
    shape: tuple[int | None, int | None] | None = None,
) -> np.ndarray:
    """Return ``value`` as a finite 2-D float array of the given shape.

    ``None`` in ``shape`` leaves that dimension free. A scalar is accepted for a 1 x 1 matrix.
    """
    arr = _to_float_array(value, name)
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    if arr.ndim != 2:
        raise InvalidArgumentError(name, "a 2-D matrix", f"{arr.ndim}-D array of {_describe_shape(arr)}")
    if shape is not None:
        rows, cols = shape
        if (rows is not None and arr.shape[0] != rows) or (cols is not None and arr.shape[1] != cols):
            want = f"({'n' if rows is None else rows}, {'m' if cols is None else cols})"
            raise InvalidArgumentError(name, f"shape {want}", _describe_shape(arr))
    _check_finite(arr, name)
    return arr


def check_symmetric(mat: np.ndarray, name: str, rtol: float = 1e-9) -> np.ndarray:
    """Check that a square matrix is symmetric and return its symmetric part."""
    if mat.shape[0] != mat.shape[1]:
        raise InvalidArgumentError(name, "a square matrix", _describe_shape(mat))
    scale = max(1.0, float(np.max(np.abs(mat))))
    asym = float(np.max(np.abs(mat - mat.T)))
    if asym > rtol * scale:
        raise InvalidArgumentError(
            name, "a symmetric matrix", f"max |M - M'| = {asym:.3g}"
        )
    return 0.5 * (mat + mat.T)


def check_psd(mat: np.ndarray, name: str, tol: float = 1e-10) -> np.ndarray:
    """Check that ``mat`` is symmetric positive semidefinite; return its symmetric part."""
    sym = check_symmetric(mat, name)
    lam = float(np.min(np.linalg.eigvalsh(sym)))
    scale = max(1.0, float(np.max(np.abs(sym))))
    if lam < -tol * scale:
        raise InvalidArgumentError(
            name, "a positive semidefinite matrix", f"smallest eigenvalue {lam:.3g}"
        )
    return sym


def check_pd(mat: np.ndarray, name: str) -> np.ndarray:
    """Check that ``mat`` is symmetric positive definite; return its symmetric part."""
    sym = check_symmetric(mat, name)
    lam = float(np.min(np.linalg.eigvalsh(sym)))
    if not lam > 0.0:
        raise InvalidArgumentError(
            name, "a positive definite matrix", f"smallest eigenvalue {lam:.3g}"
        )
    return sym


def check_real(value: Any, name: str) -> float:
    """Return ``value`` as a finite float."""
    if isinstance(value, bool) or not isinstance(value, Real | np.floating | np.integer):
        raise ArgumentTypeError(name, "a real number", f"{type(value).__name__} {value!r}")
    out = float(value)
    if not np.isfinite(out):
        raise InvalidArgumentError(name, "a finite number", repr(out))
    return out


def check_positive(value: Any, name: str, allow_zero: bool = False) -> float:
    """Return ``value`` as a finite float that is > 0 (or >= 0 with ``allow_zero``)."""
    out = check_real(value, name)
    if out < 0.0 or (out == 0.0 and not allow_zero):
        expected = "a number >= 0" if allow_zero else "a number > 0"
        raise InvalidArgumentError(name, expected, repr(out))
    return out


def check_choice(value: Any, name: str, choices: Iterable[Any]) -> Any:
    """Check that ``value`` is one of ``choices`` and return it."""
    options = list(choices)
    if value not in options:
        listed = ", ".join(repr(c) for c in options)
        raise InvalidArgumentError(name, f"one of {listed}", repr(value))
    return value
