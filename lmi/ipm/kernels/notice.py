"""The lines printed while the kernels compile on first use (:func:`compile_notice`).

The first solver built after an install compiles the kernels (30-50 s at a light load; over
two minutes at a load average of 11-15 on two cores) and numba prints nothing meanwhile;
later processes load them from numba's on-disk cache in well under a second. Whether the cache
is cold is read, before anything compiles, from the cache index of each kernel that the first
solve calls (:data:`FIRST_SOLVE_KERNELS`): numba keeps one index per kernel, next to its file or
under ``NUMBA_CACHE_DIR``, and counts it empty when it is missing, was written by another numba
or predates the kernel's source.

Where the lines go: with no logging set up by the application (a script, the ``rmpc`` command),
to stderr, as :mod:`logging` does with a warning when nothing is configured; once the application
has configured logging (a handler on the root logger or on ``lmi``), as ``INFO`` records of the
logger ``lmi.ipm.kernels.notice``, which that configuration shows or filters. The environment
variable ``RMPC_QUIET`` (any value but ``""`` and ``"0"``) silences them in both cases.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["FIRST_SOLVE_KERNELS", "QUIET_VARIABLE", "cold_kernels", "compile_notice"]

#: The kernels :class:`lmi.ipm.BlockLMISolver`'s first solve calls (those it compiles, with what
#: they call); the paths of larger problems (``grouped_iteration``, the direct Schur complement)
#: compile on their first use and are not announced.
FIRST_SOLVE_KERNELS: tuple[str, ...] = (
    "pack", "unpack", "cholesky_blocks", "residuals", "blocks_within", "rows_iteration",
)

#: The environment variable that silences the notice.
QUIET_VARIABLE = "RMPC_QUIET"

_LOG = logging.getLogger(__name__)

_START = "rmpc: compiling the LMI solver's kernels on first use (about a minute, cached for later runs)..."


def cold_kernels(names: tuple[str, ...] = FIRST_SOLVE_KERNELS) -> list[str]:
    """The kernels among ``names`` whose on-disk cache holds nothing for their current source.

    Parameters
    ----------
    names : tuple of str
        Names of compiled kernels exported by :mod:`lmi.ipm.kernels` (imports them, and numba).

    Returns
    -------
    list of str
        Those whose cache index is missing, stale or unreadable: their first call compiles.
    """
    from lmi.ipm.kernels import iteration, packed, schur, step  # the modules, not the package

    defined = {**vars(step), **vars(schur), **vars(iteration), **vars(packed)}
    cold = []
    for name in names:
        try:
            index = defined[name]._cache._cache_file._load_index()
        except Exception:  # an unreadable index is rewritten by the compile that follows
            index = {}
        if not index:
            cold.append(name)
    return cold


def _say(text: str) -> None:
    if os.environ.get(QUIET_VARIABLE, "") not in ("", "0"):
        return
    if _LOG.hasHandlers():
        _LOG.info(text)
    else:
        print(text, file=sys.stderr, flush=True)


@contextmanager
def compile_notice() -> Iterator[None]:
    """Around the first solve of a process: one line before it if the kernels' cache is cold,
    one after with the time it took.

    Examples
    --------
    >>> import numpy as np
    >>> from lmi import BlockLMISolver
    >>> with compile_notice():    # silent when the kernels are cached
    ...     res = BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])]).solve()
    >>> str(res.status)
    'optimal'
    """
    cold = cold_kernels()
    if cold:
        _say(_START)
    start = time.perf_counter()
    yield
    if cold:
        _say(f"rmpc: the LMI solver's kernels compiled in {time.perf_counter() - start:.0f} s")
