"""The benchmark suites: the experiments of each paper the toolkit reproduces.

- :mod:`benchmarks.suites.paper`: experiments E1-E6 of paper P (``rmpc bench paper``);
- :mod:`benchmarks.suites.paper_claims`: paper P's comparative claims checked on a run.
"""
