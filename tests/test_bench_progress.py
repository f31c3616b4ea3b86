"""Progress without a terminal: one plain line per finished case on standard error."""

from __future__ import annotations

import io
import subprocess
import sys

from benchmarks.core.progress import CaseProgress


def test_plain_lines_one_per_case_when_not_a_terminal() -> None:
    buf = io.StringIO()
    with CaseProgress(3, "suite x", stream=buf) as bar:
        assert bar.plain and not bar.enabled
        bar.advance("E1_RMPC")
        bar.advance("E2_GIPC", ok=False)
        bar.advance("E3_RMPC")
    lines = buf.getvalue().splitlines()
    assert len(lines) == 3
    assert lines[0].startswith("suite x: 1/3 E1_RMPC (")
    assert lines[1].startswith("suite x: 2/3 E2_GIPC failed (")
    assert lines[2].startswith("suite x: 3/3 E3_RMPC (") and lines[2].endswith(" s)")
    assert bar.failed == 1


def test_disabled_prints_nothing() -> None:
    buf = io.StringIO()
    with CaseProgress(2, "quiet", enabled=False, stream=buf) as bar:
        bar.advance("a")
    assert buf.getvalue() == ""


def test_subprocess_stderr_gets_lines_as_cases_finish() -> None:
    code = (
        "import time\n"
        "from benchmarks.core.progress import CaseProgress\n"
        "with CaseProgress(2, 'sub') as bar:\n"
        "    bar.advance('first')\n"
        "    time.sleep(0.01)\n"
        "    bar.advance('second')\n"
    )
    cmd = [sys.executable, "-c", code]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=True)
    lines = proc.stderr.splitlines()
    assert [ln.split(" (")[0] for ln in lines] == ["sub: 1/2 first", "sub: 2/2 second"]
    assert proc.stdout == ""
