"""``--scheduler`` addresses are checked for every scheme before any connection, and fail at once."""

from __future__ import annotations

import socket

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
