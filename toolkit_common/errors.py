"""The exception hierarchy of the toolkit.

Every error the toolkit raises on purpose derives from :class:`ToolkitError`, so a user can
catch all of them in one place::

    from rmpc.errors import ToolkitError

    try:
        ctrl = RMPC(plant, Q=Q, R=R)
    except ToolkitError as err:
        print(err)

Bad arguments also derive from the builtin :class:`ValueError` or :class:`TypeError`, so code
that already catches those keeps working. A solver that fails to find an answer is reported as
a *status* on the returned solution; :class:`SolverError` is raised only where the user asked
for failures to raise (``on_failure="raise"``).
"""

from __future__ import annotations


class ToolkitError(Exception):
    """Base class of every error raised on purpose by the toolkit."""


class InvalidArgumentError(ToolkitError, ValueError):
    """An argument has the right type but a wrong value (shape, sign, NaN, unknown option).

    Parameters
    ----------
    argument : str
        The name of the offending argument, as the user wrote it.
    expected : str
        What was expected, in words.
    found : str
        What was found instead.
    """

    def __init__(self, argument: str, expected: str, found: str) -> None:
        self.argument = argument
        self.expected = expected
        self.found = found
        super().__init__(f"{argument}: expected {expected}, but found {found}")


class ArgumentTypeError(ToolkitError, TypeError):
    """An argument has the wrong type."""

    def __init__(self, argument: str, expected: str, found: str) -> None:
        self.argument = argument
        self.expected = expected
        self.found = found
        super().__init__(f"{argument}: expected {expected}, but found {found}")


class ConfigError(InvalidArgumentError):
    """A configuration file (a sweep TOML, say) is malformed or names an impossible value.

    ``argument`` is the dotted path of the offending field, e.g. ``"grid.spread"``.
    """


class StoreError(InvalidArgumentError):
    """A sweep's store (``DIR/sweep.sqlite``) is damaged, foreign, locked or holds another sweep.

    ``argument`` is the store's path (or ``--out``); the message says what was found and what to
    do about it.
    """


class ControllerFileError(InvalidArgumentError):
    """A saved controller file is missing, damaged, truncated, foreign or newer than this toolkit,
    or cannot be written where asked (:func:`rmpc.load`, ``ctrl.save(path)``).

    ``argument`` is the file's path; the message says what was expected and what was found.
    """


class SingularityError(ToolkitError, ArithmeticError):
    """A model was evaluated where it is singular (3-2-1 Euler angles at pitch = +-90 deg)."""


class SolverError(ToolkitError, RuntimeError):
    """A numerical solver failed and the caller asked for failures to raise."""


class NoCertifiedGainWarning(UserWarning):
    """A controller applies an input no certified gain stands behind (zero before the first one).

    Issued once per run (until ``reset()`` or the next certified gain) with the step's status and
    a diagnosis: what blocks a certified gain and what to try. Filter it like any warning::

        warnings.filterwarnings("ignore", category=NoCertifiedGainWarning)
    """
