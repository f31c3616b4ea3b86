"""Paper V's flexible satellite as a benchmark family (``family = "flexible"``).

- :mod:`benchmarks.families.flexible.defaults`: every setting paper V leaves out, in one place;
- :mod:`benchmarks.families.flexible.controllers`: paper V's sliding-mode laws (``MTSMC``,
  ``CSMC``, with or without the PZT vibration control), paper S's PD and the LQR reference, and
  the robust MPC (``RMPC``, ``OfflineRMPC``) on the 14-state linear model;
- :mod:`benchmarks.families.flexible.family`: the scenario fields, one case simulated, the metrics;
- :mod:`benchmarks.families.flexible.region`: how far along a slew axis the robust MPC's LMIs
  reach (one SDP, checked without the solver).
"""
