"""Scenarios, sweeps, metrics, reports and the ``rmpc`` command line.

The package has one room per kind of work:

- :mod:`benchmarks.core`: the harness itself, independent of any plant: the validated
  :class:`~benchmarks.core.scenario.Scenario`, the plant-family protocol
  (:mod:`benchmarks.core.family`) and registry (:mod:`benchmarks.core.registry`), one case
  simulated and measured (:mod:`~benchmarks.core.runner`,
  what workers run), generic metrics, local processes or Dask (:mod:`~benchmarks.core.executors`,
  :mod:`~benchmarks.core.execute`), the resumable SQLite store and TOML sweeps;
- :mod:`benchmarks.families`: one sub-package per plant family (its scenario fields and
  defaults, its controllers, how a case is built and simulated, its own metrics), listed in
  ``SHIPPED_FAMILIES``; a new family is added there without editing the core;
- :mod:`benchmarks.suites`: the experiments of each paper the toolkit reproduces
  (``rmpc bench paper``) and the checks of their claims;
- :mod:`benchmarks.timing`: the solver timing reports (``rmpc timing``);
- :mod:`benchmarks.reports`: tables (Markdown, CSV, LaTeX, JSON) and figures;
- :mod:`benchmarks.cli`: the ``rmpc`` command;
- ``benchmarks/sweeps/``: the shipped sweep files.
"""
