"""Paper P's rigid satellite as a benchmark family (``family = "rigid"``, the default).

- :mod:`benchmarks.families.rigid.defaults`: every setting paper P leaves out, in one place;
- :mod:`benchmarks.families.rigid.controllers`: its controllers and saturation handling;
- :mod:`benchmarks.families.rigid.family`: its scenario fields, the plant and polytope of a case,
  the simulation and the metrics.
"""
