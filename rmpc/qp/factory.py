"""``make_backend(name, **settings)``: a QP back-end by name."""

from __future__ import annotations

from typing import Any

from rmpc.qp.base import QPBackend
from rmpc.qp.clarabel_backend import ClarabelBackend
from rmpc.qp.cvxpy_backend import CvxpyBackend
from rmpc.qp.osqp_backend import OSQPBackend
from rmpc.qp.proxqp_backend import ProxQPBackend
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = ["BACKENDS", "backend_design", "make_backend"]

#: Name -> back-end class. ``"cvxpy"`` is the reference (slow; for tests and benchmarks).
BACKENDS: dict[str, type[QPBackend]] = {
    "osqp": OSQPBackend,
    "proxqp": ProxQPBackend,
    "clarabel": ClarabelBackend,
    "cvxpy": CvxpyBackend,
}


def make_backend(name: str, *, argument: str = "name", **settings: Any) -> QPBackend:
    """Build the back-end called ``name`` with ``settings`` (unknown settings raise).

    Parameters
    ----------
    name : {"osqp", "proxqp", "clarabel", "cvxpy"}
        The back-end.
    argument : str
        The name the caller's user gave ``name`` under (``"backend"`` for a controller), used in
        the error message of an unknown back-end.
    **settings
        Settings of that back-end (see its settings class).

    Examples
    --------
    >>> from rmpc.qp import make_backend
    >>> make_backend("osqp", eps_abs=1e-7).settings.eps_abs
    1e-07
    >>> try:
    ...     make_backend("proxqp", eps=1e-3)
    ... except ValueError as err:
    ...     print(err.argument, "|", err.found)
    settings 'eps' | the unknown setting 'eps'
    """
    if not isinstance(name, str):
        raise ArgumentTypeError(argument, "a back-end name (str)", type(name).__name__)
    key = name.lower()
    if key not in BACKENDS:
        raise InvalidArgumentError(argument, f"one of {', '.join(repr(k) for k in BACKENDS)}", repr(name))
    return BACKENDS[key](**settings)


def backend_design(backend: QPBackend) -> dict[str, Any]:
    """A controller's QP back-end as a saved design writes it: ``{"backend": name,
    "solver_options": settings}``.

    Raises
    ------
    InvalidArgumentError
        Naming ``backend`` for a back-end that is not one of :data:`BACKENDS`' classes (a saved
        design rebuilds the back-end by name).
    """
    import dataclasses

    if BACKENDS.get(backend.name) is not type(backend):
        raise InvalidArgumentError(
            "backend",
            f"one of the toolkit's QP back-ends ({', '.join(BACKENDS)}) to save the controller",
            type(backend).__name__,
        )
    return {"backend": backend.name, "solver_options": dataclasses.asdict(backend.settings)}
