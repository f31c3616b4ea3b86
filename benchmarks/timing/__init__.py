"""The solver timing reports of ``rmpc timing``: one module per problem and the report around them.

- :mod:`benchmarks.timing.suite`: the command, the run and the files (``timing.json``,
  ``timing.md``, ``timing.png``, ``timing_samples.npz``);
- :mod:`benchmarks.timing.config`: the options and their checks;
- :mod:`benchmarks.timing.common`: paper P's timing problem, its polytopes, the record helpers;
- :mod:`benchmarks.timing.rmpc`, :mod:`benchmarks.timing.offline`, :mod:`benchmarks.timing.gipc`:
  the timed paths of each problem (the report's section and a stand-alone script each);
- :mod:`benchmarks.timing.scale`: the opt-in scale section (the flexible satellite, 6-20 states);
- :mod:`benchmarks.timing.c_exports`: the opt-in C section (the exported controllers against the
  anchors; :mod:`benchmarks.timing.cpg_attempt` tries CVXPYgen on the same LMIs);
- :mod:`benchmarks.timing.markdown`: ``timing.md``;
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
