"""The QP description shared by every back-end, its result, and a KKT certificate.

The problem solved by every back-end of :mod:`rmpc.qp` is

.. math::

    \\min_z \\tfrac12 z^T H z + g^T z \\quad \\text{s.t.} \\quad
    l \\le C z \\le u, \\qquad lb \\le z \\le ub,

with ``H`` symmetric positive semidefinite. Bounds may be infinite (a missing side); an
equality row has ``l_i == u_i``.

Multipliers follow one sign convention for all back-ends (OSQP's): the Lagrangian is
``1/2 z'Hz + g'z + y_C' C z + y_box' z`` (plus bound terms), so at a KKT point
``H z + g + C' y_C + y_box = 0`` with ``y_i > 0`` where the upper bound is active and
``y_i < 0`` where the lower bound is active.

Examples
--------
>>> import numpy as np
>>> from rmpc.qp import QP
>>> qp = QP(H=np.eye(2), g=[-1.0, 1.0], lb=[-0.5, -0.5], ub=[0.5, 0.5])
>>> qp.n_vars, qp.n_cons
(2, 0)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.status import Status, as_status
from toolkit_common.validation import as_matrix, as_vector, check_psd

__all__ = [
    "QP",
    "SPARSE_PSD_CHECK_LIMIT",
    "STATUSES",
    "KKTResiduals",
    "QPResult",
    "SolverResiduals",
    "as_bound_vector",
    "kkt_residuals",
]

#: The words of the toolkit's status vocabulary (:class:`~toolkit_common.status.Status`) a QP
#: back-end reports. ``"optimal"`` is the only status whose ``x`` a controller should apply
#: without further checks; ``"inaccurate"`` means the solver met only reduced tolerances (its
#: ``x`` is returned, flagged); every other status comes with ``x`` = NaN.
STATUSES: tuple[Status, ...] = (
    Status.OPTIMAL,
    Status.INACCURATE,
    Status.INFEASIBLE,
    Status.UNBOUNDED,
    Status.MAX_ITERATIONS,
    Status.TIME_LIMIT,
    Status.NUMERICAL_ERROR,
    Status.INTERRUPTED,
    Status.NOT_SOLVED,
)


def as_bound_vector(value: Any, name: str, size: int, default: float) -> np.ndarray:
    """Return a bound vector of length ``size``: finite values or the infinity ``default``.

    ``None`` gives ``default`` everywhere; a scalar is broadcast. NaN is rejected, and so is
    an infinity of the wrong sign (``+inf`` as a lower bound, ``-inf`` as an upper one).
    """
    if value is None:
        return np.full(size, default)
    if isinstance(value, str | bytes):
        raise InvalidArgumentError(name, "a numeric vector", f"{type(value).__name__} {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidArgumentError(name, "a numeric vector", f"{type(value).__name__} ({err})") from None
    if arr.ndim == 0:
        arr = np.full(size, float(arr))
    elif arr.ndim > 1 and sum(d > 1 for d in arr.shape) <= 1:
        arr = arr.reshape(-1)
    if arr.shape != (size,):
        raise InvalidArgumentError(name, f"a vector of length {size}", f"shape {arr.shape}")
    if np.any(np.isnan(arr)):
        i = int(np.argmax(np.isnan(arr)))
        raise InvalidArgumentError(name, "numbers or infinities", f"NaN at index {i}")
    wrong = arr == -default
    if np.any(wrong):
        i = int(np.argmax(wrong))
        raise InvalidArgumentError(
            name, f"finite values or {default} (a missing bound)", f"{-default} at index {i}"
        )
    return arr


#: Up to this many variables a sparse ``H`` is checked for semidefiniteness on its dense form
#: (an eigenvalue decomposition, about 0.5 s at 2000 on a 2-core machine); above, symmetry only.
SPARSE_PSD_CHECK_LIMIT = 2000


def _sparse_matrices(h_in: Any, c_in: Any) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """``H`` and ``C`` as CSC matrices (either may come dense), checked as the dense ones are."""
    h = sp.csc_matrix(h_in if sp.issparse(h_in) else as_matrix(h_in, "H"), dtype=float)
    n = h.shape[0]
    if h.shape != (n, n):
        raise InvalidArgumentError("H", "a square matrix", f"shape {h.shape}")
    if not np.isfinite(h.data).all():
        raise InvalidArgumentError("H", "finite values", "NaN or inf among its entries")
    scale = max(1.0, float(abs(h).max()) if h.nnz else 1.0)
    asym = abs(h - h.T)
    if asym.nnz and float(asym.max()) > 1e-9 * scale:
        raise InvalidArgumentError("H", "a symmetric matrix", f"|H - H'| up to {float(asym.max()):.3g}")
    h = sp.csc_matrix(0.5 * (h + h.T))
    if n <= SPARSE_PSD_CHECK_LIMIT:
        check_psd(h.toarray(), "H")
    if c_in is None:
        c = sp.csc_matrix((0, n))
    else:
        c = sp.csc_matrix(c_in if sp.issparse(c_in) else as_matrix(c_in, "C", (None, n)), dtype=float)
        if c.ndim != 2 or c.shape[1] != n:
            raise InvalidArgumentError("C", f"a matrix with {n} columns", f"shape {c.shape}")
        if not np.isfinite(c.data).all():
            raise InvalidArgumentError("C", "finite values", "NaN or inf among its entries")
    return h, c


def _check_ordered(lower: np.ndarray, upper: np.ndarray, names: tuple[str, str]) -> None:
    bad = lower > upper
    if np.any(bad):
        i = int(np.argmax(bad))
        raise InvalidArgumentError(
            f"{names[0]}, {names[1]}", f"{names[0]} <= {names[1]} element-wise",
            f"{names[0]}[{i}] = {lower[i]:.6g} > {names[1]}[{i}] = {upper[i]:.6g}",
        )


@dataclass(frozen=True)
class QP:
    """``min 1/2 z'Hz + g'z`` s.t. ``l <= C z <= u`` and ``lb <= z <= ub`` (validated).

    Parameters
    ----------
    H : (n, n) array_like
        Symmetric positive semidefinite Hessian (its symmetric part is stored).
    g : (n,) array_like
        Linear term.
    C : (m, n) array_like, optional
        Constraint matrix; ``None`` means no general constraints (``m = 0``).
    l, u : (m,) array_like, optional
        Lower and upper bounds on ``C z``; ``-inf`` / ``+inf`` (the defaults) mean none.
    lb, ub : (n,) array_like, optional
        Box bounds on ``z``; ``-inf`` / ``+inf`` (the defaults) mean none.

    Raises
    ------
    InvalidArgumentError
        On wrong shapes, a non-symmetric or indefinite ``H``, NaN, ``l > u`` or ``lb > ub``.

    Notes
    -----
    ``H`` and ``C`` may be given as ``scipy.sparse`` matrices (a large structured problem, such
    as the scenario tree of :class:`rmpc.MultiStageMPC`): both are then stored as CSC matrices
    and stay sparse; the OSQP back-end uses them as they are, the dense back-ends (ProxQP,
    Clarabel's stacking, cvxpy) need dense arrays. A sparse ``H`` is checked for symmetry;
    it is checked for semidefiniteness on its dense form up to :data:`SPARSE_PSD_CHECK_LIMIT`
    variables, above that not (an indefinite one is then reported by the solver: OSQP's
    "non convex", ``"numerical_error"``).
    """

    H: Any
    g: Any
    C: Any = None
    l: Any = None  # noqa: E741 - the name the QP solvers use for the lower bound
    u: Any = None
    lb: Any = None
    ub: Any = None

    def __post_init__(self) -> None:
        sparse = sp.issparse(self.H) or sp.issparse(self.C)
        if sparse:
            h, c = _sparse_matrices(self.H, self.C)
            n = h.shape[0]
        else:
            h = as_matrix(self.H, "H")
            n = h.shape[0]
            h = check_psd(as_matrix(h, "H", (n, n)), "H")
            c = np.zeros((0, n)) if self.C is None else as_matrix(self.C, "C", (None, n))
        g = as_vector(self.g, "g", n)
        m = c.shape[0]
        lo = as_bound_vector(self.l, "l", m, -np.inf)
        up = as_bound_vector(self.u, "u", m, np.inf)
        lb = as_bound_vector(self.lb, "lb", n, -np.inf)
        ub = as_bound_vector(self.ub, "ub", n, np.inf)
        _check_ordered(lo, up, ("l", "u"))
        _check_ordered(lb, ub, ("lb", "ub"))
        for name, arr in (("H", h), ("g", g), ("C", c), ("l", lo), ("u", up), ("lb", lb), ("ub", ub)):
            (arr.data if sp.issparse(arr) else arr).setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def is_sparse(self) -> bool:
        """``True`` when ``H`` and ``C`` are held as sparse (CSC) matrices."""
        return bool(sp.issparse(self.H))

    @property
    def n_vars(self) -> int:
        """Number of decision variables ``n``."""
        return int(self.H.shape[0])

    @property
    def n_cons(self) -> int:
        """Number of general constraint rows ``m`` (rows of ``C``)."""
        return int(self.C.shape[0])

    def objective(self, z: ArrayLike) -> float:
        """``1/2 z'Hz + g'z`` at ``z``."""
        z = as_vector(z, "z", self.n_vars)
        return float(0.5 * z @ self.H @ z + self.g @ z)

    def replace(self, **vectors: Any) -> QP:
        """A copy with some of ``g, l, u, lb, ub`` (or matrices) replaced, re-validated."""
        data = {k: getattr(self, k) for k in ("H", "g", "C", "l", "u", "lb", "ub")}
        for key, value in vectors.items():
            if key not in data:
                raise InvalidArgumentError("replace", f"keys among {sorted(data)}", repr(key))
            data[key] = value
        return QP(**data)


@dataclass(frozen=True)
class SolverResiduals:
    """Residuals as the solver itself reports them (NaN where a solver reports none).

    These are in each solver's own norms and scalings; for a solver-independent check use
    :func:`kkt_residuals`.
    """

    primal: float = float("nan")
    dual: float = float("nan")
    gap: float = float("nan")


@dataclass(frozen=True)
class QPResult:
    """The answer of one ``solve()``.

    Attributes
    ----------
    x : (n,) ndarray
        The primal solution; all NaN unless ``status`` is ``"optimal"`` or ``"inaccurate"``.
    objective : float
        ``1/2 x'Hx + g'x`` evaluated at ``x`` (NaN with ``x``).
    status : Status
        One word of :data:`STATUSES` (a plain string is converted; a word outside the
        vocabulary is an error).
    iterations : int
        Solver iterations (-1 where unknown).
    solve_time : float
        Wall time of the solver call (s), measured around the binding's ``solve``.
    residuals : SolverResiduals
        What the solver reports about its own accuracy.
    y_C : (m,) ndarray
        Multipliers of ``l <= C z <= u`` (sign convention of :mod:`rmpc.qp.problem`).
    y_box : (n,) ndarray
        Multipliers of ``lb <= z <= ub``.
    raw_status : str
        The solver's own status word, for reports.
    backend : str
        The back-end's name.
    info : dict
        Back-end specific details (e.g. OSQP's polishing status).
    """

    x: np.ndarray
    objective: float
    status: Status
    iterations: int
    solve_time: float
    residuals: SolverResiduals
    y_C: np.ndarray
    y_box: np.ndarray
    raw_status: str
    backend: str
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "status", as_status(self.status, "QPResult.status"))

    @property
    def ok(self) -> bool:
        """``True`` when ``status == "optimal"``."""
        return self.status == Status.OPTIMAL


@dataclass(frozen=True)
class KKTResiduals:
    """Solver-independent optimality certificate of a primal-dual point (infinity norms).

    Attributes
    ----------
    primal : float
        Largest bound violation of ``C z`` and ``z``.
    dual : float
        ``||H z + g + C' y_C + y_box||_inf``.
    complementarity : float
        Largest ``|y_i| * (distance of row i to the bound its sign selects)``; a multiplier
        pushing against an infinite bound counts as ``|y_i|``.
    """

    primal: float
    dual: float
    complementarity: float

    def max(self) -> float:
        """The largest of the three."""
        return max(self.primal, self.dual, self.complementarity)


def _comp(values: np.ndarray, y: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> float:
    if values.size == 0:
        return 0.0
    up_gap = np.where(np.isfinite(upper), np.abs(upper - values), 1.0)
    lo_gap = np.where(np.isfinite(lower), np.abs(values - lower), 1.0)
    terms = np.where(y > 0, y * up_gap, np.where(y < 0, -y * lo_gap, 0.0))
    return float(np.max(terms))


def _viol(values: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> float:
    if values.size == 0:
        return 0.0
    return float(np.max(np.maximum(np.maximum(lower - values, values - upper), 0.0)))


def kkt_residuals(
    qp: QP,
    x: ArrayLike,
    y_C: ArrayLike | None = None,
    y_box: ArrayLike | None = None,
) -> KKTResiduals:
    """Primal, dual and complementarity residuals of ``(x, y_C, y_box)`` for ``qp``.

    Parameters
    ----------
    qp : QP
        The problem.
    x : (n,) array_like or QPResult
        The primal point, or a result (its ``x``, ``y_C`` and ``y_box`` are used).
    y_C, y_box : array_like, optional
        Multipliers (default zeros), in the sign convention of :mod:`rmpc.qp.problem`.

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.qp import QP, kkt_residuals
    >>> qp = QP(H=np.eye(1), g=[-2.0], ub=[1.0])
    >>> kkt_residuals(qp, [1.0], y_box=[1.0]).max()
    0.0
    """
    if isinstance(x, QPResult):
        x, y_C, y_box = x.x, x.y_C, x.y_box
    n, m = qp.n_vars, qp.n_cons
    x = as_vector(x, "x", n)
    yc = np.zeros(m) if y_C is None else as_vector(y_C, "y_C", m)
    yb = np.zeros(n) if y_box is None else as_vector(y_box, "y_box", n)
    cx = qp.C @ x
    primal = max(_viol(cx, qp.l, qp.u), _viol(x, qp.lb, qp.ub))
    dual = float(np.max(np.abs(qp.H @ x + qp.g + qp.C.T @ yc + yb)))
    comp = max(_comp(cx, yc, qp.l, qp.u), _comp(x, yb, qp.lb, qp.ub))
    return KKTResiduals(primal=primal, dual=dual, complementarity=comp)
