"""Interrupts (Ctrl-C, SIGINT) in the benchmark runners: one handler and one test of what an interrupt is.

A SIGINT reaches Python as a ``KeyboardInterrupt`` raised by the signal handler at the next
bytecode the main thread runs. Inside compiled code it does not always arrive as such:

- a numba function's dispatcher that runs Python code (a ``__del__``, a type check) while the
  handler raises returns its result with the exception set, and Python reports that as
  ``SystemError: CPUDispatcher(...) returned a result with an exception set`` whose
  ``__cause__`` is the ``KeyboardInterrupt``; a case that catches ``Exception`` then records an
  interrupt as a failure;
- a ``KeyboardInterrupt`` raised inside a finaliser (``__del__``) is printed as "Exception
  ignored" and lost;
- a solver may catch SIGINT itself (OSQP installs its own handler while it solves and returns
  the status ``interrupted``; :mod:`rmpc.qp.osqp_backend` hands the signal back; so does SCS,
  whose solve :mod:`lmi.backends.scs_signal` hands it back).

:func:`is_interrupt` (:mod:`toolkit_common.interrupts`, shared with :mod:`lmi`, which may not
import this package) recognises the first kind; :class:`Interrupts` is the handler every runner
installs (:func:`benchmarks.core.execute.execute` for the suites and sweeps,
:func:`benchmarks.suites.methods.run_methods`). It counts each SIGINT, so an interrupt that was
wrapped or swallowed on its way is still known, and after it has raised a
``KeyboardInterrupt`` it raises it again every :attr:`Interrupts.resend_after` seconds until the
runner :meth:`~Interrupts.settle`\\ s, so a swallowed one does not let the case run on.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

from toolkit_common.interrupts import is_interrupt

__all__ = ["Interrupts", "is_interrupt"]


class Interrupts:
    """The SIGINT handler of a run (a context manager; it does nothing outside the main thread).

    Parameters
    ----------
    notice : callable, optional
        Receives a one-line message at the first SIGINT that does not stop the run at once.
    first_raises : bool
        ``True``: every SIGINT raises ``KeyboardInterrupt`` (the running case stops at once; for
        runs whose cases run in this process and are not kept when interrupted). ``False``: the
        first one only sets :attr:`count` (the running cases finish; the runner stops after them)
        and the second raises.
    resend_after : float
        Seconds after a raised ``KeyboardInterrupt`` at which it is raised again if the runner has
        not settled (it was swallowed on its way).

    Attributes
    ----------
    count : int
        SIGINTs received (the run's own resends not counted).
    raised : int
        ``KeyboardInterrupt`` raised by the handler: when positive, whatever the running case
        produced since is not a result.
    """

    def __init__(
        self,
        notice: Callable[[str], None] | None = None,
        first_raises: bool = False,
        resend_after: float = 0.5,
    ) -> None:
        self.count = 0
        self.raised = 0
        self.resend_after = resend_after
        self._notice = notice
        self._first_raises = first_raises
        self._previous: Any = None
        self._previous_hook: Any = None
        self._installed = False
        self._resent = 0
        self._settled = threading.Event()
        self._resender: threading.Thread | None = None

    def __enter__(self) -> Interrupts:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
            self._previous_hook = sys.unraisablehook
            sys.unraisablehook = self._unraisable
            self._installed = True
        return self

    def __exit__(self, *exc: object) -> None:
        self._settled.set()
        if self._resender is not None:
            self._resender.join()
            # a resend already on its way is taken here (and ignored), not by the handler restored
            # below, which would raise it in whatever the runner does next
            deadline = time.monotonic() + 1.0
            while self._resent > 0 and self._installed and time.monotonic() < deadline:
                time.sleep(0.005)
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)
            sys.unraisablehook = self._previous_hook
            self._installed = False

    def interrupted(self, err: BaseException | None = None) -> bool:
        """Whether the run must stop: ``err`` is an interrupt, or the handler raised one (which the
        running case may have wrapped or swallowed)."""
        return self.raised > 0 or is_interrupt(err)

    def settle(self) -> None:
        """The runner has seen the interrupt and stops: no more resends."""
        self._settled.set()

    def _handle(self, signum: int, frame: Any) -> None:
        if self._resent > 0:  # one of ours: the case swallowed the last KeyboardInterrupt
            self._resent -= 1
            if self._settled.is_set():
                return
            raise KeyboardInterrupt
        self.count += 1
        if self.count == 1 and not self._first_raises:
            if self._notice is not None:
                self._notice("interrupted: finishing the running cases (Ctrl-C again to abandon them)")
            return
        self.raised += 1
        if self._resender is None and not self._settled.is_set():
            self._resender = threading.Thread(target=self._resend, name="rmpc-interrupt-resend", daemon=True)
            self._resender.start()
        raise KeyboardInterrupt

    def _resend(self) -> None:
        while not self._settled.wait(self.resend_after):
            self._resent += 1
            os.kill(os.getpid(), signal.SIGINT)

    def _unraisable(self, info: Any) -> None:
        """A ``KeyboardInterrupt`` raised inside a finaliser is lost there; the handler has counted
        it and raises it again (no "Exception ignored" traceback on the terminal)."""
        if isinstance(info.exc_value, KeyboardInterrupt) or info.exc_type is KeyboardInterrupt:
            return
        self._previous_hook(info)
