"""The round-two closing probes (:mod:`dev.robustness.close_cases`): unique ids in the whole
catalogue, and the script probe's own judgement on scripts whose answer is known."""

from __future__ import annotations

from dev.robustness.api_cases import api_probes
from dev.robustness.cli_cases import cli_probes
from dev.robustness.close_cases import ScriptProbe, close_probes
from dev.robustness.interrupt_cases import interrupt_probes
from dev.robustness.solver_cases import solver_probes
from dev.robustness.store_cases import store_probes
from dev.robustness.sweep_cases import sweep_probes


def test_probe_ids_are_unique_in_the_whole_catalogue():
    ids = [p.id for p in api_probes() + solver_probes() + cli_probes() + store_probes() + interrupt_probes()
           + sweep_probes() + close_probes()]
    assert len(ids) == len(set(ids))
    kinds = {p.kind for p in close_probes()}
    assert {"sweep reach", "interrupt", "store", "numpy integer", "value"} <= kinds


def _run(script: str) -> str:
    return ScriptProbe("x", "api", ("x",), script=script).run(30.0).verdict


def test_a_script_probe_takes_the_verdict_its_script_prints_and_a_traceback_is_a_crash():
    assert _run("print('clear all good')") == "clear"
    assert _run("print('silent the interrupt was lost')") == "silent"
    assert _run("raise RuntimeError('boom')") == "crash"
    assert _run("print('maybe')") == "crash"  # no verdict word
    assert ScriptProbe("x", "api", ("x",), script="import time; time.sleep(5)").run(1.0).verdict == "hang"
