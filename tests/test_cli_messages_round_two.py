"""Messages that pointed the wrong way: a read-only ``--out``, a form too big over many vertices.

Before, a read-only ``--out`` was reported as "a file SQLite cannot use" (the store's message,
after the sweep had started), ``--out`` under ``/proc`` as "No such file or directory" without the
option, and an RMPC over 256 vertices with one Lyapunov matrix per vertex pair was refused naming
``lyapunov, saturation`` although ``saturation`` was never set, without the vertex count.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

from benchmarks.cli import main
from dev.robustness.cli_cases import TINY_SWEEP
from toolkit_common.errors import InvalidArgumentError


def _read_only_folder(tmp_path: Path) -> str:
    """A folder no file can be made in: mode 0o555, or ``/proc/self`` for the superuser (whom modes
    do not stop)."""
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        (folder / "probe").touch()
    except OSError:
        return str(folder)
    (folder / "probe").unlink()
    if sys.platform.startswith("linux") and os.path.isdir("/proc/self"):
        return "/proc/self"
    pytest.skip("no read-only folder to try (the superuser writes through modes; no /proc)")


def _sweep(tmp_path: Path, out: str, capsys) -> tuple[int, str]:
    config = tmp_path / "sweep.toml"
    config.write_text(TINY_SWEEP)
    code = main(["bench", "sweep", "--config", str(config), "--out", out, "--workers", "0", "--no-progress"])
    return code, capsys.readouterr().err


def test_a_read_only_out_is_refused_naming_the_option_and_saying_it_is_not_writable(tmp_path, capsys):
    folder = _read_only_folder(tmp_path)
    with pytest.raises(SystemExit) as info:
        _sweep(tmp_path, folder, capsys)
    err = capsys.readouterr().err
    assert info.value.code == 2
    assert "argument --out" in err and "not writable" in err and repr(folder) in err
    assert "SQLite" not in err and "Traceback" not in err
    assert not (Path(folder) / "sweep.sqlite").exists()


def test_an_out_below_a_read_only_folder_names_the_option_and_the_folder(tmp_path, capsys):
    folder = _read_only_folder(tmp_path)
    with pytest.raises(SystemExit) as info:
        _sweep(tmp_path, os.path.join(folder, "new", "out"), capsys)
    err = capsys.readouterr().err
    assert info.value.code == 2
    assert "argument --out" in err and f"{folder!r} above it is not writable" in err


def test_an_out_below_a_file_names_the_option_and_the_file(tmp_path, capsys):
    (tmp_path / "a-file").write_text("x")
    with pytest.raises(SystemExit) as info:
        _sweep(tmp_path, str(tmp_path / "a-file" / "out"), capsys)
    err = capsys.readouterr().err
    assert info.value.code == 2
    assert "argument --out" in err and "a-file' above it is a file" in err


def test_a_writable_out_runs_and_leaves_no_trace_of_the_check(tmp_path, capsys):
    out = tmp_path / "out"
    code, _ = _sweep(tmp_path, str(out), capsys)
    assert code == 0
    assert not [p for p in out.iterdir() if p.name.startswith(".rmpc-write-test-")]


def test_timing_refuses_a_read_only_out_before_measuring(tmp_path, capsys):
    folder = _read_only_folder(tmp_path)
    code = main(["timing", "--out", os.path.join(folder, "timing")])
    err = capsys.readouterr().err
    assert code == 2 and "--out" in err and "not writable" in err


def test_a_form_too_big_over_256_vertices_names_the_vertices_and_the_option_given_only():
    from models import PolytopicModel
    from rmpc import RMPC

    b = np.array([[0.0], [0.1]])
    vertices = [(np.array([[1.0, 0.1], [0.0, 1.0 + 0.001 * k]]), b) for k in range(256)]
    plant = PolytopicModel(vertices=vertices, dt=0.1)
    with pytest.raises(InvalidArgumentError) as info:
        RMPC(plant, np.eye(2), np.eye(1), u_max=1.0, lyapunov="vertex_pairs")
    assert info.value.argument == "plant, lyapunov"
    assert info.value.found.startswith("256 vertices, lyapunov='vertex_pairs': ")
    assert "saturation" not in str(info.value)  # never set
    assert "fewer vertices" in info.value.expected and "lyapunov='common'" in info.value.expected
