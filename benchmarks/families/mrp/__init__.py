"""Paper M's MRP satellite as a benchmark family (``family = "mrp"``).

- :mod:`benchmarks.families.mrp.defaults`: every setting paper M leaves out, in one place;
- :mod:`benchmarks.families.mrp.controllers`: paper M's backstepping controllers (``BS``,
  ``MAB``, ``TFAB``) and the robust MPC (``RMPC``, ``CRMPC``) on the error attitude;
- :mod:`benchmarks.families.mrp.family`: the scenario fields, one case simulated, the metrics.
"""
