"""The ``rmpc demo`` command: an LQR run on the nonlinear satellite of paper P."""

from __future__ import annotations

import ast
import re

import numpy as np
import pytest

from benchmarks.cli import main


def _list_after(label: str, text: str) -> list[float]:
    match = re.search(re.escape(label) + r"[^:]*:\s*(\[[^\]]*\])", text)
    assert match, f"{label!r} not found in output:\n{text}"
    return [float(v) for v in ast.literal_eval(match.group(1))]


def test_demo_returns_zero_and_prints_the_final_attitude(capsys):
    status = main(["demo", "--duration", "30"])
    out = capsys.readouterr().out
    assert status == 0
    assert "final attitude after 30 s" in out
    initial = _list_after("initial attitude", out)
    final = _list_after("final attitude", out)
    # the printed initial attitude is paper P's, in degrees
    np.testing.assert_allclose(initial, np.degrees([0.362, 0.524, -0.262]), atol=1e-3)
    # after 30 s of LQR the attitude is back within 1e-2 rad (the demo's success criterion)
    assert len(final) == 3
    assert max(abs(v) for v in final) < np.degrees(1e-2)
    assert max(abs(v) for v in final) < 0.1 * max(abs(v) for v in initial)
    # the limiter line: the applied torque never exceeds the 1 N m limit
    max_u = float(re.search(r"max \|u\| applied \(N m\):\s*([0-9.eE+-]+)", out).group(1))
    assert 0.0 < max_u <= 1.0


def test_demo_too_short_to_settle_reports_failure(capsys):
    """The exit status depends on the run: 0.5 s is not enough to reach 1e-2 rad."""
    assert main(["demo", "--duration", "0.5"]) == 1
    final = _list_after("final attitude", capsys.readouterr().out)
    assert max(abs(v) for v in final) > np.degrees(1e-2)


def test_demo_bad_duration_is_exit_2_with_one_line(capsys):
    assert main(["demo", "--duration", "-1"]) == 2
    err = capsys.readouterr().err
    assert "duration" in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


def test_demo_help_exits_zero(capsys):
    with pytest.raises(SystemExit) as info:
        main(["demo", "--help"])
    assert info.value.code == 0
    assert "--duration" in capsys.readouterr().out
