"""Paper W's four-wheel satellite with wheel faults as a benchmark family (``family = "wheel"``).

- :mod:`benchmarks.families.wheel.defaults`: every setting paper W leaves out, in one place;
- :mod:`benchmarks.families.wheel.controllers`: the compensator of paper W (``ABFTC``) and the
  robust MPC family (``RMPC``, ``CRMPC``, ``GIPC``) on the wheel-effectiveness polytope;
- :mod:`benchmarks.families.wheel.family`: the scenario fields, one case simulated, the metrics.
"""
