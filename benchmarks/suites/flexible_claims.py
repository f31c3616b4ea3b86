"""Paper V's and paper S's statements on vibration, rates and the regime, checked on a flexible run.

Three statements the flexible report used to print as words only, each turned into a test on the
run's records (as :mod:`benchmarks.suites.paper_claims` does for paper P), with the thresholds as
module constants printed with the verdicts:

- **V6** (paper V, likely): MTSMC's excitation is minimal after about 30 s and the vibration decays
  after the slew. "Excitation" is measured as the work of the hub's motion on the modes
  (``modal_work_after`` against ``modal_work_peak``), the decay by the RMS of ``eta_1`` over the
  early and the late window, and the ringing that remains is explained by comparing its decay rate
  with the uncontrolled first mode's.
- **V7** (paper V, certain as claimed): flexibility shows in the rates, hardly in the attitude: on the
  late window, the share of the body rate above ``Lambda_1 / 2`` against the share of the attitude
  error there (early in the slew that part is also the loop's own fast transient, the same with
  AVC; the report prints the AVC run's late rate part to show that what is measured late is modal).
- **S1** (paper S): the regime label (closed-loop bandwidth against ``Lambda_1``) discriminates: the
  run has cases with different labels, and the case with the higher bandwidth does more work on the
  modes (``modal_work_peak``).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence
from typing import Any

from benchmarks.families.flexible.metrics import flexible_metrics
from benchmarks.reports.measurement import records_reason, run_durations, withhold
from benchmarks.suites.paper_claims import Claim, claim_lines

__all__ = [
    "EXCITATION_FRACTION",
    "FREE_DECAY_BAND",
    "REGIME_EXPERIMENT",
    "SHOWS_FACTOR",
    "assess_flexible",
    "flexible_claims_markdown",
    "smoke_reason",
    "tail_words",
]

EXCITATION_FRACTION = 0.1
"""V6: the excitation after the early window's start is "minimal" when the hub's net work on the modes
from then on is at most this fraction of the largest work it did on them."""

FREE_DECAY_BAND = (0.5, 2.0)
"""V6: the late ringing is the free vibration of mode 1 when its measured decay rate lies within these
factors of the uncontrolled first mode's."""

SHOWS_FACTOR = 10.0
"""V7: flexibility "shows in the rates, hardly in the attitude" when, on the late window, the share of the
body rate above ``Lambda_1 / 2`` is at least this many times the attitude error's."""

REGIME_EXPERIMENT = "F6"
"""The experiment whose high-gain MTSMC is compared with F1's MTSMC for the regime label."""


def _span(values: Sequence[float]) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:g} s" if lo == hi else f"{lo:g}-{hi:g} s"


def tail_words(records: Sequence[dict[str, Any]]) -> str:
    """The final window of the residual metrics in words: ``"the last 10 s"`` (the ``tail`` of
    :func:`~benchmarks.families.flexible.metrics.flexible_metrics`), and where every run of
    ``records`` is shorter, that it is the whole run, with the run lengths the records hold."""
    tail = float(inspect.signature(flexible_metrics).parameters["tail"].default)
    spans = run_durations(records)
    if spans and max(spans) <= tail:
        return f"the last {tail:g} s (here the whole run: runs of {_span(spans)})"
    return f"the last {tail:g} s"


def smoke_reason(records: Sequence[dict[str, Any]]) -> str | None:
    """Why a run measures none of the flexible suite's claims (a smoke run), from its records."""
    return records_reason(records, "the slews' end, the late windows or a steady state")


def _find(records: Sequence[dict], exp: str, name: str) -> dict | None:
    for rec in records:
        if rec.get("experiment") == exp and rec["settings"].get("controller_name") == name:
            return rec
    return None


def _m(rec: dict | None, key: str) -> Any:
    return None if rec is None else rec["metrics"].get(key)


def _not_run(key: str, claim: str) -> Claim:
    return Claim(key, claim, "not run", "the run has no records for this statement")


def _v6(records: Sequence[dict]) -> Claim:
    claim = "MTSMC's excitation is minimal after about 30 s and decays after the slew (paper V, likely)."
    mt, mta = _find(records, "F1", "MTSMC"), _find(records, "F1", "MTSMC+AVC")
    keys = ("modal_work_after", "modal_work_peak", "eta1_rms_early", "eta1_rms_late")
    if mt is None or any(_m(mt, k) is None for k in keys):
        return _not_run("V6", claim)
    after, peak = _m(mt, "modal_work_after"), _m(mt, "modal_work_peak")
    early, late = _m(mt, "eta1_rms_early"), _m(mt, "eta1_rms_late")
    rate, free = _m(mt, "eta1_decay_rate"), _m(mt, "mode1_open_loop_decay_rate")
    t_end = mt["settings"]["duration_used"]
    w0, w1 = 0.2 * t_end, 0.4 * t_end
    minimal = peak > 0 and after <= EXCITATION_FRACTION * peak
    decays = late < early
    share = after / peak if peak > 0 else float("nan")
    evidence = (
        f"hub's net work on the modes after {w0:g} s {after:.3g} J, {100 * share:.3g} % of its largest "
        f"{peak:.3g} J ('minimal' <= {100 * EXCITATION_FRACTION:g} %); RMS eta_1 over [{w0:g}, {w1:g}] s "
        f"{early:.3g}, over the last {0.2 * t_end:g} s {late:.3g} kg^1/2 m; peak |eta_1| over "
        f"{tail_words([mt])} {mt['metrics']['eta_residual'][0]:.3g}"
    )
    why_ring = ""
    if rate is not None and free:
        lo, hi = FREE_DECAY_BAND
        ratio = rate / free
        evidence += (
            f"; eta_1 decays at {rate:.3g} 1/s, the uncontrolled first mode at {free:.3g} 1/s "
            f"(time constant {1 / free:.0f} s; ratio {ratio:.3g}, 'free' within {lo:g}-{hi:g})"
        )
        if lo <= ratio <= hi:
            why_ring = (
                f"what still rings is mode 1's free vibration, put in before {w0:g} s, decaying at the "
                "structural damping rate: the attitude loop (bandwidth "
                f"{mt['metrics'].get('bandwidth') or float('nan'):.3g} rad/s) neither feeds nor damps it"
            )
        elif ratio > hi:
            why_ring = "the loop damps mode 1 faster than its structure does"
        else:
            why_ring = "mode 1 decays slower than its structure alone would let it: the loop still feeds it"
    if mta is not None:
        evidence += f"; with AVC peak |eta_1| {mta['metrics']['eta_peak'][0]:.3g}"
    verdict = "reproduced" if minimal and decays else "partly reproduced" if minimal or decays else (
        "not reproduced")
    if why_ring:
        evidence += f"; {why_ring}"
    why = []
    if not minimal:
        why.append(f"the hub still does {100 * share:.3g} % of its work on the modes after {w0:g} s")
    if not decays:
        why.append("eta_1 is not smaller at the end than after the slew's start")
    return Claim("V6", claim, verdict, evidence, "; ".join(why))


def _v7(records: Sequence[dict]) -> Claim:
    claim = "Flexibility shows in the rates, hardly in the attitude (paper V, certain as claimed)."
    keys = ("rate_hf_share_late", "attitude_hf_share_late")
    runs = [r for r in (_find(records, "F1", n) for n in ("MTSMC", "CSMC")) if r is not None]
    runs = [r for r in runs if all(_m(r, k) is not None for k in keys)]
    if not runs:
        return _not_run("V7", claim)
    parts, ok = [], True
    for r in runs:
        rate, att = _m(r, "rate_hf_share_late"), _m(r, "attitude_hf_share_late")
        factor = rate / att if att > 0 else float("inf")
        ok = ok and factor >= SHOWS_FACTOR
        parts.append(
            f"{r['settings']['controller_name']}: part above Lambda_1/2 of the body rate {100 * rate:.3g} % "
            f"(RMS {_m(r, 'rate_hf_rms_late'):.3g} rad/s), of the attitude error {100 * att:.3g} % "
            f"(RMS {_m(r, 'attitude_hf_rms_late_deg'):.3g} deg): {factor:.3g} x"
        )
    mt, mta = _find(records, "F1", "MTSMC"), _find(records, "F1", "MTSMC+AVC")
    if mt is not None and mta is not None and _m(mta, "rate_hf_rms_late") is not None:
        parts.append(
            f"with AVC damping the modes, MTSMC's late rate part is {_m(mta, 'rate_hf_rms_late'):.3g} "
            f"rad/s against {_m(mt, 'rate_hf_rms_late'):.3g}"
        )
    t_end = runs[0]["settings"]["duration_used"]
    evidence = (
        f"on the last {0.2 * t_end:g} s, " + "; ".join(parts)
        + f" ('shows in the rates' >= {SHOWS_FACTOR:g} x the attitude's share)"
    )
    return Claim("V7", claim, "reproduced" if ok else "not reproduced", evidence,
                 "" if ok else "a run's attitude carries as large a share above Lambda_1/2 as its rates")


def _s1(records: Sequence[dict]) -> Claim:
    claim = (
        "Paper S's regime label (bandwidth below Lambda_1/3 rigid-like, Lambda_1/3-1/2 flexible, above "
        "flexible-hard) tells the loops that excite the modes from those that do not."
    )
    base, fast = _find(records, "F1", "MTSMC"), _find(records, REGIME_EXPERIMENT, "MTSMC")
    if base is None or fast is None or _m(base, "regime") is None or _m(fast, "regime") is None:
        return _not_run("S1", claim)
    labels = {r["metrics"]["regime"] for r in records if r["metrics"].get("regime")}
    if _m(base, "modal_work_peak") is None or _m(fast, "modal_work_peak") is None:
        return _not_run("S1", claim)
    wb, wf = _m(base, "modal_work_peak"), _m(fast, "modal_work_peak")
    flips = _m(base, "regime") != _m(fast, "regime")
    ordered = (wf > wb) == (_m(fast, "bandwidth") > _m(base, "bandwidth"))

    def case(rec: dict) -> str:
        m = rec["metrics"]
        return (
            f"bandwidth {m['bandwidth']:.3g} rad/s, {m['regime']}, largest work on the modes "
            f"{m['modal_work_peak']:.3g} J, peak |eta_1| {m['eta_peak'][0]:.3g}, largest modal over largest "
            f"rigid kinetic energy {m['modal_energy_ratio']:.3g}"
        )

    evidence = (
        f"F1 MTSMC: {case(base)}; {REGIME_EXPERIMENT} MTSMC (alpha_f "
        f"{fast['settings']['settings']['alpha_f']:g}): {case(fast)}; labels in the run: "
        f"{', '.join(sorted(labels))}"
    )
    if flips and ordered:
        return Claim("S1", claim, "reproduced", evidence)
    why = "both cases get the same label" if not flips else (
        "the case with the higher bandwidth does less work on the modes")
    return Claim("S1", claim, "partly reproduced" if flips or ordered else "not reproduced", evidence, why)


_CHECKS: tuple[Callable[[Sequence[dict]], Claim], ...] = (_v6, _v7, _s1)


def assess_flexible(records: Sequence[dict[str, Any]]) -> list[Claim]:
    """The verdicts V6, V7 and S1 on ``records`` of a flexible run.

    Examples
    --------
    >>> [c.verdict for c in assess_flexible([])]
    ['not run', 'not run', 'not run']
    """
    return [check(records) for check in _CHECKS]


def flexible_claims_markdown(records: Sequence[dict[str, Any]]) -> list[str]:
    """The report's section of these verdicts (one bullet each, then why where not reproduced)."""
    slew = [r for r in records if r.get("experiment") == "F1"]
    ends = run_durations(slew)
    where = ""
    if ends:
        t = max(ends)
        where = f", [{0.2 * t:g}, {0.4 * t:g}] s and [{0.8 * t:g}, {t:g}] s of this run's V-slew"
    lines = [
        "## Vibration, rates and the regime: measured verdicts",
        "",
        "Each statement tested on this run's records (`benchmarks/suites/flexible_claims.py` holds "
        f"the thresholds; windows are fractions of the run: [0.2, 0.4] and [0.8, 1] of it{where}).",
        "",
    ]
    lines += claim_lines(withhold(assess_flexible(records), smoke_reason(records)))
    lines.append("")
    return lines
