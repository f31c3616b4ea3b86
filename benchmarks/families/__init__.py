"""Plant families of the benchmarks (see :mod:`benchmarks.core.family`)."""
