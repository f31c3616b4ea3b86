"""The command line's bad and edge inputs: options, sweep files, damaged stores, sizes, schedulers."""

from __future__ import annotations

import json
import os
import sqlite3
from collections.abc import Callable

import numpy as np

from dev.robustness.probe import Expect, Probe

TINY_SWEEP = """name = "tiny"
description = "one short case"
[base]
plant = "linear"
controller = "LQR"
saturation = "limiter"
duration = 0.2
"""
"""A valid sweep of one case of 0.2 s (the damaged stores sit next to it)."""


SWEEP_ARGV = (
    "bench",
    "sweep",
    "--config",
    "{tmp}/sweep.toml",
    "--out",
    "{tmp}/out",
    "--workers",
    "0",
    "--no-progress",
)
"""``rmpc`` arguments of a sweep of ``{tmp}/sweep.toml`` into ``{tmp}/out``, run in-process."""


def _write(name: str, text: str | bytes) -> Callable[[str], None]:
    def setup(tmp: str) -> None:
        path = os.path.join(tmp, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        mode = "wb" if isinstance(text, bytes) else "w"
        with open(path, mode) as handle:
            handle.write(text)

    return setup


def _sweep_file(body: str) -> Callable[[str], None]:
    return _write("sweep.toml", body)


def _both(*setups: Callable[[str], None]) -> Callable[[str], None]:
    def setup(tmp: str) -> None:
        for step in setups:
            step(tmp)

    return setup


def _store_with_rows(tmp: str) -> str:
    from benchmarks.core.store import CaseStore

    path = os.path.join(tmp, "out", "sweep.sqlite")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with CaseStore(path) as store:
        run = store.begin_run("probe")
        for k in range(20):
            store.put_done(f"case{k:02d}", k, {"plant": "linear"}, {"metrics": {"x": k}}, run)
    return path


def _damaged_store(kind: str) -> Callable[[str], None]:
    def setup(tmp: str) -> None:
        _sweep_file(TINY_SWEEP)(tmp)
        path = os.path.join(tmp, "out", "sweep.sqlite")
        os.makedirs(os.path.dirname(path), exist_ok=True)
        if kind == "random bytes":
            with open(path, "wb") as handle:
                handle.write(np.random.default_rng(0).bytes(8192))
        elif kind == "truncated":
            _store_with_rows(tmp)
            size = os.path.getsize(path)
            with open(path, "r+b") as handle:
                handle.truncate(size // 2)
        elif kind == "foreign schema":
            with sqlite3.connect(path) as connection:
                connection.execute("CREATE TABLE cases (id INTEGER, payload BLOB)")
                connection.execute("INSERT INTO cases VALUES (1, x'00')")
        elif kind == "bad json":
            _store_with_rows(tmp)
            with sqlite3.connect(path) as connection:
                connection.execute("UPDATE cases SET record = '{not json' WHERE case_id = 'case03'")
        elif kind == "folder":
            os.makedirs(path)
        elif kind == "empty file":
            open(path, "wb").close()
        else:
            raise ValueError(kind)

    return setup


def _nested_toml(depth: int) -> str:
    return 'name = "deep"\n[base]\nsettings = ' + "[" * depth + "1" + "]" * depth + "\n"


def _another_sweep_results(tmp: str) -> None:
    _sweep_file(TINY_SWEEP)(tmp)
    out = os.path.join(tmp, "out")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "results.json"), "w") as handle:
        json.dump([{"experiment": "E1", "controller": "RMPC"}], handle)
    with open(os.path.join(out, "results.md"), "w") as handle:
        handle.write("# another sweep's results\n")


def _sweep(
    name: str, body: str, names: tuple[str, ...], kind: str = "sweep file", expect: Expect = "error"
) -> Probe:
    return Probe(
        f"cli:sweep {name}",
        "cli",
        names,
        argv=SWEEP_ARGV,
        setup=_sweep_file(body),
        kind=kind,
        expect=expect,
    )


def _store(kind: str) -> Probe:
    return Probe(
        f"cli:store {kind}",
        "cli",
        ("sweep.sqlite", "store"),
        argv=SWEEP_ARGV,
        setup=_damaged_store(kind),
        kind="store",
        expect="either" if kind == "empty file" else "error",  # SQLite takes an empty file as a new store
    )


def _paper(*options: str, names: tuple[str, ...], kind: str = "option", label: str | None = None) -> Probe:
    return Probe(
        f"cli:paper {label or ' '.join(options)}",
        "cli",
        names,
        argv=("bench", "paper", "--out", "{tmp}/out", "--no-progress", "--workers", "0", *options),
        kind=kind,
    )


def cli_probes() -> list[Probe]:
    """Every CLI probe."""
    base = TINY_SWEEP
    probes = [
        # the command and its options
        Probe("cli:no command", "cli", ("command", "choose", "required"), argv=(), kind="usage"),
        Probe("cli:unknown command", "cli", ("nonsense", "invalid choice"), argv=("nonsense",), kind="usage"),
        Probe(
            "cli:bench unknown suite",
            "cli",
            ("nonsense", "invalid choice"),
            argv=("bench", "nonsense"),
            kind="usage",
        ),
        Probe("cli:paper without --out", "cli", ("--out",), argv=("bench", "paper"), kind="usage"),
        _paper("--out", "", names=("--out",), label="--out ''"),
        _paper("--experiments", "", names=("--experiments",), label="--experiments ''"),
        _paper("--experiments", "E9", names=("--experiments", "E9")),
        _paper("--experiments", "E1,,E2", names=("--experiments",)),
        _paper("--duration-scale", "0", names=("--duration-scale",)),
        _paper("--duration-scale", "-1", names=("--duration-scale",)),
        _paper("--duration-scale", "nan", names=("--duration-scale",)),
        _paper("--duration-scale", "inf", names=("--duration-scale",)),
        _paper("--duration-scale", "1e12", names=("--duration-scale", "limit"), kind="size"),
        _paper("--workers", "-1", names=("--workers",)),
        _paper("--workers", "abc", names=("--workers",)),
        _paper("--workers", "100000", names=("--workers", "limit"), kind="size"),
        _paper("--scheduler", "not an address", names=("--scheduler",), kind="scheduler"),
        _paper("--scheduler", "tcp://", names=("--scheduler",), kind="scheduler"),
        _paper("--scheduler", "tcp://127.0.0.1:notaport", names=("--scheduler",), kind="scheduler"),
        _paper("--scheduler", "tls://", names=("--scheduler",), kind="scheduler"),
        _paper("--scheduler", "ws://host", names=("--scheduler",), kind="scheduler"),
        _paper("--scheduler", "inproc://", names=("--scheduler",), kind="scheduler"),
        _paper(
            "--scheduler",
            "tcp://127.0.0.1:1",
            names=("--scheduler", "127.0.0.1:1", "connect"),
            kind="scheduler",
            label="--scheduler unreachable",
        ),
        Probe(
            "cli:faults --experiments W9",
            "cli",
            ("--experiments", "W9"),
            argv=("bench", "faults", "--out", "{tmp}/out", "--experiments", "W9", "--no-progress"),
        ),
        Probe(
            "cli:mrp --workers -2",
            "cli",
            ("--workers",),
            argv=("bench", "mrp", "--out", "{tmp}/out", "--workers", "-2"),
        ),
        Probe(
            "cli:flexible --short --duration-scale 2",
            "cli",
            ("--short", "--duration-scale"),
            argv=("bench", "flexible", "--out", "{tmp}/out", "--short", "--duration-scale", "2"),
        ),
        Probe("cli:demo --duration -1", "cli", ("--duration",), argv=("demo", "--duration", "-1")),
        Probe("cli:demo --duration nan", "cli", ("--duration",), argv=("demo", "--duration", "nan")),
        Probe("cli:demo --duration abc", "cli", ("--duration",), argv=("demo", "--duration", "abc")),
        Probe(
            "cli:demo --duration 1e13",
            "cli",
            ("--duration", "limit"),
            argv=("demo", "--duration", "1e13"),
            kind="size",
        ),
        Probe(
            "cli:timing --steps 0", "cli", ("--steps",), argv=("timing", "--out", "{tmp}/t", "--steps", "0")
        ),
        Probe(
            "cli:timing --steps -3", "cli", ("--steps",), argv=("timing", "--out", "{tmp}/t", "--steps", "-3")
        ),
        Probe(
            "cli:timing --steps 1e9",
            "cli",
            ("--steps", "limit"),
            argv=("timing", "--out", "{tmp}/t", "--steps", str(10**9)),
            kind="size",
        ),
        Probe(
            "cli:timing --vertices 3",
            "cli",
            ("--vertices", "3"),
            argv=("timing", "--out", "{tmp}/t", "--vertices", "3"),
        ),
        Probe(
            "cli:timing --problems Foo",
            "cli",
            ("--problems", "Foo"),
            argv=("timing", "--out", "{tmp}/t", "--problems", "Foo"),
        ),
        Probe(
            "cli:timing --scale-sizes 7",
            "cli",
            ("--scale-sizes", "7"),
            argv=("timing", "--out", "{tmp}/t", "--problems", "Scale", "--scale-sizes", "7"),
        ),
        # sweep files
        Probe(
            "cli:sweep missing file",
            "cli",
            ("--config", "missing.toml"),
            argv=("bench", "sweep", "--config", "{tmp}/missing.toml", "--out", "{tmp}/out"),
            kind="sweep file",
        ),
        Probe(
            "cli:sweep config is a folder",
            "cli",
            ("--config",),
            argv=("bench", "sweep", "--config", "{tmp}", "--out", "{tmp}/out"),
            kind="sweep file",
        ),
        _sweep("malformed toml", "name = \n[base\n", ("sweep.toml", "toml")),
        _sweep("binary file", "\x00\x01\x02", ("sweep.toml", "toml")),
        _sweep("unknown top-level", base + "[extra]\nx = 1\n", ("extra",)),
        _sweep("unknown field", base.replace("duration", "durration"), ("durration",)),
        _sweep("unknown controller", base.replace('"LQR"', '"PID"'), ("controller", "PID")),
        _sweep("negative duration", base.replace("0.2", "-1.0"), ("duration",)),
        _sweep("duration nan", base.replace("0.2", "nan"), ("duration",)),
        _sweep("duration string", base.replace("0.2", '"long"'), ("duration",)),
        _sweep("duration huge", base.replace("0.2", "1e12"), ("duration", "limit"), kind="size"),
        # 20.49 samples: 20 run, and the record says so (duration_used = 0.2 next to duration = 0.2049)
        _sweep(
            "duration not a multiple of dt",
            base.replace("0.2", "0.2049"),
            ("duration", "dt"),
            expect="either",
        ),
        _sweep("dt tiny", base + "dt = 1e-12\n", ("dt", "duration"), kind="size"),
        _sweep(
            "GIPC Np huge",
            base.replace('"LQR"', '"GIPC"') + "[base.settings]\nNp = 1000000\n",
            ("Np", "MAX_HORIZON"),
            kind="size",
        ),
        _sweep(
            "OfflineRMPC n_ellipsoids huge",
            base.replace('"LQR"', '"OfflineRMPC"') + "[base.settings]\nn_ellipsoids = 10000000\n",
            ("n_ellipsoids",),
            kind="size",
        ),
        _sweep("dt zero", base + "dt = 0.0\n", ("dt",)),
        _sweep("spread 1.5", base + "spread = 1.5\n", ("spread",)),
        _sweep("u_max negative", base + "u_max = -1.0\n", ("u_max",)),
        _sweep("grid not a list", base + "[grid]\nspread = 0.3\n", ("grid.spread", "spread")),
        _sweep("grid empty list", base + "[grid]\nspread = []\n", ("grid.spread", "spread")),
        _sweep("grid unknown field", base + "[grid]\nspreed = [0.1]\n", ("spreed",)),
        _sweep(
            "grid huge",
            base
            + "[grid]\n"
            + "".join(f"settings.a{k} = [{', '.join(str(v) for v in range(10))}]\n" for k in range(6)),
            ("grid", "limit", "cases"),
            kind="size",
        ),
        _sweep(
            "montecarlo n huge",
            base + "[montecarlo]\nn = 10000000000000\nseed = 1\n",
            ("montecarlo.n", "n"),
            kind="size",
        ),
        _sweep("montecarlo n zero", base + "[montecarlo]\nn = 0\nseed = 1\n", ("montecarlo.n", "n")),
        _sweep("montecarlo n float", base + "[montecarlo]\nn = 2.5\nseed = 1\n", ("montecarlo.n", "n")),
        _sweep(
            "montecarlo seed string", base + '[montecarlo]\nn = 2\nseed = "x"\n', ("montecarlo.seed", "seed")
        ),
        _sweep("montecarlo unknown key", base + "[montecarlo]\nn = 2\nsed = 1\n", ("sed",)),
        _sweep("deeply nested", _nested_toml(5000), ("sweep.toml", "nest", "deep")),
        _sweep(
            "oversized",
            'name = "big"\ndescription = "' + "x" * (60 * 2**20) + '"\n' + base.split("\n", 2)[2],
            ("--config", "sweep.toml"),
            kind="size",
        ),
        _sweep("name with newlines", base.replace('name = "tiny"', 'name = "a\\n# b\\n"'), ("name",)),
        _sweep("settings unknown key", base + "[base.settings]\nfoo = 1\n", ("foo",)),
        _sweep("saturation unknown", base.replace('"limiter"', '"clip"'), ("saturation", "clip")),
        _sweep("disturbance_axes bad", base + "disturbance_axes = [5]\n", ("disturbance_axes",)),
        _sweep("true_inertia negative", base + "true_inertia = [-1.0, 1.0, 1.0]\n", ("true_inertia",)),
        _sweep("ic_scale nan", base + "ic_scale = nan\n", ("ic_scale",)),
        Probe(
            "cli:sweep --workers -1",
            "cli",
            ("--workers",),
            argv=("bench", "sweep", "--config", "{tmp}/sweep.toml", "--out", "{tmp}/out", "--workers", "-1"),
            setup=_sweep_file(base),
        ),
        Probe(
            "cli:sweep --out ''",
            "cli",
            ("--out",),
            argv=(
                "bench",
                "sweep",
                "--config",
                "{tmp}/sweep.toml",
                "--out",
                "",
                "--workers",
                "0",
                "--no-progress",
            ),
            setup=_sweep_file(base),
        ),
        Probe(
            "cli:sweep --out is a file",
            "cli",
            ("--out",),
            argv=(
                "bench",
                "sweep",
                "--config",
                "{tmp}/sweep.toml",
                "--out",
                "{tmp}/sweep.toml",
                "--workers",
                "0",
                "--no-progress",
            ),
            setup=_sweep_file(base),
        ),
        Probe(
            "cli:sweep --out holds another sweep's results",
            "cli",
            ("--out", "results"),
            argv=SWEEP_ARGV,
            setup=_another_sweep_results,
            kind="overwrite",
        ),
        Probe(
            "cli:sweep --scheduler not an address",
            "cli",
            ("--scheduler",),
            argv=(*SWEEP_ARGV[:6], "--scheduler", "not an address"),
            setup=_sweep_file(base),
            kind="scheduler",
        ),
        Probe(
            "cli:sweep --scheduler tls://",
            "cli",
            ("--scheduler",),
            argv=(*SWEEP_ARGV[:6], "--scheduler", "tls://"),
            setup=_sweep_file(base),
            kind="scheduler",
        ),
    ]
    probes += [
        _store(kind)
        for kind in ("random bytes", "truncated", "foreign schema", "bad json", "folder", "empty file")
    ]
    probes.append(
        Probe(
            "cli:sweep store from another sweep",
            "cli",
            ("sweep.sqlite", "store", "another"),
            argv=SWEEP_ARGV,
            setup=_both(_sweep_file(base), _store_with_rows),
            kind="store",
        )
    )
    return probes
