"""Compiled kernels of the interior-point iterations of :mod:`lmi.ipm` (numba, ``nopython``).

The blocks of the Kothare problems are small (orders 7-15) and few (5-11), so a numpy
implementation of an iteration is dominated by the fixed cost of its ~250 array calls, not by
arithmetic (measured on paper P at 2 vertices: 0.55 of 0.8 ms per iteration). An iteration is
two calls: :func:`residuals`, then :func:`rows_iteration` (or :func:`grouped_iteration` when
``H`` is formed from factored coefficients), which scales, forms and factors the Schur
complement and takes the predictor-corrector step (:mod:`lmi.ipm.kernels.iteration`). Matrix
products are BLAS/LAPACK calls made from compiled code (the Schur complement's ``dsyrk``,
``dpotrf`` and ``dgeqrf`` through :mod:`lmi.ipm.kernels.lapack`); the Cholesky factorisations of
the blocks and their eigenvalues (:mod:`lmi.ipm.kernels.eigen`: the NT scaling's eigen-decompositions
and the smallest eigenvalues of the step-length test) are plain loops.

Layout shared by every kernel. ``nb`` blocks of orders ``orders[j]``; block matrices are held
in ``(nb, kmax, kmax)`` arrays, only ``[:k, :k]`` used. A packed vector holds, block after
block (``offsets[j]:offsets[j + 1]``), the upper triangle of each block row by row (the order
of ``numpy.triu_indices``) scaled by ``w`` (1 on the diagonal, sqrt(2) off it), entry ``t`` at
row ``ent_row[t]`` and column ``ent_col[t]``.
The coefficients, with the variable scaling applied, are held as their non-zero upper-triangle
entries: entry ``e`` (block ``j``'s entries are ``sp_off[j]:sp_off[j + 1]``) is
``A_ij[a, b] = sp_val[e]`` with ``i = sp_var[e]`` and ``(a, b)`` the position pair
``sp_pair[e]``; the distinct pairs of block ``j`` are ``pair_off[j]:pair_off[j + 1]``, pair
``q`` being ``(pair_row[q], pair_col[q])`` with ``a <= b``. The
Schur complement is ``H = P'P``; its factor is held transposed, ``pt`` ``(n, size)``, so that
the rows the kernels write are contiguous.

The kernels are grouped by stage: the packed layout, the block Cholesky factors and the
residuals (:mod:`lmi.ipm.kernels.packed`), the NT scaling and the Schur complement in its three
forms (:mod:`lmi.ipm.kernels.schur`), the factorisations by BLAS/LAPACK
(:mod:`lmi.ipm.kernels.lapack`), the Newton step with its refinement and step lengths
(:mod:`lmi.ipm.kernels.step`) and the whole iteration (:mod:`lmi.ipm.kernels.iteration`); this
package re-exports the public ones. Compiled on first use and
cached next to their files (``cache=True``): the first process after an install pays the
compilation (about 30 s here at load 2), later ones load it (well under 1 s); a line on
stderr says so while they compile (:mod:`lmi.ipm.kernels.notice`). The names above are imported
on first use (:mod:`toolkit_common.lazy`), numba with them: importing :mod:`lmi.ipm` does not
import numba, building the first :class:`lmi.ipm.BlockLMISolver` does.
"""

from typing import TYPE_CHECKING

from toolkit_common.lazy import lazy_exports

if TYPE_CHECKING:
    from lmi.ipm.kernels.eigen import smallest_eigenvalue
    from lmi.ipm.kernels.iteration import (
        STEP_LOST_DEFINITENESS,
        STEP_OK,
        STEP_SINGULAR,
        blockwise_iteration,
        grouped_iteration,
        rows_iteration,
    )
    from lmi.ipm.kernels.notice import compile_notice
    from lmi.ipm.kernels.packed import blocks_within, cholesky_blocks, pack, residuals, unpack
    from lmi.ipm.kernels.schur import (
        scaling_and_schur_blockwise,
        scaling_and_schur_direct,
        scaling_and_schur_grouped,
        scaling_and_schur_rows,
    )
    from lmi.ipm.kernels.step import REFINE_STEPS, newton_step


# the module defining each public name, imported when the name is first looked up
_EXPORTS = {
    "lmi.ipm.kernels.iteration": (
        "STEP_LOST_DEFINITENESS", "STEP_OK", "STEP_SINGULAR", "blockwise_iteration", "grouped_iteration",
        "rows_iteration",
    ),
    "lmi.ipm.kernels.packed": ("blocks_within", "cholesky_blocks", "pack", "residuals", "unpack"),
    "lmi.ipm.kernels.schur": (
        "scaling_and_schur_blockwise", "scaling_and_schur_direct", "scaling_and_schur_grouped",
        "scaling_and_schur_rows",
    ),
    "lmi.ipm.kernels.notice": ("compile_notice",),
    "lmi.ipm.kernels.eigen": ("smallest_eigenvalue",),
    "lmi.ipm.kernels.step": ("REFINE_STEPS", "newton_step"),
}

__all__ = [
    "REFINE_STEPS", "STEP_LOST_DEFINITENESS", "STEP_OK", "STEP_SINGULAR", "blocks_within",
    "blockwise_iteration", "cholesky_blocks", "compile_notice", "grouped_iteration", "newton_step", "pack",
    "residuals", "rows_iteration",
    "scaling_and_schur_blockwise", "scaling_and_schur_direct", "scaling_and_schur_grouped",
    "scaling_and_schur_rows", "smallest_eigenvalue", "unpack",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
