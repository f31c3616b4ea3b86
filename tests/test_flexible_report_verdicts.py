"""The flexible report's F4 sentences on reach, the ipm and Clarabel's 'delta_shared' form are
computed from what the run measures, never asserted (the verdict flips with the measurement)."""

from __future__ import annotations

from types import SimpleNamespace

import benchmarks.families.flexible.region as region
import benchmarks.suites.flexible_report as report
from benchmarks.families.flexible import defaults
from toolkit_common.status import USABLE_STATUSES


def _reach(angle, certified=True):
    return SimpleNamespace(gamma_s=100.0, status="optimal", angle_deg=angle, contraction=0.9998,
                           peak_input=1.0, certified=certified)


def _lines(monkeypatch, reach_angle, ipm, shared):
    monkeypatch.setattr(region, "slew_reach", lambda *a, **k: _reach(reach_angle))
    monkeypatch.setattr(report, "_ipm_along_slew", lambda *a: ipm)
    monkeypatch.setattr(report, "_delta_shared_trial", lambda *a: shared)
    return "\n".join(report._reach_lines())


def test_reach_sentences_follow_the_measurements(monkeypatch):
    ok = [(12.5, "optimal", "optimal", 42), (15.0, "optimal", "optimal", 44)]
    failing = [(12.5, "optimal", "optimal", 42), (15.0, "numerical_error", "stall", 9)]
    text = _lines(monkeypatch, 16.8, ok, (10.0, "numerical_error", "NumericalError", 18))
    assert "it solves at every angle tried, up to 15 deg" in text
    assert "numerical_error (NumericalError, 18 iterations): it fails there" in text
    assert "feasible past F4's 10 deg slew (certified up to 16.8 deg)" in text
    text = _lines(monkeypatch, 8.0, failing, (10.0, "optimal", "Solved", 20))
    assert "it stops at 15 deg" in text and "it solves at every angle" not in text
    assert "optimal (Solved, 20 iterations): it solves there too" in text
    assert "No certified reach passes F4's 10 deg slew" in text


def test_rationale_no_longer_asserts_where_the_ipm_stops():
    text = defaults.rationale()
    assert "numerical errors" not in text and "measured in every run" in text


def test_delta_shared_is_measured_by_the_report():
    """The one Clarabel solve the report makes (about 3 s): its verdict names its measured status."""
    import numpy as np

    from benchmarks.families.flexible.controllers import linear_weights
    from benchmarks.families.flexible.family import _polytope
    from models import FlexibleSatellite

    sat = FlexibleSatellite.di_gennaro()
    s = defaults.CONTROLLER_DEFAULTS["OfflineRMPC"]
    poly = _polytope(sat, defaults.LINEAR_PERIOD, s["polytope"])
    Q, R = linear_weights(s, sat.n_modes)
    direction = np.concatenate((np.ones(3) / np.sqrt(3), np.zeros(3 + 2 * sat.n_modes)))
    trial = report._delta_shared_trial(poly, Q, R, direction)
    assert trial[0] == defaults.EXPERIMENT_ANGLES["small"]
    sentence = report.delta_shared_sentence(trial, poly.n_vertices)
    usable = trial[1] in {str(x) for x in USABLE_STATUSES}
    assert sentence.endswith("it solves there too" if usable else "it fails there")
    assert f"measured now: {trial[1]} ({trial[2]}, {trial[3]} iterations)" in sentence
