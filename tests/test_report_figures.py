"""The suites' figures checked for what they draw: panels, labels with units, one curve per run
with the run's data, the limit lines and the event markers.

Each figure is built from small synthetic runs by the same function the suite calls
(``benchmarks.reports.*_figure``, ``benchmarks.timing.*_figure``) and read back through its
artists (``tests/figure_checks.py``). The suites' own short runs check the figures they build
the same way (``tests/test_bench_cli.py``, ``test_bench_faults.py``, ``test_bench_mrp.py``,
``test_bench_flexible.py``).
"""

from __future__ import annotations

import numpy as np
from figure_checks import (
    UNIT,
    assert_readable,
    coincident_note,
    curves,
    hatched_spans,
    hline_values,
    hlines,
    run_curves,
    spans,
    title_inside,
    visible_axes,
    vlines,
)

from benchmarks.families.wheel.defaults import RECOVERY_DEG
from benchmarks.reports.fault_figures import fault_case_group_figure, plot_fault_case_group
from benchmarks.reports.figure_style import LINE_STYLES, run_styles
from benchmarks.reports.figures import gamma_figure, plot_gamma, plot_responses, responses_figure
from benchmarks.reports.flexible_figures import PZT_UNIT, RESIDUAL_TAIL, flexible_group_figure
from benchmarks.reports.mrp_figures import mrp_group_figure
from benchmarks.timing.plots import distributions_figure
from benchmarks.timing.scale import scale_figure

T = np.linspace(0.0, 5.0, 51)
PNG = b"\x89PNG\r\n\x1a\n"


def _paper_runs() -> list[tuple[dict, dict]]:
    """RMPC and GIPC behind the limiter on both plants, a disturbance from 2 s; GIPC has no gamma."""
    rng = np.random.default_rng(0)
    runs = []
    for ctrl in ("RMPC", "GIPC"):
        for plant in ("linear", "nonlinear"):
            rec = {"controller": ctrl, "saturation": "limiter", "plant": plant,
                   "settings": {"disturbance": [0.5, 0.5, 0.5], "disturbance_start": 2.0}}
            no_bound = np.full(T.size - 1, np.nan)
            gamma = np.abs(rng.normal(size=T.size - 1)) + 0.1 if ctrl == "RMPC" else no_bound
            runs.append((rec, {"t": T, "x": rng.normal(scale=0.1, size=(T.size, 6)),
                               "u_applied": rng.uniform(-1.0, 1.0, size=(T.size - 1, 3)), "gamma": gamma}))
    return runs


# -- paper P's responses ------------------------------------------------------------------------
def test_responses_figure_draws_attitude_torques_and_the_limit_lines():
    runs = _paper_runs()
    fig = responses_figure(runs, "E2: a title", 1.0)
    axes = visible_axes(fig)
    assert len(axes) == 6  # rows roll, pitch, yaw; columns attitude, torque
    grid = np.array(axes).reshape(3, 2)
    assert fig.get_suptitle() == "E2: a title"
    for i, (angle, torque) in enumerate((("roll", "M_x"), ("pitch", "M_y"), ("yaw", "M_z"))):
        att, tor = grid[i]
        assert angle in att.get_ylabel() and att.get_ylabel().endswith("(deg)")
        assert torque in tor.get_ylabel() and tor.get_ylabel().endswith("(N m)")
        assert len(curves(att)) == len(curves(tor)) == len(runs)  # one curve per run
        for line, (_, trace) in zip(curves(att), runs, strict=True):
            np.testing.assert_allclose(line.get_ydata(), np.degrees(trace["x"][:, i]))  # in degrees
        for line, (_, trace) in zip(curves(tor), runs, strict=True):
            np.testing.assert_allclose(line.get_ydata(), trace["u_applied"][:, i])
            assert line.get_drawstyle() == "steps-post"  # a held torque
        # the +-u_max lines, dotted, in every torque panel and only there
        assert hline_values(tor) == [-1.0, 1.0]
        assert all(line.get_linestyle() == ":" for line in hlines(tor))
        assert hlines(att) == []
        # the disturbance onset marked in every panel
        for ax in (att, tor):
            assert [float(v.get_xdata()[0]) for v in vlines(ax)] == [2.0] * len(runs)
    for ax in grid[-1]:
        assert ax.get_xlabel() == "time (s)"
    # the line style tells the plant apart, the colour the controller
    styles = [(line.get_label(), line.get_linestyle()) for line in curves(grid[0, 0])]
    assert styles == [("RMPC, limiter (linear)", "--"), ("RMPC, limiter (nonlinear)", "-"),
                      ("GIPC, limiter (linear)", "--"), ("GIPC, limiter (nonlinear)", "-")]
    colours = [line.get_color() for line in curves(grid[0, 0])]
    assert colours[0] == colours[1] != colours[2] == colours[3]
    assert len(fig.legends) == 1 and len(fig.legends[0].get_texts()) == len(runs)


def test_responses_figure_follows_u_max_and_skips_an_onset_after_the_run():
    runs = _paper_runs()
    for _, trace in runs:
        trace["t"] = T[:21]  # 2 s: the onset is the last sample, not inside the run
        trace["x"], trace["u_applied"] = trace["x"][:21], trace["u_applied"][:20]
    fig = responses_figure(runs, "short", 0.25)
    grid = np.array(visible_axes(fig)).reshape(3, 2)
    for i in range(3):
        assert hline_values(grid[i, 1]) == [-0.25, 0.25]
        assert vlines(grid[i, 0]) == vlines(grid[i, 1]) == []


def test_plot_responses_writes_the_figure_it_builds(tmp_path):
    path = plot_responses(_paper_runs(), tmp_path / "E2.png", "E2", 1.0)
    assert path == tmp_path / "E2.png" and path.read_bytes()[:8] == PNG


def test_gamma_figure_one_log_panel_per_experiment_with_a_bound():
    runs = _paper_runs()
    groups = {"E1": runs, "E2": runs[:2], "E5": runs[2:]}  # E5 holds GIPC only: no gamma, no panel
    fig = gamma_figure(groups)
    axes = visible_axes(fig)
    assert [ax.get_title() for ax in axes] == ["E1", "E2"]
    for ax in axes:
        assert ax.get_yscale() == "log" and ax.get_xlabel() == "time (s)"
        # "gamma(k)" alone passes a unit check through "(k)": the label must say it has no unit
        assert ax.get_ylabel() == "cost bound gamma(k) (dimensionless)"
        labels = [line.get_label() for line in curves(ax)]
        assert labels == ["RMPC, limiter (linear)", "RMPC, limiter (nonlinear)"]
        np.testing.assert_allclose(curves(ax)[0].get_ydata(), runs[0][1]["gamma"])
    assert gamma_figure({"E5": runs[2:]}) is None
    assert plot_gamma({"E5": runs[2:]}, "unused.png") is None


# -- paper W's fault cases ----------------------------------------------------------------------
def _wheel_runs() -> list[tuple[dict, dict]]:
    rng = np.random.default_rng(1)
    runs = []
    rank = {"faults": {"rank_deficient_windows": [[0.5, 1.5, 2, [1, 4]], [3.0, 80.0, 2, [2, 4]]]}}
    for ctrl in ("ABFTC", "RMPC"):
        runs.append(({"controller": ctrl, "label": f"{ctrl} S1", "metrics": rank},
                     {"t": T, "x": rng.normal(scale=0.1, size=(T.size, 10)),
                      "u_cmd": rng.uniform(-1.0, 1.0, size=(T.size - 1, 4)),
                      "u_applied": rng.uniform(-0.1, 0.1, size=(T.size - 1, 4))}))
    return runs


def test_fault_figure_draws_wheels_limits_and_fault_windows():
    runs = _wheel_runs()
    windows = [(1.0, 2.0), (4.0, 9.0)]  # the second ends after the run: shaded to its end
    fig = fault_case_group_figure(runs, windows, "W1: a title", 0.123, 0.5)
    grid = np.array(visible_axes(fig)).reshape(3, 2)
    assert fig.get_suptitle().startswith("W1: a title")
    assert grid[0, 0].get_ylabel() == "attitude (deg)"
    assert grid[1, 0].get_ylabel().startswith("wheel torque (N m)")
    assert grid[2, 0].get_ylabel() == "wheel momentum (N m s)"
    for col, (rec, trace) in enumerate(runs):
        att, tor, mom = grid[:, col]
        assert att.get_title() == rec["label"] and mom.get_xlabel() == "t (s)"
        assert [line.get_label() for line in curves(att)] == ["roll", "pitch", "yaw"]
        np.testing.assert_allclose(curves(att)[1].get_ydata(), np.degrees(trace["x"][:, 1]))
        applied, commanded = curves(tor)[0::2], curves(tor)[1::2]
        assert len(applied) == len(commanded) == 4  # per wheel: applied and commanded (dashed)
        assert all(line.get_linestyle() == "--" for line in commanded)
        np.testing.assert_allclose(applied[2].get_ydata(), trace["u_applied"][:, 2])
        np.testing.assert_allclose(commanded[2].get_ydata(), np.clip(trace["u_cmd"][:, 2], -0.369, 0.369))
        assert len(curves(mom)) == 4
        np.testing.assert_allclose(curves(mom)[3].get_ydata(), trace["x"][:, 9])
        assert hline_values(tor) == [-0.123, 0.123] and hline_values(mom) == [-0.5, 0.5]
        # the recovery band of the family's recovery time, dotted, in the attitude panel
        assert hline_values(att) == [-RECOVERY_DEG, RECOVERY_DEG] and RECOVERY_DEG == 2.0
        assert all(line.get_linestyle() == ":" for line in hlines(att) + hlines(tor) + hlines(mom))
        for ax in (att, tor, mom):
            assert spans(ax) == [(1.0, 2.0), (4.0, 5.0)]
            assert hatched_spans(ax) == [(0.5, 1.5), (3.0, 5.0)]  # the record's rank-deficient windows
        assert UNIT.search(att.get_ylabel()) and UNIT.search(mom.get_ylabel())  # every column labelled
    assert_readable(fig, [])
    assert hline_values(visible_axes(fault_case_group_figure(runs, windows, "W", 0.1, 0.5, 3.5))[0]) == [
        -3.5, 3.5]


def test_plot_fault_case_group_writes_a_png(tmp_path):
    path = plot_fault_case_group(_wheel_runs(), [], tmp_path / "W1.png", "W1", 0.123, 0.5)
    assert path.read_bytes()[:8] == PNG


# -- paper V's flexible satellite and paper M's MRP satellite ----------------------------------
def _flex_rec(u_max: float = 1.7, modal_bound: float | None = None) -> dict:
    return {"saturation": "limiter", "settings": {"u_max": u_max, "modal_bound": modal_bound}}


def _flex_trace(rng: np.random.Generator, avc: bool) -> dict:
    return {"t": T, "error_deg": np.abs(rng.normal(size=T.size)), "u": rng.normal(size=(T.size - 1, 3)),
            "eta": rng.normal(size=(T.size, 4)),
            "v": rng.normal(size=(T.size - 1, 4)) if avc else np.zeros((T.size - 1, 4))}


def test_flexible_figure_draws_error_torque_mode_and_pzt_per_run():
    rng = np.random.default_rng(2)
    with_avc = _flex_trace(rng, avc=True)
    without = {**with_avc, "v": np.zeros((T.size - 1, 4))}  # the same run without AVC: overlapping curves
    names = ["MTSMC+AVC", "MTSMC"]
    fig = flexible_group_figure([("MTSMC+AVC", _flex_rec(), with_avc), ("MTSMC", _flex_rec(), without)],
                                "F1: a title")
    err, tor, zoom, mode, pzt = visible_axes(fig)
    assert fig.get_suptitle() == "F1: a title"
    assert err.get_yscale() == "log" and err.get_ylabel() == "rotation error (deg)"
    assert tor.get_ylabel() == zoom.get_ylabel() == "max_i |u_i| (N m)"
    assert mode.get_ylabel() == "eta_1 (kg^1/2 m)"
    assert pzt.get_ylabel() == f"max_j |v_j| ({PZT_UNIT})" and PZT_UNIT == "kg^1/2 m/s^2"
    for ax in (err, tor, zoom, mode):
        assert [line.get_label() for line in run_curves(ax, names)] == names
    assert [line.get_label() for line in curves(pzt)] == ["MTSMC+AVC"]  # no PZT line without AVC
    np.testing.assert_allclose(curves(tor)[0].get_ydata(), np.abs(with_avc["u"]).max(axis=1))
    np.testing.assert_allclose(curves(pzt)[0].get_ydata(), np.abs(with_avc["v"]).max(axis=1))
    np.testing.assert_allclose(curves(err)[1].get_ydata(), np.maximum(without["error_deg"], 1e-6))
    np.testing.assert_allclose(curves(mode)[1].get_ydata(), without["eta"][:, 0])
    # the two runs overlap in every panel but the PZT one: they differ in line style
    assert curves(tor)[0].get_linestyle() != curves(tor)[1].get_linestyle()
    assert_readable(fig, names)
    # the torque limit of the records (1.7 N m, not the suite's 2), no modal bound: no line at eta
    assert hline_values(tor) == [1.7] and hlines(mode) == []
    # the residual window: the last RESIDUAL_TAIL seconds, shaded, and the zoom panel limited to it
    window = (max(0.0, 5.0 - RESIDUAL_TAIL), 5.0)
    assert RESIDUAL_TAIL == 10.0 and spans(err) == spans(tor) == [window]
    assert zoom.get_xlim() == window


def test_flexible_figure_residual_zoom_leaves_the_transient_out():
    t = np.linspace(0.0, 30.0, 301)
    u = np.full((t.size - 1, 3), 0.01)
    u[:5] = 2.0  # the slew's saturated start
    u[-50:, 0] = 0.05  # the residual torque of the last 5 s
    trace = {"t": t, "error_deg": np.ones(t.size), "u": u, "eta": np.zeros((t.size, 4)),
             "v": np.zeros((0, 4))}
    fig = flexible_group_figure([("MTSMC", _flex_rec(2.0), trace)], "F1")
    _, tor, zoom, _ = visible_axes(fig)  # no run drives the PZTs: no PZT panel
    assert zoom.get_xlim() == (20.0, 30.0)
    lo, hi = zoom.get_ylim()
    assert lo <= 0.01 and 0.05 <= hi < 0.1 < 2.0  # the residual torque fills the panel, the peak is out
    assert tor.get_ylim()[1] >= 2.0  # the whole run, with the limit, in the torque panel
    assert [float(line.get_ydata()[0]) for line in hlines(tor)] == [2.0]


def test_flexible_figure_modal_bounds_and_a_colour_per_run():
    rng = np.random.default_rng(5)
    items = [(f"CSMC_eps{i}", _flex_rec(), _flex_trace(rng, avc=False)) for i in range(10)]
    items.append(("RMPC_modal_bound", _flex_rec(modal_bound=0.03), _flex_trace(rng, avc=False)))
    fig = flexible_group_figure(items, "F2")
    axes = visible_axes(fig)
    assert len(axes) == 4  # error, torque, zoom, eta_1: the PZT panel left out
    names = [name for name, _, _ in items]
    assert_readable(fig, names)  # eleven runs, eleven colours
    assert len({str(line.get_color()) for line in run_curves(axes[0], names)}) == 11
    assert hline_values(axes[3]) == [-0.03, 0.03]


def test_flexible_figure_title_wraps_inside_the_figure():
    title = "F4: " + "A 10 deg slew where the linear model holds, over the 8-vertex polytope; " * 4
    rng = np.random.default_rng(6)
    fig = flexible_group_figure([("LQR", _flex_rec(), _flex_trace(rng, avc=False))], title)
    assert title_inside(fig)
    assert fig.get_suptitle().replace("\n", " ") == title.strip()  # every word kept, none cut


def _mrp_items(saturation: str = "none", u_max: float = 1.0) -> list[tuple[dict, dict]]:
    rng = np.random.default_rng(3)
    d = rng.normal(scale=0.05, size=(T.size - 1, 3))
    u = rng.uniform(-0.2, 0.2, size=(T.size - 1, 3))
    u[0] = 40.0  # the t = 0 spike
    base = {"t": T, "u_applied": u, "d": d, "error_angle_deg": np.abs(rng.normal(size=T.size))}
    estimate = rng.normal(scale=0.05, size=(T.size - 1, 3))
    settings = {"u_max": u_max, "steady_window": [2.5, 5.0], "late_window": [1.0, 5.0]}
    rec = {"saturation": saturation, "settings": settings}
    return [({**rec, "controller": "BS"}, base),
            ({**rec, "controller": "MAB"}, {**base, "torque_estimate": estimate}),
            ({**rec, "controller": "TFAB"}, {**base, "torque_estimate": -estimate})]


def test_mrp_figure_draws_error_torque_and_the_disturbance_with_its_estimates():
    items = _mrp_items()
    base, estimate = items[0][1], items[1][1]["torque_estimate"]
    names = ["BS", "MAB", "TFAB"]
    fig = mrp_group_figure(items, "M2: a title")
    err, tor, zoom, d_x, d_y, d_z = visible_axes(fig)
    assert err.get_yscale() == "log" and err.get_ylabel() == "error angle (deg)"
    assert tor.get_ylabel() == zoom.get_ylabel() == "max_i |u_i| (N m)"
    assert [line.get_label() for line in curves(err)] == names
    assert_readable(fig, names)
    for i, ax in enumerate((d_x, d_y, d_z)):  # one panel per axis: the true torque and both estimates
        assert ax.get_ylabel() == f"disturbance torque, {'xyz'[i]} (N m)"
        labels = [line.get_label() for line in curves(ax)]
        assert labels == ["MAB estimate", "TFAB estimate", "true"]
        np.testing.assert_allclose(curves(ax)[0].get_ydata(), estimate[:, i])
        np.testing.assert_allclose(curves(ax)[1].get_ydata(), -estimate[:, i])
        np.testing.assert_allclose(curves(ax)[2].get_ydata(), base["d"][:, i])
        # an estimate keeps its run's colour and style; the true torque is black and solid
        assert curves(ax)[0].get_color() == curves(err)[1].get_color()
        assert curves(ax)[0].get_linestyle() == curves(err)[1].get_linestyle()
        assert curves(ax)[2].get_color() == "k" and curves(ax)[2].get_linestyle() == "-"
        assert spans(ax) == [(1.0, 5.0)]  # the late window, where the estimate's error is measured
    # no torque limit without saturation; the steady window shaded
    assert hlines(tor) == [] and spans(err) == spans(tor) == [(2.5, 5.0)]
    # the zoom: the steady window, without the t = 0 spike
    assert zoom.get_xlim() == (2.5, 5.0)
    steady = np.abs(base["u_applied"]).max(axis=1)[T[:-1] >= 2.5]
    lo, hi = zoom.get_ylim()
    assert lo <= steady.min() and steady.max() <= hi < 40.0


def test_mrp_figure_draws_the_limit_of_the_limited_runs():
    fig = mrp_group_figure(_mrp_items("limiter", 0.8), "M3")
    tor = visible_axes(fig)[1]
    assert hline_values(tor) == [0.8] and hlines(tor)[0].get_linestyle() == ":"
    assert tor.get_ylim()[1] > 0.8


def test_mrp_figure_without_disturbance_or_estimates_leaves_the_torque_panels_out():
    items = [(rec, {**trace, "d": np.zeros((0, 3))}) for rec, trace in _mrp_items()[:1]]
    fig = mrp_group_figure(items, "M1")
    assert [ax.get_ylabel() for ax in visible_axes(fig)] == ["error angle (deg)", "max_i |u_i| (N m)",
                                                            "max_i |u_i| (N m)"]
    assert_readable(fig, ["BS"])


def test_runs_on_top_of_each_other_are_named_in_the_legend():
    """Four runs with one error curve (F2's boundary layers early in a slew): the three line
    styles cannot keep them apart, the legend's head names them; a run 1 % of the panel's range
    away is not among them."""
    rng = np.random.default_rng(7)
    same = _flex_trace(rng, avc=False)
    apart = {**same, "error_deg": same["error_deg"] + 0.01 * np.ptp(np.log10(same["error_deg"])),
             "u": same["u"] + 0.01 * np.ptp(same["u"])}
    items = [(f"CSMC_eps{i}", _flex_rec(), same) for i in range(4)] + [("MTSMC", _flex_rec(), apart)]
    names = [name for name, _, _ in items]
    fig = flexible_group_figure(items, "F2")
    err = visible_axes(fig)[0]
    assert coincident_note(err) == [set(names[:4])]
    assert_readable(fig, names)
    head = err.get_legend().get_title().get_text().replace("\n", " ")
    assert head.startswith("on top of each other: CSMC_eps0 = ")
    solo = flexible_group_figure(items[3:], "F2")  # CSMC_eps3 and MTSMC: apart but for eta_1
    err, tor, zoom, mode = visible_axes(solo)
    assert coincident_note(err) == coincident_note(tor) == coincident_note(zoom) == []
    assert coincident_note(mode) == [{"CSMC_eps3", "MTSMC"}]


def test_run_styles_never_repeat_a_colour_and_cycle_the_line_styles():
    for n in (1, 4, 11, 20, 21, 40):
        styles = run_styles(n)
        assert len({str(s["color"]) for s in styles}) == n
        assert [s["linestyle"] for s in styles] == [LINE_STYLES[i % 3] for i in range(n)]
        assert ":" not in LINE_STYLES  # dotted: the limit lines


# -- the timing report --------------------------------------------------------------------------
def _timing_report() -> tuple[dict, dict]:
    records = [
        {"problem": "RMPC", "backend": "ipm", "formulation": "delta_shared", "vertices": 2},
        {"problem": "RMPC", "backend": "clarabel", "formulation": "delta_shared", "vertices": 8},
        {"problem": "GIPC", "backend": "osqp", "formulation": "-", "vertices": 1},
        {"problem": "OfflineRMPC", "backend": "ipm", "formulation": "table", "vertices": 2},  # no samples
        {"problem": "C", "backend": "c-export", "formulation": "delta_shared", "vertices": 2},
        {"problem": "C", "backend": "ipm-numba", "formulation": "delta_shared", "vertices": 2},
    ]
    rng = np.random.default_rng(4)
    keys = [f"{r['problem']}|{r['backend']}|{r['formulation']}|{r['vertices']}" for r in records if
            r["problem"] != "OfflineRMPC"]
    samples = {key: rng.uniform(1e-3, 1e-2, 20) for key in keys}
    return {"records": records, "machine": {"platform": "test", "cpu_count": 2}}, samples


def test_timing_distributions_one_log_panel_per_problem_one_box_per_record():
    report, samples = _timing_report()
    fig = distributions_figure(report, samples)
    axes = visible_axes(fig)
    assert [ax.get_title().split(":")[0] for ax in axes] == ["RMPC", "GIPC", "C"]  # no OfflineRMPC samples
    for ax, boxes in zip(axes, (2, 1, 2), strict=True):
        assert ax.get_yscale() == "log" and ax.get_ylabel() == "time per step (s)"
        assert len(ax.patches) == boxes
        assert len(ax.get_xticklabels()) == boxes
    assert [t.get_text() for t in axes[0].get_xticklabels()] == ["ipm / delta_shared / 2v",
                                                                 "clarabel / delta_shared / 8v"]
    assert [t.get_text() for t in axes[2].get_xticklabels()] == ["c-export / delta_shared / 2v",
                                                                 "ipm-numba / delta_shared / 2v"]
    empty = distributions_figure({"records": [], "machine": {}}, {})
    assert [t.get_text() for t in visible_axes(empty)[0].texts] == ["no timing samples"]


def test_timing_scale_one_line_per_path_against_the_state_dimension():
    records = [{"backend": b, "formulation": "delta_shared", "vertices": v, "n_states": n,
                "p50_s": 1e-3 * n, "p95_s": 2e-3 * n}
               for b in ("ipm", "clarabel") for v in (2, 8) for n in (6, 10, 14)]
    fig = scale_figure(records)
    (ax,) = visible_axes(fig)
    assert ax.get_yscale() == "log" and ax.get_xlabel() == "state dimension"
    assert ax.get_ylabel().startswith("time per solve (s)")
    bars = ax.containers  # one error-bar container per path: the p50 line and the bars to p95
    assert [c.get_label() for c in bars] == [
        "ipm delta_shared, 2 vertices", "ipm delta_shared, 8 vertices",
        "clarabel delta_shared, 2 vertices", "clarabel delta_shared, 8 vertices"]
    lines = [c.lines[0] for c in bars]
    np.testing.assert_allclose(np.asarray(lines[0].get_xdata(), dtype=float), [6, 10, 14])
    np.testing.assert_allclose(np.asarray(lines[0].get_ydata(), dtype=float), [6e-3, 10e-3, 14e-3])
    assert [line.get_linestyle() for line in lines] == ["-", "--", "-", "--"]
    (caps,) = bars[0].lines[2]  # the bars reach p95
    np.testing.assert_allclose([seg[1, 1] for seg in caps.get_segments()], [12e-3, 20e-3, 28e-3])
