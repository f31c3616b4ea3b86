"""The data of a block LMI problem, held the way the interior-point kernels read it.

:class:`BlockData` is the data half of :class:`lmi.ipm.BlockLMISolver`: the blocks
``S_j = C_j - sum_i x_i A_ij`` checked (:func:`check_block`, :func:`check_factor`), each block's
upper triangle packed into one vector (:class:`PackedLayout`, the layout of
:mod:`lmi.ipm.kernels`), the blocks weighted and the variables equilibrated once, and the
coefficients kept in the three forms the kernels take: packed (``G``), as their non-zero entries
(the ``sp_*`` arrays) and in factored form ``A_ij = D_j N_ij D_j'`` (the ``dict_*`` and ``fe_*``
arrays, grouped by :func:`factor_groups`). :meth:`BlockData.set_block` replaces a block in
place; the scaled forms are refreshed before the next iteration (``_refresh``), and
:data:`DIRECT_MIN_VARIABLES` and a cost model (:data:`SCHUR_PAIR_COST`) choose the formula of the
Schur complement: from ``P`` formed (rows), from the factored coefficients (direct), or block by
block on each block's own variables (blockwise, :func:`block_variables`; ``H`` then factored in
the block-arrow order of :func:`arrow_order`).

Equilibration: ``x = D x~`` with every variable's weighted coefficients of unit Frobenius norm
over all blocks, and, for badly balanced blocks, block weights ``w_j`` (:func:`block_weights`,
powers of two): the kernels see ``w_j S_j = w_j C_j - sum_i x_i w_j A_ij`` and the dual
``Z_j / w_j``. Both are fixed at the first solve. The data kept as given (``_const``,
``_coef``) and the solver's outputs are in the original units.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_real_array

__all__ = [
    "ARROW_SHARE", "BLOCKWISE_SHARE", "BLOCK_WEIGHT_PASSES", "BLOCK_WEIGHT_SPREAD", "DIRECT_MIN_VARIABLES",
    "SCHUR_PAIR_COST", "SCHUR_PRODUCT_COST", "SCHUR_SCATTER_COST", "SCHUR_STREAM_COST", "SYMMETRY_TOL",
    "BlockData",
    "BlockFactor", "PackedLayout", "arrow_order", "block_pairs", "block_variables",
    "block_weights", "check_block", "check_factor", "concatenate_factors", "concatenate_sparse",
    "entry_weight", "factor_groups",
]

#: A block's constant and coefficients count as symmetric when their largest asymmetry is at most
#: this times their largest entry (or 1, whichever is larger): :func:`check_block` and
#: :meth:`BlockData.set_constants`.
SYMMETRY_TOL = 1e-12

#: A block's coefficients in factored form ``A_ij = D N_ij D'``: ``(D, var, p, q, value)``, the
#: dictionary ``D`` (``k x d``) and the entries ``N_ij[p, q] = N_ij[q, p] = value`` (``i = var``,
#: ``p <= q``; entries that repeat a position add up).
BlockFactor = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]

#: ``H`` is formed from the factored coefficients (:func:`lmi.ipm.kernels.scaling_and_schur_direct`)
#: only for more variables than this, and when the cost model (:data:`SCHUR_PAIR_COST`) predicts
#: it faster. Below, the Schur complement is a small part of an iteration: on paper P (61 variables with its
#: ellipsoid input bound) both ways measured the same median per solve (3.2-3.3 ms at 2
#: vertices, 7.3-7.7 ms at 8), and the rows path keeps paper P's records bit-identical (the
#: direct sum rounds differently; with a peak bound paper P has 67 variables and takes the
#: direct path). On the 14-state flexible satellite (259 variables, 2 vertices) the direct form
#: took the warm median from 876 ms to 21 ms (load ~7).
DIRECT_MIN_VARIABLES = 64

#: The cost model of the choice between the two formulas of the Schur complement
#: (:meth:`BlockData._choose_formula`, terms :meth:`BlockData._schur_terms`), in units of one
#: operation of the rows formula's ``dsyrk``: a pair of factored entries of the direct formula
#: costs :data:`SCHUR_PAIR_COST`, a multiply-add forming ``P'`` :data:`SCHUR_STREAM_COST`, and an
#: entry of ``P'`` :data:`SCHUR_PRODUCT_COST` more for the Newton step's products with the formed
#: ``P`` (the direct path makes them from the sparse coefficients, far cheaper at this scale).
#: Fitted by relative least squares (``python -m dev.ipm_formula --kernels-only``) to the time
#: per iteration of each formula (forming ``H``, plus five pairs of products ``P'v``, ``P dx``:
#: each of the two Newton solves makes one and a half, and one per refinement step, assumed one)
#: on the forms and Kothare's problems of paper P, paper W, Kothare's example 2 and the 14-state
#: flexible satellite (26-1184 variables). Three runs (14-22 cases, load 1.4-3.8 on 2 cores) gave
#: 201-545, 46-103 and 103-842 (a ``dsyrk`` operation at 0.008-0.025 ns, a pair at 4-5 ns): the
#: terms are correlated and the fit loose, but the choice is not: each run's constants and these
#: make the same choice on all 22 cases but one where both formulas measure within 10 % (paper
#: P's vertex form at 2 vertices), and every choice is the faster formula or within 1.3 times it.
#: The pair loop reads ``G`` at scattered entries and adds into ``H`` one entry at a time, where
#: ``dsyrk`` streams through cache-blocked panels; forming ``P'`` and its products move ``n m``
#: doubles through memory. The operation count used before weighed a pair as 4 operations and
#: took the direct formula where it formed ``H`` up to 6 times slower (the free-move form of the
#: flexible satellite at ``horizon=2``: 1.0 s against 0.17 s). The choice is unchanged for
#: Kothare's problems (their vertex blocks, factored and grouped, give few pairs: ``H`` in 1.2 ms
#: against 19 ms on the flexible satellite) and for every problem of at most
#: :data:`DIRECT_MIN_VARIABLES` variables.
SCHUR_PAIR_COST = 200.0
#: See :data:`SCHUR_PAIR_COST`.
SCHUR_STREAM_COST = 50.0
#: See :data:`SCHUR_PAIR_COST`.
SCHUR_PRODUCT_COST = 150.0
#: The blockwise formula's cost of adding one entry of a block's ``P_j'P_j`` into ``H`` (scattered
#: reads and writes), in the units of :data:`SCHUR_PAIR_COST`.
SCHUR_SCATTER_COST = 20.0
#: The blockwise formula (:func:`lmi.ipm.kernels.scaling_and_schur_blockwise`) is a candidate only
#: when its ``dsyrk`` work ``sum_j n_j^2 m_j`` (``n_j`` the variables block ``j`` holds, ``m_j`` its
#: packed size) is at most this share of the rows formula's ``n^2 m``: the vertex forms, whose
#: blocks hold one vertex's (or pair's) Lyapunov matrices and the shared variables (0.09 on the
#: flexible satellite's vertex form over 8 vertices). Kothare's form, whose blocks nearly all hold
#: every variable, keeps its formula and its records.
BLOCKWISE_SHARE = 0.5
#: :func:`arrow_order` keeps its groups only when the block-arrow factorisation takes at most this
#: share of a dense Cholesky's ``n^3 / 3`` operations (0.27 on the flexible satellite's vertex form
#: over 8 vertices: 8.5 against 19 ms; on its vertex-pair form, one group of 105 of 1184
#: variables, about 1.0, and the arrow took 26 against 19 ms).
ARROW_SHARE = 0.5


#: Block equilibration (:func:`block_weights`): the blocks are weighted only when the balancing
#: weights span more than this factor. Weighting block ``j`` by ``w_j`` (slack ``w_j S_j``, dual
#: ``Z_j / w_j``) leaves the central path and the Nesterov-Todd directions as they are; it
#: changes the start point (every block is shifted into its interior by one multiple of ``I``)
#: and the norms of the residuals. SDPLIB's control2-4 span 292-403 (the Lyapunov block's
#: coefficients are about 100 times those of ``P >= I``): unweighted, their first steps are
#: short (about 9 iterations of tiny steps) and they take 40/45/44 iterations; weighted, the
#: first steps have length 0.99 and they take 29/32/34. With block 0 of control2-4 scaled down
#: to spans of 10-30 the weights still saved 6-11 iterations. On Kothare problems, weighted at
#: any span (measured by forcing it), the effect was mixed and no status changed: paper P (span
#: 2.1-2.3) 130 -> 126 cold and 125 -> 129 warm-started iterations over 8 random states at 2
#: vertices, 157 -> 158 and 145 -> 144 at 8; the stress set of 6-14 states
#: (:mod:`dev.stress`, spans up to 40) 1092 -> 1175 in all, two infeasibility proofs
#: moving from the main run to phase one; the far states (:mod:`dev.far_states`) 1734 ->
#: 1616; random 8-16-state problems 358 -> 363. A threshold of 20 changed records of the fault
#: suite (``rmpc bench faults``, W1-W3, by up to 3e-6 relative through their closed loops). At
#: 100 no suite record changed (W4's CRMPC problems, span 512, are weighted and kept their
#: records to 1e-8), paper P is untouched, the far states (whose input blocks, scaled by the
#: bound at states far out, span up to about 1e4) took 1629 iterations and the stress set 1096 (one
#: problem weighted, 47 -> 51), every status unchanged.
BLOCK_WEIGHT_SPREAD = 100.0
#: Alternating passes (variables, blocks) of the Ruiz-style balancing in :func:`block_weights`.
BLOCK_WEIGHT_PASSES = 10


class PackedLayout:
    """Where each block's upper triangle sits in a packed vector (see :mod:`lmi.ipm.kernels`)."""

    def __init__(self, orders: list[int]) -> None:
        self.orders = np.asarray(orders, dtype=np.int64)
        sizes = [k * (k + 1) // 2 for k in orders]
        self.offsets = np.cumsum([0, *sizes]).astype(np.int64)
        self.size = int(self.offsets[-1])
        self._triangles = []
        for k in orders:
            iu0, iu1 = np.triu_indices(k)
            self._triangles.append((iu0, iu1, np.where(iu0 == iu1, 1.0, np.sqrt(2.0))))
        self.ent_row = np.concatenate([t[0] for t in self._triangles]).astype(np.int64)
        self.ent_col = np.concatenate([t[1] for t in self._triangles]).astype(np.int64)
        self.ent_w = np.concatenate([t[2] for t in self._triangles])
        #: the arguments every kernel takes, in order
        self.arrays = (self.orders, self.offsets, self.ent_row, self.ent_col, self.ent_w)

    def rows(self, j: int) -> slice:
        return slice(int(self.offsets[j]), int(self.offsets[j + 1]))

    def triangle(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Row and column indices of block ``j``'s upper triangle, and the packing weights."""
        return self._triangles[j]

class BlockData:
    """The blocks of ``min c'x, C_j - sum_i x_i A_ij >= 0`` as the kernels read them.

    Parameters
    ----------
    n : int
        Number of variables.
    blocks : sequence of (C_j, A_j)
        ``C_j`` is ``(k_j, k_j)`` symmetric, ``A_j`` is ``(n, k_j, k_j)`` with symmetric slices.
    factors : sequence of BlockFactor or None, optional
        Per block, its coefficients in factored form (:data:`BlockFactor`), or ``None``.

    Attributes
    ----------
    n : int
    block_orders : list of int
        ``k_j``.
    degree : int
        ``sum_j k_j``.
    block_weights : ndarray or None
        The weights ``w_j`` of the blocks as the kernels see them (``w_j C_j``, ``w_j A_ij``;
        :func:`block_weights`), fixed at the first solve like the variable scaling (``None``
        before it); later updates of the data keep them.
    """

    def __init__(
        self, n: int, blocks: Sequence[tuple[np.ndarray, np.ndarray]],
        factors: Sequence[BlockFactor | None] | None = None,
    ) -> None:
        self.n = n
        self._dscale: np.ndarray | None = None
        self.block_weights: np.ndarray | None = None
        checked = [check_block(j, const, coef, n) for j, (const, coef) in enumerate(block_pairs(blocks))]
        orders = [const.shape[0] for const, _ in checked]
        self.block_orders = orders
        self.degree = sum(orders)
        self._layout = PackedLayout(orders)
        lay = self._layout
        self._kmax = max(orders)
        self._coef: list[np.ndarray] = [np.zeros((n, k, k)) for k in orders]
        self._absent: np.ndarray | None = None
        self._dirty: set[int] = set()
        self._h_vec = np.zeros(lay.size)
        self._g_mat = np.zeros((lay.size, n))  # packed scaled coefficients
        self._sparse: tuple[np.ndarray, ...] = ()  # non-zero scaled coefficients (kernels' sp_*)
        self._sparse_parts: list[tuple[np.ndarray, ...]] = [() for _ in orders]
        # factored coefficients A_ij = D_j N_ij D_j' (kernels' dict_*, fe_*; see
        # scaling_and_schur_direct); None: D_j = I and N_ij = A_ij
        if factors is not None and len(factors) != len(checked):
            raise InvalidArgumentError("factors", f"one entry (or None) per block, {len(checked)}",
                                       f"{len(factors)} entries")
        self._factor_raw: list[BlockFactor | None] = [None] * len(checked)
        self._fact_parts: list[tuple[np.ndarray, ...]] = [() for _ in orders]
        self._fact: tuple[np.ndarray, ...] = ()
        self._groups: tuple[np.ndarray, np.ndarray] = (np.zeros(1, dtype=np.int64),
                                                       np.zeros(0, dtype=np.int64))
        # the Schur formula (_choose_formula) and each block's own variables (block_variables)
        self._formula = "rows"
        self._arrow: tuple[np.ndarray, np.ndarray] = (np.arange(n, dtype=np.int64),
                                                      np.zeros(1, dtype=np.int64))
        self._arrow_local: tuple[np.ndarray, ...] = (
            np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(1, dtype=np.int64),
            np.zeros((0, 3), dtype=np.int64))
        self._blockvars: tuple[np.ndarray, np.ndarray, np.ndarray] = block_variables(
            (np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64)))
        self._const: list[np.ndarray] = [const for const, _ in checked]
        for j, (const, coef) in enumerate(checked):
            self._set_checked(j, const, coef)
            if factors is not None and factors[j] is not None:
                self._factor_raw[j] = check_factor(j, factors[j], coef, n)

    def set_block(self, j: int, const: np.ndarray, coef: np.ndarray | None = None,
                  factor: BlockFactor | None = None) -> None:
        """Replace block ``j``'s constant (and coefficients, if given, with their factored form
        ``factor`` or none)."""
        self._check_index(j)
        if factor is not None and coef is None:
            raise InvalidArgumentError("factor", "None unless coef is given", "a factor without coef")
        const_c, coef_c = check_block(int(j), const, coef, self.n, self.block_orders[j])
        checked_factor = None if factor is None else check_factor(int(j), factor, coef_c, self.n)
        self._set_checked(int(j), const_c, coef_c)
        if coef_c is not None:
            if (checked_factor is None) != (self._factor_raw[int(j)] is None) or checked_factor is not None:
                self._dirty.add(int(j))
                self._fact_parts[int(j)] = ()
            self._factor_raw[int(j)] = checked_factor

    def set_constants(self, constants: Mapping[int, np.ndarray]) -> None:
        """Replace the constants ``C_j`` of several blocks (``{j: C_j}``), the coefficients kept.

        The same checks as :meth:`set_block` (square, the block's order, finite, symmetric), made
        on each order's stack at once; a block that fails them is named as :meth:`set_block`
        names it, and no block is set. A warm-started form sets a dozen or more small constants
        per state, where the checks block by block cost more than the setting.

        Examples
        --------
        ``min z`` subject to ``(1 - z) I >= 0`` and ``3 + z >= 0``; then the constants become
        ``2 I`` and ``1`` (the lower bound moves to ``z >= -1``):

        >>> import numpy as np
        >>> from lmi.ipm import BlockLMISolver
        >>> blocks = [(np.eye(2), np.stack([np.eye(2)])), (np.eye(1) * 3.0, -np.ones((1, 1, 1)))]
        >>> solver = BlockLMISolver(np.array([1.0]), blocks)
        >>> round(float(solver.solve().x[0]), 6)
        -3.0
        >>> solver.set_constants({0: 2.0 * np.eye(2), 1: np.eye(1)})
        >>> round(float(solver.solve().x[0]), 6)
        -1.0
        """
        items = list(constants.items())
        for j, _ in items:
            self._check_index(j)
        by_order: dict[int, list[tuple[int, np.ndarray]]] = {}
        for j, const in items:
            c_mat = np.asarray(const)
            order = self.block_orders[int(j)]
            if c_mat.dtype != np.float64 or c_mat.shape != (order, order):
                check_block(int(j), const, None, self.n, order)  # raises if it is wrong
                c_mat = np.asarray(const, dtype=float)
            by_order.setdefault(order, []).append((int(j), c_mat))
        for group in by_order.values():  # every block checked before any is set
            stack = np.stack([c_mat for _, c_mat in group])
            scale = np.maximum(1.0, np.max(np.abs(stack), axis=(1, 2)))
            asym = np.max(np.abs(stack - np.swapaxes(stack, 1, 2)), axis=(1, 2))
            bad = ~(np.all(np.isfinite(stack), axis=(1, 2)) & (asym <= SYMMETRY_TOL * scale))
            for (j, c_mat), wrong in zip(group, bad, strict=True):
                if wrong:
                    check_block(j, c_mat, None, self.n, self.block_orders[j])  # names the fault
        for group in by_order.values():
            for j, c_mat in group:
                self._set_checked(j, c_mat, None)

    def _check_index(self, j: Any) -> None:
        """``j`` must be a block index (an integer, not a bool, in range)."""
        count = len(self.block_orders)
        if isinstance(j, bool) or not (isinstance(j, int | np.integer) and 0 <= j < count):
            raise InvalidArgumentError("j", f"a block index in [0, {count})", repr(j))

    def _set_checked(self, j: int, const: np.ndarray, coef: np.ndarray | None) -> None:
        rows = self._layout.rows(j)
        iu0, iu1, w = self._layout.triangle(j)
        self._h_vec[rows] = const[iu0, iu1] * w
        if self.block_weights is not None:
            self._h_vec[rows] *= self.block_weights[j]
        self._const[j] = const.copy()
        if coef is not None and not np.array_equal(coef, self._coef[j]):
            self._coef[j] = coef.copy()
            self._dirty.add(j)
            self._absent = None

    def absent_variables(self) -> np.ndarray:
        """The indices of the variables that appear in no block (every ``A_ij = 0``)."""
        if self._absent is None:
            used = np.zeros(self.n, dtype=bool)
            for coef in self._coef:
                used |= np.any(coef != 0.0, axis=(1, 2))
            self._absent = np.flatnonzero(~used)
        return self._absent

    def _refresh(self) -> None:
        """Variable scaling (once) and the scaled coefficients of the changed blocks."""
        if self._dscale is None:
            # weight the blocks and equilibrate the variables once, x = D x~ with unit-norm
            # weighted coefficients (later updates, e.g. a bound scaling, keep both)
            if self.block_weights is None:
                self.block_weights = block_weights(self._coef, self._copies())
            weights = self.block_weights
            for j, const in enumerate(self._const):
                rows = self._layout.rows(j)
                iu0, iu1, w = self._layout.triangle(j)
                self._h_vec[rows] = const[iu0, iu1] * w * weights[j]
            norms = np.sqrt(sum(wj * wj * np.einsum("ikl,ikl->i", a, a)
                                for wj, a in zip(weights, self._coef, strict=True)))
            self._dscale = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
            self._dirty = set(range(len(self.block_orders)))
        if not self._dirty:
            return
        rebuild = not self._sparse
        for j in sorted(self._dirty):
            scaled = self._coef[j] * (self._dscale * self.block_weights[j])[:, None, None]  # (n, k, k)
            iu0, iu1, w = self._layout.triangle(j)
            upper = scaled[:, iu0, iu1]  # (n, entries), entries in packed order
            self._g_mat[self._layout.rows(j)] = (upper * w).T
            pattern = upper != 0.0
            old = self._sparse_parts[j]
            if (old and np.array_equal(pattern, old[0]) and self._fact_parts[j]
                    and self._factor_raw[j] is None):  # same non-zeros (e.g. a bound scaling)
                lo, hi = self._sparse[0][j], self._sparse[0][j + 1]
                self._sparse[3][lo:hi] = upper[pattern]
                flo, fhi = self._fact[2][j], self._fact[2][j + 1]
                self._fact[6][flo:fhi] = upper[pattern] * entry_weight(old[4][old[2]], old[5][old[2]])
                continue
            var, entry = np.nonzero(pattern)  # ordered (variable, entry), as upper[pattern]
            pair_entries, pair_of = np.unique(entry, return_inverse=True)
            self._sparse_parts[j] = (pattern, var, pair_of, upper[pattern], iu0[pair_entries],
                                     iu1[pair_entries])
            self._fact_parts[j] = self._factored_part(j)
            rebuild = True
        self._dirty.clear()
        if rebuild:
            self._sparse = concatenate_sparse(self._sparse_parts)
            self._fact = concatenate_factors(self._fact_parts, self._kmax)
            self._groups = factor_groups(self._fact_parts, self._factor_raw)
            self._blockvars = block_variables(self._sparse)
            self._formula = self._choose_formula()
            self._arrow = arrow_order(self._blockvars, self.n)
            # where each block's variables sit in that order (H is formed there directly)
            self._arrow_local = arrow_local(self._blockvars, self._sparse[0], self._arrow[0])

    @property
    def _direct(self) -> bool:
        """Whether ``H`` is formed from the factored coefficients (the direct formula)."""
        return self._formula == "direct"

    def _copies(self) -> list[int]:
        """Per block, the first block with an equal given factor (itself if none): copies of one
        block (a Kothare problem's vertex blocks) must get equal weights to stay one group of
        :func:`factor_groups`."""
        first: list[int] = []
        for j, raw in enumerate(self._factor_raw):
            first.append(j)
            if raw is None:
                continue
            for i in range(j):
                other = self._factor_raw[i]
                if (other is not None and first[i] == i and other[0].shape == raw[0].shape
                        and all(np.array_equal(a, b) for a, b in zip(raw[1:], other[1:], strict=True))):
                    first[j] = i
                    break
        return first

    def _factored_part(self, j: int) -> tuple[np.ndarray, ...]:
        """``(D, var, p, q, value)`` of block ``j`` with the variable scaling and the weights of
        :func:`lmi.ipm.kernels.scaling_and_schur_direct`, sorted by variable."""
        raw = self._factor_raw[j]
        if raw is None:  # D = I: the sparse upper-triangle entries
            _, var, pair_of, val, prow, pcol = self._sparse_parts[j]
            p, q = prow[pair_of], pcol[pair_of]
            dmat = np.eye(self.block_orders[j])
        else:
            dmat, var, p, q, val = raw
            val = val * (self._dscale[var] * self.block_weights[j])
            order = np.argsort(var, kind="stable")
            var, p, q, val = var[order], p[order], q[order], val[order]
        return dmat, var, p, q, val * entry_weight(p, q)

    def _schur_terms(self) -> dict[str, float]:
        """The terms of the cost model of :meth:`_choose_formula` (counts, not seconds).

        ``pairs``: the pairs of factored entries the direct formula visits (``e(e + 1)/2`` per
        group of ``e`` entries, once per member of the group); ``dictionary``: the products
        ``K D`` and ``(K D)'(K D)`` (``k^2 d + k d^2`` per block); ``stream``: the rows formula's
        contiguous multiply-adds forming ``P'`` (each coefficient entry and each position pair's
        packed basis over its block's rows, and the zeroing of ``P'``); ``syrk``: the ``n^2 m``
        operations of the ``dsyrk`` forming ``P'P`` (``m`` the packed size); ``products``: the ``n m``
        entries of ``P'`` the Newton step's products read when ``P`` is formed; ``block_stream``,
        ``block_syrk`` and ``scatter``: the blockwise formula's (:meth:`_blockwise_cost`) ``stream``
        (its ``P_j'`` zeroed over the block's own ``n_j`` variables only), ``sum_j n_j^2 m_j`` and
        the ``sum_j n_j^2`` additions into ``H``."""
        n, size = float(self.n), float(self._layout.size)
        grp_off, grp_blk = self._groups
        pairs = 0.0
        for g in range(grp_off.shape[0] - 1):
            entries = float(self._fact_parts[int(grp_blk[grp_off[g]])][1].shape[0])
            pairs += float(grp_off[g + 1] - grp_off[g]) * entries * (entries + 1.0) / 2.0
        dictionary, stream = 0.0, n * size
        for j, k in enumerate(self.block_orders):
            d = float(self._fact_parts[j][0].shape[1])
            rows = float(k * (k + 1) // 2)
            dictionary += k * k * d + k * d * d
            stream += (self._sparse_parts[j][1].shape[0] + self._sparse_parts[j][4].shape[0]) * rows
        bv_off = self._blockvars[0]
        block_stream, block_syrk, scatter = stream - n * size, 0.0, 0.0
        for j, k in enumerate(self.block_orders):
            nj, rows = float(bv_off[j + 1] - bv_off[j]), float(k * (k + 1) // 2)
            block_stream += nj * rows
            block_syrk += nj * nj * rows
            scatter += nj * nj
        return {"pairs": pairs, "dictionary": dictionary, "stream": stream, "syrk": n * n * size,
                "products": n * size, "block_stream": block_stream, "block_syrk": block_syrk,
                "scatter": scatter}

    def _formula_costs(self) -> dict[str, float]:
        """:func:`formula_costs` of this problem's terms (:meth:`_schur_terms`)."""
        return formula_costs(self._schur_terms())

    def _choose_formula(self) -> str:
        """The Schur formula of the iterations: ``"rows"`` for at most :data:`DIRECT_MIN_VARIABLES`
        variables; above, the one the cost model (:meth:`_formula_costs`) predicts fastest, the
        blockwise formula only where its ``dsyrk`` work is at most :data:`BLOCKWISE_SHARE` of the
        rows formula's (the blocks hold disjoint parts of the variables)."""
        if self.n <= DIRECT_MIN_VARIABLES:
            return "rows"
        t = self._schur_terms()
        costs = formula_costs(t)
        if t["block_syrk"] > BLOCKWISE_SHARE * t["syrk"]:
            costs.pop("blockwise")
        return min(costs, key=costs.__getitem__)


def formula_costs(terms: dict[str, float]) -> dict[str, float]:
    """The cost model's prediction per Schur formula (see :data:`SCHUR_PAIR_COST`) from the terms
    of :meth:`BlockData._schur_terms`, in units of one ``dsyrk`` operation: ``rows`` (``P'``
    formed, one ``dsyrk``, the step's products with the formed ``P``), ``direct`` (the pair sums)
    and ``blockwise`` (:func:`lmi.ipm.kernels.scaling_and_schur_blockwise`, estimated by forming
    ``P_j'`` and a ``dsyrk`` per block, an upper bound of its Gram form's work; its step's
    products come from the sparse coefficients, as the direct formula's, and are not counted)."""
    t = terms
    return {
        "rows": SCHUR_STREAM_COST * t["stream"] + t["syrk"] + SCHUR_PRODUCT_COST * t["products"],
        "direct": SCHUR_PAIR_COST * t["pairs"] + t["dictionary"],
        "blockwise": (SCHUR_STREAM_COST * t["block_stream"] + t["block_syrk"]
                      + SCHUR_SCATTER_COST * t["scatter"]),
    }


def block_variables(sparse: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' ``bv_off, bv_var, sp_loc`` (:func:`lmi.ipm.kernels.scaling_and_schur_blockwise`)
    from the sparse coefficients' ``sp_off, sp_var``: block ``j``'s variables, ascending, are
    ``bv_var[bv_off[j]:bv_off[j + 1]]`` and entry ``e``'s variable is ``bv_var[bv_off[j] +
    sp_loc[e]]``."""
    sp_off, sp_var = sparse[0], sparse[1]
    own, loc = [], []
    for j in range(sp_off.shape[0] - 1):
        entries = sp_var[sp_off[j]: sp_off[j + 1]]
        variables = np.unique(entries)
        own.append(variables)
        loc.append(np.searchsorted(variables, entries))
    bv_off = np.cumsum([0, *(v.shape[0] for v in own)]).astype(np.int64)
    return (bv_off, np.concatenate([np.zeros(0, dtype=np.int64), *own]).astype(np.int64),
            np.concatenate([np.zeros(0, dtype=np.int64), *loc]).astype(np.int64))


def arrow_local(blockvars: tuple[np.ndarray, ...], sp_off: np.ndarray,
                perm: np.ndarray) -> tuple[np.ndarray, ...]:
    """The blockwise kernel's ``bv_pos, sp_loc, run_off, runs`` for forming ``H`` in the variable
    order ``perm`` (:func:`lmi.ipm.kernels.scaling_and_schur_blockwise`): block ``j``'s variables'
    positions in that order, ascending, ``bv_pos[bv_off[j]:bv_off[j + 1]]``; entry ``e``'s place
    among them ``sp_loc[e]`` (``blockvars`` as :func:`block_variables` gives them, ``sp_off`` the
    blocks' entry offsets); and their contiguous runs ``runs[run_off[j]:run_off[j + 1]]``, each
    ``(first, position, length)``: the block's variables ``first .. first + length - 1`` sit at
    the positions ``position ..``. Ascending, so that a block's lower triangle lands in ``H``'s."""
    bv_off, bv_var, sp_loc = blockvars
    position = np.empty(perm.shape[0], dtype=np.int64)
    position[perm] = np.arange(perm.shape[0], dtype=np.int64)
    pos = position[bv_var]
    bv_pos, loc = np.empty_like(pos), np.empty_like(sp_loc)
    runs: list[tuple[int, int, int]] = []
    run_off = [0]
    for j in range(bv_off.shape[0] - 1):
        lo, hi = bv_off[j], bv_off[j + 1]
        order = np.argsort(pos[lo:hi], kind="stable")
        sorted_pos = pos[lo:hi][order]
        bv_pos[lo:hi] = sorted_pos
        rank = np.empty(hi - lo, dtype=np.int64)
        rank[order] = np.arange(hi - lo, dtype=np.int64)
        loc[sp_off[j]:sp_off[j + 1]] = rank[sp_loc[sp_off[j]:sp_off[j + 1]]]
        if hi > lo:  # a block may hold no variable (a constant block)
            starts = np.flatnonzero(np.diff(sorted_pos, prepend=-2) != 1)
            ends = np.append(starts[1:], hi - lo)
            runs.extend((int(a), int(sorted_pos[a]), int(b - a)) for a, b in zip(starts, ends, strict=True))
        run_off.append(len(runs))
    return (bv_pos, loc, np.asarray(run_off, dtype=np.int64),
            np.asarray(runs, dtype=np.int64).reshape(-1, 3))


def arrow_order(blockvars: tuple[np.ndarray, ...], n: int) -> tuple[np.ndarray, np.ndarray]:
    """A variable order in which ``H`` is a block arrow, for
    :func:`lmi.ipm.kernels.lapack.arrow_cholesky`: ``(perm, grp_off)``, the groups
    ``perm[grp_off[g]:grp_off[g + 1]]`` coupled to no other group, the border ``perm[grp_off[-1]:]``.

    ``H_ik`` can be non-zero only if some block holds both variables. The variables held by the
    same blocks form a class; two classes are coupled when one block holds both. Classes are taken
    as groups greedily, those coupled to the fewest variables first (the larger first among
    equals), each one coupled to no group taken before; the rest is the border. In a vertex form
    each vertex's Lyapunov matrix is a class that only the vertex's own blocks hold: those become
    the groups, the shared variables (``G``, ``Y``, the bounds) the border. When the elimination
    would save little (its operations more than :data:`ARROW_SHARE` of a dense factorisation's,
    as in the vertex-pair forms, whose pairs couple every vertex's matrix to every other), the
    order is the given one with no group: one dense factor.
    """
    bv_off, bv_var = blockvars[0], blockvars[1]
    holders: list[list[int]] = [[] for _ in range(n)]
    for j in range(bv_off.shape[0] - 1):
        for i in bv_var[bv_off[j]: bv_off[j + 1]]:
            holders[int(i)].append(j)
    classes: dict[tuple[int, ...], list[int]] = {}
    for i, blocks in enumerate(holders):
        classes.setdefault(tuple(blocks), []).append(i)
    block_size = np.diff(bv_off)

    def reach(blocks: tuple[int, ...]) -> int:  # variables coupled to the class (an upper bound)
        return int(sum(block_size[j] for j in blocks))

    taken_blocks: set[int] = set()
    groups: list[list[int]] = []
    border: list[int] = []
    for blocks in sorted(classes, key=lambda b: (reach(b), -len(classes[b]), b)):
        if blocks and not taken_blocks.intersection(blocks):
            groups.append(classes[blocks])
            taken_blocks.update(blocks)
        else:
            border.extend(classes[blocks])
    nb = float(len(border))
    arrow_flops = nb ** 3 / 3.0 + sum(g ** 3 / 3.0 + g * g * nb + g * nb * nb
                                     for g in (float(len(grp)) for grp in groups))
    if arrow_flops > ARROW_SHARE * float(n) ** 3 / 3.0:  # too little to eliminate: one dense factor
        return np.arange(n, dtype=np.int64), np.zeros(1, dtype=np.int64)
    grp_off = np.cumsum([0, *(len(g) for g in groups)]).astype(np.int64)
    perm = np.array([i for g in groups for i in g] + sorted(border), dtype=np.int64)
    return perm, grp_off


def block_weights(coefs: Sequence[np.ndarray], copies: Sequence[int] | None = None) -> np.ndarray:
    """Weights ``w_j`` (powers of two, the largest 1) that balance the blocks' coefficients.

    Ruiz-style: :data:`BLOCK_WEIGHT_PASSES` alternating passes divide each variable's column by
    the square root of its norm over all blocks and each block by the square root of its norm
    per unit of order (``sqrt(sum_i ||w_j d_i A_ij||_F^2 / k_j)``). Only the block weights are
    kept (the solver equilibrates the variables itself, on the weighted blocks); they are
    normalised to a largest weight of 1 and rounded to powers of two, so that weighting and
    unweighting are exact. All ones unless the weights span more than
    :data:`BLOCK_WEIGHT_SPREAD`, and for a block without coefficients.

    Parameters
    ----------
    coefs : sequence of (n, k_j, k_j) ndarray
        Each block's coefficients ``A_ij``.
    copies : sequence of int, optional
        ``copies[j]`` is the index of the first block that block ``j`` copies (``j`` itself when
        none): a copy gets that block's weight (the vertex blocks of a Kothare problem, which
        the kernels sum as a group, :func:`factor_groups`).

    Returns
    -------
    (len(coefs),) ndarray
    """
    count = len(coefs)
    orders = np.array([a.shape[1] for a in coefs], dtype=float)
    sq = np.array([np.einsum("ikl,ikl->i", a, a) for a in coefs])  # (blocks, n)
    w = np.ones(count)
    d = np.ones(sq.shape[1])
    for _ in range(BLOCK_WEIGHT_PASSES):
        col = np.sqrt(((w * w)[:, None] * sq).sum(axis=0)) * d
        d = d / np.sqrt(np.where(col > 0.0, col, 1.0))
        row = np.sqrt(((d * d)[None, :] * sq).sum(axis=1) / orders) * w
        w = w / np.sqrt(np.where(row > 0.0, row, 1.0))
    live = sq.sum(axis=1) > 0.0
    if not np.any(live):
        return np.ones(count)
    w = np.where(live, w / float(np.max(w[live])), 1.0)
    if float(np.max(w[live])) <= BLOCK_WEIGHT_SPREAD * float(np.min(w[live])):
        return np.ones(count)
    w = np.exp2(np.round(np.log2(w)))
    if copies is not None:
        w = w[np.asarray(copies, dtype=np.int64)]
    return w


def entry_weight(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``sqrt(2) h`` with ``h = 1`` off the diagonal (``p != q``) and ``1/2`` on it."""
    return np.where(p == q, 0.5, 1.0) * np.sqrt(2.0)


def concatenate_factors(parts: list[tuple[np.ndarray, ...]], kmax: int) -> tuple[np.ndarray, ...]:
    """The kernels' ``dict_mat, dict_dims, fe_off, fe_var, fe_p, fe_q, fe_val``."""
    dims = np.array([part[0].shape[1] for part in parts], dtype=np.int64)
    dict_mat = np.zeros((len(parts), kmax, int(dims.max())))
    for j, part in enumerate(parts):
        dict_mat[j, : part[0].shape[0], : dims[j]] = part[0]
    offsets = np.cumsum([0, *(part[1].shape[0] for part in parts)]).astype(np.int64)
    return (
        dict_mat, dims, offsets,
        np.concatenate([part[1] for part in parts]).astype(np.int64),
        np.concatenate([part[2] for part in parts]).astype(np.int64),
        np.concatenate([part[3] for part in parts]).astype(np.int64),
        np.concatenate([part[4] for part in parts]).astype(float),
    )


def factor_groups(parts: list[tuple[np.ndarray, ...]],
                   raw: list[BlockFactor | None]) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's ``grp_off, grp_blk`` (:func:`lmi.ipm.kernels.scaling_and_schur_grouped`):
    blocks given in factored form whose order, dictionary width and entries are equal form one
    group (a Kothare problem's vertex blocks); every other block is a group of its own. Groups
    are ordered by their first block. Blocks without a given factor are never grouped: their
    entry values change in place with the bound scalings (see ``_refresh``)."""
    groups: list[list[int]] = []
    for j, part in enumerate(parts):
        for grp in groups:
            head = parts[grp[0]]
            if (raw[j] is not None and raw[grp[0]] is not None and part[0].shape == head[0].shape
                    and all(np.array_equal(a, b) for a, b in zip(part[1:], head[1:], strict=True))):
                grp.append(j)
                break
        else:
            groups.append([j])
    offsets = np.cumsum([0, *(len(g) for g in groups)]).astype(np.int64)
    return offsets, np.array([j for g in groups for j in g], dtype=np.int64)


def check_factor(j: int, factor: Any, coef: np.ndarray | None, n: int) -> BlockFactor:
    """Validate a factored form ``(D, var, p, q, value)`` of block ``j``'s coefficients: it must
    reproduce them (``A_ij = D N_ij D'``) to 1e-9 relative."""
    name = f"factors[{j}]"
    if coef is None:
        raise InvalidArgumentError(name, "a factor only for a block given with coefficients", "no A")
    try:
        dmat, var, p, q, val = factor
    except (TypeError, ValueError):
        raise InvalidArgumentError(name, "a tuple (D, var, p, q, value)", repr(type(factor))) from None
    dmat = as_real_array(dmat, f"{name} D")
    k = coef.shape[1]
    if dmat.ndim != 2 or dmat.shape[0] != k or dmat.shape[1] == 0 or not np.all(np.isfinite(dmat)):
        raise InvalidArgumentError(f"{name} D", f"a finite ({k}, d) matrix", f"shape {dmat.shape}")
    d = dmat.shape[1]
    var, p, q = (_indices(a, f"{name} {label}") for a, label in ((var, "var"), (p, "p"), (q, "q")))
    val = as_real_array(val, f"{name} value").ravel()
    if not (var.shape == p.shape == q.shape == val.shape):
        raise InvalidArgumentError(f"{name} entries", "var, p, q and value of equal length",
                                   f"lengths {var.size}, {p.size}, {q.size}, {val.size}")
    if np.any((var < 0) | (var >= n)) or np.any((p < 0) | (p > q) | (q >= d)) or not np.all(np.isfinite(val)):
        raise InvalidArgumentError(f"{name} entries", f"0 <= var < {n}, 0 <= p <= q < {d}, finite values",
                                   "an entry out of range")
    nmat = np.zeros((n, d, d))
    np.add.at(nmat, (var, p, q), val)
    off = p != q
    np.add.at(nmat, (var[off], q[off], p[off]), val[off])
    rebuilt = dmat @ (nmat @ dmat.T)  # matmul: an unoptimised einsum took 5.3 s of a 7.3 s build
    err = float(np.max(np.abs(rebuilt - coef), initial=0.0))
    if err > 1e-9 * max(1.0, float(np.max(np.abs(coef), initial=0.0))):
        raise InvalidArgumentError(name, "D N_i D' equal to the block's coefficients A_i",
                                   f"a largest difference of {err:.1e}")
    return dmat, var, p, q, val


def concatenate_sparse(parts: list[tuple[np.ndarray, ...]]) -> tuple[np.ndarray, ...]:
    """The kernels' ``sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col`` from the
    per-block ``(pattern, var, pair, value, pair_row, pair_col)``."""
    entry_base = np.cumsum([0, *(part[1].shape[0] for part in parts)]).astype(np.int64)
    pair_base = np.cumsum([0, *(part[4].shape[0] for part in parts)]).astype(np.int64)
    return (
        entry_base,
        np.concatenate([part[1] for part in parts]).astype(np.int64),
        np.concatenate([part[2] + pair_base[j] for j, part in enumerate(parts)]).astype(np.int64),
        np.concatenate([part[3] for part in parts]).astype(float),
        pair_base,
        np.concatenate([part[4] for part in parts]).astype(np.int64),
        np.concatenate([part[5] for part in parts]).astype(np.int64),
    )


def block_pairs(blocks: Any) -> list[tuple[Any, Any]]:
    """``blocks`` as a non-empty list of ``(C_j, A_j)`` pairs; anything else is an error naming
    ``blocks`` (or the entry that is not a pair)."""
    if isinstance(blocks, str | bytes | np.ndarray) or not isinstance(blocks, Sequence):
        raise InvalidArgumentError("blocks", "a sequence of (C_j, A_j) pairs", type(blocks).__name__)
    if len(blocks) == 0:
        raise InvalidArgumentError("blocks", "at least one (C_j, A_j) pair", "none")
    pairs = []
    for j, pair in enumerate(blocks):
        if isinstance(pair, str | bytes) or not isinstance(pair, Sequence) or len(pair) != 2:
            found = f"{len(pair)} items" if isinstance(pair, Sequence) else type(pair).__name__
            raise InvalidArgumentError(f"blocks[{j}]", "a pair (C_j, A_j)", found)
        pairs.append((pair[0], pair[1]))
    return pairs


def check_block(
    j: int, const: Any, coef: Any, n: int, order: int | None = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """Validate block ``j``: ``C_j`` ``(k, k)`` and ``A_j`` ``(n, k, k)``, finite and symmetric."""
    name = f"blocks[{j}]"
    c_mat = as_real_array(const, f"{name} C", "a square (k, k) matrix")
    if c_mat.ndim != 2 or c_mat.shape[0] != c_mat.shape[1] or c_mat.shape[0] == 0:
        raise InvalidArgumentError(f"{name} C", "a square (k, k) matrix", f"shape {c_mat.shape}")
    k = c_mat.shape[0]
    if order is not None and k != order:
        raise InvalidArgumentError(f"{name} C", f"order {order} (the block's order)", f"order {k}")
    arrays = [("C", c_mat)]
    a_mat = None
    if coef is not None:
        a_mat = as_real_array(coef, f"{name} A", f"an ({n}, {k}, {k}) array")
        if a_mat.shape != (n, k, k):
            raise InvalidArgumentError(f"{name} A", f"shape ({n}, {k}, {k})", f"shape {a_mat.shape}")
        arrays.append(("A", a_mat))
    for label, arr in arrays:
        if not np.all(np.isfinite(arr)):
            raise InvalidArgumentError(f"{name} {label}", "finite values", "NaN or inf")
        asym = float(np.max(np.abs(arr - np.swapaxes(arr, -1, -2)), initial=0.0))
        if asym > SYMMETRY_TOL * max(1.0, float(np.max(np.abs(arr), initial=0.0))):
            raise InvalidArgumentError(f"{name} {label}", "symmetric matrices", f"asymmetry {asym:.1e}")
    return c_mat, a_mat


def _indices(value: Any, name: str) -> np.ndarray:
    """``value`` as a flat array of integer indices (integral floats too), naming ``name``."""
    arr = as_real_array(value, name, "integer indices").ravel()
    if not np.all(np.isfinite(arr) & (arr == np.round(arr))):
        raise InvalidArgumentError(name, "integer indices", "a value that is not an integer")
    return arr.astype(np.int64)
