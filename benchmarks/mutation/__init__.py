"""A mutation check of the toolkit's tests: ``python -m benchmarks.mutation`` (a benchmark, not run in CI).

It changes one thing at a time in a copy of the chosen modules (a comparison negated, ``+`` for
``-``, a constant, a dropped ``not``, a return value, a removed statement: the operators of
:mod:`benchmarks.mutation.operators`), runs the tests that run the changed line, and counts the
mutants the tests catch and those that survive. A seeded sample keeps a run within a budget.

- :mod:`benchmarks.mutation.operators`: the mutants of a module's source.
- :mod:`benchmarks.mutation.sandbox`: the temporary copy the mutants are written into and the tests
  run in; the working files are never written.
- :mod:`benchmarks.mutation.plugin`: the pytest plugin of the child processes (the per-test line
  map, the selection of a mutant's tests).
- :mod:`benchmarks.mutation.runner`: the map, the rule that picks a mutant's tests, the run.
- :mod:`benchmarks.mutation.report`: ``results.json`` and ``report.md``.
- :mod:`benchmarks.mutation.cli`: the command line.

This package imports nothing of the toolkit's other packages (the plugin is loaded into test
processes before they import anything).
"""
