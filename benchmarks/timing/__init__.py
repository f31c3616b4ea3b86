"""The solver timing reports of ``rmpc timing``: one module per problem and the report around them.

- :mod:`benchmarks.timing.suite`: the command, its configuration and the report (``timing.json``,
  ``timing.md``);
- :mod:`benchmarks.timing.rmpc`, :mod:`benchmarks.timing.offline`, :mod:`benchmarks.timing.gipc`:
  the timed paths of each problem;
- :mod:`benchmarks.timing.plots`: the time-distribution figures.
"""

from benchmarks.timing.suite import (
    PROBLEMS,
    VERTEX_COUNTS,
    TimingConfig,
    add_timing_parser,
    config_from_args,
    format_markdown,
    polytope,
    run_timing,
    run_timing_command,
)

__all__ = [
    "PROBLEMS",
    "VERTEX_COUNTS",
    "TimingConfig",
    "add_timing_parser",
    "config_from_args",
    "format_markdown",
    "polytope",
    "run_timing",
    "run_timing_command",
]
