"""What rmpc refuses: damaged or foreign stores, another sweep's folder, oversized sweeps, bad options.

Each case used to end in a traceback (sqlite3 and json errors), or silently mixed two sweeps'
results in one folder.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from benchmarks.cli import main
from benchmarks.core.store import CaseStore
from dev.robustness.cli_cases import TINY_SWEEP
from toolkit_common.errors import ConfigError, StoreError

TINY = TINY_SWEEP  # one short case of LQR on the linear plant


def _store_with_rows(path: Path, n: int = 20) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with CaseStore(path) as store:
        run = store.begin_run("test")
        for k in range(n):
            store.put_done(f"case{k:02d}", k, {"plant": "linear"}, {"metrics": {"x": k}}, run)


def _random_bytes(path: Path) -> None:
    path.write_bytes(np.random.default_rng(0).bytes(8192))


def _truncated(path: Path) -> None:
    _store_with_rows(path)
    size = path.stat().st_size
    with open(path, "r+b") as handle:
        handle.truncate(size // 2)


def _foreign_schema(path: Path) -> None:
    with sqlite3.connect(path) as connection:
        connection.execute("CREATE TABLE cases (id INTEGER, payload BLOB)")


def _folder(path: Path) -> None:
    path.mkdir()


DAMAGE = {"random bytes": _random_bytes, "truncated": _truncated, "foreign schema": _foreign_schema,
          "folder": _folder}


@pytest.mark.parametrize("kind", list(DAMAGE))
def test_a_damaged_store_is_refused_naming_the_file_and_what_to_do(tmp_path, kind):
    path = tmp_path / "sweep.sqlite"
    DAMAGE[kind](path)
    with pytest.raises(StoreError) as info:
        CaseStore(path)
    message = str(info.value)
    assert str(path) in message and "--out" in message


@pytest.mark.parametrize("kind", list(DAMAGE))
def test_the_cli_reports_a_damaged_store_in_one_line_with_exit_2(tmp_path, capsys, kind):
    config = tmp_path / "tiny.toml"
    config.write_text(TINY)
    out = tmp_path / "out"
    out.mkdir()
    DAMAGE[kind](out / "sweep.sqlite")
    code = main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0",
                 "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "sweep.sqlite" in err


def test_a_record_that_is_not_json_names_the_case(tmp_path):
    path = tmp_path / "sweep.sqlite"
    _store_with_rows(path)
    with sqlite3.connect(path) as connection:
        connection.execute("UPDATE cases SET record = '{not json' WHERE case_id = 'case03'")
    with CaseStore(path) as store, pytest.raises(StoreError, match="case03"):
        store.rows()


def test_a_locked_store_is_reported_as_locked(tmp_path):
    path = tmp_path / "sweep.sqlite"
    _store_with_rows(path, 1)
    holder = sqlite3.connect(path)
    holder.execute("BEGIN EXCLUSIVE")
    try:
        with CaseStore(path, timeout=0.1) as store, pytest.raises(StoreError, match="locked"):
            store.begin_run("second writer")
    finally:
        holder.rollback()
        holder.close()


def test_another_sweeps_folder_is_refused_then_replaced_with_overwrite(tmp_path, capsys):
    config = tmp_path / "tiny.toml"
    config.write_text(TINY)
    other = tmp_path / "other.toml"
    other.write_text(TINY.replace('name = "tiny"', 'name = "other"'))
    out = tmp_path / "out"
    args = ["bench", "sweep", "--out", str(out), "--workers", "0", "--no-progress"]
    assert main([*args, "--config", str(other)]) == 0
    before = (out / "results.json").read_text()
    capsys.readouterr()
    assert main([*args, "--config", str(config)]) == 2
    err = capsys.readouterr().err
    assert "'other'" in err and "--overwrite" in err and len(err.strip().splitlines()) == 1
    assert (out / "results.json").read_text() == before  # nothing overwritten
    assert main([*args, "--config", str(config), "--overwrite"]) == 0
    with CaseStore(out / "sweep.sqlite") as store:
        assert store.sweep_name() == "tiny"
        assert len(store.rows()) == 1


def test_a_suites_results_folder_is_refused_for_a_sweep(tmp_path, capsys):
    config = tmp_path / "tiny.toml"
    config.write_text(TINY)
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.json").write_text(json.dumps([{"experiment": "E1"}]))
    assert main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0"]) == 2
    assert "results.json without a sweep store" in capsys.readouterr().err


def test_the_same_sweep_resumes_in_its_own_folder(tmp_path):
    config = tmp_path / "tiny.toml"
    config.write_text(TINY)
    args = ["bench", "sweep", "--config", str(config), "--out", str(tmp_path / "out"), "--workers", "0",
            "--no-progress"]
    assert main(args) == 0
    assert main(args) == 0


@pytest.mark.parametrize(
    ("argv", "word"),
    [
        (["bench", "paper", "--out", "", "--workers", "0"], "--out"),
        (["bench", "paper", "--out", "X", "--experiments", ""], "--experiments"),
        (["bench", "paper", "--out", "X", "--experiments", "E1,,E2"], "--experiments"),
        (["bench", "paper", "--out", "X", "--workers", "100000"], "--workers"),
        (["bench", "paper", "--out", "X", "--duration-scale", "1e12"], "--duration-scale"),
        (["bench", "paper", "--out", "X", "--duration-scale", "nan"], "--duration-scale"),
    ],
)
def test_bad_options_are_refused_before_anything_runs(tmp_path, capsys, monkeypatch, argv, word):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert word in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_an_out_that_is_a_file_is_refused(tmp_path, capsys):
    target = tmp_path / "file.txt"
    target.write_text("x")
    with pytest.raises(SystemExit) as info:
        main(["bench", "paper", "--out", str(target)])
    assert info.value.code == 2 and "--out" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["-1", "nan", "1e13"])
def test_demo_duration_out_of_range_is_one_line_naming_the_option(capsys, value):
    assert main(["demo", "--duration", value]) == 2
    err = capsys.readouterr().err
    assert "--duration" in err and len(err.strip().splitlines()) == 1


TEN_VALUES = "[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]"
TEN_FIELDS = ("u_max", "ic_scale", "duration", "disturbance", "disturbance_start")
GRID_OF_A_MILLION = "[grid]\n" + "".join(f"{field} = {TEN_VALUES}\n" for field in TEN_FIELDS) + (
    "spread = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]\n"
)


def _write_sweep(tmp_path: Path, body: str) -> Path:
    config = tmp_path / "sweep.toml"
    config.write_text(body)
    return config


@pytest.mark.parametrize(
    ("extra", "where"),
    [
        (GRID_OF_A_MILLION, "grid"),
        ("[montecarlo]\nn = 10000000000000\nseed = 1\n", "montecarlo.n"),
    ],
    ids=["grid 10^6", "draws 10^13"],
)
def test_a_sweep_beyond_max_cases_is_refused_before_expanding(tmp_path, extra, where):
    from benchmarks.core.sweep_spec import load_sweep

    body = TINY.replace('plant = "linear"', 'plant = "nonlinear"') if "montecarlo" in extra else TINY
    with pytest.raises(ConfigError) as info:
        load_sweep(_write_sweep(tmp_path, body + extra))
    assert info.value.argument == where and "max_cases" in str(info.value)


def test_max_cases_lifts_the_bound(tmp_path):
    from benchmarks.core.sweep_spec import expand, load_sweep

    body = TINY + "[grid]\nduration = [0.1, 0.2, 0.3]\n"
    with pytest.raises(ConfigError, match="max_cases = 2 cases"):
        load_sweep(_write_sweep(tmp_path, "max_cases = 2\n" + body))
    assert len(expand(load_sweep(_write_sweep(tmp_path, "max_cases = 3\n" + body)))) == 3


def test_a_deeply_nested_or_oversized_sweep_file_is_refused(tmp_path):
    from benchmarks.core.sweep_spec import load_sweep

    deep = 'name = "deep"\n[base]\nsettings = ' + "[" * 5000 + "1" + "]" * 5000 + "\n"
    with pytest.raises(ConfigError, match="nested too deep"):
        load_sweep(_write_sweep(tmp_path, deep))
    big = 'name = "big"\ndescription = "' + "x" * (2**20 + 1) + '"\n'
    with pytest.raises(ConfigError, match="at most 1048576 bytes"):
        load_sweep(_write_sweep(tmp_path, big))


@pytest.mark.parametrize("name", ["a\\n# b", "", "  ", "tab\\there"])
def test_a_sweep_name_must_be_one_printable_line(tmp_path, name):
    from benchmarks.core.sweep_spec import load_sweep

    with pytest.raises(ConfigError) as info:
        load_sweep(_write_sweep(tmp_path, TINY.replace('name = "tiny"', f'name = "{name}"')))
    assert info.value.argument == "name"


def test_a_case_past_its_time_limit_is_stored_as_time_limit_and_the_rest_runs(tmp_path):
    """Two RMPC cases on the linear plant: 0.2 s (20 samples, well under a second) is done; 1200 s
    (120000 samples; 120 s of it took 6-9 s here, 1200 s about ten times that) is stopped by a
    5 s limit and stored as a time_limit error.
    The solver's compiled kernels are loaded first (after a fresh install that compiles them,
    10-20 s), so the short case's time is its own: at 5 s and a load of about 6 it was once cut."""
    from lmi.ipm import BlockLMISolver

    BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])])  # loads (or compiles) the kernels
    body = TINY.replace('controller = "LQR"', 'controller = "RMPC"') + "[grid]\nduration = [0.2, 1200.0]\n"
    config = _write_sweep(tmp_path, body)
    out = tmp_path / "out"
    args = ["--out", str(out), "--workers", "0", "--no-progress", "--case-time-limit", "5"]
    assert main(["bench", "sweep", "--config", str(config), *args]) == 1  # a case failed
    with CaseStore(out / "sweep.sqlite") as store:
        rows = {row["scenario"]["duration"]: row for row in store.rows()}
    stopped = rows[1200.0]
    assert stopped["status"] == "error" and stopped["error"].startswith("time_limit: "), stopped["error"]
    assert rows[0.2]["status"] == "done"


# --- sizes that a case would refuse after the sweep started are refused when the file is read -----

WHEEL = 'name = "w"\n[base]\nfamily = "wheel"\ncontroller = "ABFTC"\nsaturation = "limiter"\n'
MRP = 'name = "m"\n[base]\nfamily = "mrp"\ncontroller = "BS"\n'
FLEXIBLE = 'name = "f"\n[base]\nfamily = "flexible"\ncontroller = "MTSMC"\n'
GIPC_TINY = TINY.replace('controller = "LQR"', 'controller = "GIPC"')
OFFLINE_TINY = TINY.replace('controller = "LQR"', 'controller = "OfflineRMPC"')

STEPS, HORIZON, ELLIPSOIDS = "MAX_STEPS = 10000000", "MAX_HORIZON = 20000", "at most 40 for shrink = 0.5"
READ_TIME_SIZES = {
    # name: (sweep file, the key the error names, the limit it states)
    "duration 1e12": (TINY.replace("duration = 0.2", "duration = 1e12"), "base.duration", STEPS),
    "grid duration 1e12": (TINY + "[grid]\nduration = [0.2, 1e12]\n", "grid.duration", STEPS),
    "wheel dt 1e-9": (WHEEL + "dt = 1e-9\n", "base.dt", STEPS),
    "wheel dt past the run": (WHEEL + "dt = 1000.0\n", "base.dt", "at least one sample"),
    "mrp dt 1e-9": (MRP + "dt = 1e-9\nplant_step = 1e-9\n", "base.dt", STEPS),
    "flexible dt 1e-9": (FLEXIBLE + "dt = 1e-9\n", "base.dt", STEPS),
    "GIPC Np 10^6": (GIPC_TINY + "[base.settings]\nNp = 1000000\n", "base.settings.Np", HORIZON),
    "GIPC grid Np": (GIPC_TINY + "[grid]\nsettings.Np = [400, 20001]\n", "grid.settings.Np", HORIZON),
    "wheel GIPC Np": (
        WHEEL.replace('"ABFTC"', '"GIPC"') + "[base.settings]\nNp = 1000000\n", "base.settings.Np", HORIZON
    ),
    "OfflineRMPC 41 ellipsoids": (
        OFFLINE_TINY + "[base.settings]\nn_ellipsoids = 41\n", "base.settings.n_ellipsoids", ELLIPSOIDS
    ),
    "flexible OfflineRMPC 41 ellipsoids": (
        FLEXIBLE.replace('"MTSMC"', '"OfflineRMPC"') + "[base.settings]\nn_ellipsoids = 41\n",
        "base.settings.n_ellipsoids",
        ELLIPSOIDS,
    ),
}


@pytest.mark.parametrize(("body", "where", "limit"), READ_TIME_SIZES.values(), ids=list(READ_TIME_SIZES))
def test_a_size_beyond_what_a_case_runs_is_refused_when_the_sweep_is_read(tmp_path, body, where, limit):
    """Each of these ran and then failed in every case (exit 1 after running); now the reader names
    the key, the limit and what to do."""
    from benchmarks.core.sweep_spec import load_sweep

    with pytest.raises(ConfigError) as info:
        load_sweep(_write_sweep(tmp_path, body))
    assert info.value.argument == where, str(info.value)
    assert limit in info.value.expected, str(info.value)
    if "MAX_" in limit:
        assert "lifts it" in info.value.expected


@pytest.mark.parametrize("name", ["duration 1e12", "GIPC Np 10^6"])
def test_the_cli_refuses_such_a_sweep_with_one_line_before_running(tmp_path, capsys, name):
    body, where, _ = READ_TIME_SIZES[name]
    config, out = _write_sweep(tmp_path, body), tmp_path / "out"
    assert main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"rmpc: error: {where}: ") and err.count("\n") == 1, err
    assert not out.exists()  # refused before the folder (or any case) was made


def test_the_read_time_bound_on_samples_is_the_simulators(monkeypatch):
    """``check_run_length`` takes exactly what ``simulate`` takes by default: round(duration / dt) up to
    ``rmpc.sim.simulate.MAX_STEPS`` samples, and at least one."""
    import importlib
    import inspect

    from benchmarks.core.family import check_run_length

    sim = importlib.import_module("rmpc.sim.simulate")  # the module (rmpc.sim.simulate is also the function)

    assert inspect.signature(sim.simulate).parameters["max_steps"].default == sim.MAX_STEPS
    assert check_run_length(float(sim.MAX_STEPS), 1.0, "duration") == sim.MAX_STEPS
    assert check_run_length(sim.MAX_STEPS + 0.4, 1.0, "duration") == sim.MAX_STEPS  # rounds like simulate
    with pytest.raises(ConfigError, match="MAX_STEPS"):
        check_run_length(sim.MAX_STEPS + 0.6, 1.0, "duration")
    assert check_run_length(0.6, 1.0, "dt") == 1
    with pytest.raises(ConfigError, match="at least one sample"):
        check_run_length(0.4, 1.0, "dt")
    monkeypatch.setattr(sim, "MAX_STEPS", 10)  # the bound is read from the simulator, not copied
    with pytest.raises(ConfigError, match="MAX_STEPS = 10 "):
        check_run_length(0.11, 0.01, "duration")
