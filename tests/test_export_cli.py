"""``rmpc export c --controller FILE --out DIR``: the files of ``rmpc.export_c`` from a saved file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rmpc
from benchmarks.cli import main
from models import PolytopicModel
from rmpc import LQR, RMPC, export_c


def _plant() -> PolytopicModel:
    a = [np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * k]]) for k in (0.1, 10.0)]
    return PolytopicModel([(m, np.array([[0.0], [0.0787]])) for m in a], dt=0.1)


@pytest.mark.parametrize("kind", ["lqr", "rmpc"])
def test_the_command_writes_what_export_c_writes_for_the_loaded_controller(kind, tmp_path: Path,
                                                                           capsys) -> None:
    plant = _plant()
    if kind == "lqr":
        ctrl = LQR(PolytopicModel([plant.vertices[0]], dt=0.1), Q=np.eye(2), R=np.eye(1))
    else:
        ctrl = RMPC(plant, np.diag([1.0, 0.0]), [[2e-5]], u_max=2.0, input_constraint="peak")
    saved = ctrl.save(tmp_path / "design.rmpc")
    assert main(["export", "c", "--controller", str(saved), "--out", str(tmp_path / "cli")]) == 0
    printed = capsys.readouterr().out
    assert "rmpc_controller.h" in printed and "static memory" in printed
    export_c(rmpc.load(saved), tmp_path / "python")
    for name in ("rmpc_controller.h", "rmpc_controller.c"):
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "python" / name).read_bytes()


def test_bad_files_and_unexportable_controllers_end_with_status_2(tmp_path: Path, capsys) -> None:
    out = str(tmp_path / "out")
    assert main(["export", "c", "--controller", str(tmp_path / "missing.rmpc"), "--out", out]) == 2
    err = capsys.readouterr().err
    assert "missing.rmpc" in err and "--controller" in err  # the option and the file
    (tmp_path / "bad.rmpc").write_text("{ not json")
    assert main(["export", "c", "--controller", str(tmp_path / "bad.rmpc"), "--out", out]) == 2
    assert "bad.rmpc" in capsys.readouterr().err
    assert main(["export", "c", "--controller", str(tmp_path), "--out", out]) == 2  # a folder
    err = capsys.readouterr().err
    assert "--controller" in err and "directory" in err and str(tmp_path) in err
    vertex = RMPC(_plant(), np.diag([1.0, 0.0]), [[2e-5]], u_max=2.0, lyapunov="vertex")
    saved = vertex.save(tmp_path / "vertex.rmpc")
    assert main(["export", "c", "--controller", str(saved), "--out", out]) == 2
    assert "Kothare's form" in capsys.readouterr().err
    assert not Path(out, "rmpc_controller.c").exists()
