"""Scenarios, sweeps, metrics, reports and the ``rmpc`` command line."""
