"""Paper P's comparative claims, checked against the records of a paper run.

Paper P states its comparisons in words; :func:`assess_claims` turns each into a test on the
metrics of ``rmpc bench paper`` and says whether this toolkit reproduces it, with the numbers.
The thresholds that make words such as "far past" or "close" measurable are module constants,
printed with the verdicts, so a reader can disagree with them in the open.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from benchmarks.core.metrics import AXES

__all__ = [
    "CLOSE_RELATIVE",
    "FAR_PAST_FACTOR",
    "LIMIT_TOL",
    "REJECTED_ERROR",
    "STABLE_ERROR",
    "Claim",
    "assess_claims",
    "claim_lines",
    "claims_markdown",
]

FAR_PAST_FACTOR = 2.0
"""E1: a torque is "far past" the limit when the largest command exceeds this many times ``u_max``."""

CLOSE_RELATIVE = 0.25
"""E2 (limiter) and E3: two ``sum|e|`` are "close" when they differ by at most this fraction of the larger."""

REJECTED_ERROR = 1e-3
"""E4, E5: the disturbance is rejected when the final error on every axis is below this (rad)."""

STABLE_ERROR = 0.02
"""E6: "stays stable" when the final error on every axis is below this (rad), the settling band."""

LIMIT_TOL = 1e-6
"""Inside the limit: at most ``u_max (1 + LIMIT_TOL)``; saturated: at least ``u_max (1 - LIMIT_TOL)``."""


@dataclass(frozen=True)
class Claim:
    """One of paper P's claims and what the run measured.

    Attributes
    ----------
    experiment : str
        "E1" .. "E6".
    claim : str
        Paper P's claim in words.
    verdict : str
        "reproduced", "reproduced with GIPC behind the limiter" (E5), "partly reproduced",
        "not reproduced" or "not run" (the run lacks the records the claim needs).
    evidence : str
        The measured numbers the verdict rests on.
    why : str
        Where the claim is not reproduced: why, from the measurements; otherwise empty.
    """

    experiment: str
    claim: str
    verdict: str
    evidence: str
    why: str = ""


def _find(records: Sequence[dict], exp: str, ctrl: str, plant: str, sat: str) -> dict | None:
    for rec in records:
        if (rec.get("experiment"), rec.get("controller"), rec.get("plant"), rec.get("saturation")) == (
            exp, ctrl, plant, sat,
        ):
            return rec
    return None


def _sum_e(rec: dict) -> dict[str, float]:
    return {a: float(rec["metrics"]["sum_abs_err"][a]) for a in AXES}


def _final(rec: dict) -> float:
    return max(float(v) for v in rec["metrics"]["final_abs_err"].values())


def _recovered(rec: dict) -> str:
    """ ", recovered after X s (peak Y rad)" from the record's recovery metric, if it has one."""
    rv = rec["metrics"].get("recovery")
    if not rv or rv.get("peak_error") is None:
        return ""
    t_rec = rv["recovery_time"]
    when = "not within the run" if t_rec is None else f"{t_rec:.2f} s after the onset"
    return f" (within {rv['band']:g} rad {when}, peak {rv['peak_error']:.3g} rad)"


def _axes_text(values: dict[str, float]) -> str:
    return "/".join(f"{values[a]:.1f}" for a in AXES)


def _u_max(rec: dict) -> float:
    return float(rec["settings"].get("u_max", 1.0))


def _rel_gap(a: float, b: float) -> float:
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def _not_run(exp: str, claim: str) -> Claim:
    return Claim(exp, claim, "not run", "the run has no records for this experiment")


def _e1(records: Sequence[dict]) -> Claim:
    claim = "Both controllers ask for torques far past 1 N m at the start."
    rmpc, gipc = (_find(records, "E1", c, "linear", "none") for c in ("RMPC", "GIPC"))
    if rmpc is None or gipc is None:
        return _not_run("E1", claim)
    peaks = {name: float(r["metrics"]["max_abs_u_cmd"]) for name, r in (("RMPC", rmpc), ("GIPC", gipc))}
    ok = all(p > FAR_PAST_FACTOR * _u_max(rmpc) for p in peaks.values())
    evidence = (
        f"largest commanded torque RMPC {peaks['RMPC']:.2f} N m, GIPC {peaks['GIPC']:.2f} N m "
        f"(threshold {FAR_PAST_FACTOR:g} x u_max)"
    )
    return Claim("E1", claim, "reproduced" if ok else "not reproduced", evidence,
                 "" if ok else "the unconstrained gains of this run's weights are gentler than paper P's")


def _e2(records: Sequence[dict]) -> Claim:
    claim = (
        "With the limiter RMPC and GIPC are close; with the constraint inside the controller, "
        "RMPC's sum|e| is below GIPC's on every axis."
    )
    lim = [_find(records, "E2", c, "linear", "limiter") for c in ("RMPC", "GIPC")]
    con = [_find(records, "E2", c, "linear", "constraint") for c in ("RMPC", "GIPC")]
    if None in lim or None in con:
        return _not_run("E2", claim)
    lim_e = [_sum_e(r) for r in lim]  # type: ignore[arg-type]
    con_e = [_sum_e(r) for r in con]  # type: ignore[arg-type]
    gaps = {a: _rel_gap(lim_e[0][a], lim_e[1][a]) for a in AXES}
    close = all(g <= CLOSE_RELATIVE for g in gaps.values())
    below = all(con_e[0][a] < con_e[1][a] for a in AXES)
    evidence = (
        f"limiter: RMPC {_axes_text(lim_e[0])}, GIPC {_axes_text(lim_e[1])} "
        f"(largest gap {max(gaps.values()):.0%}, 'close' <= {CLOSE_RELATIVE:.0%}); "
        f"constraint: RMPC {_axes_text(con_e[0])}, GIPC {_axes_text(con_e[1])} (roll/pitch/yaw)"
    )
    if close and below:
        return Claim("E2", claim, "reproduced", evidence)
    why = []
    if not close:
        why.append("with the limiter the two differ by more than the 'close' threshold on some axis")
    if not below:
        why.append("with the constraint RMPC's sum|e| is not below GIPC's on every axis")
    verdict = "partly reproduced" if (close or below) else "not reproduced"
    return Claim("E2", claim, verdict, evidence, "; ".join(why))


def _e3(records: Sequence[dict]) -> Claim:
    claim = "The nonlinear responses stay close to the linear ones."
    pairs = []
    for ctrl in ("RMPC", "GIPC"):
        for sat in ("limiter", "constraint"):
            lin, non = _find(records, "E2", ctrl, "linear", sat), _find(records, "E3", ctrl, "nonlinear", sat)
            if lin is not None and non is not None:
                gap = max(_rel_gap(_sum_e(lin)[a], _sum_e(non)[a]) for a in AXES)
                pairs.append((f"{ctrl} {sat}", gap))
    if not pairs:
        return _not_run("E3", claim)
    ok = all(g <= CLOSE_RELATIVE for _, g in pairs)
    evidence = "largest sum|e| gap nonlinear vs linear: " + ", ".join(f"{n} {g:.0%}" for n, g in pairs)
    evidence += f" ('close' <= {CLOSE_RELATIVE:.0%})"
    return Claim("E3", claim, "reproduced" if ok else "not reproduced", evidence,
                 "" if ok else "the nonlinear kinematics move the response away from the linearisation")


def _e4(records: Sequence[dict]) -> Claim:
    claim = "RMPC alone does not remove the disturbance's effect; CRMPC does."
    rmpc, crmpc = (_find(records, "E4", c, "nonlinear", "constraint") for c in ("RMPC", "CRMPC"))
    if rmpc is None or crmpc is None:
        return _not_run("E4", claim)
    f_r, f_c = _final(rmpc), _final(crmpc)
    ok_r, ok_c = f_r > REJECTED_ERROR, f_c < REJECTED_ERROR
    evidence = (
        f"final error (worst axis) RMPC {f_r:.3g} rad, CRMPC {f_c:.3g} rad{_recovered(crmpc)} "
        f"(rejected < {REJECTED_ERROR:g})"
    )
    if ok_r and ok_c:
        return Claim("E4", claim, "reproduced", evidence)
    why = "RMPC rejects the step by itself" if not ok_r else "CRMPC has not settled by the end of the run"
    return Claim("E4", claim, "partly reproduced" if (ok_r or ok_c) else "not reproduced", evidence, why)


def _e5(records: Sequence[dict]) -> Claim:
    claim = (
        "At +-70 % GIPC's torques saturate, while CRMPC's stay inside the limit and it still rejects "
        "the disturbance."
    )
    gipc, crmpc = (_find(records, "E5", c, "nonlinear", "constraint") for c in ("GIPC", "CRMPC"))
    if gipc is None or crmpc is None:
        return _not_run("E5", claim)
    u_max = _u_max(crmpc)
    g_peak, c_peak = float(gipc["metrics"]["max_abs_u"]), float(crmpc["metrics"]["max_abs_u"])
    g_sat = g_peak >= u_max * (1 - LIMIT_TOL)
    c_inside = c_peak <= u_max * (1 + LIMIT_TOL) and not crmpc["settings"].get("limiter_in_loop", False)
    c_rejects = _final(crmpc) < REJECTED_ERROR
    evidence = (
        f"largest applied torque GIPC {g_peak:.3f} N m (time on the limit "
        f"{float(gipc['metrics']['saturated_fraction']):.1%}), CRMPC {c_peak:.3f} N m without a limiter "
        f"in the loop; CRMPC final error {_final(crmpc):.3g} rad{_recovered(crmpc)}"
    )
    crmpc_ok = c_inside and c_rejects
    limited = _find(records, "E5", "GIPC", "nonlinear", "limiter")
    l_sat = limited is not None and float(limited["metrics"]["saturated_fraction"]) > 0.0
    if limited is not None:
        evidence += (
            f"; GIPC behind the limiter (no constraint in its QP): on the limit "
            f"{float(limited['metrics']['saturated_fraction']):.1%} of the time, largest command "
            f"{float(limited['metrics']['max_abs_u_cmd']):.3g} N m, final error {_final(limited):.3g} rad"
        )
    if g_sat and crmpc_ok:
        return Claim("E5", claim, "reproduced", evidence)
    why = []
    if not g_sat:
        du = gipc["settings"].get("settings", {}).get("du_max")
        why.append(
            "GIPC with the limit as a constraint of its QP does not saturate: the steady torque the step "
            "needs is the disturbance's own magnitude whatever the inertia (a heavier satellite slows the "
            "transient, it does not raise that torque), and its increment bound"
            + (f" ({du:g} N m per sample)" if du is not None else "")
            + " keeps the transient gentle; "
            + (
                "paper P's saturation is GIPC's behaviour behind the limiter"
                if l_sat
                else "the limiter case was not run or did not saturate either"
            )
        )
    if not c_inside:
        why.append("CRMPC's torque leaves the limit or relies on a limiter")
    if not c_rejects:
        why.append("CRMPC has not rejected the disturbance by the end of the run")
    if crmpc_ok and l_sat:
        verdict = "reproduced with GIPC behind the limiter"
    elif crmpc_ok or g_sat or l_sat:
        verdict = "partly reproduced"
    else:
        verdict = "not reproduced"
    return Claim("E5", claim, verdict, evidence, "; ".join(why))


def _e6(records: Sequence[dict]) -> Claim:
    claim = (
        "From the 30 % larger initial attitude both controllers stay stable; RMPC's constraint still holds."
    )
    recs = [r for r in records if r.get("experiment") == "E6"]
    if not recs:
        return _not_run("E6", claim)
    finals = {f"{r['controller']} {r['plant']}": _final(r) for r in recs}
    stable = all(f < STABLE_ERROR for f in finals.values())
    rmpc = [r for r in recs if r["controller"] == "RMPC"]
    holds = all(
        float(r["metrics"]["max_abs_u"]) <= _u_max(r) * (1 + LIMIT_TOL)
        and float(r["metrics"]["constraint_violation"]) <= LIMIT_TOL
        for r in rmpc
    )
    evidence = "final error (worst axis): " + ", ".join(f"{k} {v:.2g} rad" for k, v in finals.items())
    evidence += "; RMPC largest torque " + ", ".join(
        f"{r['plant']} {float(r['metrics']['max_abs_u']):.3f} N m" for r in rmpc
    )
    ok = stable and holds and bool(rmpc)
    why = "" if ok else ("a controller has not settled" if not stable else "RMPC's torque left the limit")
    return Claim("E6", claim, "reproduced" if ok else "not reproduced", evidence, why)


_CHECKS: tuple[Callable[[Sequence[dict]], Claim], ...] = (_e1, _e2, _e3, _e4, _e5, _e6)


def assess_claims(records: Sequence[dict[str, Any]]) -> list[Claim]:
    """Each of paper P's comparative claims, with the verdict on ``records`` of a paper run.

    Parameters
    ----------
    records : sequence of dict
        The records of ``rmpc bench paper`` (``results.json``).

    Returns
    -------
    list of Claim
        One per experiment E1-E6, in order; "not run" where the records are missing.

    Examples
    --------
    >>> from benchmarks.suites.paper_claims import assess_claims
    >>> [c.verdict for c in assess_claims([])]
    ['not run', 'not run', 'not run', 'not run', 'not run', 'not run']
    """
    return [check(records) for check in _CHECKS]


def claims_markdown(claims: Sequence[Claim]) -> list[str]:
    """The Markdown lines of the claims section of ``results.md``."""
    lines = [
        "## Paper P's claims",
        "",
        "Each comparative claim of paper P, tested on this run's records "
        "(`benchmarks/suites/paper_claims.py` holds the thresholds). The sweep "
        "`rmpc bench sweep --config paper_claims` repeats E4/E5 over the true inertia and over the "
        "disturbance axes.",
        "",
    ]
    lines += claim_lines(claims)
    lines.append("")
    return lines


def claim_lines(claims: Sequence[Claim]) -> list[str]:
    """One Markdown bullet per claim (verdict, claim, what was measured), then why where it is not
    reproduced; the verdict sections of every suite's report use it."""
    lines = []
    for c in claims:
        lines.append(f"- **{c.experiment}: {c.verdict}.** {c.claim} Measured: {c.evidence}.")
        if c.why:
            lines.append(f"  Why: {c.why}.")
    return lines
