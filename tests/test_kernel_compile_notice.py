"""The line printed while the interior-point solver's kernels compile on first use.

One test compiles the kernels into a fresh numba cache (30-130 s, marked ``slow``); the others
check where the lines go with the cache's state given.
"""

from __future__ import annotations

import logging
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from lmi.ipm.kernels import notice
from lmi.ipm.kernels.notice import FIRST_SOLVE_KERNELS, compile_notice

ROOT = Path(__file__).resolve().parents[1]
START = "rmpc: compiling the LMI solver's kernels on first use (about a minute, cached for later runs)..."
DONE = re.compile(r"rmpc: the LMI solver's kernels compiled in \d+ s")

SCRIPT = """
import numpy as np
from lmi import BlockLMISolver
from lmi.ipm.kernels.notice import cold_kernels
print(cold_kernels())
BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])])
print(cold_kernels())
"""


def _first_solver(cache: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != notice.QUIET_VARIABLE}
    env["NUMBA_CACHE_DIR"] = str(cache)
    out = subprocess.run([sys.executable, "-c", SCRIPT], cwd=ROOT, env=env, capture_output=True, text=True,
                         timeout=900, check=False)
    assert out.returncode == 0, out.stderr
    return out


@pytest.mark.slow
def test_a_cold_cache_is_announced_before_the_compile_and_a_warm_one_is_not(tmp_path: Path) -> None:
    first = _first_solver(tmp_path)
    said = [line for line in first.stderr.splitlines() if line.startswith("rmpc:")]
    assert len(said) == 2 and said[0] == START and DONE.fullmatch(said[1]), first.stderr
    assert first.stdout.splitlines() == [repr(list(FIRST_SOLVE_KERNELS)), "[]"]
    second = _first_solver(tmp_path)
    assert "rmpc:" not in second.stderr, second.stderr
    assert second.stdout.splitlines() == ["[]", "[]"]


def test_the_lines_are_info_records_once_logging_is_configured_and_quiet_silences_them(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(notice, "cold_kernels", lambda: ["pack"])
    monkeypatch.delenv(notice.QUIET_VARIABLE, raising=False)
    caplog.set_level(logging.INFO, logger=notice.__name__)
    with compile_notice():
        pass
    said = [r.getMessage() for r in caplog.records]
    assert len(said) == 2 and said[0] == START and DONE.fullmatch(said[1]), said
    assert {r.levelno for r in caplog.records} == {logging.INFO}
    assert capsys.readouterr().err == ""  # pytest's handler is configured: no bare stderr line
    caplog.clear()
    monkeypatch.setenv(notice.QUIET_VARIABLE, "1")
    with compile_notice():
        pass
    assert caplog.records == []


def test_nothing_is_said_when_no_kernel_is_cold(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(notice, "cold_kernels", lambda: [])
    monkeypatch.delenv(notice.QUIET_VARIABLE, raising=False)
    caplog.set_level(logging.INFO, logger=notice.__name__)
    with compile_notice():
        pass
    assert caplog.records == []


def test_without_logging_configured_the_lines_go_to_stderr(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(notice, "cold_kernels", lambda: ["pack"])
    monkeypatch.delenv(notice.QUIET_VARIABLE, raising=False)
    monkeypatch.setattr(notice._LOG, "hasHandlers", lambda: False)
    with compile_notice():
        pass
    err = capsys.readouterr().err.splitlines()
    assert err[0] == START and DONE.fullmatch(err[1]) and len(err) == 2
