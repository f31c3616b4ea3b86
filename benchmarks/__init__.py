"""Scenarios, sweeps, metrics, reports and the ``rmpc`` command line.

One module per job:

- :mod:`benchmarks.defaults`: every setting paper P leaves out, in one place;
- :mod:`benchmarks.scenario`: the validated :class:`~benchmarks.scenario.Scenario` of one run;
- :mod:`benchmarks.controllers`: the controller registry and saturation handling;
- :mod:`benchmarks.runner`: one scenario simulated and measured (what workers run);
- :mod:`benchmarks.metrics`: errors, settling, overshoot, torques, solver effort;
- :mod:`benchmarks.executors` and :mod:`benchmarks.execute`: local processes or Dask, one loop;
- :mod:`benchmarks.store`: the SQLite store that makes sweeps resumable;
- :mod:`benchmarks.sweep`: TOML sweeps (grid and Monte-Carlo) and their reports;
- :mod:`benchmarks.paper`: experiments E1-E6 of paper P;
- :mod:`benchmarks.report`, :mod:`benchmarks.plots`, :mod:`benchmarks.progress`: tables, figures,
  the progress bar;
- :mod:`benchmarks.cli`: ``rmpc demo``, ``rmpc bench paper``, ``rmpc bench sweep``.
"""
