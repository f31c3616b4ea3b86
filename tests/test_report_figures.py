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
from figure_checks import curves, hline_values, hlines, spans, visible_axes, vlines

from benchmarks.reports.fault_figures import fault_case_group_figure, plot_fault_case_group
from benchmarks.reports.figures import gamma_figure, plot_gamma, plot_responses, responses_figure
from benchmarks.reports.flexible_figures import flexible_group_figure
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
    assert styles == [("RMPC limiter (linear)", "--"), ("RMPC limiter (nonlinear)", "-"),
                      ("GIPC limiter (linear)", "--"), ("GIPC limiter (nonlinear)", "-")]
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
        assert ax.get_yscale() == "log" and ax.get_ylabel() == "gamma(k)" and ax.get_xlabel() == "time (s)"
        labels = [line.get_label() for line in curves(ax)]
        assert labels == ["RMPC limiter (linear)", "RMPC limiter (nonlinear)"]
        np.testing.assert_allclose(curves(ax)[0].get_ydata(), runs[0][1]["gamma"])
    assert gamma_figure({"E5": runs[2:]}) is None
    assert plot_gamma({"E5": runs[2:]}, "unused.png") is None


# -- paper W's fault cases ----------------------------------------------------------------------
def _wheel_runs() -> list[tuple[dict, dict]]:
    rng = np.random.default_rng(1)
    runs = []
    for ctrl in ("ABFTC", "RMPC"):
        runs.append(({"controller": ctrl, "label": f"{ctrl} S1"},
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
        assert hlines(att) == []
        for ax in (att, tor, mom):
            assert spans(ax) == [(1.0, 2.0), (4.0, 5.0)]


def test_plot_fault_case_group_writes_a_png(tmp_path):
    path = plot_fault_case_group(_wheel_runs(), [], tmp_path / "W1.png", "W1", 0.123, 0.5)
    assert path.read_bytes()[:8] == PNG


# -- paper V's flexible satellite and paper M's MRP satellite ----------------------------------
def test_flexible_figure_draws_error_torque_mode_and_pzt_per_run():
    rng = np.random.default_rng(2)
    with_avc = {"t": T, "error_deg": np.abs(rng.normal(size=T.size)), "u": rng.normal(size=(T.size - 1, 3)),
                "eta": rng.normal(size=(T.size, 4)), "v": rng.normal(size=(T.size - 1, 4))}
    without = {**with_avc, "v": np.zeros((0, 4))}
    fig = flexible_group_figure([("MTSMC+AVC", with_avc), ("MTSMC", without)], "F1: a title")
    err, tor, mode, pzt = visible_axes(fig)
    assert fig.get_suptitle() == "F1: a title"
    assert err.get_yscale() == "log" and err.get_ylabel() == "rotation error (deg)"
    assert tor.get_ylabel() == "max_i |u_i| (N m)" and mode.get_ylabel() == "eta_1 (kg^1/2 m)"
    assert pzt.get_ylabel() == "max_j |v_j| (PZT)" and pzt.get_xlabel() == "t (s)"
    for ax in (err, tor, mode):
        assert [line.get_label() for line in curves(ax)] == ["MTSMC+AVC", "MTSMC"]
    assert [line.get_label() for line in curves(pzt)] == ["MTSMC+AVC"]  # no PZT without AVC
    np.testing.assert_allclose(curves(tor)[0].get_ydata(), np.abs(with_avc["u"]).max(axis=1))
    np.testing.assert_allclose(curves(pzt)[0].get_ydata(), np.abs(with_avc["v"]).max(axis=1))
    np.testing.assert_allclose(curves(err)[1].get_ydata(), np.maximum(without["error_deg"], 1e-6))
    np.testing.assert_allclose(curves(mode)[1].get_ydata(), without["eta"][:, 0])


def test_mrp_figure_draws_error_torque_and_the_disturbance_with_its_estimates():
    rng = np.random.default_rng(3)
    d = rng.normal(scale=0.05, size=(T.size - 1, 3))
    base = {"t": T, "u_applied": rng.normal(size=(T.size - 1, 3)), "d": d,
            "error_angle_deg": np.abs(rng.normal(size=T.size))}
    estimate = rng.normal(scale=0.05, size=(T.size - 1, 3))
    items = [({"controller": "BS"}, base), ({"controller": "MAB"}, {**base, "torque_estimate": estimate})]
    fig = mrp_group_figure(items, "M2: a title")
    err, tor, dist = visible_axes(fig)
    assert err.get_yscale() == "log" and err.get_ylabel() == "error angle (deg)"
    assert tor.get_ylabel() == "max_i |u_i| (N m)"
    assert dist.get_ylabel() == "disturbance torque (N m)" and dist.get_xlabel() == "t (s)"
    assert [line.get_label() for line in curves(err)] == ["BS", "MAB"]
    labels = [line.get_label() for line in curves(dist)]
    assert labels == ["MAB estimate (x)", "true (x)", "true (y)", "true (z)"]
    assert curves(dist)[0].get_linestyle() == "--"
    np.testing.assert_allclose(curves(dist)[0].get_ydata(), estimate[:, 0])
    np.testing.assert_allclose(curves(dist)[2].get_ydata(), d[:, 1])


# -- the timing report --------------------------------------------------------------------------
def _timing_report() -> tuple[dict, dict]:
    records = [
        {"problem": "RMPC", "backend": "ipm", "formulation": "delta_shared", "vertices": 2},
        {"problem": "RMPC", "backend": "clarabel", "formulation": "delta_shared", "vertices": 8},
        {"problem": "GIPC", "backend": "osqp", "formulation": "-", "vertices": 1},
        {"problem": "OfflineRMPC", "backend": "ipm", "formulation": "table", "vertices": 2},  # no samples
    ]
    rng = np.random.default_rng(4)
    keys = [f"{r['problem']}|{r['backend']}|{r['formulation']}|{r['vertices']}" for r in records[:3]]
    samples = {key: rng.uniform(1e-3, 1e-2, 20) for key in keys}
    return {"records": records, "machine": {"platform": "test", "cpu_count": 2}}, samples


def test_timing_distributions_one_log_panel_per_problem_one_box_per_record():
    report, samples = _timing_report()
    fig = distributions_figure(report, samples)
    axes = visible_axes(fig)
    assert [ax.get_title().split(":")[0] for ax in axes] == ["RMPC", "GIPC"]  # no OfflineRMPC samples
    for ax, boxes in zip(axes, (2, 1), strict=True):
        assert ax.get_yscale() == "log" and ax.get_ylabel() == "time per step (s)"
        assert len(ax.patches) == boxes
        assert len(ax.get_xticklabels()) == boxes
    assert [t.get_text() for t in axes[0].get_xticklabels()] == ["ipm / delta_shared / 2v",
                                                                 "clarabel / delta_shared / 8v"]
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
