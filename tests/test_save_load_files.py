"""The controller file itself: its envelope and checksum, bad files, bad paths, atomic writes.

Every bad file is refused with :class:`rmpc.errors.ControllerFileError` (an
``InvalidArgumentError``, so a ``ValueError``) naming the file and what is wrong with it.
"""

from __future__ import annotations

import json
import os
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import rmpc
from models import PolytopicModel, RigidSatellite
from rmpc import LQR, RMPC, ScheduledRMPC
from rmpc.errors import ControllerFileError, InvalidArgumentError
from rmpc.io.design import Design, DesignError, encode
from rmpc.io.format import FORMAT, VERSION, canonical, checksum

PLANT = PolytopicModel([(np.array([[1.0, 0.1], [0.0, 0.99]]), np.array([[0.0], [0.0787]])),
                        (np.array([[1.0, 0.1], [0.0, 0.0]]), np.array([[0.0], [0.0787]]))], dt=0.1,
                       state_names=["angle", "rate"], input_names=["voltage"])


@pytest.fixture
def saved(tmp_path: Path) -> Path:
    ctrl = RMPC(PLANT, Q=np.diag([1.0, 0.0]), R=[[2e-5]], u_max=2.0, input_constraint="peak")
    return ctrl.save(tmp_path / "design.rmpc")


def _rewrite(path: Path, change: Any, fix_checksum: bool = True) -> None:
    """Apply ``change`` to the file's JSON (and recompute its checksum unless told not to)."""
    payload = json.loads(path.read_text(encoding="utf-8"))
    change(payload)
    if fix_checksum:
        payload["sha256"] = checksum(payload)
    path.write_text(json.dumps(payload), encoding="utf-8")


def _refused(path: Path, *words: str) -> ControllerFileError:
    with pytest.raises(ControllerFileError) as info:
        rmpc.load(path)
    message = str(info.value)
    assert str(path) in message, message
    for word in words:
        assert word in message, message
    assert isinstance(info.value, InvalidArgumentError) and isinstance(info.value, ValueError)
    return info.value


def test_the_file_is_one_json_document_with_the_envelope_and_a_checksum(saved: Path) -> None:
    payload = json.loads(saved.read_bytes().decode("utf-8"))
    assert set(payload) == {"format", "version", "kind", "toolkit_version", "design", "sha256"}
    assert (payload["format"], payload["version"], payload["kind"]) == (FORMAT, VERSION, "RMPC")
    assert payload["sha256"] == checksum(payload)
    plant = payload["design"]["plant"]
    assert plant["A"][1] == [[1.0, 0.1], [0.0, 0.0]] and plant["state_names"] == ["angle", "rate"]
    assert payload["design"]["arguments"]["R"] == [[2e-05]]
    # canonical text: sorted keys, no spaces, no NaN literal
    assert canonical({"b": 1, "a": [0.1]}) == b'{"a":[0.1],"b":1}'
    with pytest.raises(ValueError):
        canonical({"a": float("nan")})


def test_numbers_read_back_to_the_same_bits_and_non_finite_ones_are_strings() -> None:
    values = np.array([0.1, 1.0 / 3.0, 2e-308, 1.7976931348623157e308, np.pi, -0.0, np.inf, -np.inf])
    encoded = encode(values)
    assert encoded[-2:] == ["inf", "-inf"]
    back = Design({"v": json.loads(json.dumps(encoded))}).array("v")
    assert np.array_equal(back, values) and np.signbit(back[5])
    assert np.isnan(Design({"v": encode(float("nan"))}).number("v"))
    with pytest.raises(InvalidArgumentError, match=r"design\.solver_options"):
        encode({"callback": print}, "design.solver_options")


def test_a_damaged_file_is_refused_by_its_checksum(saved: Path) -> None:
    text = saved.read_text(encoding="utf-8")
    saved.write_text(text.replace("2e-05", "3e-05"), encoding="utf-8")
    _refused(saved, "checksum", "damaged")


def test_a_truncated_file_says_it_ends_early(saved: Path) -> None:
    data = saved.read_bytes()
    for cut in [*(len(data) * k // 10 for k in range(1, 10)), len(data) - 2, 7, 10, 13]:
        saved.write_bytes(data[:cut])
        _refused(saved, "truncated")


@pytest.mark.parametrize("content", [b"\x89PNG\r\n\x1a\n\x00\x00", b"format = 'rmpc-controller'\n", b"",
                                     b"[1, 2]", b'{"a": NaN}'])
def test_not_json_or_not_a_controller_file_is_refused(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "bad.rmpc"
    path.write_bytes(content)
    err = _refused(path)
    assert any(word in str(err) for word in ("UTF-8", "not JSON", "empty", "not a controller file", "NaN"))


def test_a_foreign_json_file_is_refused_by_its_format(saved: Path) -> None:
    _rewrite(saved, lambda p: p.update(format="acme-controller"))
    _refused(saved, "'acme-controller'", "not a controller file")


def test_a_newer_version_is_refused_naming_both_versions(saved: Path) -> None:
    _rewrite(saved, lambda p: p.update(version=VERSION + 1, toolkit_version="9.0"))
    _refused(saved, f"version {VERSION + 1}", "9.0", "newer toolkit", f"format version {VERSION} or older")


def test_an_unknown_kind_is_refused(saved: Path) -> None:
    _rewrite(saved, lambda p: p.update(kind="PIDController"))
    _refused(saved, "'PIDController'", "RMPC")


def test_a_design_without_a_field_is_refused_naming_it(saved: Path) -> None:
    _rewrite(saved, lambda p: p["design"]["arguments"].pop("certificate_tol"))
    _refused(saved, "design.arguments.certificate_tol", "missing")


def test_a_design_with_an_unknown_field_is_refused_naming_it(saved: Path) -> None:
    _rewrite(saved, lambda p: p["design"]["plant"].update(colour="blue"))
    _refused(saved, "design.plant", "colour")


def test_a_design_of_the_wrong_type_is_refused_naming_the_field(saved: Path) -> None:
    _rewrite(saved, lambda p: p["design"]["arguments"].update(Q="identity"))
    _refused(saved, "design.arguments.Q")
    _rewrite(saved, lambda p: p["design"]["arguments"].update(Q=[[1.0, 0.0], [0.0, -1.0]]))
    _refused(saved, "Q")  # the constructor's own check, through the file's error


def test_missing_files_and_directories_are_refused(tmp_path: Path) -> None:
    _refused(tmp_path / "nothing.rmpc", "no such file")
    _refused(tmp_path, "a directory")
    with pytest.raises(TypeError, match="path"):
        rmpc.load(42)


def test_saving_into_a_missing_folder_or_onto_a_directory_is_refused(tmp_path: Path) -> None:
    lqr = LQR(PLANT, Q=np.eye(2), R=np.eye(1))
    with pytest.raises(ControllerFileError, match="no such folder"):
        lqr.save(tmp_path / "missing" / "lqr.rmpc")
    with pytest.raises(ControllerFileError, match="a directory"):
        lqr.save(tmp_path)


def test_what_a_file_cannot_hold_is_refused_when_saving(tmp_path: Path) -> None:
    sat = RigidSatellite.paper_p()
    sched = ScheduledRMPC(lambda x: sat.polytope(x, 0.01, 0.3), Q=np.eye(6), R=np.eye(3))
    with pytest.raises(InvalidArgumentError, match="polytope_at"):
        sched.save(tmp_path / "sched.rmpc")
    pickle.loads(pickle.dumps(ScheduledRMPC.for_satellite(sat, dt=0.01, spread=0.3, Q=np.eye(6),
                                                          R=np.eye(3))))

    class MyRMPC(RMPC):
        pass

    with pytest.raises(InvalidArgumentError, match="MyRMPC"):
        MyRMPC(PLANT, Q=np.eye(2), R=np.eye(1)).save(tmp_path / "mine.rmpc")
    assert list(tmp_path.iterdir()) == []


def test_an_interrupted_save_leaves_the_old_file_and_no_temporary(
    saved: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    before = saved.read_bytes()
    lqr = LQR(PLANT, Q=np.eye(2), R=np.eye(1))

    def interrupted(fd: int) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        lqr.save(saved)
    monkeypatch.undo()

    def refused(src: Any, dst: Any) -> None:
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "replace", refused)
    with pytest.raises(ControllerFileError, match="PermissionError"):
        lqr.save(saved)
    monkeypatch.undo()
    assert saved.read_bytes() == before
    assert [p.name for p in saved.parent.iterdir()] == [saved.name]
    assert type(rmpc.load(saved)) is RMPC


def test_a_design_reader_refuses_what_it_was_not_asked_for() -> None:
    design = Design({"a": 1.0, "b": [1, 2]})
    assert design.number("a") == 1.0
    with pytest.raises(DesignError, match=r"design: .*unknown field.*b"):
        design.finish()
    with pytest.raises(DesignError, match=r"design\.c"):
        design.value("c")
    with pytest.raises(DesignError, match=r"design\.b"):
        design.number("b")


def test_a_new_file_is_readable_by_others_and_a_replaced_one_keeps_its_mode(tmp_path: Path) -> None:
    lqr = LQR(PLANT, Q=np.eye(2), R=np.eye(1))
    path = lqr.save(tmp_path / "lqr.rmpc")
    assert path.stat().st_mode & 0o777 == 0o644  # not the temporary file's 0o600
    path.chmod(0o640)
    lqr.save(path)
    assert path.stat().st_mode & 0o777 == 0o640
