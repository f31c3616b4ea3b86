"""Argument checks that raise :mod:`toolkit_common.errors` with messages naming the argument.

Every package of the toolkit checks its arguments here, so one kind of argument gets one check
and one message:

- numbers and choices: :func:`check_real`, :func:`check_positive`, :func:`check_bool`,
  :func:`check_choice`;
- arrays: :func:`as_array`, :func:`as_vector`, :func:`as_matrix`, :func:`check_symmetric`, :func:`check_psd`,
  :func:`check_pd`;
- per-component values given as a scalar or one per component (gains, limits):
  :func:`as_positive_values`, :func:`as_optional_limits`;
- square matrices given as a scalar, a diagonal or in full (gains, weights, an inertia):
  :func:`as_square_matrix`, :func:`as_inertia`;
- arguments that were renamed: :func:`renamed_arguments`.

(Length: about 460 lines, most of them the documentation and examples of the checks; one module,
so that every package finds its argument checks in one place.)
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable
from numbers import Integral, Real
from typing import Any, Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = [
    "as_array",
    "as_inertia",
    "as_matrix",
    "as_optional_limits",
    "as_positive_values",
    "as_real_array",
    "as_square_matrix",
    "as_vector",
    "check_bool",
    "check_choice",
    "check_count",
    "check_pd",
    "check_positive",
    "check_psd",
    "check_real",
    "check_symmetric",
    "is_integer",
    "is_real",
    "renamed_arguments",
]

_F = TypeVar("_F", bound=Callable[..., Any])


def _describe_shape(arr: np.ndarray) -> str:
    return f"shape {arr.shape}"


def _to_float_array(
    value: Any, name: str, expected: str = "a numeric array", *, copy: bool = False, allow_bool: bool = False
) -> np.ndarray:
    """``value`` as a float array (a new one with ``copy``).

    A string, ``None``, a non-numeric value or a complex value with a nonzero imaginary part is an
    error that says what was found (a complex array whose imaginary parts are all zero, as
    eigenvalue routines return, is taken as its real part).
    """
    rejected = str | bytes if allow_bool else str | bytes | bool | np.bool_
    if value is None:
        raise ArgumentTypeError(name, expected, "None")
    if isinstance(value, rejected):
        raise ArgumentTypeError(name, expected, f"{type(value).__name__} {value!r}")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as err:
        raise ArgumentTypeError(name, expected, f"{type(value).__name__} ({err})") from None
    if np.iscomplexobj(raw):
        imaginary = np.abs(np.imag(raw))
        if raw.size and float(np.nanmax(imaginary, initial=0.0)) > 0.0:
            where = tuple(int(i) for i in np.argwhere(imaginary > 0)[0])
            raise ArgumentTypeError(
                name, "real values", f"complex {raw[where] if where else raw[()]} at index {where}"
            )
        raw = np.real(raw)
    try:
        return np.array(raw, dtype=float) if copy else np.asarray(raw, dtype=float)
    except (TypeError, ValueError) as err:
        raise ArgumentTypeError(name, expected, f"{type(value).__name__} ({err})") from None


def as_real_array(value: Any, name: str, expected: str = "a numeric array") -> np.ndarray:
    """``value`` as a float array of any shape, without copying when it already is one.

    Unlike ``np.asarray(value, dtype=float)``, a complex value is refused (numpy would drop its
    imaginary part with a warning) and a string, ``None`` or a non-numeric value is an error
    naming ``name`` and saying what was found; NaN and inf pass (check them where they matter).

    Examples
    --------
    >>> from toolkit_common.validation import as_real_array
    >>> as_real_array([[1, 2]], "C").dtype
    dtype('float64')
    >>> as_real_array([1.0, 2.0 + 1.0j], "C")
    Traceback (most recent call last):
    ...
    toolkit_common.errors.ArgumentTypeError: C: expected real values, but found complex (2+1j) at index (1,)
    """
    return _to_float_array(value, name, expected)


def _check_finite(arr: np.ndarray, name: str) -> None:
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        where = tuple(int(i) for i in bad)
        raise InvalidArgumentError(
            name, "finite values", f"{arr[tuple(bad)]} at index {where}"
        )


def as_array(value: Any, name: str) -> np.ndarray:
    """``value`` as a new finite float array of any shape.

    Examples
    --------
    >>> from toolkit_common.validation import as_array
    >>> as_array([[1, 2], [3, 4]], "M").shape
    (2, 2)
    >>> as_array([1.0, float("nan")], "M")
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: M: expected finite values, but found nan at index (1,)
    """
    arr = _to_float_array(value, name, copy=True)
    _check_finite(arr, name)
    return arr


def as_vector(value: ArrayLike, name: str, size: int | None = None) -> np.ndarray:
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


def is_integer(value: Any) -> bool:
    """Whether ``value`` is an integer: a Python ``int`` or a NumPy integer (``np.int64(10)``, as
    indexing and ``len`` of arrays give them), not a ``bool``.

    Examples
    --------
    >>> import numpy as np
    >>> from toolkit_common.validation import is_integer
    >>> is_integer(10), is_integer(np.int64(10)), is_integer(True), is_integer(10.0)
    (True, True, False, False)
    """
    return isinstance(value, Integral) and not isinstance(value, bool | np.bool_)


def is_real(value: Any) -> bool:
    """Whether ``value`` is a real number: a Python ``int`` or ``float`` or a NumPy integer or
    floating scalar, not a ``bool`` (NaN and inf included: check them where they matter)."""
    return isinstance(value, Real | np.floating | np.integer) and not isinstance(value, bool | np.bool_)


def check_real(value: Any, name: str) -> float:
    """Return ``value`` as a finite float."""
    if not is_real(value):
        found = "None" if value is None else f"{type(value).__name__} {value!r}"
        raise ArgumentTypeError(name, "a real number", found)
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
    """Check that ``value`` is one of ``choices`` and return it (an array or any value that cannot
    be compared is not one of them)."""
    options = list(choices)
    try:
        known = not isinstance(value, np.ndarray) and any(bool(value == option) for option in options)
    except (TypeError, ValueError):
        known = False
    if not known:
        listed = ", ".join(repr(c) for c in options)
        raise InvalidArgumentError(name, f"one of {listed}", repr(value))
    return value


def check_bool(value: Any, name: str) -> bool:
    """Return ``value`` as a ``bool``; only ``True`` and ``False`` (Python or NumPy) are accepted.

    Examples
    --------
    >>> from toolkit_common.validation import check_bool
    >>> check_bool(True, "flag")
    True
    >>> check_bool(1, "flag")
    Traceback (most recent call last):
    ...
    toolkit_common.errors.ArgumentTypeError: flag: expected True or False, but found int 1
    """
    if not isinstance(value, bool | np.bool_):
        raise ArgumentTypeError(name, "True or False", f"{type(value).__name__} {value!r}")
    return bool(value)


def check_count(value: Any, name: str, *, limit: int | None = None, limit_name: str = "limit",
                unit: str = "", expected: str = "a positive integer") -> int:
    """Return ``value`` as an ``int >= 1`` (a NumPy integer is accepted, a ``bool`` is not), at most
    ``limit`` when one is given: the error then names the limit's argument ``limit_name`` and how to
    lift it.

    Examples
    --------
    >>> from toolkit_common.validation import check_count
    >>> check_count(3, "n_axes", limit=1000, limit_name="max_axes", unit=" axes")
    3
    >>> try:
    ...     check_count(5000, "n_axes", limit=1000, limit_name="max_axes", unit=" axes")
    ... except ValueError as err:
    ...     print(err)
    n_axes: expected at most max_axes = 1000 axes (pass a larger max_axes to lift it), but found 5000
    """
    if not is_integer(value) or value < 1:
        raise InvalidArgumentError(name, expected, repr(value))
    if limit is not None and value > limit:
        raise InvalidArgumentError(
            name, f"at most {limit_name} = {limit}{unit} (pass a larger {limit_name} to lift it)", repr(value)
        )
    return int(value)


def _positive_values(
    value: Any, name: str, size: int | None, allow_zero: bool, allow_inf: bool, per: str, what: str,
    optional: bool,
) -> np.ndarray:
    """The body of :func:`as_positive_values` and :func:`as_optional_limits` (one wording)."""
    none = "None, " if optional else ""
    expected = f"{none}a number or one number per {per}"
    arr = _to_float_array(value, name, expected, copy=True, allow_bool=False)
    if arr.ndim == 0:
        arr = np.full(1 if size is None else size, float(arr))
    if arr.ndim != 1 or (size is not None and arr.shape != (size,)):
        count = "" if size is None else f" ({size} of them)"
        raise InvalidArgumentError(name, expected + count, f"shape {arr.shape}")
    sign_ok = arr >= 0.0 if allow_zero else arr > 0.0
    finite_ok = np.isfinite(arr) | (allow_inf & (arr == np.inf))
    if not np.all(sign_ok & finite_ok):
        bound = ">= 0" if allow_zero else "> 0"
        if allow_inf:
            wanted = f"{what} {bound} (inf for none)"
        elif np.all(np.isfinite(arr)):
            wanted = f"{what} {bound}"
        else:
            wanted = f"finite {what} {bound}"
        raise InvalidArgumentError(name, ("None or " if optional else "") + wanted, repr(arr.tolist()))
    return arr


def as_positive_values(
    value: ArrayLike,
    name: str,
    size: int | None,
    *,
    allow_zero: bool = False,
    allow_inf: bool = False,
    per: str = "component",
    what: str = "values",
) -> np.ndarray:
    """Per-component values, each > 0: a scalar (the same for every component) or one per component.

    Parameters
    ----------
    value : float or array_like
        A number, or ``size`` numbers.
    name : str
        Argument name for error messages.
    size : int or None
        Number of components; ``None`` accepts a vector of any length (a scalar then gives one
        component).
    allow_zero : bool
        Accept values equal to 0.
    allow_inf : bool
        Accept ``inf`` (a limit that is not there).
    per : str
        What a component is, for the messages ("axis", "wheel", "mode", ...).
    what : str
        What the values are, for the messages ("values", "gains", "limits", ...).

    Returns
    -------
    ndarray, shape (size,)
        A new float array.

    Raises
    ------
    ArgumentTypeError
        When ``value`` is not numeric (a string, a bool).
    InvalidArgumentError
        On a wrong length, NaN, ``inf`` (unless allowed) or a value <= 0 (< 0 with ``allow_zero``).

    Examples
    --------
    >>> from toolkit_common.validation import as_positive_values
    >>> as_positive_values(0.5, "gain", 3, per="axis").tolist()
    [0.5, 0.5, 0.5]
    >>> as_positive_values([1.0, -2.0, 3.0], "gain", 3, per="axis")
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: gain: expected values > 0, but found [1.0, -2.0, 3.0]
    """
    return _positive_values(value, name, size, allow_zero, allow_inf, per, what, optional=False)


def as_optional_limits(value: Any, name: str, size: int, *, per: str = "component") -> np.ndarray | None:
    """``None`` (no limit) or finite limits > 0, one per component (a scalar applies to every one).

    The bounds of a command (``u_max``), of its increment or of its rate; the checks are those of
    :func:`as_positive_values`.

    Examples
    --------
    >>> from toolkit_common.validation import as_optional_limits
    >>> as_optional_limits(None, "u_max", 3) is None
    True
    >>> as_optional_limits(2.0, "u_max", 3, per="axis").tolist()
    [2.0, 2.0, 2.0]
    >>> as_optional_limits([1.0, 0.0, 1.0], "u_max", 3, per="axis")
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: u_max: expected None or limits > 0, but found [1.0, 0.0, 1.0]
    """
    if value is None:
        return None
    return _positive_values(value, name, size, False, False, per, "limits", optional=True)


def as_square_matrix(
    value: ArrayLike,
    name: str,
    size: int,
    *,
    scalar: bool = True,
    allow_zero: bool = False,
    definite: Literal["pd", "psd"] | None = "pd",
    entries: str = "diagonal entries",
) -> np.ndarray:
    """A ``size x size`` matrix given as a scalar ``s`` (``s I``), a diagonal ``v`` or in full.

    Gains, weights and inertias are written all three ways; this is their one reading.

    Parameters
    ----------
    value : float or array_like
        ``s`` (when ``scalar``), ``size`` diagonal entries, or a ``(size, size)`` matrix.
    name : str
        Argument name for error messages.
    size : int
        Order of the matrix.
    scalar : bool
        Accept a scalar (``s I``).
    allow_zero : bool
        Accept a zero scalar or zero diagonal entries (they must be > 0 otherwise, >= 0 with it).
    definite : {"pd", "psd"} or None
        Check a full matrix to be symmetric positive definite (``"pd"``), semidefinite
        (``"psd"``; its symmetric part is returned in both cases), or only finite (``None``).
    entries : str
        What the diagonal entries are, for the messages ("principal inertias (kg m^2)", ...).

    Returns
    -------
    ndarray, shape (size, size)
        A new float array.

    Examples
    --------
    >>> from toolkit_common.validation import as_square_matrix
    >>> as_square_matrix(2.0, "K", 2).tolist()
    [[2.0, 0.0], [0.0, 2.0]]
    >>> as_square_matrix([1.0, 3.0], "K", 2).tolist()
    [[1.0, 0.0], [0.0, 3.0]]
    >>> as_square_matrix([[1.0, 2.0], [2.0, 1.0]], "K", 2)
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: K: expected a positive definite matrix, but found \
smallest eigenvalue -1
    """
    forms = f"{'a scalar, ' if scalar else ''}{size} {entries} or a {size} x {size} matrix"
    arr = _to_float_array(value, name, forms, copy=True, allow_bool=False)
    if arr.ndim == 0 and scalar:
        return check_positive(float(arr), name, allow_zero=allow_zero) * np.eye(size)
    if arr.ndim == 1:
        diag = as_vector(arr, name, size)
        if np.any(diag < 0.0) or (not allow_zero and np.any(diag == 0.0)):
            sign = "non-negative" if allow_zero else "positive"
            raise InvalidArgumentError(name, f"{sign} {entries}", repr(diag.tolist()))
        return np.diag(diag)
    if arr.ndim != 2:
        raise InvalidArgumentError(name, forms, f"shape {arr.shape}")
    mat = as_matrix(arr, name, (size, size))
    if definite == "pd":
        return check_pd(mat, name)
    if definite == "psd":
        return check_psd(mat, name)
    return mat


def as_inertia(value: Any, name: str = "inertia") -> np.ndarray:
    """A rigid body's inertia: three principal inertias (> 0) or a 3 x 3 symmetric positive definite matrix.

    Returns the ``3 x 3`` matrix (kg m^2); see :func:`as_square_matrix`.

    Examples
    --------
    >>> from toolkit_common.validation import as_inertia
    >>> as_inertia([1.0, 2.0, 3.0]).diagonal().tolist()
    [1.0, 2.0, 3.0]
    >>> as_inertia([1.0, -2.0, 3.0])
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: inertia: expected positive principal inertias (kg m^2), but \
found [1.0, -2.0, 3.0]
    """
    return as_square_matrix(value, name, 3, scalar=False, entries="principal inertias (kg m^2)")


def renamed_arguments(**renames: str) -> Callable[[_F], _F]:
    """Decorate a function whose keyword arguments were renamed: an old name raises a clear error.

    ``@renamed_arguments(old="new")``: a call with ``old=...`` raises
    :class:`~toolkit_common.errors.ArgumentTypeError` naming ``old`` and saying to write ``new``,
    where Python would only say that ``old`` is unexpected. The signature shown by ``help`` and
    the documentation is the function's own.

    Examples
    --------
    >>> from toolkit_common.validation import renamed_arguments
    >>> @renamed_arguments(inertia_spread="spread")
    ... def polytope(dt, spread=None):
    ...     return spread
    >>> polytope(0.1, spread=0.2)
    0.2
    >>> polytope(0.1, inertia_spread=0.2)
    Traceback (most recent call last):
    ...
    toolkit_common.errors.ArgumentTypeError: inertia_spread: expected the argument 'spread' (renamed), \
but found inertia_spread=0.2
    """

    def decorate(func: _F) -> _F:
        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            for old, new in renames.items():
                if old in kwargs:
                    raise ArgumentTypeError(
                        old, f"the argument {new!r} (renamed)", f"{old}={kwargs[old]!r}"
                    )
            return func(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate
