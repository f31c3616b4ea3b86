"""A run killed while it publishes its reports leaves a hidden staging folder; the next run into the
same output folder removes it (and says so), and it is never read as a run's results."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from benchmarks.compare import compare_runs
from benchmarks.core.publish import remove_stale_stages, staged_reports
from toolkit_common.errors import InvalidArgumentError

_KILLED_WRITER = textwrap.dedent("""
    import os, signal, sys
    from pathlib import Path
    from benchmarks.core.publish import staged_reports
    with staged_reports(Path(sys.argv[1])) as stage:
        (stage / "results.json").write_text('[{"case_id": "new", "x": 1}]')
        os.kill(os.getpid(), signal.SIGKILL)
""")


def _stages(out: Path) -> list[str]:
    return sorted(p.name for p in out.iterdir() if p.name.startswith(".staging-"))


def test_a_staging_folder_left_by_a_killed_run_is_removed_by_the_next_one(tmp_path):
    (tmp_path / "results.json").write_text('[{"case_id": "old", "x": 0}]')
    done = subprocess.run([sys.executable, "-c", _KILLED_WRITER, str(tmp_path)], check=False)
    assert done.returncode == -9
    left = _stages(tmp_path)
    assert len(left) == 1  # what the kill leaves
    # never a run's results: compare refuses it, and the output folder still holds the old reports
    with pytest.raises(InvalidArgumentError, match="killed while writing"):
        compare_runs(tmp_path / left[0], tmp_path)
    assert "old" in (tmp_path / "results.json").read_text()
    lines: list[str] = []
    with staged_reports(tmp_path, notice=lines.append) as stage:
        (stage / "results.json").write_text('[{"case_id": "next", "x": 2}]')
    assert _stages(tmp_path) == []
    assert len(lines) == 1 and left[0] in lines[0] and "killed while writing" in lines[0]
    assert "next" in (tmp_path / "results.json").read_text()


def test_the_staging_folder_of_a_run_still_going_is_left_alone(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        live = tmp_path / f".staging-{sleeper.pid}-abc"
        live.mkdir()
        (live / "results.json").write_text("[]")
        assert remove_stale_stages(tmp_path, notice=lambda line: None) == []
        assert live.is_dir()
    finally:
        sleeper.kill()
        sleeper.wait()
    time.sleep(0.05)
    assert remove_stale_stages(tmp_path, notice=lambda line: None) == [live.name]


def test_a_clean_run_says_nothing(tmp_path, capsys):
    with staged_reports(tmp_path) as stage:
        (stage / "results.md").write_text("# ok")
    assert capsys.readouterr().err == "" and _stages(tmp_path) == []
