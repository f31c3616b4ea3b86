"""The control laws of the field's papers, one sub-package per plant family.

- :mod:`rmpc.laws.wheel`: paper W's adaptive backstepping fault compensation;
- :mod:`rmpc.laws.mrp`: paper M's command-filtered (modular adaptive) backstepping with its
  command filter and extended state observer;
- :mod:`rmpc.laws.flexible`: papers S and V's laws for the flexible satellite (sliding modes,
  PD, vibration control).

:mod:`rmpc.laws.continuous` is their common base: a continuous-time law with an internal state,
run sampled.
"""
