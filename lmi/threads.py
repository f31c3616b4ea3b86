"""Run small dense linear algebra on one BLAS thread.

The LMI problems here are tiny; OpenBLAS nevertheless splits a 61 x 120 product over its
threads, and on a loaded 2-core machine the thread hand-off made one such product take 5 ms
instead of 17 us (measured). Solves therefore run inside ``threadpoolctl``'s limit of one BLAS
thread. The controller is created per solver object, on first use (after the solver's own
BLAS is loaded), so no process-wide setting is changed outside a solve.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from typing import Any

from threadpoolctl import ThreadpoolController

__all__ = ["SingleThreadBlas"]


class SingleThreadBlas:
    """``with blas.limit(): ...`` runs the block with one BLAS thread."""

    def __init__(self) -> None:
        self._controller: Any = None

    def limit(self) -> AbstractContextManager[Any]:
        if self._controller is None:
            self._controller = ThreadpoolController()
        return self._controller.limit(limits=1, user_api="blas")
