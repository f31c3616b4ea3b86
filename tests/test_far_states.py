"""States far outside the region (:mod:`dev.far_states`): the IPM proves them infeasible by
itself, with a certificate the independent check accepts, and the records say so.

Two problems of the benchmark's set (2 and 5 states, 1e3 beyond the slab the input can hold),
one repeat; no time is asserted (the benchmark measures it).
"""

from __future__ import annotations

import pytest

from dev.far_states import far_problems, format_far, run_far
from lmi.infeasibility import MIN_RADIUS


@pytest.fixture(scope="module")
def records():
    return run_far(far_problems(sizes=(2, 5), seeds=(1,), distances=(1e3,)), repeats=1)


def test_far_states_are_proved_infeasible_by_the_ipm_itself(records):
    assert [r["label"] for r in records] == ["n2-v2-infeasible-s1-d1000", "n5-v2-infeasible-s1-d1000"]
    for r in records:
        assert r["status"] == "infeasible" and r["certificate_ok"], r
        assert r["solver_status"] == "ipm infeasible"  # no phase one, no Clarabel
        assert r["certificate_radius"] >= MIN_RADIUS
        assert r["far_alone_status"] == "infeasible"  # the same without the fallback


def test_the_comparison_state_is_feasible_and_the_far_one_beyond_the_region(records):
    for r in records:
        assert r["feasible_status"] == "optimal"
        # the slab holds the whole region, so the state is at least 1e3 times beyond it (the
        # bisection stops within 1 %)
        assert r["beyond"] >= 0.99e3
        assert r["time_ratio"] == pytest.approx(r["far_time_s"] / r["feasible_time_s"])


def test_the_table_counts_the_proofs(records):
    text = format_far(records)
    assert "2 of 2 infeasible with a checked certificate" in text
    assert text.count("| n") == 2
