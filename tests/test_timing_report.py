"""``rmpc timing``: a quick run writes timing.json (API keys on every record), timing.md and the
figure; bad option values raise errors naming the option (the CLI's exit status 2)."""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest
from figure_checks import capture, visible_axes

import benchmarks.timing.plots as timing_plots
import benchmarks.timing.scale as timing_scale
from benchmarks.timing import VERTEX_COUNTS, add_timing_parser, config_from_args, polytope
from toolkit_common.errors import InvalidArgumentError

API_KEYS = ("problem", "formulation", "backend", "vertices", "p50_s", "p95_s", "max_s", "status_counts",
            "max_rel_err")


def _parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="rmpc")
    add_timing_parser(parser.add_subparsers(dest="command", required=True))
    return parser.parse_args(["timing", *argv])


def test_quick_run_writes_the_report(tmp_path, capsys, monkeypatch):
    built = capture(monkeypatch, timing_plots, "distributions_figure")
    out = tmp_path / "timing"
    # 2 RMPC states on the 2-vertex polytope (every path), 5 ellipsoids, 50 GIPC QPs: ~10 s.
    args = _parse(["--out", str(out), "--quick", "--steps", "2", "--vertices", "2", "--no-progress"])
    assert args.func(args) == 0
    assert "rebuild-per-step / fast path" in capsys.readouterr().out

    report = json.loads((out / "timing.json").read_text())
    assert {"machine", "versions", "records"} <= set(report)
    assert report["versions"]["clarabel"] != "not installed"
    assert report["machine"]["cpu_count"] >= 1
    assert len(report["machine"]["load_average_start"]) == 3
    records = report["records"]
    for rec in records:
        missing = [k for k in API_KEYS if k not in rec]
        assert not missing, (missing, rec)
        assert rec["problem"] in ("RMPC", "OfflineRMPC", "GIPC")
        assert 0 < rec["p50_s"] <= rec["p95_s"] <= rec["max_s"]
        assert sum(rec["status_counts"].values()) == rec["steps"] > 0
        if rec["problem"] == "RMPC":  # None exactly when no state had both a gamma and a reference
            assert 0 <= rec["compared_steps"] <= rec["steps"]
            assert (rec["max_rel_err"] is None) == (rec["compared_steps"] == 0)
        if rec["max_rel_err"] is not None:
            assert rec["max_rel_err"] >= 0.0
    seen = {(r["problem"], r["backend"], r["formulation"]) for r in records}
    rmpc_paths = [("clarabel", "delta_shared"), ("clarabel", "delta"), ("clarabel", "standard"),
                  ("ipm", "delta_shared"), ("cvxpy:CLARABEL", "delta"), ("cvxpy-rebuild:CLARABEL", "delta"),
                  ("cvxpy:SCS", "delta")]
    for backend, formulation in rmpc_paths:
        assert ("RMPC", backend, formulation) in seen
    assert {r["backend"] for r in records if r["problem"] == "GIPC"} == {
        "proxqp", "osqp", "clarabel", "cvxpy:CLARABEL"}
    assert {r["formulation"] for r in records if r["problem"] == "OfflineRMPC"} == {
        "lookup", "lookup+interpolation"}
    assert {r["vertices"] for r in records if r["problem"] != "GIPC"} == {2}

    # Accuracy: the default path and the QP back-ends agree with their high-accuracy references.
    fast = next(r for r in records if r["problem"] == "RMPC" and r["backend"] == "clarabel"
                and r["formulation"] == "delta_shared")
    assert fast["status_counts"].get("optimal", 0) >= 1
    # every optimal state compared with the reference (measured: 2 of 2)
    assert fast["compared_steps"] == fast["status_counts"]["optimal"]
    assert fast["max_rel_err"] < 1e-6 and fast["min_margin"] > -1e-7
    for rec in records:
        if rec["problem"] == "GIPC":
            assert rec["status_counts"] == {"optimal": rec["steps"]}
            assert rec["max_rel_err"] < 1e-6
        if rec["problem"] == "OfflineRMPC":
            assert rec["max_rel_err"] < 1e-5 and rec["design_time_s"] > 0
    (ratio,) = report["rebuild_over_fast"]
    assert ratio["vertices"] == 2 and ratio["rebuild_over_fast"] > 0
    assert math.isfinite(ratio["rebuild_p50_s"])

    md = (out / "timing.md").read_text()
    for text in ("## Machine", "load average", "| cvxpy |", "## RMPC", "rebuild / fast", "## OfflineRMPC",
                 "## GIPC", "timing.png"):
        assert text in md, text
    png = (out / "timing.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    samples = np.load(out / "timing_samples.npz")
    assert len(samples.files) == len(records)
    # the figure: one log panel per problem, one box per record, labelled with its path
    ((_args, fig),) = built
    panels = visible_axes(fig)
    problems = [p for p in ("RMPC", "OfflineRMPC", "GIPC") if any(r["problem"] == p for r in records)]
    assert [ax.get_title().split(":")[0] for ax in panels] == problems
    for ax, problem in zip(panels, problems, strict=True):
        recs = [r for r in records if r["problem"] == problem]
        labels = [r["backend"] if problem == "GIPC"
                  else f"{r['backend']} / {r['formulation']} / {r['vertices']}v" for r in recs]
        assert ax.get_yscale() == "log" and ax.get_ylabel() == "time per step (s)"
        assert [t.get_text() for t in ax.get_xticklabels()] == labels and len(ax.patches) == len(recs)


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--steps", "0"], "--steps"),
        (["--steps", "many"], "--steps"),
        (["--vertices", "3"], "--vertices"),
        (["--vertices", "two"], "--vertices"),
        (["--problems", "LQR"], "--problems"),
        (["--rebuild-steps", "0"], "--rebuild-steps"),
        (["--scs-steps", "-1"], "--scs-steps"),
    ],
)
def test_bad_values_name_the_option(tmp_path, argv, option):
    args = _parse(["--out", str(tmp_path / "t"), *argv])
    with pytest.raises(InvalidArgumentError) as err:
        args.func(args)
    assert err.value.argument == option
    assert option in str(err.value)
    assert not (tmp_path / "t").exists()  # nothing measured, nothing written


def test_out_must_not_be_a_file(tmp_path):
    target = tmp_path / "a_file"
    target.write_text("x")
    args = _parse(["--out", str(target), "--quick"])
    with pytest.raises(InvalidArgumentError) as err:
        args.func(args)
    assert err.value.argument == "--out"


def test_options_and_defaults(tmp_path):
    cfg = config_from_args(_parse(["--out", str(tmp_path)]))
    assert cfg.vertices == VERTEX_COUNTS and cfg.problems == ("RMPC", "OfflineRMPC", "GIPC")
    assert cfg.steps == 40 and not cfg.quick
    cfg = config_from_args(_parse(["--out", str(tmp_path), "--quick", "--vertices", "8", "2", "8",
                                   "--problems", "gipc", "RMPC"]))
    assert cfg.vertices == (2, 8) and cfg.problems == ("RMPC", "GIPC") and cfg.steps == 3
    with pytest.raises(SystemExit):  # --out is required (argparse: exit status 2)
        _parse([])


@pytest.mark.parametrize("count", VERTEX_COUNTS)
def test_polytopes_hold_the_nominal_plant(count):
    poly = polytope(count)
    assert poly.n_vertices == count
    # The nominal B (inertia J0) is a convex combination of the vertices' B: the corners in 1/J
    # average to 1/J0 only approximately, so check containment through the rate rows' diagonal.
    b_rates = np.array([np.diag(poly.B[j][3:]) for j in range(count)])
    nominal = np.diag(poly.nominal[1][3:])
    assert np.all(b_rates.min(axis=0) <= nominal) and np.all(nominal <= b_rates.max(axis=0))
    if count == 4:  # Ixx = Iyy scaled together
        assert np.allclose(b_rates[:, 0], b_rates[:, 1])


def test_scale_section_quick_run(tmp_path, monkeypatch):
    """``--problems Scale --quick``: the 6-state rigid hub of the flexible model at 2 and 8
    vertices, 2 states each, and cvxpy + Clarabel (textbook and delta LMIs) on the first state
    (~6 s). Every path has a record with its state dimension and formulation; the IPM ends
    optimal on every state and agrees with Clarabel wherever Clarabel is optimal; the report has
    the scale table and the time-against-size figure.

    The gamma error is taken over the states where both the path and Clarabel are optimal, so
    the number of comparisons is Clarabel's count of optimal states. Measured: Clarabel optimal
    on both states at 2 vertices (IPM warm and cold within 1.7e-7 of it), "inaccurate" on both at
    8 vertices (nothing to compare, error ``None``). Asserted: at least the 2-vertex comparisons
    happen, the error is ``None`` exactly when nothing was compared, and below 1e-6 (6x the
    measured 1.7e-7; both solvers stop at a relative gap of 1e-8)."""
    built = capture(monkeypatch, timing_scale, "scale_figure")
    out = tmp_path / "scale"
    args = _parse(["--out", str(out), "--quick", "--problems", "Scale", "--no-progress",
                   "--scale-cvxpy-steps", "1"])
    assert args.func(args) == 0
    records = json.loads((out / "timing.json").read_text())["records"]
    paths = {("ipm", "delta_shared"), ("ipm-cold", "delta_shared"), ("clarabel", "delta_shared"),
             ("cvxpy:CLARABEL", "standard"), ("cvxpy:CLARABEL", "delta")}
    assert {(r["backend"], r["formulation"], r["vertices"], r["n_states"]) for r in records} == {
        (*p, v, 6) for p in paths for v in (2, 8)}
    assert all(r["steps"] == 1 for r in records if r["backend"] == "cvxpy:CLARABEL")
    reference = {r["vertices"]: r for r in records if r["backend"] == "clarabel"}
    compared = {}
    for rec in records:
        assert rec["problem"] == "Scale"
        assert 0 < rec["p50_s"] <= rec["p95_s"] <= rec["max_s"]
        if rec["backend"].startswith("ipm"):
            assert rec["status_counts"] == {"optimal": 2}
            count = reference[rec["vertices"]]["status_counts"].get("optimal", 0)
            compared[rec["backend"], rec["vertices"]] = count
            assert (rec["max_rel_err"] is None) == (count == 0)
            if count:
                assert rec["max_rel_err"] < 1e-6
    assert compared["ipm", 2] == compared["ipm-cold", 2] == 2
    assert reference[2]["max_rel_err"] == 0.0  # the reference is Clarabel's own path
    md = (out / "timing.md").read_text()
    assert "## Scale" in md and "timing_scale.png" in md
    assert (out / "timing_scale.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the figure: one line per path and vertex count at the state dimension, at its p50
    ((_args, fig),) = built
    (ax,) = visible_axes(fig)
    assert ax.get_yscale() == "log" and ax.get_xlabel() == "state dimension"
    lines = {c.get_label(): c.lines[0] for c in ax.containers}
    assert set(lines) == {f"{b} {f}, {v} vertices" for b, f in paths for v in (2, 8)}
    for rec in records:
        line = lines[f"{rec['backend']} {rec['formulation']}, {rec['vertices']} vertices"]
        assert list(line.get_xdata()) == [6] and list(line.get_ydata()) == [rec["p50_s"]]


@pytest.mark.parametrize("argv", [["--scale-sizes", "7"], ["--scale-steps", "0"],
                                  ["--scale-cvxpy-steps", "-1"], ["--problems", "scale", "LQR"]])
def test_scale_options_are_checked(argv):
    with pytest.raises(InvalidArgumentError, match=argv[0]):
        config_from_args(_parse(["--out", "x", *argv]))
