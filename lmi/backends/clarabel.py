"""Direct Clarabel back-end: the conic data built once, a few entries updated per state.

The Kothare LMIs are written as conic data ``A z + s = b`` once
(:class:`~lmi.backends.conic.KothareConic`: PSD triangle and non-negative cones, the state in
``b`` only, the input and output bounds as scalings of the rows of their off-diagonal blocks) and
handed to Clarabel at each solve with the state's ``b`` and the bounds' ``A``.

The formulations (``"delta_shared"``, the default, ``"delta"`` and ``"standard"``) are those of
:mod:`lmi.backends.conic`.
"""

from __future__ import annotations

import time
from typing import Any

import clarabel
import numpy as np

from lmi.backends.base import KothareBackend, RawResult
from lmi.backends.conic import KothareConic
from lmi.data import KothareData
from lmi.status import CLARABEL_STATUS_MAP, INFEASIBLE, SOLVER_ERROR, UNBOUNDED
from lmi.threads import SingleThreadBlas
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.interrupts import reraise_interrupt

# RawResult is defined in lmi.backends.base; it stays importable from here.
__all__ = ["DEFAULT_CLARABEL_OPTIONS", "ClarabelKothare", "RawResult", "clarabel_settings"]

#: Tolerances, chosen deliberately: 1e-8 gap and feasibility gave status "Solved" with recomputed
#: relative LMI margins >= -1.1e-8 on 20 random states of paper P's satellite with 2 and 8
#: vertices; 1e-9 and 1e-10 made Clarabel stop with "AlmostSolved" on up to 80 % of the 8-vertex
#: solves (the delta formulation's conditioning limit), with no gain in the certificate.
#: Chordal decomposition is off: the LMI cones are dense, and with it on, Clarabel took 51 ms
#: instead of 30 ms per solve of paper P's 2-vertex problem (and refuses data updates).
DEFAULT_CLARABEL_OPTIONS: dict[str, Any] = {
    "chordal_decomposition_enable": False,
    "tol_gap_abs": 1e-8,
    "tol_gap_rel": 1e-8,
    "tol_feas": 1e-8,
    "max_iter": 200,
    "verbose": False,
}


def clarabel_settings(options: dict[str, Any] | None) -> Any:
    """Clarabel ``DefaultSettings`` from the defaults above and ``options``.

    Unknown keys raise :class:`~toolkit_common.errors.InvalidArgumentError` naming them.
    """
    settings = clarabel.DefaultSettings()
    known = {name for name in dir(settings) if not name.startswith("_") and name != "default"}
    merged = {**DEFAULT_CLARABEL_OPTIONS, **(options or {})}
    unknown = sorted(set(merged) - known)
    if unknown:
        raise InvalidArgumentError(
            "solver_options", f"Clarabel settings (e.g. {', '.join(sorted(known)[:6])}, ...)",
            f"unknown setting(s) {unknown}",
        )
    for key, value in merged.items():
        try:
            setattr(settings, key, value)
        except (TypeError, ValueError) as err:
            raise InvalidArgumentError(
                f"solver_options[{key!r}]", "a valid value", f"{value!r} ({err})"
            ) from None
    return settings


class ClarabelKothare(KothareBackend):
    """The Kothare problem as fixed conic data for Clarabel's own API.

    Parameters
    ----------
    data : KothareData
    options : dict, optional
        Clarabel settings over :data:`DEFAULT_CLARABEL_OPTIONS` (:func:`clarabel_settings`).
    conic : KothareConic, optional
        The conic data of ``data``, when another back-end has built it already (the
        interior-point back-end's fallback); built here otherwise.
    """

    name = "clarabel"

    def __init__(
        self, data: KothareData, options: dict[str, Any] | None = None, *, conic: KothareConic | None = None
    ) -> None:
        self.data = data
        self._options = None if options is None else dict(options)
        self.settings = clarabel_settings(self._options)
        self._blas = SingleThreadBlas()
        self.conic = KothareConic(data) if conic is None else conic

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles leave Clarabel's settings object behind (it does not pickle);
        :meth:`__setstate__` builds it again from the options."""
        state = dict(self.__dict__)
        del state["settings"]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.settings = clarabel_settings(self._options)

    def solve(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray,
              outer: np.ndarray | None = None) -> RawResult:
        """Solve at the (normalised) state ``x`` with the (normalised) bounds; ``outer``: the
        constant of the nesting block, for conic data that have it
        (:meth:`~lmi.backends.conic.KothareConic.b_vector`)."""
        conic = self.conic
        b = conic.b_vector(x, outer)
        a_mat = conic.a_matrix(u_max, y_max)
        start = time.perf_counter()
        try:
            with self._blas.limit():
                solver = clarabel.DefaultSolver(conic.P, conic.objective, a_mat, b, conic.cones,
                                                self.settings)
                sol = solver.solve()
        except BaseException as err:
            reraise_interrupt(err)  # Ctrl-C, bare or wrapped by the binding: not a failed solve
            return RawResult(SOLVER_ERROR, repr(err), np.nan, None, None, None, time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        raw = str(sol.status)
        status = CLARABEL_STATUS_MAP.get(raw, SOLVER_ERROR)
        if status in (INFEASIBLE, UNBOUNDED):  # the last iterate is no answer: return none
            return RawResult(status, raw, np.nan, None, None, int(sol.iterations), elapsed)
        z = np.asarray(sol.x)
        q_mat, y_mat = conic.variables(z)
        dual = float(sol.obj_val_dual)
        return RawResult(status, raw, self.gamma(z[0]), q_mat, y_mat, int(sol.iterations), elapsed,
                         gamma_dual=self.gamma(dual) if np.isfinite(dual) else None)
