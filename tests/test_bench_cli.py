"""``rmpc bench``: the paper suite on a short horizon writes every file; bad input exits 2 in one line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from figure_checks import capture, curves, hline_values, visible_axes, vlines

import benchmarks.reports.figures as paper_figures
from benchmarks.cli import main
from benchmarks.families.rigid.defaults import U_MAX
from benchmarks.suites.paper import EXPERIMENTS, paper_cases

ROOT = Path(__file__).resolve().parent.parent

_CONTRACT_METRICS = ("sum_abs_err", "final_abs_err", "max_abs_u", "solve_time_p50")


def test_paper_suite_short_writes_every_file(tmp_path, capsys, monkeypatch):
    responses = capture(monkeypatch, paper_figures, "responses_figure")
    gammas = capture(monkeypatch, paper_figures, "gamma_figure")
    out = tmp_path / "paper"
    status = main(["bench", "paper", "--out", str(out), "--short", "--workers", "2"])
    stdout = capsys.readouterr().out
    assert status == 0, stdout
    assert "21 cases done, 0 failed" in stdout
    for name in ("results.json", "results.md", "results.csv", "results.tex", "results_table.json",
                 "run.json"):
        assert (out / name).stat().st_size > 0, name
    figures = {p.name for p in (out / "figures").glob("*.png")}
    assert figures == {f"{e}.png" for e in EXPERIMENTS} | {"E3_linear_vs_nonlinear.png", "gamma.png"}
    assert len(list((out / "traces").glob("*.npz"))) == 21

    records = json.loads((out / "results.json").read_text())
    assert isinstance(records, list) and len(records) == 21
    expected = {(c.experiment, c.scenario.controller, c.scenario.plant, c.scenario.saturation)
                for c in paper_cases()}
    assert {(r["experiment"], r["controller"], r["plant"], r["saturation"]) for r in records} == expected
    for rec in records:
        assert rec["plant"] in ("linear", "nonlinear")
        assert rec["saturation"] in ("none", "limiter", "constraint")
        for key in _CONTRACT_METRICS:
            assert key in rec["metrics"], key
        for key in ("sum_abs_err", "final_abs_err"):
            assert set(rec["metrics"][key]) == {"roll", "pitch", "yaw"}
        assert rec["settings"]["duration"] == pytest.approx(2.25)
        assert "Q_diag" in rec["settings"]["settings"] or rec["controller"] == "GIPC"
    by = {(r["experiment"], r["controller"], r["saturation"]): r for r in records}
    # E1 has no constraint: the torques jump far past the 1 N m limit at the start (paper P)
    assert by[("E1", "RMPC", "none")]["metrics"]["max_abs_u"] > 2.0
    assert by[("E1", "GIPC", "none")]["metrics"]["max_abs_u"] > 2.0
    # E2: the limiter and the constraints keep the applied torque within 1 N m
    for ctrl in ("RMPC", "GIPC"):
        for sat in ("limiter", "constraint"):
            assert by[("E2", ctrl, sat)]["metrics"]["max_abs_u"] <= 1.0 + 1e-9

    md = (out / "results.md").read_text()
    for exp in EXPERIMENTS:
        assert f"## {exp}" in md
    assert "## Settings" in md and "resolve_threshold" in md and "R_diag" in md
    assert "disturbance axes" in md and "figures/gamma.png" in md
    assert "\\begin{tabular}" in (out / "results.tex").read_text()
    assert (out / "results.csv").read_text().count("\n") == 22  # header + 21 cases
    _check_paper_figures(records, responses, gammas)


def _check_paper_figures(records, responses, gammas):
    """What the suite drew: per experiment one curve per run in each of the six panels, the
    +-U_MAX lines in the torque panels, the disturbance onset where there is one; gamma(k) of
    the runs with a cost bound (RMPC, CRMPC), one log panel per experiment."""
    runs = {}
    for rec in records:
        runs.setdefault(rec["experiment"], []).append(rec)
    runs["E3_linear_vs_nonlinear"] = runs["E2"] + runs["E3"]
    drawn = []
    for args, fig in responses:
        title = args[1]
        exp = "E3_linear_vs_nonlinear" if title.startswith("E2 (linear") else title.split(":")[0]
        drawn.append(exp)
        assert args[2] == U_MAX
        grid = visible_axes(fig)
        assert len(grid) == 6
        for ax in grid:
            assert len(curves(ax)) == len(runs[exp]), (exp, ax.get_ylabel())
        for ax in grid[1::2]:  # the torque column
            assert ax.get_ylabel().endswith("(N m)") and hline_values(ax) == [-U_MAX, U_MAX]
        onsets = [r for r in runs[exp] if r["settings"]["disturbance"]]
        assert len(vlines(grid[0])) == len(onsets)
    assert sorted(drawn) == sorted([*EXPERIMENTS, "E3_linear_vs_nonlinear"])
    ((_groups,), fig) = gammas[0]
    bounded = sorted({r["experiment"] for r in records if r["controller"] in ("RMPC", "CRMPC")})
    assert [ax.get_title() for ax in visible_axes(fig)] == bounded
    for ax in visible_axes(fig):
        expected = [r for r in runs[ax.get_title()] if r["controller"] in ("RMPC", "CRMPC")]
        assert ax.get_yscale() == "log" and len(curves(ax)) == len(expected)


def _sweep_file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("[base\nplant = 'linear'\n", "bad.toml"),  # malformed TOML
        ("[base]\nspredd = 0.1\n", "base.spredd"),  # unknown field
        ("[bases]\nspread = 0.1\n", "bases"),  # unknown table
        ("[grid]\nspread = [0.1, -0.2]\n", "grid.spread"),  # negative spread
        ("[base]\nu_max = 0.0\n", "base.u_max"),  # u_max <= 0
        ("[base]\nu_max = -1\n", "base.u_max"),
        ("[grid]\ncontroller = ['RMPC', 'MPC2']\n", "grid.controller"),  # unknown controller
        ("[grid]\nsettings.Npp = [1]\n", "grid.settings.Npp"),
        ("[grid]\nspread = 0.3\n", "grid.spread"),  # not a list
        ("[grid]\nsped = [0.3]\n", "grid.sped"),
        ("[montecarlo]\nn = 0\n", "montecarlo.n"),
        ("[montecarlo]\nn = 2\ndraws = 3\n", "montecarlo.draws"),
    ],
)
def test_bad_sweep_input_exits_2_with_one_line_naming_the_field(tmp_path, capsys, text, field):
    config = _sweep_file(tmp_path, text)
    status = main(["bench", "sweep", "--config", str(config), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("rmpc: error: ")
    assert field in lines[0] and "expected" in lines[0]
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()  # nothing written for a bad file


def test_missing_config_file_exits_2(tmp_path, capsys):
    status = main(["bench", "sweep", "--config", str(tmp_path / "none.toml"), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1 and "--config" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["bench", "sweep", "--config", "x.toml", "--out", "o", "--workers", "-1"],
        ["bench", "sweep", "--out", "o"],
        ["bench", "paper", "--out", "o", "--duration-scale", "0"],
        ["bench", "paper", "--out", "o", "--short", "--duration-scale", "0.5"],
        ["bench", "tables"],
    ],
)
def test_bad_usage_exits_2(argv, capsys):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert "Traceback" not in capsys.readouterr().err


def test_unknown_experiment_exits_2(tmp_path, capsys):
    status = main(["bench", "paper", "--out", str(tmp_path / "p"), "--experiments", "E1,E9"])
    err = capsys.readouterr().err
    assert status == 2 and "--experiments" in err and "'E9'" in err


def test_bad_input_through_the_installed_entry_point_has_no_traceback(tmp_path):
    config = _sweep_file(tmp_path, "[base]\ncontroller = 'PID'\n")
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks.cli", "bench", "sweep", "--config", str(config), "--out",
         str(tmp_path / "o")], capture_output=True, text=True, cwd=ROOT, timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "rmpc: error: base.controller: expected one of 'RMPC', 'GIPC', 'CRMPC', 'CRMPC-MIT', 'OfflineRMPC', "
        "'LQR', but found 'PID'"
    ]


def test_bench_help_lists_paper_and_sweep(capsys):
    with pytest.raises(SystemExit) as info:
        main(["bench", "sweep", "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    assert "--scheduler" in out and "--workers" in out and "--config" in out


def test_timing_command_is_wired_into_the_parser(capsys):
    pytest.importorskip("benchmarks.timing")
    with pytest.raises(SystemExit) as info:
        main(["timing", "--help"])
    assert info.value.code == 0
    assert "--out" in capsys.readouterr().out


def test_paper_results_md_states_every_claim(tmp_path):
    out = tmp_path / "paper"
    assert main(["bench", "paper", "--out", str(out), "--short", "--workers", "0",
                 "--experiments", "E4,E5"]) == 0
    md = (out / "results.md").read_text()
    assert "## Paper P's claims" in md
    for exp in ("E4", "E5"):
        assert f"**{exp}: " in md
    assert "**E1: not run.**" in md
