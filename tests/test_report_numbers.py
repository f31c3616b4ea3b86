"""Every report rendered from a short run says only what the run's records hold.

One module-scoped short run per suite (paper E1 and E4, faults W1, mrp M1, flexible F1, in this
process: about three minutes on two loaded cores). For each ``results.md``: no verdict word (a
smoke run gives "no measurement"); every time its prose states (a number with the unit s) is a
time of the records (run lengths, starts, windows, recovery and settling times; the run line's
wall time), a window the claims cut from a run length, or a threshold the claims module prints;
every other number is a value of the records (or a percentage of one), a claims threshold, or
computed from the numbers printed in the same line (:mod:`tests.report_numbers`). The figures'
titles are whole: the title drawn is the title asked for, wrapped at spaces, inside the figure.
"""

from __future__ import annotations

import inspect
import json
from pathlib import Path

import numpy as np
import pytest
from figure_checks import capture, title_inside
from matplotlib.backends.backend_agg import FigureCanvasAgg
from report_numbers import numbers, prose, record_values, seconds, unexplained

from benchmarks.families.flexible.metrics import flexible_metrics
from benchmarks.families.rigid.defaults import SHORT_DURATION_SCALE
from benchmarks.reports import fault_figures, figures, flexible_figures, mrp_figures
from benchmarks.reports.measurement import NO_MEASUREMENT
from benchmarks.suites import (
    faults,
    faults_claims,
    flexible,
    flexible_claims,
    mrp,
    mrp_claims,
    paper,
    paper_claims,
)
from models import FlexibleSatellite

SUITES = ("paper", "faults", "mrp", "flexible")

#: The figure builders of the suites and where their title is among the arguments.
_BUILDERS = (
    (figures, "responses_figure", 1),
    (fault_figures, "fault_case_group_figure", 2),
    (mrp_figures, "mrp_group_figure", 1),
    (flexible_figures, "flexible_group_figure", 1),
)


_CLAIMS = {"paper": paper_claims, "faults": faults_claims, "mrp": mrp_claims, "flexible": flexible_claims}


def _constants(suite: str) -> list[float]:
    """The thresholds the suite's claims module prints with its verdicts (module constants)."""
    out: list[float] = []
    for mod in (_CLAIMS[suite],):
        for name in dir(mod):
            value = getattr(mod, name)
            if not name.isupper() or isinstance(value, bool):
                continue
            if isinstance(value, int | float):
                out.append(float(value))
            elif isinstance(value, tuple):
                out += [float(v) for v in value if isinstance(v, int | float) and not isinstance(v, bool)]
    return out


#: Numbers the reports take from the code rather than from the records, each with its source:
#: the bound of faults' R1 ("about 10 s": ABOUT_FACTOR x R1_SECONDS, as the claims module
#: computes it), the truth plant's integration step of the mrp suite (a constant of the suite),
#: the 4 of the error angle 4 atan|se|, the final window of the flexible metrics, and the
#: flexible model's first modal and free-free frequencies (properties of the published model).
def _code_values() -> dict[str, list[float]]:
    ev = np.linalg.eigvals(FlexibleSatellite.di_gennaro().linearize()[0])
    tail = float(inspect.signature(flexible_metrics).parameters["tail"].default)
    return {
        "paper": [],
        "faults": [faults_claims.ABOUT_FACTOR * faults_claims.R1_SECONDS],
        "mrp": [mrp.PLANT_STEP, mrp.CONTROL_PERIOD, 4.0],
        "flexible": [tail, float(np.min(ev.imag[ev.imag > 1e-9])),
                     float(FlexibleSatellite.di_gennaro().frequencies[0])],
    }


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, list[tuple[str, object]]]]:
    """Each suite's short run (a subset of its experiments, in this process), with the titles
    asked of its figure builders and the figures built."""
    base = tmp_path_factory.mktemp("reports")
    mp = pytest.MonkeyPatch()
    built = {mod.__name__ + name: (capture(mp, mod, name), where) for mod, name, where in _BUILDERS}
    out: dict[str, tuple[Path, list[tuple[str, object]]]] = {}
    try:
        jobs = {
            "paper": lambda d: paper.run_paper(
                d, workers=0, duration_scale=SHORT_DURATION_SCALE, experiments=["E1", "E4"], progress=False
            ),
            "faults": lambda d: faults.run_faults(
                d, workers=0, time_scale=faults.SHORT_TIME_SCALE, experiments=["W1"], progress=False
            ),
            "mrp": lambda d: mrp.run_mrp(
                d, workers=0, time_scale=mrp.SHORT_TIME_SCALE, experiments=["M1"], progress=False
            ),
            "flexible": lambda d: flexible.run_flexible(
                d, workers=0, time_scale=flexible.SHORT_TIME_SCALE, experiments=["F1"], progress=False
            ),
        }
        for name, job in jobs.items():
            for calls, _ in built.values():
                calls.clear()
            outcome = job(base / name)
            assert not outcome.failures, outcome.failures
            titles = [(args[where], fig) for calls, where in built.values() for args, fig in calls]
            out[name] = (base / name, titles)
    finally:
        mp.undo()
    return out


@pytest.mark.parametrize("suite", SUITES)
def test_a_short_run_gives_no_verdict(runs, suite):
    md = (runs[suite][0] / "results.md").read_text(encoding="utf-8")
    for word in ("reproduced", "not reproduced", "partly"):
        assert word not in md, f"{suite}: {word!r} in a smoke run's report"
    assert f": {NO_MEASUREMENT}.**" in md  # the claims say why instead


@pytest.mark.parametrize("suite", SUITES)
def test_every_time_in_the_prose_is_one_of_the_run(runs, suite):
    out = runs[suite][0]
    text = prose((out / "results.md").read_text(encoding="utf-8"))
    durations = record_values(out, times_only=True)
    # the claims' windows: fractions of a run (flexible: [0.2, 0.4] and [0.8, 1]; mrp: the second half)
    windows = np.concatenate([durations * f for f in (0.2, 0.4, 0.5, 0.8)])
    pool = np.concatenate([durations, windows, _constants(suite), _code_values()[suite]])
    assert seconds(text), "the prose states no time at all"
    assert unexplained(text, pool, times=True) == []


@pytest.mark.parametrize("suite", SUITES)
def test_every_number_in_the_prose_comes_from_the_run(runs, suite):
    out = runs[suite][0]
    text = prose((out / "results.md").read_text(encoding="utf-8"))
    pool = np.concatenate([record_values(out), _constants(suite), _code_values()[suite]])
    assert len(numbers(text)) > 10
    assert unexplained(text, pool, scales=(1.0, 100.0)) == []


@pytest.mark.parametrize("suite", SUITES)
def test_figure_titles_are_whole(runs, suite):
    titles = runs[suite][1]
    assert titles, "no figure was built"
    for title, fig in titles:
        drawn = fig.get_suptitle()  # type: ignore[attr-defined]
        # the whole title, wrapped at spaces only (no word cut, nothing left out)
        assert " ".join(drawn.split()).startswith(" ".join(str(title).split())), (title, drawn)
        if not isinstance(fig.canvas, FigureCanvasAgg):  # type: ignore[attr-defined]
            FigureCanvasAgg(fig)  # the renderer savefig uses
        assert title_inside(fig), drawn  # type: ignore[arg-type]


def test_paper_titles_and_texts_read_the_disturbance_start_from_the_records(runs):
    out, titles = runs["paper"]
    md = (out / "results.md").read_text(encoding="utf-8")
    e4 = next(t for t, _ in titles if str(t).startswith("E4: "))
    records = json.loads((out / "results.json").read_text(encoding="utf-8"))
    starts = {r["settings"]["disturbance_start"] for r in records if r["experiment"] == "E4"}
    assert len(starts) == 1
    (start,) = starts
    assert start < min(r["settings"]["duration"] for r in records)  # the short run's own step
    assert f"from t = {start:g} s" in str(e4) and f"from t = {start:g} s" in md
    assert "| duration per run (s) | 2.25 |" in md
