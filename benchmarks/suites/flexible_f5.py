"""Experiment F5 of the flexible suite: paper S's baselines head to head on F1's V-slew.

Paper S (Fathi and Bolandi's survey of flexible satellites, in Persian) surveys the industrial
baselines for flexible spacecraft; F5
runs six of them on F1's 160 deg V-slew (the same plant, disturbance, 2 N m clip, 0.01 s period
and length) and measures them with F1's metrics: PD and PD with the disturbance observer
(:class:`rmpc.AttitudePD`), adaptive SMC (:class:`rmpc.AdaptiveSMC`), nonlinear PD
(:class:`rmpc.NonlinearPD`), adaptive-gain PD (:class:`rmpc.AdaptivePD`) and PD behind a ZVD
shaper on the first mode (:class:`rmpc.ShapedPD`). The robust MPC and paper V's laws are not run
again: the report shows F1's MTSMC and CSMC and F4's MTSMC-to-OfflineRMPC hand-over on the same
slew as reference rows when the run has them.

Every sentence of the F5 section is computed from the run's records (:func:`f5_verdicts`,
:func:`f5_lines`): which baseline settles fastest (F1's ``t_s``, the last time the error exceeds
1 deg), which excites the first mode least over the slew (peak ``|eta_1|``) and which leaves the
least modal energy over the last 10 s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from benchmarks.reports.sections import rows_table
from benchmarks.suites.flexible_claims import tail_words

__all__ = ["F5_BASELINES", "F5_REFERENCES", "f5_lines", "f5_verdicts"]

#: F5's cases: (tag, scenario fields) on F1's V-slew, in report order.
F5_BASELINES: tuple[tuple[str, dict[str, Any]], ...] = (
    ("PD", {"controller": "PD"}),
    ("PD-DOB", {"controller": "PD", "settings": {"disturbance_observer": True}}),
    ("ASMC", {"controller": "ASMC"}),
    ("NPD", {"controller": "NPD"}),
    ("APD", {"controller": "APD"}),
    ("ZVD-PD", {"controller": "ZVD-PD"}),
)

#: The reference rows on the same slew, from other experiments of the run: (experiment, closed loop).
F5_REFERENCES: tuple[tuple[str, str], ...] = (("F1", "MTSMC"), ("F1", "CSMC"), ("F4", "MTSMC>OfflineRMPC"))


def _names(best: Sequence[tuple[float, str]]) -> str:
    return " and ".join(name for _, name in best)


def _lowest(pairs: Sequence[tuple[float, str]]) -> list[tuple[float, str]]:
    """The pairs with the lowest value (ties kept, in the given order)."""
    low = min(v for v, _ in pairs)
    return [(v, n) for v, n in pairs if v == low]


def f5_verdicts(records: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """What F5's sentences say, computed from the F5 records.

    Returns
    -------
    dict
        ``settled``: ``(t_s, name)`` of the baselines that settled, fastest first;
        ``unsettled``: the names of the others; ``fastest``: the names with the lowest ``t_s``
        (empty if none settled); ``least_peak`` / ``least_residual``: the names with the lowest
        peak ``|eta_1|`` / residual modal energy, with ``peak`` / ``residual`` their
        ``(value, name)`` pairs in record order.

    Examples
    --------
    >>> def rec(name, t_s, peak, energy):
    ...     m = {"t_s": t_s, "eta_peak": [peak], "modal_energy_residual": energy}
    ...     return {"experiment": "F5", "settings": {"controller_name": name}, "metrics": m}
    >>> recs = [rec("PD", None, 0.1, 2e-5), rec("NPD", 98.0, 0.12, 1e-5), rec("APD", 90.0, 0.1, 3e-5)]
    >>> v = f5_verdicts(recs)
    >>> v["fastest"], v["unsettled"], v["least_peak"], v["least_residual"]
    (['APD'], ['PD'], ['PD', 'APD'], ['NPD'])
    """
    recs = [r for r in records if r["experiment"] == "F5"]
    names = [r["settings"]["controller_name"] for r in recs]
    pairs = list(zip(recs, names, strict=True))
    settled = sorted((float(r["metrics"]["t_s"]), n) for r, n in pairs if r["metrics"]["t_s"] is not None)
    peak = [(float(r["metrics"]["eta_peak"][0]), n) for r, n in pairs]
    residual = [(float(r["metrics"]["modal_energy_residual"]), n) for r, n in pairs]
    return {
        "settled": settled,
        "unsettled": [n for r, n in pairs if r["metrics"]["t_s"] is None],
        "fastest": [n for _, n in _lowest(settled)] if settled else [],
        "peak": peak,
        "residual": residual,
        "least_peak": [n for _, n in _lowest(peak)] if peak else [],
        "least_residual": [n for _, n in _lowest(residual)] if residual else [],
    }


def f5_lines(records: Sequence[dict[str, Any]], row: Callable[[dict[str, Any]], dict[str, str]]) -> list[str]:
    """F5's reference rows (a table, ``row`` renders one record) and its computed sentences."""
    recs = [r for r in records if r["experiment"] == "F5"]
    if not recs:
        return []
    lines: list[str] = []
    refs = [
        r
        for exp, name in F5_REFERENCES
        for r in records
        if r["experiment"] == exp and r["settings"]["controller_name"] == name
    ]
    if refs:
        lines += [
            "Reference rows on the same slew from this run (" + ", ".join(
                f"{r['experiment']} {r['settings']['controller_name']}" for r in refs
            ) + "):",
            "",
            rows_table([row(r) for r in refs]),
            "",
        ]
    v = f5_verdicts(records)
    if v["settled"]:
        order = "; ".join(f"{n} {t:.4g} s" for t, n in v["settled"])
        first = v["settled"][0][0]
        settle = f"- Settles fastest (t_s, 1 deg): {' and '.join(v['fastest'])} at {first:.4g} s "
        settle += f"(in order: {order})"
        settle += "; not settled within the run: " + (", ".join(v["unsettled"]) or "none") + "."
    else:
        settle = "- None of paper S's baselines settles within the run (the error exceeds 1 deg at the end)."
    peak_best = _lowest(v["peak"])
    peak_worst = max(v["peak"])
    res_best = _lowest(v["residual"])
    res_worst = max(v["residual"])
    lines += [
        f"Computed from F5's {len(recs)} records:",
        "",
        settle,
        f"- Excites the first mode least over the slew (peak |eta_1|): {_names(peak_best)} at "
        f"{peak_best[0][0]:.3g} (largest: {peak_worst[1]} at {peak_worst[0]:.3g}).",
        f"- Leaves the least modal energy over {tail_words(recs)}: {_names(res_best)} at "
        f"{res_best[0][0]:.3g} "
        f"(largest: {res_worst[1]} at {res_worst[0]:.3g}).",
        "",
    ]
    return lines
