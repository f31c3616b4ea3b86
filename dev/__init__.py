"""Development tools of the repository, not part of the installed distribution.

``pip install .`` installs ``models``, ``lmi``, ``rmpc``, ``benchmarks`` and ``toolkit_common``;
this folder stays in the checkout. Run its tools from the repository root (the root must be on
``sys.path``, as ``python -m`` puts it; the tests get it from ``pythonpath`` in ``pyproject.toml``):

- ``python -m dev.robustness --out DIR``: several hundred bad and edge inputs through the API and
  the ``rmpc`` command, each given a verdict (:mod:`dev.robustness`).
- ``python -m dev.stress``: the seeded stress set of Kothare problems feasible or infeasible by
  construction, solved by each back-end (:mod:`dev.stress`).
- ``python -m dev.generic_stress``: generic open-loop-unstable problems of 8 to 30 states, the
  interior-point method against cvxpy + Clarabel (:mod:`dev.generic_stress`).
- ``python -m dev.far_states``: states 10 to 10^6 times outside the region the input bound
  allows, each proved infeasible (:mod:`dev.far_states`).
- ``python -m dev.public_lmi``: SDPLIB's control2-4 against their published optima
  (:mod:`dev.public_lmi`).
- ``python -m dev.offline_timing --out DIR``: the off-line design's timing per back-end
  (:mod:`dev.offline_timing`).
- ``python dev/blas_kernels.py --out DIR``: the test suite under several OpenBLAS kernel choices.
- Mutation testing with mutmut, configured in ``pyproject.toml`` (``[tool.mutmut]``); the last
  run's report is ``dev/reports/mutation/report.md``.

The shipped packages never import this one (``tests/test_distribution_contents.py``).
"""
