"""The bad-input probe: its verdicts, its runner's time limit, and that every target's valid call succeeds.

The probe measures how the toolkit answers bad input, so its own judgement is tested here on
inputs whose answer is known: a call that sleeps is a hang, an IndexError from numpy a crash, a
toolkit error that names the argument clear and one that does not unclear.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from dev.robustness.api_cases import api_probes, targets
from dev.robustness.cli_cases import cli_probes
from dev.robustness.probe import Probe
from dev.robustness.runner import run_api_probe
from dev.robustness.verdicts import classify_cli, classify_exception
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_positive


@pytest.mark.parametrize("target", targets(), ids=lambda t: t[0])
def test_every_target_accepts_its_valid_call(target):
    """Each bad value is the only change from a call that succeeds, so a verdict is about that value."""
    _, build, _, _ = target
    build()


def test_probe_ids_are_unique():
    ids = [p.id for p in api_probes() + cli_probes()]
    assert len(ids) == len(set(ids))


def _raise(error: BaseException) -> None:
    raise error


def test_toolkit_error_naming_the_argument_and_value_is_clear():
    with pytest.raises(InvalidArgumentError) as caught:
        check_positive(-1.0, "dt")
    assert classify_exception(caught.value, ("dt",)) == "clear"
    assert classify_exception(caught.value, ("u_max",)) == "unclear"
    assert classify_exception(caught.value, ("dt",), ("nan",)) == "unclear"


def test_error_raised_inside_numpy_is_a_crash():
    try:
        np.zeros(2)[5]
    except IndexError as error:
        assert classify_exception(error, ("x",)) == "crash"
    try:
        np.linalg.cholesky(-np.eye(2))
    except np.linalg.LinAlgError as error:  # a ValueError subclass, raised by numpy
        assert classify_exception(error, ()) == "crash"


def test_memory_and_recursion_errors_are_crashes():
    assert classify_exception(MemoryError(), ()) == "crash"
    assert classify_exception(RecursionError(), ()) == "crash"


@pytest.mark.parametrize(
    ("returncode", "stderr", "verdict"),
    [
        (None, "", "hang"),
        (0, "", "silent"),
        (2, "rmpc: error: --out: expected a folder, but found ''", "clear"),
        (2, "rmpc: error: something is wrong", "unclear"),
        (2, "Traceback (most recent call last):\n  File ...\nKeyError: 'x'", "crash"),
        (1, "rmpc: error: --out: bad", "crash"),
        (2, "rmpc: error: --out: bad\nmore words\neven more", "unclear"),
    ],
)
def test_cli_verdicts(returncode, stderr, verdict):
    assert classify_cli(returncode, stderr, ("--out",)) == verdict


def test_runner_calls_a_sleeping_call_a_hang_within_the_limit():
    probe = Probe("sleep", "api", (), call=lambda: time.sleep(30))
    start = time.perf_counter()
    outcome = run_api_probe(probe, timeout=1.0)
    assert outcome.verdict == "hang"
    assert time.perf_counter() - start < 20  # the child was killed, not waited for


def test_runner_verdicts_for_accepted_crashing_and_clear_calls():
    silent = run_api_probe(Probe("ok", "api", ("x",), call=lambda: 1.0), timeout=20)
    assert silent.verdict == "silent"
    either = run_api_probe(Probe("ok", "api", ("x",), call=lambda: 1.0, expect="either"), timeout=20)
    assert either.verdict == "clear"
    not_finite = run_api_probe(
        Probe("nan", "api", ("x",), call=lambda: float("nan"), expect="either"), timeout=20
    )
    assert not_finite.verdict == "silent"
    crash = run_api_probe(Probe("idx", "api", ("x",), call=lambda: np.zeros(1)[3]), timeout=20)
    assert crash.verdict == "crash"
    clear = run_api_probe(Probe("dt", "api", ("dt",), call=lambda: check_positive(0.0, "dt")), timeout=20)
    assert clear.verdict == "clear", clear.detail


def test_runner_memory_limit_turns_a_huge_allocation_into_memory_error():
    outcome = run_api_probe(Probe("big", "api", (), call=lambda: np.ones(10**11)), timeout=30)
    assert outcome.verdict == "crash"
    assert "MemoryError" in outcome.detail
