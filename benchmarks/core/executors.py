"""Where cases run: worker processes on this machine, in-process, or a Dask cluster.

All three offer the same small interface (:class:`CaseExecutor`), so the loop of
:mod:`benchmarks.core.execute` is one code path: ``submit`` a payload, ``wait_any`` for finished
futures, ``result`` of one (raising :class:`WorkerLost` when the infrastructure, not the case,
failed), ``restart`` after a crash where possible, and ``close``.

- :class:`ProcessExecutor`: a :class:`concurrent.futures.ProcessPoolExecutor` with the
  ``forkserver`` start method (``spawn`` where there is none); workers ignore SIGINT, so
  Ctrl-C reaches only the parent, which decides what to do with running cases.
- :class:`InlineExecutor` (``--workers 0``): runs each case in the calling process, for
  debugging and profiling.
- :class:`DaskExecutor` (``--scheduler ADDRESS``): a ``dask.distributed.Client``; Dask
  reschedules the cases of a lost worker itself.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import signal
import socket
import time
from collections.abc import Callable
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any, Protocol

from toolkit_common.errors import ConfigError

__all__ = [
    "CaseExecutor",
    "DaskExecutor",
    "InlineExecutor",
    "ProcessExecutor",
    "WorkerLost",
    "make_executor",
    "make_executor_and_out",
]


class WorkerLost(RuntimeError):
    """The process or cluster running a case failed; the case itself did not report."""


class CaseExecutor(Protocol):
    """The interface of :mod:`benchmarks.core.execute`."""

    workers: int
    description: str

    def submit(self, fn: Callable[[Any], Any], payload: Any) -> Any: ...  # pragma: no cover

    def wait_any(self, futures: set[Any], timeout: float) -> set[Any]: ...  # pragma: no cover

    def result(self, future: Any) -> Any: ...  # pragma: no cover

    def cancel(self, future: Any) -> bool: ...  # pragma: no cover

    def restart(self) -> bool: ...  # pragma: no cover

    def close(self, abandon: bool = False) -> None: ...  # pragma: no cover


def _init_worker() -> None:
    """Worker initializer: ignore SIGINT and use one BLAS/OpenMP thread.

    Ctrl-C in a terminal reaches the whole process group; only the parent acts on it. The
    workers already use every core between them, so threads inside one would only compete.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    import numpy  # noqa: F401  (load BLAS so the limit below reaches it)
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)


#: Modules the fork server imports once, so that each worker starts with them loaded (importing
#: the controllers, cvxpy, python-control and SciPy costs about 2 s of CPU per process).
PRELOAD: tuple[str, ...] = (
    "benchmarks.core.runner", "rmpc", "rmpc.mpc.gipc", "rmpc.mpc.crmpc", "lmi", "control", "scipy.integrate",
)


def _context() -> multiprocessing.context.BaseContext:
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(PRELOAD))  # takes effect when the fork server starts
    return ctx


class ProcessExecutor:
    """``workers`` processes on this machine.

    Parameters
    ----------
    workers : int
        Number of worker processes (>= 1).
    """

    def __init__(self, workers: int) -> None:
        self.workers = workers
        self.description = f"{workers} worker process{'es' if workers != 1 else ''}"
        self._pool = self._new_pool()

    def _new_pool(self) -> cf.ProcessPoolExecutor:
        return cf.ProcessPoolExecutor(
            max_workers=self.workers, mp_context=_context(), initializer=_init_worker
        )

    def submit(self, fn: Callable[[Any], Any], payload: Any) -> cf.Future:
        """Queue ``fn(payload)``."""
        return self._pool.submit(fn, payload)

    def wait_any(self, futures: set[cf.Future], timeout: float) -> set[cf.Future]:
        """The futures that are done after at most ``timeout`` s (at least one, unless timed out)."""
        done, _ = cf.wait(futures, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return set(done)

    def result(self, future: cf.Future) -> Any:
        """The value of a done future; :class:`WorkerLost` if its worker died."""
        try:
            return future.result()
        except BrokenProcessPool as err:
            raise WorkerLost(f"a worker process died ({err})") from None
        except cf.CancelledError:
            raise WorkerLost("the case was cancelled") from None

    def cancel(self, future: cf.Future) -> bool:
        """Cancel a case that has not started; ``True`` if it will not run."""
        return future.cancel()

    def restart(self) -> bool:
        """Replace a broken pool by a fresh one."""
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = self._new_pool()
        return True

    def pids(self) -> list[int]:
        """Process ids of the current workers."""
        procs = getattr(self._pool, "_processes", None) or {}
        return [p.pid for p in procs.values() if p.pid is not None]

    def close(self, abandon: bool = False) -> None:
        """Shut the pool down; with ``abandon`` terminate running workers first."""
        if abandon:
            for proc in list((getattr(self._pool, "_processes", None) or {}).values()):
                if proc.is_alive():
                    proc.terminate()
        self._pool.shutdown(wait=not abandon, cancel_futures=True)


class InlineExecutor:
    """Runs each case in the calling process when it is submitted (``--workers 0``)."""

    workers = 1
    #: cases submitted before their results are taken: one, so that a case's result is stored
    #: before the next case runs (a second case run first would hold the first's result unstored,
    #: and an interrupt during it would lose a finished case)
    in_flight = 1
    description = "in-process (no workers)"

    def submit(self, fn: Callable[[Any], Any], payload: Any) -> cf.Future:
        future: cf.Future = cf.Future()
        future.set_result(fn(payload))
        return future

    def wait_any(self, futures: set[cf.Future], timeout: float) -> set[cf.Future]:
        return {f for f in futures if f.done()}

    def result(self, future: cf.Future) -> Any:
        return future.result()

    def cancel(self, future: cf.Future) -> bool:
        return False

    def restart(self) -> bool:
        return False

    def close(self, abandon: bool = False) -> None:
        return None


class DaskExecutor:
    """Cases on a Dask cluster reached at ``address`` (``tcp://host:port``).

    Parameters
    ----------
    address : str
        The scheduler address.
    timeout : float
        Seconds to wait for the connection, and for the scheduler's answer to a first question
        (the peer must say it is a scheduler before Dask's client is built).
    """

    def __init__(self, address: str, timeout: float = 20.0) -> None:
        try:
            from distributed import Client
        except ImportError:  # pragma: no cover - an optional dependency
            raise ConfigError(
                "--scheduler",
                "dask.distributed installed (pip install 'rmpc-satellite[dask]')",
                "it is missing",
            ) from None
        scheme, _, _ = scheduler_host_port(address)
        connection_args = _tls_connection_args(address, scheme)
        _probe(address, timeout)
        _identify_scheduler(address, timeout, connection_args)
        try:
            self._client = Client(address, timeout=timeout, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as err:
            msg = str(err).splitlines()[0] if str(err) else type(err).__name__
            raise ConfigError(
                "--scheduler", "the address of a reachable Dask scheduler", f"{address!r} ({msg})"
            ) from None
        info = self._client.scheduler_info()
        self.workers = max(1, sum(int(w.get("nthreads", 1)) for w in info.get("workers", {}).values()))
        self.description = f"Dask scheduler {address} ({self.workers} worker threads)"

    def submit(self, fn: Callable[[Any], Any], payload: Any) -> Any:
        return self._client.submit(fn, payload, pure=False)

    def wait_any(self, futures: set[Any], timeout: float) -> set[Any]:
        # distributed.wait needs a default client; this one is private, so poll (cases take seconds)
        deadline = time.monotonic() + timeout
        while True:
            done = {f for f in futures if f.done()}
            if done or time.monotonic() >= deadline:
                return done
            time.sleep(0.02)

    def result(self, future: Any) -> Any:
        from distributed import KilledWorker

        try:
            return future.result()
        except KilledWorker as err:
            # Dask retried the case on other workers and every one died: blame the case
            return {"ok": False, "error": f"KilledWorker: {err}".replace("\n", " "), "traceback": ""}
        except Exception as err:
            raise WorkerLost(f"the Dask cluster failed: {type(err).__name__}: {err}") from None

    def cancel(self, future: Any) -> bool:
        future.cancel()
        return True

    def restart(self) -> bool:
        return False

    def close(self, abandon: bool = False) -> None:
        self._client.close()


SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss")
"""Address schemes ``--scheduler`` accepts (every one runs over TCP, so it can be probed first)."""


def scheduler_host_port(address: str) -> tuple[str, str, int]:
    """``(scheme, host, port)`` of a scheduler address, or :class:`ConfigError` naming ``--scheduler``.

    ``host:port`` without a scheme means ``tcp://host:port`` (as in Dask).

    Examples
    --------
    >>> scheduler_host_port("tcp://10.0.0.5:8786")
    ('tcp', '10.0.0.5', 8786)
    >>> scheduler_host_port("[::1]:8786")
    ('tcp', '::1', 8786)
    """
    expected = f"an address scheme://host:port with scheme among {', '.join(SCHEDULER_SCHEMES)}"
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    if scheme not in SCHEDULER_SCHEMES:
        raise ConfigError("--scheduler", expected, repr(address))
    host, _, port = rest.rstrip("/").rpartition(":")
    host = host.strip("[]")
    if not host or any(c.isspace() for c in host) or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError("--scheduler", expected, repr(address))
    return scheme, host, int(port)


def _probe(address: str, timeout: float) -> None:
    """Check the address's form, then fail at once (not after the client's timeout) when nothing
    listens there."""
    _, host, port = scheduler_host_port(address)
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as err:
        raise ConfigError(
            "--scheduler", "the address of a reachable Dask scheduler", f"{address!r} ({err.strerror or err})"
        ) from None


def _tls_connection_args(address: str, scheme: str) -> dict[str, Any]:
    """The client's connection settings from Dask's configuration (its TLS context for ``tls://``).

    A ``tls://`` or ``wss://`` address needs Dask's TLS settings (``distributed.comm.tls.ca-file``,
    ``.client.cert`` and ``.client.key`` in the Dask configuration, or the matching
    ``DASK_DISTRIBUTED__COMM__TLS__...`` variables); without them Dask's client raised a
    ``TypeError`` after connecting and printed a ``Client.__del__`` traceback 40 s later, so the
    address is refused before any connection.
    """
    from distributed.security import Security

    args = Security().get_connection_args("client")
    if scheme in ("tls", "wss") and args.get("ssl_context") is None:
        raise ConfigError(
            "--scheduler",
            f"a {scheme}:// address with Dask's TLS settings configured (distributed.comm.tls.ca-file, "
            ".client.cert and .client.key in the Dask configuration)",
            f"{address!r} with no TLS settings",
        )
    return args


def _identify_scheduler(address: str, timeout: float, connection_args: dict[str, Any]) -> None:
    """Ask ``address`` who it is, within ``timeout`` s in all, before Dask's client is built.

    Dask's client waits without a limit for the handshake of a peer that accepts the connection
    and then says nothing (its ``timeout`` covers the connection only), and when its start fails
    its ``__del__`` prints a traceback up to 40 s later; so one connection is opened here, in a
    thread of its own with a deadline, and the peer must answer ``identity`` as a scheduler.
    """
    import asyncio
    import threading

    from distributed.comm import connect

    answer: dict[str, Any] = {}

    async def ask() -> None:
        comm = await connect(address, timeout=timeout, **connection_args)
        try:
            await comm.write({"op": "identity", "reply": True})
            answer["identity"] = await comm.read()
        finally:
            await comm.close()

    def run() -> None:
        try:
            asyncio.run(asyncio.wait_for(ask(), timeout))
        except BaseException as err:  # reported by the caller's thread
            answer["error"] = err

    thread = threading.Thread(target=run, name="rmpc-scheduler-probe", daemon=True)
    thread.start()
    thread.join(timeout + 5.0)
    err = answer.get("error")
    identity = answer.get("identity")
    kind = identity.get("type") if isinstance(identity, dict) else None
    if thread.is_alive() or isinstance(err, TimeoutError):
        found = f"{address!r} (no answer from a Dask scheduler within {timeout:g} s)"
    elif err is not None:
        found = f"{address!r} ({type(err).__name__}: {str(err).splitlines()[0] if str(err) else 'closed'})"
    elif kind != "Scheduler":
        found = f"{address!r} (a Dask {kind or 'peer'} that is not a scheduler)"
    else:
        return
    raise ConfigError("--scheduler", "the address of a reachable Dask scheduler", found)


def make_executor(workers: int | None, scheduler: str | None) -> CaseExecutor:
    """The executor for ``--workers N`` (0: in-process) or ``--scheduler ADDRESS``."""
    if scheduler is not None:
        return DaskExecutor(scheduler)
    if workers is None:
        workers = default_workers()
    if workers == 0:
        return InlineExecutor()
    return ProcessExecutor(workers)


def make_executor_and_out(
    workers: int | None, scheduler: str | None, out: str | Path
) -> tuple[CaseExecutor, Path]:
    """The executor, then the output directory ``out`` (created), in that order.

    A bad ``--scheduler`` fails before anything is written; if ``out`` cannot be created the
    executor is closed before the error propagates.
    """
    executor = make_executor(workers, scheduler)
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError:
        executor.close()
        raise
    return executor, out


def default_workers() -> int:
    """One worker per CPU this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on every platform
        return max(1, os.cpu_count() or 1)
