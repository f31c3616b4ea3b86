"""The harness core: scenarios, the plant-family registry, running and storing cases, sweeps.

Nothing here knows a particular plant; the families (:mod:`benchmarks.families`) bring the
plants, their fields, controllers and metrics.
"""
