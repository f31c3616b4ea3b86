"""The robust MPC's forms from a sweep file: each reachable, checked as Python checks it, run as in Python.

Before, a sweep file with ``settings.lyapunov``, ``cost``, ``free_moves``, ``saturation``, ``soft``,
``disturbance``, ``certificate_tol`` or ``on_failure`` was refused as an unknown setting: the forms
existed only through Python and ``rmpc bench methods``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks.core.scenario import Scenario
from benchmarks.core.sweep import run_sweep
from benchmarks.core.sweep_spec import SHIPPED, expand, load_sweep, parse_sweep
from benchmarks.families.rigid.defaults import CONTROLLER_DEFAULTS
from benchmarks.families.rmpc_forms import FORM_DEFAULTS, OUTPUT_DEFAULTS
from models import RigidSatellite
from toolkit_common.errors import ConfigError, ToolkitError

E_ROLL_RATE = [[0.0], [0.0], [0.0], [1.0], [0.0], [0.0]]


def _rmpc_sweep(settings: dict, **fields) -> dict:
    return {
        "base": {"controller": "RMPC", "plant": "linear", "duration": 0.02, **fields, "settings": settings}
    }


def _python_rmpc(**options):
    """The controller the rigid family builds, written out in Python (paper P's polytope, its weights)."""
    from rmpc import RMPC

    sat = RigidSatellite.paper_p()
    poly = sat.polytope(sat.initial_state(), 0.01, 0.3, "scalar")
    rmpc_defaults = CONTROLLER_DEFAULTS["RMPC"]
    q, r = np.diag(rmpc_defaults["Q_diag"]), np.diag(rmpc_defaults["R_diag"])
    return poly, RMPC(poly, q, r, u_max=1.0, **{"input_constraint": "ellipsoid", **options})


GOOD = [
    ({"lyapunov": "vertex"}, {"lyapunov": "vertex"}),
    ({"lyapunov": "vertex_pairs"}, {"lyapunov": "vertex_pairs"}),
    ({"cost": "nominal"}, {"cost": "nominal"}),
    ({"free_moves": 1}, {"free_moves": 1}),
    (
        {"saturation": "auxiliary", "input_constraint": "peak"},
        {"saturation": "auxiliary", "input_constraint": "peak"},
    ),
    ({"soft": {"u": 100}}, {"soft": {"u": 100.0}}),
    ({"disturbance": {"E": E_ROLL_RATE, "w_max": 0.01}}, {"disturbance": (np.array(E_ROLL_RATE), 0.01)}),
    ({"disturbance": [[0, 0, 0, 1, 0, 0], 0.01, 0.5]}, {"disturbance": (np.array(E_ROLL_RATE), 0.01, 0.5)}),
    ({"cost": "nominal", "lyapunov": "vertex_pairs"}, {"cost": "nominal", "lyapunov": "vertex_pairs"}),
    (
        {"soft": {"u": [100, 0, 5]}, "input_constraint": "peak"},
        {"soft": {"u": [100.0, 0.0, 5.0]}, "input_constraint": "peak"},
    ),
    (
        {"soft": {"u": [100, 0, 5], "u_limit": [0.5, 0, 0.2]}},
        {"soft": {"u": (100.0, 0.0, 5.0), "u_limit": (0.5, 0.0, 0.2)}},
    ),
]


@pytest.mark.parametrize(("settings", "python"), GOOD, ids=[str(g[0]) for g in GOOD])
def test_each_form_is_reachable_from_a_sweep_and_builds_the_controller_python_builds(settings, python):
    (scenario,) = expand(parse_sweep(_rmpc_sweep(settings)))
    poly, reference = _python_rmpc(**python)
    built = scenario.plant_family.build_controller(poly, scenario).controller
    assert _same_form(built.form, reference.form)
    assert not built.form.is_kothare
    assert built.problem.data.input_constraint == reference.problem.data.input_constraint


def _same_form(a, b) -> bool:
    fields = ("lyapunov", "cost", "free_moves", "saturation", "soft")
    if any(getattr(a, f) != getattr(b, f) for f in fields) or (a.disturbance is None) != (
        b.disturbance is None
    ):
        return False
    return a.disturbance is None or (
        np.array_equal(a.disturbance.E, b.disturbance.E)
        and (a.disturbance.w_max, a.disturbance.lam) == (b.disturbance.w_max, b.disturbance.lam)
    )


def test_the_solve_options_are_reachable_and_reach_the_controller():
    settings = {"certificate_tol": 1e-5, "on_failure": "raise"}
    (scenario,) = expand(parse_sweep(_rmpc_sweep(settings)))
    poly, _ = _python_rmpc()
    built = scenario.plant_family.build_controller(poly, scenario).controller
    assert built.problem.certificate_tol == 1e-5
    assert built.certified.on_failure == "raise"


#: (settings, the Python keyword arguments that are refused the same way, the sweep's key path)
BAD = [
    ({"lyapunov": "quartic"}, {"lyapunov": "quartic"}, "base.settings.lyapunov"),
    ({"lyapunov": 3}, {"lyapunov": 3}, "base.settings.lyapunov"),
    ({"cost": "average"}, {"cost": "average"}, "base.settings.cost"),
    ({"soft": {"u": [1.0, -1.0, 0.0]}}, {"soft": {"u": [1.0, -1.0, 0.0]}}, "base.settings.soft.u[1]"),
    ({"soft": {"u": [0.0, 0.0, 0.0]}}, {"soft": {"u": [0.0, 0.0, 0.0]}}, "base.settings.soft.u"),
    (
        {"soft": {"u": [1.0, 0.0, 0.0], "u_limit": [0.5, 0.2, 0.0]}},
        {"soft": {"u": [1.0, 0.0, 0.0], "u_limit": [0.5, 0.2, 0.0]}},
        "base.settings.soft.u_limit[1]",
    ),
    ({"free_moves": 2}, {"free_moves": 2}, "base.settings.free_moves"),
    ({"free_moves": True}, {"free_moves": True}, "base.settings.free_moves"),
    ({"saturation": "clip"}, {"saturation": "clip"}, "base.settings.saturation"),
    (
        {"saturation": "auxiliary"},
        {"saturation": "auxiliary"},
        "base.settings.saturation, base.settings.input_constraint",
    ),
    ({"soft": {"u": -1.0}}, {"soft": {"u": -1.0}}, "base.settings.soft.u"),
    ({"soft": {"u": float("nan")}}, {"soft": {"u": float("nan")}}, "base.settings.soft.u"),
    ({"soft": {"u": "big"}}, {"soft": {"u": "big"}}, "base.settings.soft.u"),
    ({"soft": {"y": 1.0}}, {"soft": {"y": 1.0}}, "base.settings.soft"),
    ({"soft": {"x": 1.0}}, {"soft": {"x": 1.0}}, "base.settings.soft"),
    ({"soft": {}}, {"soft": {}}, "base.settings.soft"),
    (
        {"disturbance": {"E": [[1.0]], "w_max": 0.01}},
        {"disturbance": (np.array([[1.0]]), 0.01)},
        "base.settings.disturbance.E",
    ),
    (
        {"disturbance": {"E": E_ROLL_RATE, "w_max": -1.0}},
        {"disturbance": (np.array(E_ROLL_RATE), -1.0)},
        "base.settings.disturbance.w_max",
    ),
    (
        {"disturbance": {"E": E_ROLL_RATE, "w_max": 0.01, "lam": 1.0}},
        {"disturbance": (np.array(E_ROLL_RATE), 0.01, 1.0)},
        "base.settings.disturbance.lam",
    ),
    ({"disturbance": [E_ROLL_RATE]}, {"disturbance": (np.array(E_ROLL_RATE),)}, "base.settings.disturbance"),
    (
        {"disturbance": {"E": E_ROLL_RATE, "w_max": 0.01}, "free_moves": 1},
        {"disturbance": (np.array(E_ROLL_RATE), 0.01), "free_moves": 1},
        "base.settings.free_moves, base.settings.disturbance",
    ),
    ({"on_failure": "ignore"}, {"on_failure": "ignore"}, "base.settings.on_failure"),
]


@pytest.mark.parametrize(("settings", "python", "path"), BAD, ids=[str(b[0]) for b in BAD])
def test_a_bad_form_is_refused_with_pythons_message_at_the_sweep_files_key_path(settings, python, path):
    with pytest.raises(ToolkitError) as in_python:
        _python_rmpc(**python)
    with pytest.raises(ConfigError) as in_sweep:
        parse_sweep(_rmpc_sweep(settings))
    assert in_sweep.value.argument == path
    assert in_sweep.value.expected == in_python.value.expected  # the constructor's own check
    assert in_sweep.value.found == in_python.value.found


@pytest.mark.parametrize(
    ("settings", "path", "words"),
    [
        ({"soft": 5}, "base.settings.soft", "a table of weights"),
        ({"disturbance": {"E": E_ROLL_RATE}}, "base.settings.disturbance.w_max", "w_max"),
        ({"disturbance": {"E": E_ROLL_RATE, "w_max": 0.1, "q": 1}}, "base.settings.disturbance.q", "unknown"),
        ({"disturbance": 0.1}, "base.settings.disturbance", "a table"),
        ({"certificate_tol": 0.0}, "base.settings.certificate_tol", "> 0"),
    ],
)
def test_a_value_toml_writes_otherwise_than_python_is_refused_naming_the_key(settings, path, words):
    with pytest.raises(ConfigError) as info:
        parse_sweep(_rmpc_sweep(settings))
    assert info.value.argument == path and words in str(info.value)


def test_a_form_that_needs_the_scenarios_input_bound_names_the_saturation_field_too():
    with pytest.raises(ConfigError) as info:
        parse_sweep(_rmpc_sweep({"soft": {"u": 10.0}}, saturation="limiter"))
    assert info.value.argument == "base.settings.soft, base.saturation"
    assert "saturation = 'constraint'" in info.value.expected


def test_a_form_with_the_scheduled_polytope_is_refused_naming_kinematics():
    with pytest.raises(ConfigError) as info:
        parse_sweep(_rmpc_sweep({"lyapunov": "vertex"}, kinematics="scheduled", plant="nonlinear"))
    assert info.value.argument == "base.kinematics" and "settings.lyapunov" in info.value.expected


def test_an_error_between_a_grid_setting_and_a_base_setting_names_each_where_it_is():
    data = _rmpc_sweep({"disturbance": {"E": E_ROLL_RATE, "w_max": 0.01}})
    data["grid"] = {"settings": {"free_moves": [0, 1]}}
    with pytest.raises(ConfigError) as info:
        parse_sweep(data)
    assert info.value.argument == "grid.settings.free_moves, base.settings.disturbance"


def test_a_form_setting_of_another_controller_is_refused():
    with pytest.raises(ConfigError) as info:
        parse_sweep({"base": {"controller": "GIPC", "settings": {"lyapunov": "vertex"}}})
    assert info.value.argument == "base.settings.lyapunov" and "RMPC only" in info.value.found


def test_the_forms_left_at_their_defaults_keep_the_records_and_case_ids():
    rmpc = Scenario.from_dict({"controller": "RMPC"})
    assert set(rmpc.to_dict()["settings"]) == set(CONTROLLER_DEFAULTS["RMPC"])
    assert set(rmpc.settings) == set(CONTROLLER_DEFAULTS["RMPC"]) | set(FORM_DEFAULTS) | set(OUTPUT_DEFAULTS)
    soft = Scenario.from_dict({"controller": "RMPC", "settings": {"soft": {"u": 1}}})
    assert soft.to_dict()["settings"]["soft"] == {"u": 1.0} and soft.case_id != rmpc.case_id
    # a record's scenario read back (a resumed sweep) is the same case
    for sc in (
        soft,
        Scenario.from_dict(
            {"controller": "RMPC", "settings": {"disturbance": {"E": E_ROLL_RATE, "w_max": 0.01, "lam": 0.5}}}
        ),
    ):
        again = Scenario.from_dict(json.loads(json.dumps(sc.to_dict())))
        assert again.case_id == sc.case_id and again == sc


def test_the_shipped_forms_sweep_runs_and_its_records_are_those_of_the_controller_built_in_python(tmp_path):
    from benchmarks.core.metrics import compute_metrics
    from rmpc import simulate

    spec = load_sweep(SHIPPED / "forms.toml")
    outcome = run_sweep(SHIPPED / "forms.toml", tmp_path, workers=0, progress=False)
    assert outcome.total == len(expand(spec)) == 4 and outcome.failed == 0
    records = json.loads((Path(tmp_path) / "results.json").read_text())
    assert len(records) == 4
    for record in records:
        forms = {
            k: record["settings"]["settings"].get(k, FORM_DEFAULTS[k]) for k in ("lyapunov", "free_moves")
        }
        poly, ctrl = _python_rmpc(
            input_constraint="peak", saturation="auxiliary", soft={"u": 1000.0}, **forms
        )
        x0 = RigidSatellite.paper_p().initial_state()
        traj = simulate(ctrl, poly, x0, duration=0.03)
        metrics = compute_metrics(traj, 1.0, 0.02)
        assert record["metrics"]["status_counts"] == {"optimal": 3}
        for key in ("sum_abs_err", "iae", "max_abs_u"):
            stored, measured = record["metrics"][key], metrics[key]
            if isinstance(measured, dict):  # per axis
                assert set(stored) == set(measured)
                stored, measured = [stored[a] for a in sorted(stored)], [measured[a] for a in sorted(stored)]
            np.testing.assert_allclose(stored, measured, rtol=1e-9, atol=1e-12)
    assert {
        (r["settings"]["settings"].get("lyapunov"), r["settings"]["settings"].get("free_moves"))
        for r in records
    } == {(None, None), ("vertex_pairs", None), (None, 1), ("vertex_pairs", 1)}


@pytest.mark.parametrize("family", ["wheel", "mrp"])
def test_the_other_families_rmpc_takes_the_forms_from_a_sweep(family, monkeypatch):
    import rmpc.mpc.robust_mpc as robust_mpc
    from benchmarks.core.runner import run_scenario

    built = []
    init = robust_mpc.RMPC.__init__

    def spy(self, *args, **kwargs):
        init(self, *args, **kwargs)
        built.append(self)

    monkeypatch.setattr(robust_mpc.RMPC, "__init__", spy)
    extra = {"fault_kind": "none"} if family == "wheel" else {}
    base = {**extra, "family": family, "controller": "RMPC", "saturation": "constraint"}
    dt = Scenario.from_dict(base).dt
    settings = {"lyapunov": "vertex", "soft": {"u": 100.0}, "on_failure": "raise"}
    (scenario,) = expand(parse_sweep({"base": {**base, "duration": 3 * dt, "settings": settings}}))
    record = run_scenario(scenario)
    assert record["metrics"]["status_counts"] == {"optimal": 3}
    (ctrl,) = built
    assert (ctrl.form.lyapunov, dict(ctrl.form.soft), ctrl.certified.on_failure) == (
        "vertex",
        {"u": 100.0},
        "raise",
    )
    assert ctrl.plant.n_states == 6
    with pytest.raises(ConfigError) as info:
        parse_sweep({"base": {**base, "settings": {"disturbance": {"E": [[1.0]] * 14, "w_max": 0.1}}}})
    assert info.value.argument == "base.settings.disturbance.E" and "(6, q)" in info.value.expected


def test_the_flexible_rmpc_takes_the_forms_on_its_14_states_and_soft_output_bounds_with_its_modal_bound():
    base = {"family": "flexible", "controller": "RMPC", "saturation": "constraint"}
    with pytest.raises(ConfigError) as info:
        parse_sweep({"base": {**base, "settings": {"disturbance": {"E": E_ROLL_RATE, "w_max": 0.1}}}})
    assert info.value.argument == "base.settings.disturbance.E" and "(14, q)" in info.value.expected
    with pytest.raises(ConfigError) as info:
        parse_sweep({"base": {**base, "settings": {"soft": {"y": 10.0}}}})
    assert info.value.argument == "base.settings.soft" and "output bounds" in info.value.expected
    (scenario,) = expand(
        parse_sweep({"base": {**base, "modal_bound": 0.02, "settings": {"soft": {"y": 10.0}}}})
    )
    assert dict(scenario.settings["soft"]) == {"y": 10.0}


# -- the forms with steps (horizon, step_gains) ------------------------------------------------------

@pytest.mark.parametrize(("settings", "want"), [
    ({"horizon": 2, "lyapunov": "vertex_pairs"}, (2, "common", "vertex_pairs")),
    ({"horizon": 2, "step_gains": "vertex"}, (2, "vertex", "common")),
])
def test_the_steps_are_reachable_from_a_sweep(settings, want):
    (scenario,) = expand(parse_sweep(_rmpc_sweep(settings)))
    poly, _ = _python_rmpc()
    built = scenario.plant_family.build_controller(poly, scenario).controller
    assert (built.form.horizon, built.form.step_gains, built.form.lyapunov) == want


STEPS_BAD = [
    ({"horizon": 0}, "base.settings.horizon"),
    ({"horizon": 2.5}, "base.settings.horizon"),
    ({"step_gains": "per_vertex"}, "base.settings.step_gains"),
    ({"step_gains": "vertex"}, "base.settings.step_gains, base.settings.horizon"),
    ({"horizon": 2, "cost": "nominal"}, "base.settings.horizon, base.settings.cost"),
]


@pytest.mark.parametrize(("settings", "path"), STEPS_BAD, ids=[str(b[0]) for b in STEPS_BAD])
def test_a_bad_step_setting_is_refused_with_pythons_message_at_its_key_path(settings, path):
    with pytest.raises(ToolkitError) as in_python:
        _python_rmpc(**settings)
    with pytest.raises(ConfigError) as in_sweep:
        parse_sweep(_rmpc_sweep(settings))
    assert in_sweep.value.argument == path
    assert in_sweep.value.expected == in_python.value.expected
    assert in_sweep.value.found == in_python.value.found
