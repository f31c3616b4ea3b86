"""Bad and edge inputs tried as a new user would, each classified by what the toolkit does.

The probe runs a catalogue of inputs through the Python API (:mod:`.api_cases`) and the ``rmpc``
command (:mod:`.cli_cases`) and gives each one a verdict (:mod:`.verdicts`):

- ``clear``: a ``ValueError``/``TypeError`` (API) or exit status 2 with a one-line message and no
  traceback (CLI), and the message names what the user gave (the argument, the option, the file);
- ``unclear``: an error of the right kind whose message does not name what the user gave;
- ``crash``: an exception of another kind, or one raised inside a library rather than by the
  toolkit (API); a traceback or an unexpected exit status (CLI);
- ``silent``: the input was accepted although it should have been refused;
- ``hang``: no answer within the time limit.

Run it with ``python -m dev.robustness --out DIR``; it writes ``DIR/probe.json`` (one record
per input) and ``DIR/probe.md`` (counts per verdict and the list of inputs that are not ``clear``).
"""

from dev.robustness.verdicts import VERDICTS, Outcome

__all__ = ["VERDICTS", "Outcome"]
