"""Judging a reference solver by what it certifies, not by its status.

A reference such as Clarabel at tolerances of 1e-10 reaches them on one CPU and stops at its
reduced tolerances ("AlmostSolved" -> ``"inaccurate"``) on another: its status at a tolerance it
cannot promise depends on the machine's rounding. What does not: the toolkit's own certificate of
the reference's point (the LMIs recomputed there), and the bracket its primal and dual objectives
put around the optimum, whatever accuracy the solver reached on the machine at hand.
"""

from __future__ import annotations

from lmi import LMISolution

#: Relative slack on each side of the bracket: the certificates' own tolerance (a point passing
#: the certificate may sit this far outside the feasible set, so its gamma this far below it).
CERT_REL = 1e-7


def reference_bracket(want: LMISolution) -> tuple[float, float]:
    """``(lower, upper)`` around the optimal gamma from a certified reference answer.

    ``upper``: the reference's gamma at a point the toolkit's certificate accepts; ``lower``: its
    dual objective (the solver's own bound from below). Asserts that the reference gave both.
    """
    assert want.status in ("optimal", "inaccurate"), (want.status, want.solver_status)
    assert want.certificate is not None and want.certificate.ok, want.margins
    assert want.gamma_dual is not None, "the reference reports no dual bound"
    return min(want.gamma, want.gamma_dual), max(want.gamma, want.gamma_dual)


def assert_gamma_in_reference_bracket(got: LMISolution, want: LMISolution, rel: float = CERT_REL) -> None:
    """``got.gamma`` lies in the reference's bracket, widened by ``rel`` relative on each side.

    ``got`` must be certified too: then ``got.gamma <= upper`` says it is no worse than a point
    the reference found feasible, and ``got.gamma >= lower`` that it does not claim less than
    the reference proves possible. Where the reference reached 1e-10 the bracket is that narrow.
    """
    assert got.certificate is not None and got.certificate.ok, got.margins
    lower, upper = reference_bracket(want)
    assert lower * (1.0 - rel) <= got.gamma <= upper * (1.0 + rel), (
        got.gamma, lower, upper, want.status, want.solver_status,
    )
