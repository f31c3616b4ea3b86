"""Run small dense linear algebra on one BLAS thread.

The LMI problems here are tiny; OpenBLAS nevertheless splits a 61 x 120 product over its
threads, and on a loaded 2-core machine the thread hand-off made one such product take 5 ms
instead of 17 us (measured). Solves therefore run inside ``threadpoolctl``'s limit of one BLAS
thread. The controller is created per solver object, on first use (after the solver's own
BLAS is loaded), so no process-wide setting is changed outside a solve.

Entering and leaving the limit costs 12-20 us (measured: two OpenBLAS libraries, numpy's and
scipy's, each set twice); when every BLAS library already runs one thread (a limit taken by
the caller, or ``OPENBLAS_NUM_THREADS=1``) :meth:`SingleThreadBlas.limit` only reads the thread
counts (about 1 us) and changes nothing, so nested limits cost nothing extra.
"""

from __future__ import annotations

from contextlib import AbstractContextManager, nullcontext
from typing import Any

from threadpoolctl import ThreadpoolController

__all__ = ["SingleThreadBlas"]


class SingleThreadBlas:
    """``with blas.limit(): ...`` runs the block with one BLAS thread."""

    def __init__(self) -> None:
        self._blas: Any = None

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles (Dask workers) hold no controller: each makes its own on first use."""
        return {"_blas": None}

    def limit(self) -> AbstractContextManager[Any]:
        """A context in which every BLAS library runs one thread (a no-op if they already do)."""
        if self._blas is None:
            self._blas = ThreadpoolController().select(user_api="blas")
        if all(lib.num_threads == 1 for lib in self._blas.lib_controllers):
            return nullcontext()
        return self._blas.limit(limits=1)
