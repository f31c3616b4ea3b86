"""The C99 core of the on-line Kothare solve (:mod:`lmi.ccore.generate`).

``ipm.c``/``ipm.h`` (the interior-point method of :class:`lmi.ipm.BlockLMISolver` for the fixed
block structure of Kothare's on-line problem, its per-state data update and the certificate of
:func:`lmi.certify`) and ``dense.c``/``dense.h`` (the small dense kernels) ship as package data;
:func:`lmi.ccore.generate.write_solver` writes the problem header they are compiled with.
"""

from lmi.ccore.generate import (
    SOURCES,
    STATUS_CODES,
    check_controller,
    problem_header,
    solver_source,
    write_solver,
)

__all__ = ["SOURCES", "STATUS_CODES", "check_controller", "problem_header", "solver_source", "write_solver"]
