"""MUP's method keys by name: each builds the form its table names (the same answer as the
options written out), MUP's per-component input bound by default, and clear refusals."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.suites.methods_problems import build_problem
from rmpc import RMPC
from rmpc.mpc.methods import METHODS, NOT_YET
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

#: The options each key stands for, written out here independently of the module's table.
EXPECTED = {
    "kothare": {},
    "cuzzola": {"lyapunov": "vertex"},
    "mao": {"lyapunov": "vertex_pairs"},
    "wan": {"cost": "nominal"},
    "cao": {"saturation": "auxiliary"},
    "mao_cao": {"lyapunov": "vertex_pairs", "saturation": "auxiliary"},
    "wan_cao": {"cost": "nominal", "saturation": "auxiliary"},
    "li": {"horizon": 2, "step_gains": "vertex", "lyapunov": "common"},
    "shi": {"horizon": 3, "lyapunov": "vertex_pairs", "saturation": "auxiliary"},
    "ding": {"cost": "nominal", "lyapunov": "vertex_pairs"},
    "huang": {"saturation": "auxiliary", "unsaturated_weight": 1e3},
    "zhang": {"saturation": "auxiliary", "lyapunov": "saturation_dependent"},
    "wan_huang": {"cost": "nominal", "saturation": "auxiliary", "unsaturated_weight": 1e3},
    "mao_huang": {"lyapunov": "vertex_pairs", "saturation": "auxiliary", "unsaturated_weight": 1e3},
    "wan_zhang": {"cost": "nominal", "saturation": "auxiliary", "lyapunov": "saturation_dependent"},
}
#: MUP's soft-constrained keys: the options of their base key (the caller gives the soft limits).
SOFT_CON = {
    "kothare_soft_con": {}, "wan_soft_con": {"cost": "nominal"}, "cao_soft_con": {"saturation": "auxiliary"},
    "wan_cao_soft_con": {"cost": "nominal", "saturation": "auxiliary"},
}
#: The tuning parameters the caller gives (MUP's demo values above).
GIVEN = ("unsaturated_weight",)
#: MUP's 19 keys (rmpc_methods/feas_<key>.m).
MUP_KEYS = {
    "kothare", "kothare_soft_con", "cuzzola", "mao", "wan", "wan_soft_con", "cao", "cao_soft_con",
    "mao_cao", "wan_cao", "wan_cao_soft_con", "ding", "li", "huang", "shi", "zhang", "wan_huang",
    "mao_huang", "wan_zhang",
}


def test_every_mup_key_is_either_carried_or_refused_by_name() -> None:
    assert set(METHODS) == set(EXPECTED) | set(SOFT_CON)
    assert set(METHODS) | set(NOT_YET) == MUP_KEYS and not set(METHODS) & set(NOT_YET)


@pytest.mark.parametrize("key", list(EXPECTED))
def test_a_key_gives_the_answer_of_its_options_written_out(key: str) -> None:
    p = build_problem("mup_demo")
    common = {"Q": p.Q, "R": p.R, "u_max": p.u_max}
    given = {name: EXPECTED[key][name] for name in GIVEN if name in EXPECTED[key]}
    by_key = RMPC.from_method(key, p.plant, **common, **given)
    by_hand = RMPC(p.plant, input_constraint="peak", **common, **EXPECTED[key])
    assert by_key.input_constraint == "peak"
    got, want = by_key.solve(p.x0), by_hand.solve(p.x0)
    assert got.status == want.status == "optimal"
    assert got.gamma == pytest.approx(want.gamma, rel=1e-6)
    np.testing.assert_allclose(got.F, want.F, rtol=1e-4, atol=1e-6 * np.abs(want.F).max())


def test_the_caller_may_choose_the_input_bound_kind() -> None:
    p = build_problem("mup_demo")
    ctrl = RMPC.from_method("wan", p.plant, Q=p.Q, R=p.R, u_max=float(np.min(p.u_max)),
                            input_constraint="ellipsoid")
    assert ctrl.input_constraint == "ellipsoid" and ctrl.form.cost == "nominal"


def test_refusals_name_the_argument() -> None:
    p = build_problem("mup_demo")
    kw = {"Q": p.Q, "R": p.R}
    with pytest.raises(InvalidArgumentError, match=r"key: .*'kothare'.*found 'kotare'"):
        RMPC.from_method("kotare", p.plant, **kw)
    with pytest.raises(ArgumentTypeError, match="key"):
        RMPC.from_method(1, p.plant, **kw)
    with pytest.raises(InvalidArgumentError, match=r"lyapunov: expected 'vertex'.*found 'common'"):
        RMPC.from_method("cuzzola", p.plant, lyapunov="common", **kw)


def test_shi_takes_the_callers_horizon_and_li_refuses_another() -> None:
    """shi's ``horizon=3`` is MUP's demo's choice, the caller's own is taken; li's two steps are the
    method."""
    p = build_problem("mup_demo")
    kw = {"Q": p.Q, "R": p.R, "u_max": p.u_max}
    assert RMPC.from_method("shi", p.plant, **kw).form.horizon == 3
    assert RMPC.from_method("shi", p.plant, horizon=5, **kw).form.horizon == 5
    with pytest.raises(InvalidArgumentError, match=r"horizon: expected 2 \(method 'li' sets it\)"):
        RMPC.from_method("li", p.plant, horizon=3, **kw)
#: MUP's soft-constraint parameters of its demo (``soft_con/mup_rmpc_soft_con_demo.m``): u_sl = 0.4,
#: y_sl = [1; 0.5], Wsu = 1e4, Wsy = 1e2 I, Esu = 1, Esy = I.
MUP_SOFT = {"u": [1e4], "u_limit": [0.4], "y": [1e2, 1e2], "y_limit": [1.0, 0.5]}


@pytest.mark.parametrize("key", list(SOFT_CON))
def test_a_soft_con_key_is_its_base_form_with_the_callers_soft_limits(key: str) -> None:
    p = build_problem("mup_demo")
    common = {"Q": p.Q, "R": p.R, "u_max": p.u_max, "output_matrix": p.output_matrix, "y_max": p.y_max}
    by_key = RMPC.from_method(key, p.plant, soft=MUP_SOFT, **common)
    by_hand = RMPC(p.plant, input_constraint="peak", soft=MUP_SOFT, **common, **SOFT_CON[key])
    got, want = by_key.solve(p.x0), by_hand.solve(p.x0)
    assert got.status == want.status == "optimal"
    assert got.gamma == pytest.approx(want.gamma, rel=1e-6)
    # the soft limits bind at x0 (u_sl = 0.4 against a hard bound of 10): one slack per component
    assert set(got.slack) == {"u0", "y0", "y1"} and min(got.slack.values()) > 1e-3
    hard = RMPC.from_method(key.removesuffix("_soft_con"), p.plant, **common).solve(p.x0)
    assert got.gamma > 1.5 * hard.gamma  # measured: 517 / 43.3 (kothare), 78.1 / 23.5 (wan)


def test_a_soft_con_key_needs_the_soft_limits() -> None:
    p = build_problem("mup_demo")
    kw = {"Q": p.Q, "R": p.R, "u_max": p.u_max}
    with pytest.raises(InvalidArgumentError, match=r"soft: expected MUP's soft limits for 'wan_soft_con'"):
        RMPC.from_method("wan_soft_con", p.plant, **kw)
    with pytest.raises(InvalidArgumentError, match=r"soft: expected MUP's soft limits.*found \{'u': 100.0\}"):
        RMPC.from_method("kothare_soft_con", p.plant, soft={"u": 100.0}, **kw)
    with pytest.raises(InvalidArgumentError, match=r"soft\['u_limit'\]\[0\]: expected a finite soft limit"):
        RMPC.from_method("cao_soft_con", p.plant, soft={"u": [1.0], "u_limit": [-0.4]}, **kw)
