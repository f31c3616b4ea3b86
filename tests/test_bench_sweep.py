"""Sweeps: expansion, the store, resuming after SIGINT or a killed worker, errors, Dask vs serial."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from benchmarks.cli import main
from benchmarks.core import runner
from benchmarks.core.store import STORE_NAME
from benchmarks.core.sweep import expand, left_out, load_sweep, parse_sweep
from models import PAPER_P_INERTIA
from toolkit_common.errors import ConfigError

ROOT = Path(__file__).resolve().parent.parent
SWEEPS = ROOT / "benchmarks" / "sweeps"

#: 16 GIPC runs of 2.5 s on the nonlinear satellite (a fifth of a second of CPU each).
_RESUMABLE = """
name = "resumable"
[base]
controller = "GIPC"
plant = "nonlinear"
duration = 2.5
[montecarlo]
n = 16
seed = 3
"""

#: Metrics that measure time and so differ between runs.
_TIMING = ("solve_time", "step_time", "wall_time")


def _write(tmp_path: Path, text: str, name: str = "sweep.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _store_rows(out: Path) -> list[tuple]:
    with sqlite3.connect(out / STORE_NAME) as db:
        return list(db.execute("SELECT case_id, status, run FROM cases"))


def _cli(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "benchmarks.cli", "bench", "sweep", *args, "--no-progress"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )


def _wait_for_done(out: Path, at_least: int, proc: subprocess.Popen, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        if (out / STORE_NAME).exists():
            try:
                if sum(1 for r in _store_rows(out) if r[1] == "done") >= at_least:
                    return
            except sqlite3.OperationalError:  # the schema is being created
                pass
        time.sleep(0.05)
    raise AssertionError("the sweep did not progress")


# -- expansion -----------------------------------------------------------------------------------


def test_shipped_sweep_files_are_valid_and_smoke_is_small():
    files = sorted(SWEEPS.glob("*.toml"))
    assert "smoke.toml" in {f.name for f in files} and len(files) >= 3
    for path in files:
        assert expand(load_sweep(path)), path
    smoke = expand(load_sweep("smoke"))  # a shipped sweep by name
    assert 1 <= len(smoke) <= 8
    assert all(sc.duration <= 2.0 for sc in smoke)


def test_grid_times_draws_with_stable_ids_and_draws_inside_the_box():
    spec = parse_sweep({
        "base": {"controller": "LQR", "saturation": "limiter", "mode": "box"},
        "grid": {"plant": ["linear", "nonlinear"], "spread": [0.1, 0.5], "settings": {"R_diag": [[1, 1, 1]]}},
        "montecarlo": {"n": 5, "seed": 11},
    })
    cases = expand(spec)
    assert len(cases) == 2 * 2 * 5
    assert [c.case_id for c in cases] == [c.case_id for c in expand(spec)]  # stable
    assert len({c.case_id for c in cases}) == 20
    for c in cases:
        ratio = np.asarray(c.true_inertia) / np.asarray(PAPER_P_INERTIA)
        assert np.all(np.abs(ratio - 1.0) <= c.spread + 1e-12)
        assert c.settings["R_diag"] == (1.0, 1.0, 1.0)
    # the same draws for every grid point (common random numbers)
    rel = [tuple(np.round((np.asarray(c.true_inertia) / PAPER_P_INERTIA - 1) / c.spread, 12)) for c in cases]
    assert rel[:5] == rel[5:10] == rel[15:20]
    # scalar mode: one factor for the three axes
    scalar = expand(parse_sweep({"base": {"controller": "GIPC"}, "montecarlo": {"n": 3, "seed": 1}}))
    for c in scalar:
        ratio = np.asarray(c.true_inertia) / np.asarray(PAPER_P_INERTIA)
        assert np.ptp(ratio) < 1e-12


def test_one_settings_table_serves_several_controllers():
    spec = parse_sweep({"base": {"settings": {"Np": 100, "resolve_threshold": 0.8}},
                        "grid": {"controller": ["RMPC", "GIPC"]}})
    rmpc, gipc = expand(spec)
    assert rmpc.settings["resolve_threshold"] == 0.8 and "Np" not in rmpc.settings
    assert gipc.settings["Np"] == 100 and "resolve_threshold" not in gipc.settings
    # a setting no controller of the sweep has is a mistake, not silently ignored
    with pytest.raises(ConfigError) as info:
        parse_sweep({"base": {"controller": "RMPC", "settings": {"Np": 100}}})
    assert info.value.argument == "base.settings.Np" and "GIPC only" in str(info.value)
    with pytest.raises(ConfigError) as info:
        parse_sweep({"grid": {"controller": ["RMPC"], "settings": {"Nc": [2, 3]}}})
    assert info.value.argument == "grid.settings.Nc"


def test_combinations_a_controller_cannot_run_are_left_out_and_listed():
    spec = parse_sweep({"grid": {"controller": ["LQR", "RMPC"], "saturation": ["limiter", "constraint"]}})
    cases = expand(spec)
    assert [(c.controller, c.saturation) for c in cases] == [
        ("LQR", "limiter"), ("RMPC", "limiter"), ("RMPC", "constraint")
    ]
    assert left_out(spec) == ["LQR with saturation = 'constraint'"]
    with pytest.raises(ConfigError) as info:  # nothing left to run: an error naming the field
        parse_sweep({"base": {"controller": "LQR"}})
    assert info.value.argument == "base.saturation"
    with pytest.raises(ConfigError) as info:  # a combination impossible otherwise
        parse_sweep({"base": {"dt": 0.1}, "grid": {"duration": [1.0, 0.05]}})
    assert info.value.argument == "grid.duration"


def test_repeated_grid_values_run_once():
    cases = expand(parse_sweep({"base": {"controller": "GIPC"}, "grid": {"u_max": [1, 1.0, 2]}}))
    assert len(cases) == 2


# -- the store, errors, resuming -------------------------------------------------------------------


def test_a_failing_case_is_recorded_and_the_sweep_goes_on(tmp_path, capsys, monkeypatch):
    config = _write(tmp_path, """
[base]
controller = "LQR"
saturation = "limiter"
plant = "linear"
duration = 0.3
[grid]
u_max = [0.5, 1.0, 2.0]
""")
    original = runner.simulate_scenario

    def flaky(scenario, *args, **kwargs):
        if scenario.u_max == 1.0:
            raise FloatingPointError("boom in the middle")
        return original(scenario, *args, **kwargs)

    monkeypatch.setattr(runner, "simulate_scenario", flaky)
    out = tmp_path / "out"
    assert main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0"]) == 1
    captured = capsys.readouterr()
    assert "3 cases, 0 finished before, 3 run now (1 failed)" in captured.out
    rows = _store_rows(out)
    assert sorted(r[1] for r in rows) == ["done", "done", "error"]
    errors = json.loads((out / "errors.json").read_text())
    assert errors[0]["error"] == "FloatingPointError: boom in the middle"
    assert "Traceback" in errors[0]["traceback"]
    assert len(json.loads((out / "results.json").read_text())) == 2
    assert "boom in the middle" in (out / "results.md").read_text()
    # a re-run skips every stored case, the failed one too ...
    assert main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0"]) == 1
    assert "3 finished before, 0 run now" in capsys.readouterr().out
    # ... unless asked to retry it
    monkeypatch.setattr(runner, "simulate_scenario", original)
    assert main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0",
                 "--retry-errors"]) == 0
    assert sorted(r[1] for r in _store_rows(out)) == ["done", "done", "done"]
    assert (out / "results.csv").read_text().count("\n") == 4


def test_sigint_then_rerun_finishes_every_case_exactly_once(tmp_path):
    config = _write(tmp_path, _RESUMABLE)
    out = tmp_path / "out"
    proc = _cli("--config", str(config), "--out", str(out), "--workers", "2")
    _wait_for_done(out, 2, proc)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr and "Traceback" not in stderr
    first = {cid: run for cid, status, run in _store_rows(out)}
    assert 2 <= len(first) < 16
    assert all(status == "done" for _, status, _ in _store_rows(out))
    assert len(json.loads((out / "results.json").read_text())) == len(first)  # written on interrupt too

    again = _cli("--config", str(config), "--out", str(out), "--workers", "2")
    stdout, stderr = again.communicate(timeout=180)
    assert again.returncode == 0, stderr
    assert f"16 cases, {len(first)} finished before, {16 - len(first)} run now (0 failed)" in stdout
    rows = _store_rows(out)
    assert len(rows) == 16 and len({r[0] for r in rows}) == 16
    assert all(r[1] == "done" for r in rows)
    assert {cid: run for cid, _, run in rows if cid in first} == first  # not run a second time
    assert {run for cid, _, run in rows if cid not in first} == {2}
    records = json.loads((out / "results.json").read_text())
    assert sorted(r["experiment"] for r in records) == sorted(r[0] for r in rows)


def test_killed_worker_is_replaced_and_every_case_runs_exactly_once(tmp_path):
    psutil = pytest.importorskip("psutil")
    config = _write(tmp_path, _RESUMABLE)
    out = tmp_path / "out"
    proc = _cli("--config", str(config), "--out", str(out), "--workers", "2")
    _wait_for_done(out, 1, proc)
    parent = psutil.Process(proc.pid)
    # workers are forked by the forkserver (a child of the sweep), or are direct children (spawn)
    workers = [w for child in parent.children() for w in child.children()]
    workers += [c for c in parent.children() if "multiprocessing" not in " ".join(c.cmdline())]
    assert workers, [p.cmdline() for p in parent.children(recursive=True)]
    os.kill(workers[0].pid, signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 0, stderr
    assert "restarted the workers" in stderr
    rows = _store_rows(out)
    assert len(rows) == 16 and len({r[0] for r in rows}) == 16 and all(r[1] == "done" for r in rows)

    again = _cli("--config", str(config), "--out", str(out), "--workers", "2")
    stdout, stderr = again.communicate(timeout=120)
    assert again.returncode == 0, stderr
    assert "16 cases, 16 finished before, 0 run now" in stdout
    assert _store_rows(out) == rows


# -- Dask --------------------------------------------------------------------------------------------


def _comparable(metrics: dict) -> dict:
    return {k: v for k, v in metrics.items() if not k.startswith(_TIMING)}


def _assert_close(a, b, where):
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            _assert_close(a[key], b[key], f"{where}.{key}")
    elif a is None or b is None or isinstance(a, str):
        assert a == b, where
    else:
        assert a == pytest.approx(b, rel=1e-9, abs=1e-12), where


def test_dask_local_cluster_gives_the_same_metrics_as_a_serial_run(tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    config = _write(tmp_path, """
[base]
plant = "nonlinear"
duration = 0.5
disturbance = 0.5
disturbance_start = 0.2
[grid]
controller = ["GIPC", "RMPC"]
[montecarlo]
n = 2
seed = 5
""")
    serial, dask_out = tmp_path / "serial", tmp_path / "dask"
    assert main(["bench", "sweep", "--config", str(config), "--out", str(serial), "--workers", "0"]) == 0
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", host="127.0.0.1",
        dashboard_address=":0",
    ) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        status = main(["bench", "sweep", "--config", str(config), "--out", str(dask_out), "--scheduler",
                       cluster.scheduler_address])
    assert status == 0
    assert "Dask scheduler tcp://127.0.0.1" in (dask_out / "results.md").read_text()
    a = {r["case_id"]: r for r in json.loads((serial / "results.json").read_text())}
    b = {r["case_id"]: r for r in json.loads((dask_out / "results.json").read_text())}
    assert set(a) == set(b) and len(a) == 4
    for cid in a:
        assert a[cid]["settings"] == b[cid]["settings"]
        _assert_close(_comparable(a[cid]["metrics"]), _comparable(b[cid]["metrics"]), cid)


def test_unreachable_scheduler_exits_2(tmp_path, capsys):
    config = _write(tmp_path, "[base]\ncontroller = 'GIPC'\nduration = 0.1\n")
    status = main(["bench", "sweep", "--config", str(config), "--out", str(tmp_path / "o"), "--scheduler",
                   "tcp://127.0.0.1:9"])
    err = capsys.readouterr().err
    assert status == 2 and "--scheduler" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
