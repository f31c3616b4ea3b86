"""The C core called from Python: the interior-point method of ``ipm.c`` built as the extension
module ``_lmi_ccore`` (:mod:`lmi.ccore.runtime`).

``pip install .`` compiles ``lmi/ccore/ipm.c`` and ``dense.c`` with ``-DKOTHARE_RUNTIME``
(``setup.py``): the source an exported controller compiles, with the problem's sizes and tables
read from a ``kothare_problem_t`` (``runtime.h``) instead of generated macros. This module loads
that build through :mod:`ctypes` and wraps one problem in a :class:`CoreSolver`, which
:class:`lmi.backends.ipm.IPMKothare` uses in place of :class:`lmi.ipm.BlockLMISolver` for its
solves (``core="auto"``, the default, or ``"c"``): no numba compilation on first use, and one
implementation for the Python package and the flight code.

The build is found only if its ``SOURCE_HASH`` (SHA-256 of the C sources it was compiled from)
matches the C sources this package ships: a checkout whose C files changed after the install
runs the numba kernels, with a warning, until it is reinstalled. :func:`core_status` says which
and why.

Examples
--------
>>> from lmi.ccore.runtime import core_status
>>> isinstance(core_status(), str)
True
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib
import threading
import warnings
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

import numpy as np

from lmi.ccore.generate import CORE_DOUBLE_TABLES, CORE_INT_TABLES, LIMITS, core_tables

__all__ = ["HASHED_SOURCES", "CoreResult", "CoreSolver", "StaleCoreWarning", "core_library", "core_status",
           "source_hash"]

#: The C files whose bytes make the build's source hash, in this order (``setup.py`` hashes the same).
HASHED_SOURCES = ("dense.c", "dense.h", "ipm.c", "ipm.h", "runtime.h", "module.c")

#: The solver's words of ``kothare_rt_solve`` (``runtime.h``), as :class:`lmi.ipm.BlockLMISolver`
#: names them before :data:`lmi.ipm.solver.SOLVER_STATUS_MAP`.
WORDS = ("optimal", "infeasible", "max_iterations", "numerical_error", "insufficient_progress", "inaccurate")

# one call into the core at a time: it keeps the call's problem and workspace in file-scope pointers
_CALL_LOCK = threading.Lock()


class StaleCoreWarning(RuntimeWarning):
    """The installed C core was built from other C sources than the package's: reinstall."""


class Problem(ctypes.Structure):
    """``kothare_problem_t`` of ``runtime.h`` (same field order)."""

    _fields_ = [
        *[(name, ctypes.c_int) for name in ("nv", "nb", "kmax", "size", "nent", "basis", "nbound", "degree",
                                             "max_iter", "warm_max_iter")],
        *[(name, ctypes.c_double) for name in ("tol_feas", "tol_gap_abs", "tol_gap_rel", "warm_gap",
                                                "warm_feas", "inf_radius", "qr_switch")],
        *[(name, ctypes.POINTER(ctypes.c_int)) for name in CORE_INT_TABLES],
        *[(name, ctypes.POINTER(ctypes.c_double)) for name in CORE_DOUBLE_TABLES],
    ]


def source_hash() -> str:
    """SHA-256 of :data:`HASHED_SOURCES` as this package ships them."""
    digest = hashlib.sha256()
    package = resources.files("lmi.ccore")
    for name in HASHED_SOURCES:
        digest.update((package / name).read_bytes())
    return digest.hexdigest()


@cache
def _load() -> tuple[Any, str]:
    """The loaded library (or ``None``) and a sentence saying which build runs, once per process."""
    try:
        module = importlib.import_module("_lmi_ccore")
    except ImportError as err:
        return None, f"no C core build ({err}); the numba kernels run"
    built, shipped = getattr(module, "SOURCE_HASH", "unknown"), source_hash()
    if built != shipped:
        warnings.warn(
            f"the installed C core ({module.__file__}) was built from other C sources than "
            "lmi/ccore's; the numba kernels run instead: reinstall the package (pip install .)",
            StaleCoreWarning, stacklevel=3)
        return None, f"stale C core build at {module.__file__} (source hash {built[:12]} != {shipped[:12]})"
    lib = ctypes.CDLL(module.__file__)
    problem_p, void_p, double_p = ctypes.POINTER(Problem), ctypes.c_void_p, ctypes.POINTER(ctypes.c_double)
    lib.kothare_rt_workspace_bytes.argtypes = [problem_p]
    lib.kothare_rt_workspace_bytes.restype = ctypes.c_size_t
    lib.kothare_rt_init.argtypes = [problem_p, void_p]
    lib.kothare_rt_init.restype = None
    lib.kothare_rt_reset_warm_start.argtypes = [problem_p, void_p]
    lib.kothare_rt_reset_warm_start.restype = None
    lib.kothare_rt_solve.argtypes = [problem_p, void_p, double_p, double_p, ctypes.c_int, double_p, double_p,
                                     double_p, double_p]
    lib.kothare_rt_solve.restype = ctypes.c_int
    return lib, f"C core {module.__file__}"


def core_library() -> Any:
    """The loaded C core (a :class:`ctypes.CDLL`), or ``None`` when there is no current build."""
    return _load()[0]


def core_status() -> str:
    """One sentence: the C core build this process runs, or why the numba kernels run instead."""
    return _load()[1]


def _pointer(array: np.ndarray, kind: Any) -> Any:
    return array.ctypes.data_as(ctypes.POINTER(kind))


@dataclass
class CoreResult:
    """One solve of :meth:`CoreSolver.solve` (the fields of :class:`lmi.ipm.solver.IPMResult` that
    :class:`~lmi.backends.ipm.IPMKothare` reads).

    ``word`` is the solver's own word (:data:`WORDS`); ``x`` the variables; ``Z`` the dual blocks
    in the data's units (a Farkas ray normalised to unit norm when ``word`` is ``"infeasible"``).
    """

    word: str
    x: np.ndarray
    Z: list[np.ndarray]
    iterations: int
    primal_residual: float
    dual_residual: float
    gap: float
    infeasibility_radius: float


class CoreSolver:
    """One Kothare problem in the C core: the data of an :class:`~lmi.backends.ipm.IPMKothare`
    (its blocks in their current coordinates, the bound-scaled entries, the solver's settings)
    and the core's workspace (the warm-start point and the equilibration between solves).

    Parameters
    ----------
    backend : IPMKothare
        The back-end whose ``_base_blocks``, ``_scaled_blocks``, ``conic`` and ``_solver``
        (its settings; the Python solver itself is not run) give the data.

    Raises
    ------
    RuntimeError
        When there is no C core build (:func:`core_library`).
    ValueError
        When the problem is beyond :data:`lmi.ccore.generate.LIMITS`.
    """

    def __init__(self, backend: Any) -> None:
        lib = core_library()
        if lib is None:
            raise RuntimeError(core_status())
        core = core_tables(backend)
        if (core.sizes["nv"] > LIMITS["variables"] or core.sizes["kmax"] > LIMITS["order"]
                or core.sizes["nb"] > LIMITS["blocks"]):
            raise ValueError(f"beyond the C core's limits {LIMITS}: {core.sizes}")
        self.n_ub, self.n_yb = core.n_ub, core.n_yb
        self._sizes = core.sizes
        self._orders = [int(k) for k in core.tables["order"]]
        self._tables = {name: np.ascontiguousarray(core.tables[name], dtype=np.intc)
                        for name in CORE_INT_TABLES}
        for name in CORE_DOUBLE_TABLES:
            values = core.tables[name]
            self._tables[name] = np.ascontiguousarray(values if values.size else np.zeros(1), dtype=float)
        self._reals = core.reals
        self._bind(lib)
        nbytes = int(lib.kothare_rt_workspace_bytes(ctypes.byref(self._problem)))
        self._work = np.zeros(nbytes // 8 + 2, dtype=np.float64)  # numpy aligns to 16 bytes
        nv, nb, kmax = core.sizes["nv"], core.sizes["nb"], core.sizes["kmax"]
        self._x, self._z = np.zeros(nv), np.zeros((nb, kmax, kmax))
        self._weights, self._info = np.zeros(nb), np.zeros(5)
        self._bounds = np.zeros(core.sizes["nbound"])
        with _CALL_LOCK:
            lib.kothare_rt_init(ctypes.byref(self._problem), self._work.ctypes.data_as(ctypes.c_void_p))

    def _bind(self, lib: Any) -> None:
        """The ``kothare_problem_t`` over this solver's tables (pointers into its arrays)."""
        problem = Problem(**self._sizes, **self._reals)
        for name in CORE_INT_TABLES:
            setattr(problem, name, _pointer(self._tables[name], ctypes.c_int))
        for name in CORE_DOUBLE_TABLES:
            setattr(problem, name, _pointer(self._tables[name], ctypes.c_double))
        self._problem, self._lib = problem, lib

    @property
    def workspace_bytes(self) -> int:
        """Bytes of the core's workspace for this problem."""
        return int(self._work.nbytes)

    def reset_warm_start(self) -> None:
        """Forget the warm-start point (the next solve starts cold)."""
        with _CALL_LOCK:
            self._lib.kothare_rt_reset_warm_start(ctypes.byref(self._problem),
                                                  self._work.ctypes.data_as(ctypes.c_void_p))

    def solve(self, xs: np.ndarray, u_max: np.ndarray, y_max: np.ndarray, warm_start: bool) -> CoreResult:
        """:meth:`lmi.ipm.BlockLMISolver.solve` on the data at the normalised state ``xs`` and the
        normalised bounds ``u_max``, ``y_max`` (sized as the problem's)."""
        xs = np.ascontiguousarray(xs, dtype=float)
        n_b = self.n_ub + self.n_yb
        if n_b:
            self._bounds[:n_b] = np.concatenate([np.ravel(u_max), np.ravel(y_max)])
        double = ctypes.c_double
        with _CALL_LOCK:
            word = self._lib.kothare_rt_solve(
                ctypes.byref(self._problem), self._work.ctypes.data_as(ctypes.c_void_p), _pointer(xs, double),
                _pointer(self._bounds, double), int(bool(warm_start)), _pointer(self._x, double),
                _pointer(self._z, double), _pointer(self._weights, double), _pointer(self._info, double))
        word_name = WORDS[word]
        # the dual blocks in the data's units: Z_j = w_j Z~_j (lmi.ipm.solver.BlockLMISolver._run)
        z_out = [self._z[j, :k, :k] * self._weights[j] for j, k in enumerate(self._orders)]
        if word_name == "infeasible":
            norm = float(np.sqrt(sum(float(np.sum(z * z)) for z in z_out)))
            z_out = [z / norm for z in z_out]
        pres, dres, gap, radius, its = self._info
        return CoreResult(word_name, self._x.copy(), z_out, int(its), float(pres), float(dres), float(gap),
                          float(radius) if word_name == "infeasible" else float("nan"))

    def __getstate__(self) -> dict[str, Any]:
        """Pickles and copies carry the data and the workspace's bytes, not the C pointers."""
        state = dict(self.__dict__)
        for name in ("_problem", "_lib"):
            state.pop(name)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        """The copied workspace keeps the warm start (the core carves its arrays again there)."""
        self.__dict__.update(state)
        lib = core_library()
        if lib is None:
            raise RuntimeError(core_status())
        self._bind(lib)
