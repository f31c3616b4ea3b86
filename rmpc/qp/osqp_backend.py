"""OSQP 1.x back-end (ADMM; Stellato et al. 2020, "OSQP: an operator splitting solver for
quadratic programs", Math. Prog. Comp. 12).

OSQP's form is ``l <= A z <= u``; the box rows are stacked under ``C``:
``A = [C; I]``. Infinite bounds are passed as is (OSQP clips them to its own infinity), so
changing which bounds are infinite needs no rebuild. ``update`` changes ``q``, ``l`` and
``u`` in place (``update_data_vec``) and the next solve starts from the previous primal-dual
pair (``warm_starting``).

Accuracy. On the GIPC QPs of this toolkit (tight ``|du| <= 0.01`` boxes, Hessian
eigenvalues from 1 to ~3000) OSQP at its default ``eps_abs = eps_rel = 1e-3`` was measured
off by up to 20 % of the ``du`` bound while reporting ``solved``; against an exact
(active-set refined) reference, ``eps = 1e-5`` with polishing was still off by 5 %, 1e-6 by
0.7 %, 1e-7 by 2e-5 and 1e-8 by 1e-7 of the bound (a median of 50 ADMM iterations, about
0.03 ms per warm-started solve). The defaults here are ``eps_abs = eps_rel = 1e-8`` with
``polishing=True``; ``QPResult.info["polish_status"]`` tells whether polishing succeeded
(1), was not needed (2: no active constraint) or failed (-1, the answer is then only
ADMM-accurate).

Output. OSQP 1.1.3 prints "Polishing not needed - no active set detected at optimal point"
on every such solve even with ``verbose=False`` (osqp/osqp issue #785); with ``verbose``
off this back-end sends Python's ``sys.stdout`` to a null sink for the duration of the
solve call (OSQP writes through ``PySys_WriteStdout``).

Interrupts. OSQP installs its own SIGINT handler while it solves, so Ctrl-C during a solve
stops the solve (status ``interrupted``) and never reaches Python. This back-end raises the
signal again in the process, where Python's handler acts on it (``KeyboardInterrupt`` by
default); when the process goes on (SIGINT ignored, as in the benchmark's worker processes, or
a handler that only takes note), the solve is run again, so an interrupt never becomes a solver
failure. ``"interrupted"`` remains only after :data:`_SIGINT_RETRIES` interrupted solves in a row.
"""

from __future__ import annotations

import dataclasses
import signal
import sys
import time
from typing import Any, ClassVar

import numpy as np
import osqp
import scipy.sparse as sp

from rmpc.qp.base import DEFAULT_TIME_LIMIT, BackendSettings, QPBackend
from rmpc.qp.problem import QPResult, SolverResiduals
from toolkit_common.status import Status
from toolkit_common.validation import is_integer

__all__ = ["OSQPBackend", "OSQPSettings"]


@dataclasses.dataclass(frozen=True)
class OSQPSettings(BackendSettings):
    """Settings of :class:`OSQPBackend` (names as in OSQP 1.x; tolerances tightened).

    Attributes
    ----------
    eps_abs, eps_rel : float
        Absolute and relative termination tolerances (OSQP default 1e-3; here 1e-8).
    eps_prim_inf, eps_dual_inf : float
        Infeasibility detection tolerances (OSQP defaults).
    max_iter : int
        ADMM iteration limit.
    polishing : bool
        Polish the ADMM answer by an active-set solve (here on).
    polish_refine_iter : int
        Iterative refinement steps of polishing.
    warm_starting : bool
        Start each solve from the previous primal-dual pair.
    scaling : int
        Ruiz equilibration iterations (0 turns scaling off).
    adaptive_rho : bool
        Adapt the ADMM step ``rho``.
    rho, sigma, alpha : float
        ADMM parameters (OSQP defaults).
    time_limit : float
        Bound in seconds on one solve (:data:`~rmpc.qp.base.DEFAULT_TIME_LIMIT` by default;
        ``inf`` means none, passed to OSQP as its own "none", 1e10 s); a solve it stops reports
        ``"time_limit"``.
    verbose : bool
        Let OSQP print.
    """

    eps_abs: float = 1e-8
    eps_rel: float = 1e-8
    eps_prim_inf: float = 1e-4
    eps_dual_inf: float = 1e-4
    max_iter: int = 10000
    polishing: bool = True
    polish_refine_iter: int = 3
    warm_starting: bool = True
    scaling: int = 10
    adaptive_rho: bool = True
    rho: float = 0.1
    sigma: float = 1e-6
    alpha: float = 1.6
    time_limit: float = DEFAULT_TIME_LIMIT
    verbose: bool = False

    _POSITIVE: ClassVar[tuple[str, ...]] = ("eps_prim_inf", "eps_dual_inf", "rho", "sigma", "alpha")
    _NONNEGATIVE: ClassVar[tuple[str, ...]] = ("eps_abs", "eps_rel")
    _COUNTS: ClassVar[tuple[str, ...]] = ("max_iter", "polish_refine_iter")
    _SECONDS: ClassVar[tuple[str, ...]] = ("time_limit",)
    _FLAGS: ClassVar[tuple[str, ...]] = ("polishing", "warm_starting", "adaptive_rho", "verbose")

    def __post_init__(self) -> None:
        super().__post_init__()
        from toolkit_common.errors import InvalidArgumentError

        if not is_integer(self.scaling) or self.scaling < 0:
            raise InvalidArgumentError("OSQPSettings.scaling", "an integer >= 0", repr(self.scaling))
        if self.eps_abs == 0 and self.eps_rel == 0:
            raise InvalidArgumentError("OSQPSettings.eps_abs, eps_rel", "at least one > 0", "both 0")


class _NullSink:
    def write(self, _text: str) -> int:
        return 0

    def flush(self) -> None:
        return None


_NULL = _NullSink()
_S = osqp.SolverStatus


#: Times a solve that OSQP's own SIGINT handler stopped is run again after the signal is handed
#: to the process (see the module's note on interrupts).
_SIGINT_RETRIES = 3


class OSQPBackend(QPBackend):
    """QP back-end on OSQP 1.x (sparse ADMM, warm-started, polished).

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.qp import QP, OSQPBackend
    >>> be = OSQPBackend(eps_abs=1e-8, eps_rel=1e-8)
    >>> be.setup(QP(H=np.eye(2), g=[-1.0, -1.0], ub=[0.5, 2.0]))
    >>> res = be.solve()
    >>> res.status, np.round(res.x, 6).tolist()
    ('optimal', [0.5, 1.0])
    """

    name = "osqp"
    settings_class = OSQPSettings
    STATUS_MAP: ClassVar[dict[Any, Status]] = {
        int(_S.OSQP_SOLVED): Status.OPTIMAL,
        int(_S.OSQP_SOLVED_INACCURATE): Status.INACCURATE,
        int(_S.OSQP_PRIMAL_INFEASIBLE): Status.INFEASIBLE,
        int(_S.OSQP_PRIMAL_INFEASIBLE_INACCURATE): Status.INFEASIBLE,
        int(_S.OSQP_DUAL_INFEASIBLE): Status.UNBOUNDED,
        int(_S.OSQP_DUAL_INFEASIBLE_INACCURATE): Status.UNBOUNDED,
        int(_S.OSQP_MAX_ITER_REACHED): Status.MAX_ITERATIONS,
        int(_S.OSQP_TIME_LIMIT_REACHED): Status.TIME_LIMIT,
        int(_S.OSQP_NON_CVX): Status.NUMERICAL_ERROR,
        int(_S.OSQP_SIGINT): Status.INTERRUPTED,
        int(_S.OSQP_UNSOLVED): Status.NOT_SOLVED,
    }

    def _setup(self) -> None:
        assert self._qp is not None
        qp = self._qp
        n = qp.n_vars
        p = sp.triu(sp.csc_matrix(qp.H), format="csc")
        a = sp.vstack([sp.csc_matrix(qp.C), sp.identity(n, format="csc")], format="csc")
        self._m = qp.n_cons
        self._solver = osqp.OSQP()
        options = dataclasses.asdict(self.settings)
        options["time_limit"] = min(options["time_limit"], 1e10)
        self._solver.setup(p, self._vec["g"], a, self._lower(), self._upper(), **options)

    def _lower(self) -> np.ndarray:
        return np.concatenate((self._vec["l"], self._vec["lb"]))

    def _upper(self) -> np.ndarray:
        return np.concatenate((self._vec["u"], self._vec["ub"]))

    def _update(self, changed: dict[str, np.ndarray]) -> None:
        kwargs: dict[str, np.ndarray] = {}
        if "g" in changed:
            kwargs["q"] = changed["g"]
        if {"l", "lb"} & changed.keys():
            kwargs["l"] = self._lower()
        if {"u", "ub"} & changed.keys():
            kwargs["u"] = self._upper()
        self._solver.update(**kwargs)

    def _solve(self) -> QPResult:
        quiet = not self.settings.verbose
        saved = sys.stdout
        start = time.perf_counter()
        try:
            if quiet:
                sys.stdout = _NULL  # type: ignore[assignment]
            res = self._solver.solve(raise_error=False)
            for _ in range(_SIGINT_RETRIES):
                if int(res.info.status_val) != int(_S.OSQP_SIGINT):
                    break
                # OSQP caught a SIGINT meant for the process: hand it over (the default handler
                # raises KeyboardInterrupt here); a process that goes on gets the solve it asked for
                signal.raise_signal(signal.SIGINT)
                res = self._solver.solve(raise_error=False)
        except Exception as err:  # the binding raises on a failed setup/factorisation
            sys.stdout = saved
            return self._result(
                Status.NUMERICAL_ERROR, f"exception: {err}", None, None, None, -1,
                time.perf_counter() - start, SolverResiduals(),
            )
        finally:
            sys.stdout = saved
        elapsed = time.perf_counter() - start
        info = res.info
        raw = int(info.status_val)
        m = self._m
        y = None if res.y is None else np.asarray(res.y)
        return self._result(
            self.map_status(raw), str(info.status), res.x,
            None if y is None else y[:m], None if y is None else y[m:],
            int(info.iter), elapsed,
            SolverResiduals(primal=float(info.prim_res), dual=float(info.dual_res),
                            gap=float(getattr(info, "duality_gap", float("nan")))),
            {"polish_status": int(info.status_polish)},
        )
