"""``--scheduler`` addresses are checked for every scheme before any connection, and fail at once."""

from __future__ import annotations

import contextlib
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator

import pytest

from benchmarks.cli import main
from benchmarks.core.executors import scheduler_host_port
from toolkit_common.errors import ConfigError


@pytest.mark.parametrize(
    ("address", "expected"),
    [
        ("tcp://10.0.0.5:8786", ("tcp", "10.0.0.5", 8786)),
        ("tls://sched.example:8786", ("tls", "sched.example", 8786)),
        ("ws://host:80/", ("ws", "host", 80)),
        ("10.0.0.5:8786", ("tcp", "10.0.0.5", 8786)),
        ("[::1]:8786", ("tcp", "::1", 8786)),
    ],
)
def test_well_formed_addresses(address, expected):
    assert scheduler_host_port(address) == expected


@pytest.mark.parametrize(
    "address",
    ["not an address", "tcp://", "tls://", "tcp://127.0.0.1:notaport", "inproc://", "ws://host",
     "udp://host:1", "tcp://:8786", "tcp://host:0", "tcp://host:70000", ""],
)
def test_malformed_addresses_are_refused_naming_the_option(address):
    with pytest.raises(ConfigError, match=r"^--scheduler: "):
        scheduler_host_port(address)


def _closed_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.mark.parametrize("scheme", ["tcp", "tls", "ws"])
def test_an_address_where_nothing_listens_fails_before_dask_connects(tmp_path, capsys, monkeypatch, scheme):
    """The port is probed first, so Dask's client (which waited 40 s, then printed a traceback) is never
    built: the test makes building it an error."""
    import distributed

    def no_client(*args, **kwargs):
        raise AssertionError("distributed.Client built for an address nothing listens on")

    monkeypatch.setattr(distributed, "Client", no_client)
    code = main(["bench", "paper", "--out", str(tmp_path / "out"), "--scheduler",
                 f"{scheme}://127.0.0.1:{_closed_port()}", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "--scheduler" in err and len(err.strip().splitlines()) == 1, err


def test_the_cli_refuses_a_malformed_address_with_one_line(tmp_path, capsys):
    assert main(["bench", "paper", "--out", str(tmp_path / "out"), "--scheduler", "not an address"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rmpc: error: --scheduler: ") and len(err.strip().splitlines()) == 1


# --- a refused connection ends cleanly: the whole of stderr, after the process has exited ---------


@contextlib.contextmanager
def _listener(mode: str) -> Iterator[int]:
    """A TCP port that accepts connections and then says nothing (``"silent"``) or hangs up (``"close"``)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    server.settimeout(0.2)
    held: list[socket.socket] = []
    stop = threading.Event()

    def serve() -> None:
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            if mode == "close":
                conn.close()
            else:
                held.append(conn)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield server.getsockname()[1]
    finally:
        stop.set()
        thread.join()
        for conn in held:
            conn.close()
        server.close()


def _run(args: list[str], tmp_path) -> subprocess.CompletedProcess[str]:
    """``python -m benchmarks.cli ...`` in a child process; its pipes close only when every process
    holding them has exited, so late output (a ``__del__`` at exit) is in what comes back."""
    return subprocess.run(
        [sys.executable, "-m", "benchmarks.cli", *args], capture_output=True, text=True, timeout=120,
        cwd=tmp_path,
    )


@pytest.mark.parametrize(
    ("address", "says"),
    [
        ("tcp://127.0.0.1:1", "Connection refused"),
        ("ws://127.0.0.1:1", "Connection refused"),
        ("tls://127.0.0.1:1", "with no TLS settings"),
        ("not an address", "scheme://host:port"),
        ("tls://127.0.0.1:{close}", "with no TLS settings"),
        ("tcp://127.0.0.1:{close}", "reachable Dask scheduler"),
    ],
)
def test_a_refused_scheduler_prints_one_line_and_nothing_after_exit(tmp_path, address, says):
    """``rmpc bench paper --short --scheduler ADDRESS`` exits 2 with one line on stderr and nothing on
    stdout. With something listening, a ``tls://`` address (no TLS settings) ended in Dask's
    ``TypeError`` traceback and, 40 s later, a ``Client.__del__`` traceback."""
    with _listener("close") as port:
        argv = ["bench", "paper", "--short", "--scheduler", address.format(close=port), "--out",
                str(tmp_path / "out"), "--no-progress"]
        done = _run(argv, tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    assert done.stderr.startswith("rmpc: error: --scheduler: ") and done.stderr.count("\n") == 1, done.stderr
    assert says in done.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("scheme", ["tcp", "ws"])
def test_a_peer_that_never_answers_is_refused_after_the_timeout(tmp_path, scheme):
    """A port that accepts and then stays silent: Dask's client waited for its handshake with no limit
    (until the peer hung up); the scheduler probe gives up after its timeout, cleanly. The child's
    120 s limit in :func:`_run` is only a guard against the hang."""
    code = (
        "import sys\n"
        "from benchmarks.core.executors import DaskExecutor\n"
        "from toolkit_common.errors import ConfigError\n"
        "try:\n"
        f"    DaskExecutor({scheme!r} + '://127.0.0.1:' + sys.argv[1], timeout=1.0)\n"
        "except ConfigError as err:\n"
        "    print(err)\n"
    )
    with _listener("silent") as port:
        done = subprocess.run([sys.executable, "-c", code, str(port)], capture_output=True, text=True,
                              timeout=120, cwd=tmp_path)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert done.stdout.startswith("--scheduler: ")
    assert "no answer from a Dask scheduler within 1 s" in done.stdout


def test_a_dask_worker_is_not_taken_for_a_scheduler():
    """A worker's address speaks Dask but is no scheduler: Dask's client failed with a ``TypeError`` and
    a ``Client.__del__`` traceback; the probe asks the peer who it is first."""
    import distributed

    from benchmarks.core.executors import DaskExecutor

    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", host="127.0.0.1",
        dashboard_address=":0",
    ) as cluster:
        worker = next(iter(cluster.scheduler_info["workers"]))
        with pytest.raises(ConfigError, match="a Dask Worker that is not a scheduler"):
            DaskExecutor(worker, timeout=5.0)
        executor = DaskExecutor(cluster.scheduler_address, timeout=5.0)
        assert executor.workers == 1
        executor.close()
