"""The toolkit's own dense interior-point back-end (:mod:`lmi.ipm`) on the Clarabel conic data.

Same conic data as :class:`lmi.backend_clarabel.ClarabelKothare` (built once, ``b`` and the
bound row scalings updated per state); the solver reduces each Newton step to the small Schur
complement in the LMI variables instead of factoring Clarabel's svec-space KKT system.
"""

from __future__ import annotations

import time
from typing import Any

import clarabel
import numpy as np

from lmi.backend_clarabel import ClarabelKothare, RawResult
from lmi.data import KothareData
from lmi.ipm import ConeSpec, DenseConeIPM
from lmi.status import INACCURATE, MAX_ITERATIONS, NUMERICAL_ERROR, OPTIMAL
from toolkit_common.errors import InvalidArgumentError

__all__ = ["DEFAULT_IPM_OPTIONS", "IPMKothare"]

DEFAULT_IPM_OPTIONS: dict[str, Any] = {
    "tol_feas": 1e-8,
    "tol_gap_abs": 1e-8,
    "tol_gap_rel": 1e-8,
    "max_iter": 60,
}
_STATUS = {
    "optimal": OPTIMAL,
    "inaccurate": INACCURATE,
    "max_iterations": MAX_ITERATIONS,
    "numerical_error": NUMERICAL_ERROR,
}


class IPMKothare(ClarabelKothare):
    """Kothare problem solved by :class:`lmi.ipm.DenseConeIPM`."""

    name = "ipm"

    def __init__(self, data: KothareData, options: dict[str, Any] | None = None) -> None:
        options = dict(options or {})
        unknown = sorted(set(options) - set(DEFAULT_IPM_OPTIONS))
        if unknown:
            raise InvalidArgumentError(
                "solver_options", f"IPM settings ({', '.join(sorted(DEFAULT_IPM_OPTIONS))})",
                f"unknown setting(s) {unknown}",
            )
        merged = {**DEFAULT_IPM_OPTIONS, **options}
        for key in ("tol_feas", "tol_gap_abs", "tol_gap_rel"):
            if not (isinstance(merged[key], float | int) and merged[key] > 0):
                raise InvalidArgumentError(f"solver_options[{key!r}]", "a number > 0", repr(merged[key]))
        if not (isinstance(merged["max_iter"], int) and merged["max_iter"] > 0):
            raise InvalidArgumentError(
                "solver_options['max_iter']", "an integer > 0", repr(merged["max_iter"])
            )
        super().__init__(data, None)
        specs = []
        for cone, start, stop in zip(self._cones, self._offsets[:-1], self._offsets[1:], strict=True):
            dim = int(stop - start)
            if isinstance(cone, clarabel.PSDTriangleConeT):
                order = round((np.sqrt(8 * dim + 1) - 1) / 2)
                specs.append(ConeSpec("psd", order))
            else:
                specs.append(ConeSpec("nonneg", dim))
        self._solver = DenseConeIPM(self._q, self._A.toarray(), specs, **merged)
        self._dense_a = self._A.toarray()

    def _dense_a_matrix(self, u_max: np.ndarray, y_max: np.ndarray) -> np.ndarray:
        row_scale = np.ones(self._dense_a.shape[0])
        for start, sel, bound_index, kind in self._scaled_rows:
            bounds = u_max if kind == "u" else y_max
            row_scale[start + sel] = 1.0 / (bounds[0] if bounds.size == 1 else bounds[bound_index])
        return self._dense_a * row_scale[:, None]

    def solve(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray) -> RawResult:
        b = self._b_vector(x)
        g = self._dense_a_matrix(u_max, y_max) if self._scaled_rows else None
        start = time.perf_counter()
        try:
            with self._blas.limit():
                res = self._solver.solve(b, g)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as err:
            elapsed = time.perf_counter() - start
            return RawResult(NUMERICAL_ERROR, repr(err), np.nan, None, None, None, elapsed)
        elapsed = time.perf_counter() - start
        z = res.x
        gamma = float(z[0])
        if self.data.formulation != "standard":
            gamma /= self.data.dt
        return RawResult(
            _STATUS.get(res.status, NUMERICAL_ERROR), res.status, gamma, self._q_affine.value(z),
            self._y_affine.value(z), res.iterations, elapsed,
        )
