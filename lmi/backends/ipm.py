"""The toolkit's own structure-exploiting interior-point back-end (:mod:`lmi.ipm`).

The LMIs are the same conic data as for :class:`lmi.backends.clarabel.ClarabelKothare`
(:class:`~lmi.backends.conic.KothareConic`, built once); here each cone is kept as a matrix,
``S_j = C_j - sum_i z_i A_ij``, and handed to :class:`lmi.ipm.BlockLMISolver`. Per state only
the state block's constant and the bound scalings of the input (and output) blocks change; they
are written in place. Successive solves are warm-started (see :data:`DEFAULT_IPM_OPTIONS`). A
solve that fails goes to phase one and then to a :class:`~lmi.backends.clarabel.ClarabelKothare`
the back-end owns, built on the same conic data (:meth:`IPMKothare.solve`); a strictly
feasible point phase one found goes with the answer (``RawResult.interior``), so that no
solve whose phase one decided ends ``"numerical_error"``.

With ``nesting=True`` the conic data have one more block, the nesting ``Q_outer - Q >= 0`` of
the off-line design (:class:`lmi.offline.NestedKothareProblem`), and every solve takes the outer
``Q`` (:meth:`IPMKothare.solve`); without it nothing differs from the on-line problem.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import clarabel
import numpy as np

from lmi.affine import smat_matrix, svec_indices, svec_matrix
from lmi.backends.base import KothareBackend, RawResult
from lmi.backends.clarabel import ClarabelKothare
from lmi.backends.conic import KothareConic
from lmi.ccore.generate import LIMITS
from lmi.ccore.runtime import CoreSolver, core_library, core_status
from lmi.data import KothareData
from lmi.infeasibility import InfeasibilityCertificate, check_farkas
from lmi.ipm import BlockLMISolver
from lmi.ipm.blocks import DIRECT_MIN_VARIABLES
from lmi.ipm.solver import INFEASIBILITY_RADIUS, SOLVER_STATUS_MAP
from lmi.kothare_factors import VariableLayout, cost_block_factors
from lmi.scaling import MIN_SPREAD, scale_data, state_scaling
from lmi.status import INACCURATE, INFEASIBLE, NUMERICAL_ERROR, OPTIMAL
from lmi.threads import SingleThreadBlas
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import is_integer, is_real

__all__ = ["CORE_CHOICES", "DEFAULT_IPM_OPTIONS", "REBALANCE_MAX_RESIDUAL", "REBALANCE_QR_GAP",
           "IPMKothare", "check_ipm_values"]

#: A failed cold solve is retried in coordinates balanced on its last ``Q`` (option
#: ``rebalance``) only if its relative primal and dual residuals came below this.
REBALANCE_MAX_RESIDUAL = 1e-3

#: An on-line solve that ends ``"optimal"`` and whose QR phase began at a relative gap of at least
#: this (the Cholesky factor of the Schur complement lost the step's accuracy far from the optimum,
#: see :data:`lmi.ipm.solver.QR_SWITCH`) rebuilds the problem in coordinates balanced on its
#: answer's ``Q~`` for the next solves (option ``rebalance``; :meth:`IPMKothare.solve`). Near the
#: optimum the QR phase is the end game of any IPM (the Schur complement's condition number grows
#: as the gap closes); far from it, it comes from the coordinates, and its steps are the costly
#: ones (``P`` formed and factored). On the generic stress set's ``n20-v2-generic-none-s0``
#: (:mod:`dev.generic_stress`; 481 variables) every step of every warm solve was a QR step, from a
#: relative gap of 1.2e-3 (87 ms a step against about 11 ms for a Cholesky step), its iterate's
#: slacks spanning 1e-6..1e4 and the Schur complement, scaled to a unit diagonal, with 211
#: eigenvalues below 1e-12 of the largest; balanced on the previous answer, 3-4 of 9, from 1.6e-6.
#: Paper P's closed loop on the numba path (E1, 40 samples, 2 and 8 vertices) began its QR phases
#: at relative gaps of at most 1.0e-6 and 4.7e-6 (medians 3e-7, 7e-7): those solves keep their
#: coordinates. (A rule on the share of QR steps instead, half of a solve's, rebalanced paper P's
#: 8-vertex loop again and again: its solves end with 4-5 QR steps of 8-10.)
REBALANCE_QR_GAP = 1e-4

#: Settings. Tolerances: relative residuals and gap 1e-8, as for Clarabel (see
#: :data:`lmi.backends.clarabel.DEFAULT_CLARABEL_OPTIONS`); on paper P's closed loop gamma then
#: agrees with a converged 1e-10 Clarabel reference to 1.1e-8 relative or better (measured).
#: The absolute gap tolerance is 1e-12, not Clarabel's 1e-8: the solver's objective is gamma at
#: the normalised state (times ``dt`` in the delta formulations), whose size depends only on the
#: weights, so an absolute 1e-8 meant a different relative accuracy for every problem. Measured
#: on Kothare's example (objective 3e-3): with 1e-8 a solve stopped at a relative gap of 1.4e-6,
#: leaving the state 3.8e-6 outside its ellipsoid (x' Q^-1 x - 1); with 1e-12 the relative gap
#: decided (3 more iterations) and the excess was 4e-12. On paper P (objective about 2) the
#: relative test decides in both cases.
#: ``warm_start``: start each solve from an interior iterate of the previous one (a failed warm
#: start is retried cold, so answers never depend on it); ``max_iter`` limits a cold start,
#: ``warm_max_iter`` a warm one.
#: ``max_iter`` is 100, not 60: the main run's proof of infeasibility (its Farkas ray,
#: :meth:`lmi.ipm.BlockLMISolver.solve`) took up to 57 iterations on the generic stress set's
#: infeasible problems of 20-30 states (:mod:`dev.generic_stress`), 61 and 66 on two of
#: them; at 60 those two ended ``"max_iterations"`` and went to phase one, which proved one
#: (129 iterations in all, 71 s instead of 9 s) and not the other (its certificate's radius
#: 7e7, below the 1e8 asked).
#: ``fallback``: a solve that does not end ``"optimal"`` is
#: re-solved by Clarabel, which also certifies infeasibility. ``state_scaling``: solve in the
#: coordinates of :func:`lmi.scaling.state_scaling` (a diagonal change of state coordinates
#: from the nominal LQR problem; answers are mapped back, and the certificate is computed in
#: the original coordinates). Measured on the 14-state flexible satellite (2 vertices, Ts =
#: 0.05 s): without it every cold solve stalled ("insufficient_progress" after 18-19
#: iterations), with it every solve converged in 19-22 iterations cold, 8-11 warm.
#: ``rebalance``: a solve that fails but comes within :data:`REBALANCE_MAX_RESIDUAL` of
#: feasibility is retried cold once, in coordinates balanced on its last ``Q`` (see
#: :meth:`IPMKothare.solve`); the problem keeps those coordinates (the Cholesky factor of that
#: ``Q``, :meth:`IPMKothare._rebalanced_scaling`). The Riccati diagonal does not see the
#: constraints: on the flexible satellite's 8-vertex 'groups' polytope at 0.5 s
#: (``Q1 = diag(400 I6, 0.1 I8)``, peak bound 2 N m) the input bound squeezes the optimal
#: ellipsoid along the modal coordinates, whose ``Q~`` diagonal then spans 1e-4..20 (2e5), and
#: the cold solves at rest 13-20 deg about the slew axis and with the modal bound at 10 deg ended
#: "inaccurate" or "insufficient_progress" after 35-48 iterations. Rebalanced, they ended
#: "optimal" in 48-69 iterations in all (0.4-1.4 s at load 1-2), gamma within 7e-10 of cvxpy +
#: Clarabel at 1e-10 on the delta form at 14 deg. An on-line solve that ends ``"optimal"`` but began
#: its QR phase at a relative gap of at least :data:`REBALANCE_QR_GAP` rebalances the next solves
#: the same way, on its answer's ``Q~`` (:meth:`IPMKothare.solve`).
#: ``infeasibility_radius``: a run ends ``"infeasible"`` when its dual iterate proves that no
#: solution of norm below this exists (:meth:`lmi.ipm.BlockLMISolver.solve`; ``inf`` switches the
#: test off and leaves infeasible problems to phase one); the proof is checked again on the conic
#: data (:meth:`IPMKothare.solve`).
DEFAULT_IPM_OPTIONS: dict[str, Any] = {
    "tol_feas": 1e-8,
    "tol_gap_abs": 1e-12,
    "tol_gap_rel": 1e-8,
    "max_iter": 100,
    "warm_start": True,
    "warm_max_iter": 25,
    "fallback": True,
    "state_scaling": True,
    "phase_one": True,
    "rebalance": True,
    "infeasibility_radius": INFEASIBILITY_RADIUS,
    "core": "auto",
}

#: Values of the ``core`` setting: which implementation runs the interior-point iterations of an
#: on-line solve. ``"c"``: the C core (:mod:`lmi.ccore.runtime`, the extension ``pip install .``
#: builds from the source every exported controller compiles); ``"numba"``: the numba kernels of
#: :class:`lmi.ipm.BlockLMISolver`; ``"auto"``: the C core when it is built and carries the
#: problem (the on-line problem, sizes within :data:`lmi.ccore.generate.LIMITS`), else numba.
#: Phase one, the rebalanced retries and the off-line design's nested problems run numba.
#: Measured on paper P's satellite (``python -m benchmarks.timing.ccore``): the C core's warm
#: solve is faster than the numba path at 2, 4 and 8 vertices, and needs no compilation on first
#: use (numba's took 30-50 s after an install).
CORE_CHOICES = ("auto", "c", "numba")


def _check_options(options: dict[str, Any]) -> dict[str, Any]:
    unknown = sorted(set(options) - set(DEFAULT_IPM_OPTIONS))
    if unknown:
        raise InvalidArgumentError(
            "solver_options", f"IPM settings ({', '.join(sorted(DEFAULT_IPM_OPTIONS))})",
            f"unknown setting(s) {unknown}",
        )
    return check_ipm_values({**DEFAULT_IPM_OPTIONS, **options})


def check_ipm_values(options: dict[str, Any]) -> dict[str, Any]:
    """The values of the interior-point settings in ``options`` checked, as numbers of the right kind.

    The one check of an ``"ipm"`` back-end's ``solver_options`` values, for Kothare's problem and
    the forms (:class:`lmi.forms.FormProblem`) alike; names it does not know are left alone (the
    caller refuses the names it does not take).

    Raises
    ------
    InvalidArgumentError
        Naming the setting (``solver_options['max_iter']``), what was expected and what was found.

    Examples
    --------
    >>> check_ipm_values({"max_iter": 0})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: solver_options['max_iter']: expected an integer >= 1, ...
    """
    merged = dict(options)
    for key in ("tol_feas", "tol_gap_abs", "tol_gap_rel", "warm_gap", "warm_feas"):
        if key not in merged:
            continue
        value = merged[key]
        if not (is_real(value) and value > 0):  # NaN fails too
            raise InvalidArgumentError(f"solver_options[{key!r}]", "a number > 0", repr(value))
        merged[key] = float(value)
    if "infeasibility_radius" in merged:
        radius = merged["infeasibility_radius"]
        if not (is_real(radius) and radius > 0):
            raise InvalidArgumentError("solver_options['infeasibility_radius']",
                                       "a number > 0 (inf: no test)", repr(radius))
    for key in ("max_iter", "warm_max_iter"):
        if key not in merged:
            continue
        value = merged[key]
        if not (is_integer(value) and value >= 1):
            raise InvalidArgumentError(f"solver_options[{key!r}]", "an integer >= 1", repr(value))
        merged[key] = int(value)
    for key in ("warm_start", "fallback", "state_scaling", "phase_one", "rebalance"):
        if key in merged and not isinstance(merged[key], bool):
            raise InvalidArgumentError(f"solver_options[{key!r}]", "True or False", repr(merged[key]))
    if "core" in merged:
        if merged["core"] not in CORE_CHOICES:
            raise InvalidArgumentError("solver_options['core']", f"one of {CORE_CHOICES}",
                                       repr(merged["core"]))
        if merged["core"] == "c" and core_library() is None:
            raise InvalidArgumentError("solver_options['core']", "'auto' or 'numba' (no C core here)",
                                       f"'c': {core_status()}")
    return merged


def _nest_args(outer: np.ndarray | None) -> tuple[np.ndarray, ...]:
    """``(outer,)`` for the nesting block, ``()`` without it: the on-line problem's stages are
    called exactly as they are without the nesting option."""
    return () if outer is None else (outer,)


class IPMKothare(KothareBackend):
    """Kothare problem solved by :class:`lmi.ipm.BlockLMISolver`, Clarabel as its fallback.

    Attributes
    ----------
    original_data : KothareData
        The problem as given.
    data : KothareData
        The problem in the solver's coordinates ``x~ = diag(t)^-1 x`` (``original_data`` when
        ``t = 1``).
    conic : KothareConic
        The conic data of ``data``.
    fallback_solver : ClarabelKothare
        The Clarabel back-end on the same ``conic``, which gets the solves that fail.

    Parameters
    ----------
    data : KothareData
    options : dict, optional
        Settings over :data:`DEFAULT_IPM_OPTIONS`.
    nesting : bool
        Add the nesting block ``Q_outer - Q >= 0`` of the off-line design (the last block); every
        solve then takes ``outer``. Default ``False``: the on-line problem.
    """

    name = "ipm"

    def __init__(self, data: KothareData, options: dict[str, Any] | None = None, *,
                 nesting: bool = False) -> None:
        merged = _check_options(dict(options or {}))
        self.nesting = bool(nesting)
        t = state_scaling(data) if merged.pop("state_scaling") else np.ones(data.n)
        self.original_data = data
        self._warm_start = merged.pop("warm_start")
        self._fallback = merged.pop("fallback")
        self._phase_one = merged.pop("phase_one")
        self._rebalance = merged.pop("rebalance")
        self._core_choice = merged.pop("core")
        self._solver_options = merged
        self._blas = SingleThreadBlas()
        self._initial_scaling = t
        self._build(t)

    def reset(self) -> None:
        """Back to the state of a fresh back-end: no warm-start point, the initial state coordinates.

        A rebalanced retry keeps its coordinates for the next solves (see :meth:`solve`); a
        reset returns to those of the construction, so the next solve gives what a new
        back-end on the same data gives.
        """
        if np.array_equal(self._t, self._initial_scaling):
            self._solver.reset_warm_start()
            if self._core is not None:
                self._core.reset_warm_start()
        else:
            self._build(self._initial_scaling)

    def _build(self, t: np.ndarray) -> None:
        """The conic data, the solver and the fallback in the coordinates ``x~ = T^-1 x``, ``T =
        diag(t)`` for a vector ``t`` (:func:`lmi.scaling.state_scaling`) or ``t`` itself (a
        rebalanced retry, :meth:`_rebalanced_scaling`)."""
        data = self.original_data
        self._t = t
        self._scaled = bool(t.ndim == 2 or np.any(t != 1.0))
        self.data = scale_data(data, t) if self._scaled else data
        conic = self.conic = KothareConic(self.data, nesting=self.nesting)
        self.fallback_solver = ClarabelKothare(self.data, None, conic=conic)
        a_dense = conic.A.toarray()
        h = conic.b_static
        blocks: list[tuple[np.ndarray, np.ndarray]] = []
        self._block_rows: list[slice] = []
        for cone, start, stop in zip(conic.cones, conic.offsets[:-1], conic.offsets[1:], strict=True):
            g_rows, h_rows = a_dense[start:stop], h[start:stop]
            dim = int(stop - start)
            if isinstance(cone, clarabel.PSDTriangleConeT):
                order = round((np.sqrt(8 * dim + 1) - 1) / 2)
                blocks.append((smat_matrix(h_rows, order), smat_matrix(g_rows.T, order)))
            else:  # a non-negative cone is a diagonal block
                eye = np.eye(dim)
                blocks.append((np.diag(h_rows), g_rows.T[:, :, None] * eye[None]))
            self._block_rows.append(slice(int(start), int(stop)))
        self._base_blocks = blocks
        # the bound-scaled blocks: entry masks (k x k) per (block, bound index, kind)
        self._scaled_blocks: list[tuple[int, list[tuple[np.ndarray, np.ndarray, str]]]] = []
        for start, sel, bound_index, kind in conic.scaled_rows:
            j = int(np.searchsorted(conic.offsets, start, side="right") - 1)
            order = blocks[j][0].shape[0]
            rows, cols = svec_indices(order)
            parts = []
            for idx in np.unique(bound_index):
                pick = sel[bound_index == idx]
                mask = np.zeros((order, order), dtype=bool)
                mask[rows[pick], cols[pick]] = True
                mask[cols[pick], rows[pick]] = True
                parts.append((mask, idx, kind))
            self._scaled_blocks.append((j, parts))
        self._nest_block = len(blocks) - 1 if self.nesting else None
        use_core = self._core_choice != "numba" and self._core_carries(blocks, t)
        self._solver = BlockLMISolver(conic.objective, blocks, factors=self._block_factors(len(blocks)),
                                      load_kernels=not use_core, **self._solver_options)
        self._core = CoreSolver(self) if use_core else None

    @property
    def core(self) -> str:
        """Which implementation runs this back-end's solves now: ``"c"`` or ``"numba"`` (see
        :data:`CORE_CHOICES`)."""
        return "c" if self._core is not None else "numba"

    def _core_carries(self, blocks: list[tuple[np.ndarray, np.ndarray]], t: np.ndarray) -> bool:
        """Whether the C core solves this problem: it is built, the problem is the on-line one
        (the state block first, no nesting block, every variable in some block) and within
        :data:`lmi.ccore.generate.LIMITS`; with ``core="c"`` a problem it does not carry is an
        error. With ``core="auto"`` also: at most :data:`lmi.ipm.blocks.DIRECT_MIN_VARIABLES`
        variables (beyond, the numba solver forms the Schur complement from the factored
        coefficients, which the C core does not: on the 14-state flexible satellite that took a
        warm solve from 876 ms to 21 ms, and the C core's rows path ended "inaccurate" where it
        ends "optimal"), and the construction's coordinates (a rebalanced retry after a failed
        solve runs numba, as it did before the C core: the failure paths are unchanged)."""
        n = self.data.n
        orders = [c.shape[0] for c, _ in blocks]
        if self._core_choice == "auto" and (blocks[0][1].shape[0] > DIRECT_MIN_VARIABLES
                                            or t is not self._initial_scaling):
            return False
        reasons = []
        if core_library() is None:
            reasons.append(core_status())
        if self.nesting:
            reasons.append("the nesting block of the off-line design")
        if orders[0] != n + 1 or np.any(blocks[0][0] != 0.0):
            reasons.append("no state block first")
        n_var = blocks[0][1].shape[0]
        if not all(any(np.any(coef[i] != 0.0) for _, coef in blocks) for i in range(n_var)):
            reasons.append("a variable in no block")
        if (n_var > LIMITS["variables"] or max(orders) > LIMITS["order"] or len(blocks) > LIMITS["blocks"]):
            reasons.append(f"sizes beyond {LIMITS}")
        if reasons and self._core_choice == "c":
            raise InvalidArgumentError("solver_options['core']", "'auto' or 'numba' for this problem",
                                       f"'c', which does not carry it: {'; '.join(reasons)}")
        return not reasons

    def _block_factors(self, count: int) -> list:
        """The cost blocks' factored coefficients (:mod:`lmi.kothare_factors`), ``None`` for the
        state, bound and diagonal blocks (their coefficients are used as they are)."""
        n, m = self.data.n, self.data.m
        conic = self.conic
        o_y = 1 + conic.n_q
        o_w = o_y + conic.n_y + conic.n_x + conic.n_z if conic.n_w else None
        cost = cost_block_factors(self.data, VariableLayout.of(n, m, 1, o_y, o_w))
        return [None, *cost, *([None] * (count - 1 - len(cost)))]

    def _update_blocks(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray,
                       outer: np.ndarray | None = None) -> None:
        n = self.data.n
        const = np.zeros((n + 1, n + 1))
        const[0, 0] = 1.0
        const[0, 1:] = x
        const[1:, 0] = x
        self._solver.set_block(0, const)
        for j, parts in self._scaled_blocks:
            const_j, coef_j = self._base_blocks[j]
            scale = np.ones(const_j.shape)
            for mask, idx, kind in parts:
                bounds = u_max if kind == "u" else y_max
                scale[mask] = 1.0 / (bounds[0] if bounds.size == 1 else bounds[idx])
            self._solver.set_block(j, const_j, coef_j * scale)
        if outer is not None:
            assert self._nest_block is not None
            self._solver.set_block(self._nest_block, outer)

    def solve(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray,
              outer: np.ndarray | None = None) -> RawResult:
        """Solve with the IPM; a failure goes to phase one, then (unless proved infeasible) to
        Clarabel.

        ``outer`` (required with ``nesting``, refused without): the outer ellipsoid's ``Q`` at
        the normalised state ``x``, in the caller's coordinates, i.e. ``Q_outer / ||x_orig||^2``
        for the design state ``x_orig = ||x_orig|| x``. Every stage maps it into the coordinates it
        solves in, as it maps the state (:meth:`_outer_scaled`).

        A solve that ends ``"infeasible"`` (its dual iterate a Farkas ray, see
        :meth:`lmi.ipm.BlockLMISolver.solve`) is checked by :func:`lmi.infeasibility.check_farkas`
        on the conic data of the fallback; checked, the answer is ``"infeasible"`` with that
        certificate and ``solver_status`` ``"ipm infeasible"``; unchecked, the solve counts as
        failed (``"infeasible (unchecked)"``) and goes on as below. Any other solve that does
        not end ``"optimal"`` runs phase one
        (:meth:`lmi.ipm.BlockLMISolver.phase_one`). If it proves the problem infeasible and
        the proof passes :func:`lmi.infeasibility.check_farkas` on the conic data of the
        fallback (independent of the IPM's own packing, equilibration and factored forms), the
        answer is ``"infeasible"`` with that certificate (``RawResult.infeasibility``) and
        ``solver_status`` ``"ipm <word>; phase one infeasible"``. If phase one is inconclusive,
        the solve is retried cold in coordinates balanced on the failed run's ``Q~`` whatever its
        residuals (:meth:`_retry_inconclusive`; ``"...; rebalanced <word>"``), with phase one
        again if that fails. If phase one finds a strictly feasible point, the solve is retried
        cold in coordinates balanced on that point's ``Q~`` (:meth:`_retry_on_point`;
        ``"...; rebalanced on it <word>"``), and the point goes with the answer as its
        ``interior`` (:meth:`_with_point`): :class:`lmi.KothareProblem` mixes it into an answer
        that is not certified, or gives it as the answer (``"inaccurate"``, ``gamma`` an upper
        bound). Otherwise the failed solve is handed to Clarabel as before (same conic data),
        which classifies it or solves it; ``solver_status`` then reads ``"ipm <word>; phase one
        <word>; clarabel <word>"``.
        Before that, a failed solve whose relative residuals came below
        :data:`REBALANCE_MAX_RESIDUAL` and whose last ``Q~`` has a condition number above
        :data:`lmi.scaling.MIN_SPREAD` is retried cold once in coordinates in which that ``Q~``
        is a multiple of the identity (``rebalance``; :meth:`_rebalanced_scaling`): the method is
        invariant to the coordinates except for its start point, which is centred only for a
        balanced optimum, and a near-feasible iterate has about the optimum's shape. The data are
        rebuilt in the new coordinates (about 0.05-0.1 s at 14 states, counted in ``solve_time``)
        and kept for the next solves. ``solver_status`` then reads ``"<word>; rebalanced
        <word>"``. A solve that ends ``"optimal"`` never gets here: paper P's answers are
        unchanged. An ``"optimal"`` on-line solve whose QR phase began at a relative gap of at
        least :data:`REBALANCE_QR_GAP` is returned as it is, and the problem is rebuilt in
        coordinates balanced on its ``Q~`` for the next solves (:meth:`_rebalanced_after`).
        Times and iterations are the sums over every stage.
        """
        if (outer is None) == self.nesting:
            raise InvalidArgumentError(
                "outer", "Q_outer with nesting=True, None without",
                "None" if outer is None else "a matrix for a back-end without the nesting block",
            )
        xs, us, ys, norm = self._balanced(x, u_max, y_max)
        qs = self._outer_scaled(outer, norm)
        raw = self._solve_ipm(xs, us, ys, qs)
        if raw.status == OPTIMAL:
            return self._rebalanced_after(raw, xs, self._unscale(raw, norm))
        if raw.status == INFEASIBLE:
            return dataclasses.replace(raw, solver_status=f"ipm {raw.solver_status}")
        t_new = self._rebalanced_scaling(raw, xs) if self._rebalance else None
        if t_new is not None:
            start = time.perf_counter()
            self._build(t_new)
            xs, us, ys, norm = self._balanced(x, u_max, y_max)
            qs = self._outer_scaled(outer, norm)
            retry = self._solve_ipm(xs, us, ys, qs)
            raw = dataclasses.replace(
                retry, solver_status=f"{raw.solver_status}; rebalanced {retry.solver_status}",
                iterations=(raw.iterations or 0) + (retry.iterations or 0),
                solve_time=raw.solve_time + time.perf_counter() - start,
            )
            if raw.status == OPTIMAL:
                return self._unscale(raw, norm)
        point: RawResult | None = None
        if self._phase_one:
            raw, feasible_x = self._decide(raw, xs, us, ys, *_nest_args(qs))
            if raw.status == INFEASIBLE:
                return raw
            if feasible_x is None and raw.Q is not None and self._rebalance:
                # phase one inconclusive (its optimum t* ~ 0 in these coordinates: the feasible
                # set too thin for them): once more in coordinates balanced on the failed run's
                # Q~, whatever its residuals, and phase one again there
                raw, feasible_x = self._retry_inconclusive(raw, xs, x, u_max, y_max, outer)
                if raw.status in (OPTIMAL, INFEASIBLE):
                    return raw
            if feasible_x is not None:
                raw, point = self._retry_on_point(raw, feasible_x, x, u_max, y_max, outer)
                if raw.status == OPTIMAL:
                    return raw
            xs, us, ys, norm = self._balanced(x, u_max, y_max)
            qs = self._outer_scaled(outer, norm)
        if not self._fallback:
            answer = self._unscale(raw, norm)
            if point is not None:
                answer = dataclasses.replace(answer, solver_status=f"ipm {raw.solver_status}")
            return answer if point is None else self._with_point(answer, point)
        backup = self.fallback_solver.solve(xs, us, ys, *_nest_args(qs))
        iterations = None if backup.iterations is None else backup.iterations + (raw.iterations or 0)
        answer = self._unscale(dataclasses.replace(
            backup, solver_status=f"ipm {raw.solver_status}; clarabel {backup.solver_status}",
            iterations=iterations, solve_time=raw.solve_time + backup.solve_time,
        ), norm)
        return answer if point is None else self._with_point(answer, point)

    def _rebalanced_after(self, raw: RawResult, xs: np.ndarray, answer: RawResult) -> RawResult:
        """``answer`` (``raw``, an ``"optimal"`` on-line solve at the normalised state ``xs``, in
        the caller's coordinates) as it is; when its QR phase began at a relative gap of at least
        :data:`REBALANCE_QR_GAP` (``rebalance`` on, no nesting block), the problem is rebuilt
        for the next solves in coordinates in which ``raw``'s ``Q~`` is a multiple of the identity
        (:meth:`_balanced_on`), the rebuild's time added to ``answer``'s. The next solve then
        starts cold (the warm-start point belongs to the old coordinates); :meth:`reset` returns
        to the construction's coordinates."""
        if (not self._rebalance or self.nesting or raw.Q is None
                or not self._last_qr_gap >= REBALANCE_QR_GAP):
            return answer
        start = time.perf_counter()
        t_new = self._balanced_on(0.5 * (raw.Q + raw.Q.T), xs)
        if t_new is not None:
            self._build(t_new)
        return dataclasses.replace(answer, solve_time=answer.solve_time + time.perf_counter() - start)

    def _balanced(self, x: np.ndarray, u_max: np.ndarray,
                  y_max: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """The state in the solver's coordinates, normalised again (exact: the LMIs are
        homogeneous), the bounds divided alike, and that norm. Unscaled, nothing is touched, so
        the answers are bit-identical to the unscaled solver's."""
        if not self._scaled:
            return x, u_max, y_max, 1.0
        xs = x / self._t if self._t.ndim == 1 else np.linalg.solve(self._t, x)
        norm = float(np.linalg.norm(xs))
        return xs / norm, u_max / norm, y_max / norm, norm

    def _outer_scaled(self, outer: np.ndarray | None, norm: float) -> np.ndarray | None:
        """``Q_outer`` (at the normalised state, caller's coordinates) in the solver's:
        ``T^-1 Q_outer T^-T / norm^2``, as ``Q~`` is to ``Q`` (:meth:`_unscale` is the inverse), with
        ``norm`` the length of the state in these coordinates (:meth:`_balanced`). Unscaled, the
        matrix as given (symmetrised)."""
        if outer is None:
            return None
        sym = 0.5 * (outer + outer.T)
        if not self._scaled:
            return sym
        t = self._t
        if t.ndim == 1:
            mapped = sym / np.outer(t, t)
        else:
            mapped = np.linalg.solve(t, np.linalg.solve(t, sym).T)
        mapped = mapped / norm**2
        return 0.5 * (mapped + mapped.T)

    def _rebalanced_scaling(self, raw: RawResult, xs: np.ndarray) -> np.ndarray | None:
        """Coordinates balanced on the failed solve ``raw`` at the normalised state ``xs``
        (``None``: nothing to gain).

        ``T L ||L^-1 xs||`` with ``L`` the Cholesky factor of its last ``Q~ = L L'`` (the current
        coordinates ``x~ = T^-1 x``): in the new coordinates that ``Q~`` is a multiple of the
        identity, and the state keeps its length (``||L^-1 xs|| / ||L^-1 xs|| = 1``), so the
        objective the solver sees, gamma at the normalised state, keeps its size. (Scaled to the
        level of ``Q~``'s largest diagonal entry instead, the objective fell to 4e-6 on a fault
        scenario's states, where the absolute gap tolerance of 1e-12 then decided termination at
        a relative gap of 1e-6, and 5 of 1500 answers failed their certificate.) Only if that
        run came within :data:`REBALANCE_MAX_RESIDUAL` of feasibility (its ``Q~`` then has about
        the optimum's shape) and the condition number of ``Q~`` exceeds
        :data:`lmi.scaling.MIN_SPREAD`.

        The full factor, not only the diagonal: on the generic stress set's
        ``n30-v2-generic-none-s1`` (:mod:`dev.generic_stress`) the run ended "inaccurate"
        after 52 iterations, ``S`` and ``Z`` spanning 17 decades near the optimum (block
        eigenvalues from 3e-12 to 7e5 and from 3e-14 to 1e4) and the relative gap stuck at
        1.5e-8; its ``Q`` had eigenvalues from 0.035 to 7.9e4 but a diagonal within a factor 4,
        which the diagonal rule left as it was. In the coordinates of ``L`` the retry ended
        "optimal" after 35 more iterations, gamma within 3e-9 of the failed run's; so did
        ``n30-v2-feasible-ellipsoid-s1``.
        """
        if raw.Q is None or self._last_residual > REBALANCE_MAX_RESIDUAL:
            return None
        return self._balanced_on(0.5 * (raw.Q + raw.Q.T), xs)

    def _balanced_on(self, q_mat: np.ndarray, xs: np.ndarray) -> np.ndarray | None:
        """The coordinates ``T L ||L^-1 xs||`` in which ``Q~ = q_mat = L L'`` (current
        coordinates, normalised state ``xs``) is a multiple of the identity (see
        :meth:`_rebalanced_scaling`); ``None`` unless ``q_mat`` is finite, positive definite
        and spans more than :data:`lmi.scaling.MIN_SPREAD`."""
        if not np.all(np.isfinite(q_mat)):
            return None
        lam = np.linalg.eigvalsh(q_mat)
        if not (lam[0] > 0.0 and lam[-1] > MIN_SPREAD * lam[0]):
            return None
        low = np.linalg.cholesky(q_mat)
        step = low * float(np.linalg.norm(np.linalg.solve(low, xs)))
        return self._t[:, None] * step if self._t.ndim == 1 else self._t @ step

    def _decide(self, raw: RawResult, xs: np.ndarray, u_max: np.ndarray, y_max: np.ndarray,
                outer: np.ndarray | None = None) -> tuple[RawResult, np.ndarray | None]:
        """Phase one after the failed solve ``raw`` (blocks already at this state): ``raw`` as
        ``"infeasible"`` with the checked certificate, or ``raw`` with phase one's word, time
        and iterations added; and phase one's strictly feasible point (the solver's variables)
        when it found one, else ``None``."""
        start = time.perf_counter()
        try:
            with self._blas.limit():
                res = self._solver.phase_one()
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as err:
            return dataclasses.replace(raw, solver_status=f"{raw.solver_status}; phase one {err!r}",
                                       solve_time=raw.solve_time + time.perf_counter() - start), None
        word = res.status
        cert = None
        if res.status == "infeasible":
            cert = self.farkas_check(res.Z, xs, u_max, y_max, *_nest_args(outer))
            if not cert.ok:
                word = "infeasible (unchecked)"
        iterations = (raw.iterations or 0) + res.iterations
        elapsed = raw.solve_time + time.perf_counter() - start
        if cert is not None and cert.ok:
            return RawResult(INFEASIBLE, f"ipm {raw.solver_status}; phase one infeasible", np.nan, None,
                             None, iterations, elapsed, infeasibility=cert), None
        feasible_x = res.x if res.status == "feasible" and res.x is not None else None
        return dataclasses.replace(raw, solver_status=f"{raw.solver_status}; phase one {word}",
                                   iterations=iterations, solve_time=elapsed), feasible_x

    def _retry_inconclusive(self, raw: RawResult, xs: np.ndarray, x: np.ndarray, u_max: np.ndarray,
                            y_max: np.ndarray, outer: np.ndarray | None
                            ) -> tuple[RawResult, np.ndarray | None]:
        """After phase one was inconclusive: a cold retry in coordinates balanced on the failed
        run's ``Q~`` (:meth:`_balanced_on`, whatever the run's residuals), then, if that fails
        too, phase one there (:meth:`_decide`). Returns the answer (``"optimal"`` in the caller's
        coordinates, ``"infeasible"`` with its checked proof, or ``raw`` with the words, times and
        iterations added) and phase one's strictly feasible point, if it found one."""
        t_new = self._balanced_on(0.5 * (raw.Q + raw.Q.T), xs) if raw.Q is not None else None
        if t_new is None:
            return raw, None
        start = time.perf_counter()
        self._build(t_new)
        xs, us, ys, norm = self._balanced(x, u_max, y_max)
        qs = self._outer_scaled(outer, norm)
        retry = self._solve_ipm(xs, us, ys, qs)
        merged = dataclasses.replace(
            retry, solver_status=f"{raw.solver_status}; rebalanced {retry.solver_status}",
            iterations=(raw.iterations or 0) + (retry.iterations or 0),
            solve_time=raw.solve_time + time.perf_counter() - start,
        )
        if merged.status == OPTIMAL:
            # at a feasible set this thin the optimum's recomputed margins may fall just below the
            # certificate's tolerance (Kothare's example 2 at 7e4 times beyond the bound: -3.5e-5):
            # phase one here gives the strictly feasible point to mix in (KothareProblem._mixed)
            decided, inner = self._decide(merged, xs, us, ys, *_nest_args(qs))
            interior = None
            if inner is not None:
                q_in, y_in = self.conic.variables(inner)
                interior = self._interior(self._unscale(dataclasses.replace(
                    merged, gamma=self.gamma(inner[0]), Q=0.5 * (q_in + q_in.T), Y=y_in), norm))
            return self._unscale(dataclasses.replace(
                merged, solver_status=f"ipm {merged.solver_status}", iterations=decided.iterations,
                solve_time=decided.solve_time, interior=interior), norm), None
        if merged.status == INFEASIBLE:
            return dataclasses.replace(merged, solver_status=f"ipm {merged.solver_status}"), None
        return self._decide(merged, xs, us, ys, *_nest_args(qs))

    def _retry_on_point(self, raw: RawResult, feasible_x: np.ndarray, x: np.ndarray, u_max: np.ndarray,
                        y_max: np.ndarray, outer: np.ndarray | None) -> tuple[RawResult, RawResult]:
        """After phase one found the strictly feasible ``feasible_x`` (the solver's variables in the
        current coordinates): that point as an answer in the caller's coordinates (status
        ``"inaccurate"``, see :meth:`_with_point`), and a cold retry in coordinates
        balanced on its ``Q~`` (:meth:`_balanced_on`): ``"optimal"`` in the caller's
        coordinates (carrying the point as its ``interior``), or ``raw`` with the retry's word,
        time and iterations added (``raw`` as it is without ``rebalance``)."""
        xs, _, _, norm = self._balanced(x, u_max, y_max)
        q_mat, y_mat = self.conic.variables(feasible_x)
        q_mat = 0.5 * (q_mat + q_mat.T)
        point = self._unscale(dataclasses.replace(
            raw, status=INACCURATE, gamma=self.gamma(feasible_x[0]), Q=q_mat, Y=y_mat), norm)
        t_new = self._balanced_on(q_mat, xs) if self._rebalance else None
        if t_new is None:
            return raw, point
        start = time.perf_counter()
        self._build(t_new)
        xs, us, ys, norm = self._balanced(x, u_max, y_max)
        retry = self._solve_ipm(xs, us, ys, self._outer_scaled(outer, norm))
        merged = dataclasses.replace(
            raw, solver_status=f"{raw.solver_status}; rebalanced on it {retry.solver_status}",
            iterations=(raw.iterations or 0) + (retry.iterations or 0),
            solve_time=raw.solve_time + time.perf_counter() - start,
        )
        if retry.status == OPTIMAL:
            return self._unscale(dataclasses.replace(
                retry, solver_status=f"ipm {merged.solver_status}", iterations=merged.iterations,
                solve_time=merged.solve_time, interior=self._interior(point)), norm), point
        return merged, point

    @staticmethod
    def _interior(point: RawResult) -> tuple[float, np.ndarray, np.ndarray]:
        """``(gamma, Q, Y)`` of phase one's point (caller's coordinates, normalised state)."""
        assert point.Q is not None and point.Y is not None
        return point.gamma, point.Q, point.Y

    @classmethod
    def _with_point(cls, answer: RawResult, point: RawResult) -> RawResult:
        """The last stage's ``answer`` (caller's coordinates) carrying phase one's strictly feasible
        ``point`` as its ``interior``, which :class:`lmi.KothareProblem` mixes in (or gives as the
        answer) if the answer is not certified; an answer without ``Q`` is replaced by the point
        itself, ``"inaccurate"``: a gain whose ``gamma`` is only an upper bound on the optimum."""
        if answer.Q is not None and answer.Y is not None:
            return dataclasses.replace(answer, interior=cls._interior(point))
        return dataclasses.replace(
            point, solver_status=f"{answer.solver_status}; phase one's point (gamma an upper bound)",
            iterations=answer.iterations, solve_time=answer.solve_time, interior=cls._interior(point))

    def farkas_check(self, z_blocks: list[np.ndarray], xs: np.ndarray, u_max: np.ndarray,
                     y_max: np.ndarray, outer: np.ndarray | None = None) -> InfeasibilityCertificate:
        """Check multipliers ``Z`` (one block per LMI block of the solver) as a Farkas certificate
        on the conic data Clarabel would be given at this (normalised, balanced) state and
        bounds: ``A`` with the bound rows scaled, ``b`` with the state block (and the nesting
        block's ``outer``, in the solver's coordinates)."""
        parts, cones = [], []
        for cone, zj, rows in zip(self.conic.cones, z_blocks, self._block_rows, strict=True):
            if isinstance(cone, clarabel.PSDTriangleConeT):
                parts.append(svec_matrix(0.5 * (zj + zj.T)))
                cones.append(("psd", zj.shape[0]))
            else:  # a non-negative cone: its IPM block is diagonal, only the diagonal of Z counts
                parts.append(np.diag(zj).copy())
                cones.append(("nonneg", rows.stop - rows.start))
        conic = self.conic
        return check_farkas(conic.a_matrix(u_max, y_max), conic.b_vector(xs, outer), cones,
                            np.concatenate(parts))

    def _unscale(self, raw: RawResult, norm: float) -> RawResult:
        """Back to the caller's coordinates and state: ``Q = T Q~ T' norm^2``, ``Y = Y~ T' norm^2``,
        ``gamma norm^2``."""
        if raw.Q is None or raw.Y is None or not self._scaled:
            return raw
        t, s2 = self._t, norm**2
        if t.ndim == 2:
            return dataclasses.replace(raw, gamma=raw.gamma * s2, Q=(t @ raw.Q @ t.T) * s2,
                                       Y=(raw.Y @ t.T) * s2)
        return dataclasses.replace(raw, gamma=raw.gamma * s2, Q=raw.Q * np.outer(t, t) * s2,
                                   Y=raw.Y * t[None, :] * s2)

    def _solve_ipm(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray,
                   outer: np.ndarray | None = None) -> RawResult:
        start = time.perf_counter()
        if self._core is not None and outer is None:
            return self._solve_core(x, u_max, y_max, start)
        try:
            self._update_blocks(x, u_max, y_max, outer)
            with self._blas.limit():
                res = self._solver.solve(warm_start=self._warm_start)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as err:
            self._last_residual, self._last_qr_gap = np.inf, np.nan
            return RawResult(NUMERICAL_ERROR, repr(err), np.nan, None, None, None,
                             time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        self._last_residual = max(res.primal_residual, res.dual_residual)
        self._last_qr_gap = res.qr_start_gap
        return self._raw(res.status, res.solver_status, res.x, res.Z, res.iterations, elapsed,
                         (x, u_max, y_max, *_nest_args(outer)))

    def _raw(self, status: str, word: str, x_vec: np.ndarray, z_blocks: list[np.ndarray], iterations: int,
             elapsed: float, at: tuple[np.ndarray, ...]) -> RawResult:
        """The :class:`RawResult` of one run (numba's or the C core's): an ``"infeasible"`` run's
        ray checked by :meth:`farkas_check` at ``at`` (state, bounds and outer ``Q``), else ``Q``, ``Y``
        and gamma from the variables ``x_vec``."""
        if status == INFEASIBLE:
            cert = self.farkas_check(z_blocks, *at)
            if cert.ok:
                return RawResult(INFEASIBLE, "infeasible", np.nan, None, None, iterations, elapsed,
                                 infeasibility=cert)
            return RawResult(NUMERICAL_ERROR, "infeasible (unchecked)", np.nan, None, None, iterations,
                             elapsed)
        q_mat, y_mat = self.conic.variables(x_vec)
        return RawResult(status, word, self.gamma(x_vec[0]), q_mat, y_mat, iterations, elapsed)

    def _solve_core(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray, start: float) -> RawResult:
        """:meth:`_solve_ipm` by the C core: the same iterations, the same result. A solve that does
        not end ``"optimal"`` also sets the Python solver's blocks at this state, for phase one."""
        assert self._core is not None
        res = self._core.solve(x, u_max, y_max, self._warm_start)
        elapsed = time.perf_counter() - start
        self._last_residual = max(res.primal_residual, res.dual_residual)
        self._last_qr_gap = np.nan  # the C core does not report its QR phase
        status = SOLVER_STATUS_MAP[res.word]
        if status != OPTIMAL:
            self._update_blocks(x, u_max, y_max)
        return self._raw(status, res.word, res.x, res.Z, res.iterations, elapsed, (x, u_max, y_max))
