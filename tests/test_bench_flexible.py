"""The flexible family of the harness and ``rmpc bench flexible`` (issue 15, parts 3 and 4)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from figure_checks import assert_readable, capture, curves, hline_values, hlines, run_curves, visible_axes

import benchmarks.reports.flexible_figures as flexible_figures
import benchmarks.suites.flexible as flexible_suite
from benchmarks.cli import main
from benchmarks.core.runner import run_scenario
from benchmarks.core.scenario import Scenario
from benchmarks.families.flexible.family import eta1_frequency
from benchmarks.families.flexible.metrics import highpass
from benchmarks.suites.flexible import F4_MODAL_BOUND, MODAL_BOUND_POLYTOPE, flexible_cases, inconsistencies
from models.flexible.scenario import F2_EPSILONS, F3_INTEGRAL_GAINS
from toolkit_common.errors import ConfigError

CONTRACT_KEYS = (
    "final_abs_err", "sum_abs_err", "max_abs_u", "solve_time_p50", "t_s", "ci", "eta_peak", "v_peak", "regime"
)


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"experiment": "orbit"}, "experiment"),
        ({"controller": "MTSMC", "switch": "sign"}, "switch"),
        ({"controller": "CSMC", "integral_gain": 0.01}, "integral_gain"),
        ({"controller": "MTSMC", "saturation": "constraint"}, "saturation"),
        ({"u_max": 0.0}, "u_max"),
        ({"duration": 0.1, "dt": 0.5}, "duration"),
        ({"avc": "yes"}, "avc"),
        ({"angle_deg": 200.0}, "angle_deg"),
        ({"settings": {"polytope": "box"}}, "polytope"),
        ({"settings": {"shrink": 1.5}}, "shrink"),
        ({"scenario": "M2"}, "scenario"),  # an mrp-family field
        ({"controller": "RMPC", "handover_deg": 20.0}, "handover_deg"),
        ({"modal_bound": 0.0}, "modal_bound"),
        ({"modal_bound": -0.02}, "modal_bound"),
        ({"modal_bound": float("inf")}, "modal_bound"),
        ({"modal_bound": "0.02"}, "modal_bound"),
        ({"controller": "MTSMC", "modal_bound": 0.02}, "modal_bound"),
        ({"settings": {"formulation": "exact"}}, "formulation"),
    ],
)
def test_bad_flexible_fields_name_the_field(data, field):
    with pytest.raises(ConfigError, match=field):
        Scenario.from_dict({"family": "flexible", "controller": "OfflineRMPC", **data})


def test_linear_controllers_default_to_their_period_and_constraint():
    off = Scenario.from_dict({"family": "flexible", "controller": "OfflineRMPC"})
    smc = Scenario.from_dict({"family": "flexible", "controller": "MTSMC"})
    assert (off.dt, off.saturation, off.plant) == (0.5, "constraint", "flexible")
    assert (smc.dt, smc.saturation) == (0.01, "limiter")


def test_suite_cases_cover_the_four_experiments():
    cases = flexible_cases()
    by_exp = {e: [c.scenario for c in cases if c.experiment == e] for e in ("F1", "F2", "F3", "F4")}
    assert {(s.controller, s.avc) for s in by_exp["F1"]} == {
        (c, a) for c in ("MTSMC", "CSMC") for a in (False, True)
    }
    for ctrl in ("MTSMC", "CSMC"):
        eps = sorted(s.epsilon for s in by_exp["F2"] if s.controller == ctrl and s.switch == "tanh")
        assert eps == sorted(F2_EPSILONS)
    assert any(s.switch == "sign" for s in by_exp["F2"])
    gains = sorted(s.integral_gain for s in by_exp["F3"] if s.controller == "MTSMC")
    assert gains == sorted(F3_INTEGRAL_GAINS)
    assert {s.experiment for s in by_exp["F3"]} == {"steady"}
    f4 = {
        s.controller: s
        for s in by_exp["F4"]
        if s.handover_deg is None and s.settings.get("polytope", "groups") == "groups" and not s.modal_bound
    }
    assert set(f4) == {"MTSMC", "LQR", "OfflineRMPC", "RMPC"}
    assert {s.experiment for s in f4.values()} == {"small"}
    assert {s.duration for s in f4.values()} == {None}  # every F4 run is the whole slew
    assert f4["RMPC"].settings["polytope"] == f4["OfflineRMPC"].settings["polytope"] == "groups"
    (bounded,) = [s for s in by_exp["F4"] if s.modal_bound is not None and s.settings["polytope"] == "groups"]
    assert (bounded.controller, bounded.experiment, bounded.modal_bound) == ("RMPC", "small", F4_MODAL_BOUND)
    pair = [s for s in by_exp["F4"] if s.settings.get("polytope") == MODAL_BOUND_POLYTOPE]
    assert sorted(s.modal_bound or 0.0 for s in pair) == [0.0, F4_MODAL_BOUND]
    assert {(s.controller, s.experiment) for s in pair} == {("RMPC", "small")}
    (hand,) = [s for s in by_exp["F4"] if s.handover_deg is not None]
    assert (hand.controller, hand.experiment, hand.dt) == ("OfflineRMPC", "vslew", 0.01)
    assert f4["RMPC"].saturation == f4["OfflineRMPC"].saturation == "constraint"
    with pytest.raises(ConfigError, match="--experiments"):
        flexible_cases(experiments=["F7"])


def _run(**data):
    return run_scenario(Scenario.from_dict({"family": "flexible", **data}))


@pytest.mark.parametrize("avc", [False, True])
def test_mtsmc_case_has_the_contract_keys_and_avc_drives_the_pzt(avc):
    rec = _run(controller="MTSMC", avc=avc, duration=0.5)
    m = rec["metrics"]
    for key in CONTRACT_KEYS:
        assert key in m, key
    assert set(m["final_abs_err"]) == set(m["sum_abs_err"]) == {"roll", "pitch", "yaw"}
    assert rec["plant"] == "flexible"
    assert rec["settings"]["controller_name"] == ("MTSMC+AVC" if avc else "MTSMC")
    assert (m["v_peak"] > 0.0) == avc
    assert m["status_counts"] == {"ok": 50}


@pytest.mark.parametrize("data", [{"controller": "CSMC", "switch": "sign"}, {"controller": "PD"}])
def test_csmc_sign_and_pd_cases_respect_the_limiter(data):
    rec = _run(duration=0.5, **data)
    m = rec["metrics"]
    assert rec["settings"]["limiter_in_loop"]
    assert 0.0 < m["max_abs_u"] <= 2.0 + 1e-12
    assert m["regime"] in ("rigid-like", "flexible", "flexible-hard")


def test_offline_rmpc_keeps_its_peak_bound_on_the_small_slew():
    rec = _run(
        controller="OfflineRMPC",
        experiment="small",
        duration=3.0,
        settings={"polytope": "nominal", "n_ellipsoids": 2},
    )
    m, s = rec["metrics"], rec["settings"]
    assert s["n_vertices"] == 1 and s["n_ellipsoids"] == 2
    assert not s["limiter_in_loop"]
    assert m["status_counts"] == {"optimal": 6}  # every step inside the table, no fallback
    assert 0.0 < m["max_abs_u"] <= 2.0 + 1e-6  # the LMIs' peak bound, no limiter in the loop
    assert m["final_error_deg"] < 15.0
    for key in CONTRACT_KEYS:
        assert key in m, key


def test_handover_runs_mtsmc_then_the_offline_table():
    rec = _run(
        controller="OfflineRMPC",
        experiment="small",
        angle_deg=21.0,
        handover_deg=20.0,
        dt=0.01,
        duration=8.0,
        settings={"polytope": "nominal", "n_ellipsoids": 2},
    )
    m, s = rec["metrics"], rec["settings"]
    assert s["controller_name"] == "MTSMC>OfflineRMPC"
    assert s["limiter_in_loop"] and m["max_abs_u"] <= 2.0 + 1e-12
    assert 0.0 < s["handover_time"] < 8.0
    steps = round(s["handover_time"] / 0.01)
    assert m["status_counts"]["ok"] == steps  # MTSMC's steps, then the table's
    assert s["n_ellipsoids"] == 2 and sum(m["status_counts"].values()) == 800


def test_online_rmpc_reports_its_solves():
    rec = _run(controller="RMPC", experiment="small", duration=1.0, settings={"polytope": "nominal"})
    m = rec["metrics"]
    assert sum(m["status_counts"].values()) == 2
    assert m["solve_time_p50"] > 0.0
    assert m["max_abs_u"] <= 2.0 + 1e-6


def test_eta1_frequency_of_a_damped_sine():
    t = np.arange(0.0, 60.0, 0.01)
    y = 0.01 + np.exp(-0.005 * t) * np.sin(0.7681 * t + 0.3)
    assert eta1_frequency(t, y) == pytest.approx(0.7681, rel=2e-3)
    assert eta1_frequency(t[:50], y[:50]) is None


def _f2(eps_ci):
    return [
        {
            "experiment": "F2",
            "controller": "CSMC",
            "settings": {"epsilon": e, "switch": "tanh"},
            "metrics": {"ci": c},
        }
        for e, c in eps_ci
    ]


def test_inconsistency_lines_follow_the_numbers():
    falling = inconsistencies(_f2([(0.01, 0.5), (0.002, 0.9), (0.05, 0.1)]))
    rising = inconsistencies(_f2([(0.01, 0.5), (0.002, 0.4), (0.05, 0.9)]))
    assert any("monotone here" in line for line in falling)
    assert any("not monotone" in line for line in rising)
    assert any("couples mainly to x" in line for line in falling)


def test_bench_flexible_short_writes_every_file(tmp_path, capsys, monkeypatch):
    built = capture(monkeypatch, flexible_figures, "flexible_group_figure")
    out = tmp_path / "flex"
    args = ["bench", "flexible", "--out", str(out), "--short", "--workers", "0", "--experiments", "F1"]
    status = main([*args, "--no-progress"])
    stdout = capsys.readouterr().out
    assert status == 0, stdout
    assert "4 cases done, 0 failed" in stdout
    records = json.loads((out / "results.json").read_text())
    assert {r["settings"]["controller_name"] for r in records} == {"MTSMC", "MTSMC+AVC", "CSMC", "CSMC+AVC"}
    for rec in records:
        for key in CONTRACT_KEYS:
            assert key in rec["metrics"], key
    md = (out / "results.md").read_text()
    for section in ("## F1", "## Paper V's reported results", "## Inconsistencies", "## Settings", "**V4**"):
        assert section in md
    assert (out / "figures" / "F1.png").stat().st_size > 0
    # the figure: the four closed loops in each panel, each in its colour and line style; the
    # PZT panel holds the runs with AVC (the others' commands are zero)
    ((items, title), fig) = built[0]
    assert len(built) == 1 and title == f"F1: {flexible_suite.EXPERIMENTS['F1']}"  # the whole title
    err, tor, zoom, mode, rate, pzt = visible_axes(fig)
    names = [name for name, _, _ in items]
    assert len(names) == 4 and err.get_yscale() == "log" and rate.get_yscale() == "log"
    assert_readable(fig, names)
    for ax in (err, tor, zoom, mode, rate):
        assert [line.get_label() for line in run_curves(ax, names)] == names
    assert tor.get_ylabel() == "max_i |u_i| (N m)" and pzt.get_ylabel().startswith("max_j |v_j| (kg")
    # the rate panel: the body rate's part above Lambda_1/2 of each run, from its trace
    assert rate.get_ylabel() == "||w_hf|| (rad/s)"
    for line, (_, rec, trace) in zip(run_curves(rate, names), items, strict=True):
        cut = rec["settings"]["first_mode_frequency"] / 2.0
        hf = np.linalg.norm(highpass(np.asarray(trace["w"]), 0.01, cut), axis=1)
        np.testing.assert_allclose(line.get_ydata(), np.maximum(hf, 1e-9), rtol=1e-12)
    avc = [(name, trace) for name, _, trace in items if name.endswith("_AVC")]  # the suite's tags
    assert [line.get_label() for line in curves(pzt)] == [name for name, _ in avc] and len(avc) == 2
    for line, (_, trace) in zip(curves(pzt), avc, strict=True):
        np.testing.assert_allclose(line.get_ydata(), np.abs(trace["v"]).max(axis=1))
        assert np.max(line.get_ydata()) > 0.0
    # AVC on and off of one law: different line styles; the records' torque limit dotted
    styles = {line.get_label(): line.get_linestyle() for line in curves(err)}
    assert styles["MTSMC"] != styles["MTSMC_AVC"] and styles["CSMC"] != styles["CSMC_AVC"]
    assert hline_values(tor) == sorted({r["settings"]["u_max"] for r in records}) == [2.0]
    assert hlines(mode) == []  # no modal bound in F1
    assert len(list((out / "traces").glob("F1_*.npz"))) == 4
    assert len((out / "results.csv").read_text().strip().splitlines()) == 5
    assert json.loads((out / "run.json").read_text())["done"] == 4


def test_bench_flexible_short_figures_f2_and_f4(tmp_path, capsys, monkeypatch):
    """F2's eleven runs and F4's modal bound (F4 cut to its cheap cases: MTSMC, LQR and RMPC with
    the bound on the 2-vertex polytope) as the suite draws them."""
    full = flexible_suite.flexible_cases
    cheap = {"MTSMC", "LQR", "RMPC_effectiveness_modal_bound"}
    monkeypatch.setattr(
        flexible_suite,
        "flexible_cases",
        lambda *a, **k: [c for c in full(*a, **k) if c.experiment != "F4" or c.tag in cheap],
    )
    built = capture(monkeypatch, flexible_figures, "flexible_group_figure")
    out = tmp_path / "flex"
    status = main(["bench", "flexible", "--out", str(out), "--short", "--workers", "0", "--experiments",
                   "F2,F4", "--no-progress"])
    assert status == 0, capsys.readouterr().out
    records = json.loads((out / "results.json").read_text())
    figures = {title.split(":")[0]: (items, title, fig) for (items, title), fig in built}
    assert sorted(figures) == ["F2", "F4"]
    for exp, (items, title, fig) in figures.items():
        names = [name for name, _, _ in items]
        assert_readable(fig, names)  # F2: eleven runs, eleven colours; F4: its long title inside
        assert title == f"{exp}: {flexible_suite.EXPERIMENTS[exp]}"
        axes = visible_axes(fig)
        assert len(axes) == 5  # error, torque, its residual window, eta_1, rates: no run drives a PZT
        assert axes[4].get_ylabel() == "||w_hf|| (rad/s)"
        assert not any("v_j" in ax.get_ylabel() for ax in axes)
        bounds = sorted({r["settings"]["modal_bound"] for r in records if r["experiment"] == exp} - {None})
        assert hline_values(axes[3]) == sorted([-b for b in bounds] + bounds)
    assert len(figures["F2"][0]) == 11
    assert hline_values(visible_axes(figures["F4"][2])[3]) == [-flexible_suite.F4_MODAL_BOUND,
                                                              flexible_suite.F4_MODAL_BOUND]


def test_shipped_gain_sweep_expands():
    from benchmarks.core.sweep import expand, load_sweep

    cases = expand(load_sweep("flexible_gains"))
    assert len(cases) == 18
    assert {c.family for c in cases} == {"flexible"}
    slopes = {c.settings["alpha_f"] for c in cases if c.controller == "MTSMC"}
    assert slopes == {0.05, 0.1, 0.2}
