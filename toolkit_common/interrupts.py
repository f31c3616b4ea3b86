"""What an interrupt is, for every package: a ``KeyboardInterrupt``, or an error raised because of one.

A SIGINT reaches Python as a ``KeyboardInterrupt`` raised at the next bytecode the main thread
runs. Inside compiled code it does not always arrive bare: a numba dispatcher that runs Python
code while the handler raises reports ``SystemError: CPUDispatcher(...) returned a result with
an exception set`` whose ``__cause__`` is the ``KeyboardInterrupt``; a solver binding may wrap it
in its own error. Code that catches a solver's errors (``except BaseException`` around a
Clarabel solve, to record its panics as a failed solve) re-raises what :func:`is_interrupt`
recognises, as a ``KeyboardInterrupt`` (:func:`reraise_interrupt`), so Ctrl-C is never recorded
as a failed solve. (:mod:`benchmarks.core.interrupts` builds the runners' handler on it.)
"""

from __future__ import annotations

__all__ = ["is_interrupt", "reraise_interrupt"]


def is_interrupt(err: BaseException | None) -> bool:
    """Whether ``err`` is a ``KeyboardInterrupt`` or was raised because of one.

    The chain of ``__cause__`` and ``__context__`` is followed (a numba dispatcher's
    ``SystemError`` carries the interrupt as its cause).

    Examples
    --------
    >>> try:
    ...     try:
    ...         raise KeyboardInterrupt
    ...     except KeyboardInterrupt as ki:
    ...         raise SystemError("returned a result with an exception set") from ki
    ... except SystemError as err:
    ...     wrapped = err
    >>> is_interrupt(wrapped), is_interrupt(ValueError("x")), is_interrupt(None)
    (True, False, False)
    """
    todo: list[BaseException] = [err] if err is not None else []
    seen: set[int] = set()
    while todo:
        exc = todo.pop()
        if id(exc) in seen:
            continue
        seen.add(id(exc))
        if isinstance(exc, KeyboardInterrupt):
            return True
        todo.extend(e for e in (exc.__cause__, exc.__context__) if e is not None)
    return False


def reraise_interrupt(err: BaseException) -> None:
    """Raise ``err`` again if it is an interrupt: itself when bare, else a ``KeyboardInterrupt`` from it.

    Called in an ``except`` clause that otherwise turns ``err`` into a status; returns when
    ``err`` is not an interrupt.

    Examples
    --------
    >>> try:
    ...     try:
    ...         raise SystemError("wrapped") from KeyboardInterrupt()
    ...     except BaseException as err:
    ...         reraise_interrupt(err)
    ... except KeyboardInterrupt as ki:
    ...     type(ki.__cause__).__name__
    'SystemError'
    """
    if isinstance(err, KeyboardInterrupt):
        raise err
    if is_interrupt(err):
        raise KeyboardInterrupt from err
