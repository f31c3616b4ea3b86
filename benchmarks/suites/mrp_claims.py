"""Paper M's qualitative outcomes, checked against the records of an ``rmpc bench mrp`` run.

Paper M reports its results as figures and words only (no number survives). :func:`assess_paper_m`
turns each outcome R1-R4 into a test on the run's metrics and says whether this toolkit
reproduces it, with the numbers, as :mod:`benchmarks.suites.paper_claims` does for paper P. The
thresholds that make words such as "very small", "clear" or "no chattering" measurable are module
constants, printed with the verdicts. The error is the error angle ``4 atan|se|`` on the steady
window (the run's second half); the estimate error and the chattering ratio are measured on the
late window (:func:`benchmarks.families.mrp.family.late_window_start`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from benchmarks.reports.sections import dash
from benchmarks.suites.paper_claims import Claim, claim_lines

__all__ = [
    "CHATTER_RATIO",
    "CLEAR_ERROR_DEG",
    "ESTIMATE_ERROR",
    "FIRST_SECONDS",
    "MINIMAL_ERROR_DEG",
    "SMALL_ERROR_DEG",
    "assess_paper_m",
    "paper_m_claims_markdown",
]

SMALL_ERROR_DEG = 1e-6
"""R1: a "very small" tracking error: the largest error angle on the steady window below this (deg)."""

FIRST_SECONDS = 5.0
"""R2: "largest in the first seconds": the largest applied torque occurs before this time (s)."""

CLEAR_ERROR_DEG = 0.2
"""R3: BS "keeps a clear error": its largest error angle on the steady window is at least this (deg)."""

MINIMAL_ERROR_DEG = 0.05
"""R3: MAB's error is "minimal": at most this (deg), and BS's at least 10 times MAB's."""

ESTIMATE_ERROR = 2e-3
"""R3: the NESO "estimates the torque well": ``max |Tdhat_i - Td_i|`` on the late window at most this (N m),
about 3 % of the disk's largest torque (0.07 N m)."""

CHATTER_RATIO = 1.5
"""R4: "no chattering": the torque's total variation per second on the late window at most this many
times the disk torque's (a torque that follows the disk smoothly scores about 1)."""


def _find(records: Sequence[dict], exp: str, ctrl: str, scale: float = 1.0) -> dict | None:
    for rec in records:
        if (rec.get("experiment"), rec.get("controller")) == (exp, ctrl) and rec["settings"].get(
            "inertia_scale_used", 1.0
        ) == scale:
            return rec
    return None


def _m(rec: dict | None, key: str) -> Any:
    return None if rec is None else rec["metrics"].get(key)


def _late(records: Sequence[dict]) -> str:
    for rec in records:
        window = rec["settings"].get("late_window")
        if window is not None:
            return f"t >= {window[0]:g} s"
    return "the late window"


def _not_run(key: str, claim: str, what: str = "the run has no records for this outcome") -> Claim:
    return Claim(key, claim, "not run", what)


def _r1(records: Sequence[dict]) -> Claim:
    claim = "Nominal: BS and MAB both track the constant target with very small error."
    errs = {c: _m(_find(records, "M1", c), "err_angle_ss_max_deg") for c in ("BS", "MAB")}
    if None in errs.values():
        return _not_run("R1", claim)
    ok = all(e < SMALL_ERROR_DEG for e in errs.values())
    evidence = (
        f"M1 largest error angle on the steady window: BS {errs['BS']:.3g} deg, MAB {errs['MAB']:.3g} deg "
        f"('very small' < {SMALL_ERROR_DEG:g} deg)"
    )
    return Claim("R1", claim, "reproduced" if ok else "not reproduced", evidence,
                 "" if ok else f"an error on the steady window is {SMALL_ERROR_DEG:g} deg or more")


def _r2(records: Sequence[dict]) -> Claim:
    claim = "Torques are realisable, and largest in the first seconds."
    recs = [r for r in records if r.get("experiment") == "M1"]
    if not recs:
        return _not_run("R2", claim)
    peaks = [(r["controller"], r["metrics"]["max_abs_u"], r["metrics"]["max_abs_u_time"]) for r in recs]
    early = all(t < FIRST_SECONDS for _, _, t in peaks)
    evidence = "M1 largest torque (at time): " + ", ".join(f"{c} {u:.2f} N m ({t:g} s)" for c, u, t in peaks)
    evidence += (
        f" ('first seconds' < {FIRST_SECONDS:g} s; paper M gives no torque limit, so 'realisable' is "
        "shown by the magnitudes, not tested)"
    )
    why = "" if early else "a controller's largest torque comes later in the run"
    return Claim("R2", claim, "reproduced" if early else "not reproduced", evidence, why)


def _r3(records: Sequence[dict]) -> Claim:
    claim = (
        "With the disk, BS keeps a clear error; MAB's error is minimal and the NESO estimates the "
        "torque well."
    )
    bs, mab = (_m(_find(records, "M2", c), "err_angle_ss_max_deg") for c in ("BS", "MAB"))
    est = _m(_find(records, "M2", "MAB"), "td_est_err_max")
    if bs is None or mab is None:
        return _not_run("R3", claim)
    clear, minimal = bs >= CLEAR_ERROR_DEG, mab <= MINIMAL_ERROR_DEG and bs >= 10.0 * mab
    well = est is not None and est <= ESTIMATE_ERROR
    evidence = (
        f"M2 largest error angle on the steady window: BS {bs:.3g} deg ('clear' >= {CLEAR_ERROR_DEG:g}), "
        f"MAB {mab:.3g} deg ('minimal' <= {MINIMAL_ERROR_DEG:g} and 10 x below BS; BS/MAB "
        f"{bs / mab if mab > 0 else float('inf'):.3g}); NESO estimate error {dash(est, '.2e')} N m on "
        f"{_late(records)} ('well' <= {ESTIMATE_ERROR:g})"
    )
    parts = {"BS's error is not clear": clear, "MAB's error is not minimal": minimal,
             "the NESO's estimate error is larger": well}
    why = "; ".join(k for k, v in parts.items() if not v)
    n_ok = sum(parts.values())
    verdict = "reproduced" if n_ok == 3 else ("partly reproduced" if n_ok else "not reproduced")
    return Claim("R3", claim, verdict, evidence, why)


def _r4(records: Sequence[dict]) -> Claim:
    claim = "MAB's error is below TF-AB's; no instability, no chattering."
    mab_rec, tf_rec = _find(records, "M2", "MAB"), _find(records, "M2", "TFAB")
    if mab_rec is None or tf_rec is None:
        return _not_run("R4", claim)
    mab, tf = mab_rec["metrics"]["err_angle_ss_max_deg"], tf_rec["metrics"]["err_angle_ss_max_deg"]
    below = mab < tf
    stable = mab_rec["metrics"]["err_angle_final_deg"] < mab_rec["metrics"]["err_angle_initial_deg"]
    ratio = mab_rec["metrics"].get("chatter_ratio")
    smooth = ratio is not None and ratio <= CHATTER_RATIO
    ratios = ", ".join(
        f"{r['controller']} {dash(r['metrics'].get('chatter_ratio'), '.3g')}"
        for r in records
        if r.get("experiment") == "M2"
    )
    evidence = (
        f"M2: MAB {mab:.3g} deg vs TF-AB {tf:.3g} deg; MAB's final error "
        f"{mab_rec['metrics']['err_angle_final_deg']:.3g} deg from "
        f"{mab_rec['metrics']['err_angle_initial_deg']:.3g} deg; torque variation per second on "
        f"{_late(records)} over the disk torque's ({ratios}; 'no chattering' <= {CHATTER_RATIO:g} for MAB); "
        "the ranking depends on the tuning: the sweep mrp_gains varies TF-AB's Gamma and MAB's w_o"
    )
    parts = {"MAB's error is not below TF-AB's": below, "MAB's error grew": stable,
             "MAB's torque varies faster than the 'no chattering' bound": smooth}
    why = "; ".join(k for k, v in parts.items() if not v)
    n_ok = sum(parts.values())
    verdict = "reproduced" if n_ok == 3 else ("partly reproduced" if n_ok else "not reproduced")
    return Claim("R4", claim, verdict, evidence, why)


_CHECKS: tuple[Callable[[Sequence[dict]], Claim], ...] = (_r1, _r2, _r3, _r4)


def assess_paper_m(records: Sequence[dict[str, Any]]) -> list[Claim]:
    """Each of paper M's outcomes R1-R4, with the verdict on ``records`` of an mrp run.

    Parameters
    ----------
    records : sequence of dict
        The records of ``rmpc bench mrp`` (``results.json``).

    Returns
    -------
    list of Claim
        One per outcome, in order; "not run" where the records are missing.

    Examples
    --------
    >>> [c.verdict for c in assess_paper_m([])]
    ['not run', 'not run', 'not run', 'not run']
    """
    return [check(records) for check in _CHECKS]


#: The Markdown lines of the verdicts (one bullet per outcome, then why where not reproduced).
paper_m_claims_markdown = claim_lines
