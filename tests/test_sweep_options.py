"""RMPC's solver options from a sweep file: reachable, checked by the constructor with the case's backend.

Before, ``settings.solver_options`` (e.g. the ipm's ``core``: ``"auto"``, ``"c"`` or ``"numba"``)
was refused as an unknown setting: the options existed only through Python.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks.core.scenario import Scenario
from benchmarks.core.sweep_spec import expand, parse_sweep
from benchmarks.families.rigid.defaults import CONTROLLER_DEFAULTS
from models import RigidSatellite
from toolkit_common.errors import ConfigError, ToolkitError


def _sweep(settings: dict, **fields) -> dict:
    return {
        "base": {"controller": "RMPC", "plant": "linear", "duration": 0.02, **fields, "settings": settings}
    }


def _python_rmpc(**options):
    """The rigid family's RMPC written out in Python (paper P's polytope, its weights)."""
    from rmpc import RMPC

    sat = RigidSatellite.paper_p()
    poly = sat.polytope(sat.initial_state(), 0.01, 0.3, "scalar")
    d = CONTROLLER_DEFAULTS["RMPC"]
    return RMPC(poly, np.diag(d["Q_diag"]), np.diag(d["R_diag"]), u_max=1.0, input_constraint="ellipsoid",
                **options)


@pytest.mark.parametrize("family", ["rigid", "wheel", "mrp", "flexible"])
def test_solver_options_reach_the_rmpc_of_every_family_and_the_case_runs(family, monkeypatch):
    import rmpc.mpc.robust_mpc as robust_mpc
    from benchmarks.core.runner import run_scenario

    seen = []
    init = robust_mpc.RMPC.__init__

    def spy(self, *args, **kwargs):
        init(self, *args, **kwargs)
        seen.append(kwargs.get("solver_options"))

    monkeypatch.setattr(robust_mpc.RMPC, "__init__", spy)
    extra = {"fault_kind": "none"} if family == "wheel" else {}
    base = {**extra, "family": family, "controller": "RMPC", "saturation": "constraint"}
    dt = Scenario.from_dict(base).dt
    options = {"core": "numba", "max_iter": 60}
    settings = {"solver_options": options, "on_failure": "raise"}
    (scenario,) = expand(parse_sweep({"base": {**base, "duration": 3 * dt, "settings": settings}}))
    record = run_scenario(scenario)
    assert seen[-1] == options
    counts = record["metrics"]["status_counts"]  # the flexible RMPC reuses a gain inside its ellipsoid
    assert set(counts) <= {"optimal", "reused"} and counts["optimal"] >= 1 and sum(counts.values()) == 3
    assert record["settings"]["settings"]["solver_options"] == options


#: (settings, the Python keyword arguments refused the same way, the sweep's key path)
BAD = [
    ({"solver_options": {"core": "fortran"}}, {"solver_options": {"core": "fortran"}},
     "base.settings.solver_options.core"),
    ({"solver_options": {"bogus": 1}}, {"solver_options": {"bogus": 1}}, "base.settings.solver_options"),
    ({"solver_options": {"max_iter": 0}}, {"solver_options": {"max_iter": 0}},
     "base.settings.solver_options.max_iter"),
    ({"solver_options": {"core": "numba"}, "backend": "clarabel"},
     {"solver_options": {"core": "numba"}, "backend": "clarabel"}, "base.settings.solver_options"),
    ({"solver_options": {"tol_feas": 1e-9}, "lyapunov": "vertex"},
     {"solver_options": {"tol_feas": 1e-9, "core": "c"}, "lyapunov": "vertex"}, None),
]


@pytest.mark.parametrize(("settings", "python", "path"), BAD, ids=[str(b[0]) for b in BAD])
def test_a_bad_solver_option_is_refused_with_pythons_message_at_the_key_path(settings, python, path):
    if path is None:  # the forms' problem takes other ipm settings than Kothare's: core is not one of them
        with pytest.raises(ToolkitError):
            _python_rmpc(**python)
        bad = {**settings, "solver_options": python["solver_options"]}
        with pytest.raises(ConfigError) as in_sweep:
            parse_sweep(_sweep(bad))
        assert in_sweep.value.argument == "base.settings.solver_options"
        assert "'core'" in in_sweep.value.found
        return
    with pytest.raises(ToolkitError) as in_python:
        _python_rmpc(**python)
    with pytest.raises(ConfigError) as in_sweep:
        parse_sweep(_sweep(settings))
    assert in_sweep.value.argument == path
    assert in_sweep.value.expected.startswith(in_python.value.expected)  # the constructor's own check
    assert "backend" in in_sweep.value.expected
    assert in_sweep.value.found == in_python.value.found


@pytest.mark.parametrize(
    ("options", "path", "expected"),
    [
        (5, "base.settings.solver_options", "a table of the backend's settings"),
        ({"core": ["c"]}, "base.settings.solver_options.core", "a number, a string, true or false"),
    ],
)
def test_a_value_that_is_not_a_table_of_scalars_is_refused_naming_the_key(options, path, expected):
    with pytest.raises(ConfigError) as info:
        parse_sweep(_sweep({"solver_options": options}))
    assert info.value.argument == path and info.value.expected.startswith(expected)


def test_solver_options_with_the_scheduled_polytope_are_refused_naming_kinematics():
    with pytest.raises(ConfigError) as info:
        parse_sweep(_sweep({"solver_options": {"core": "numba"}}, kinematics="scheduled", plant="nonlinear"))
    assert info.value.argument == "base.kinematics" and "settings.solver_options" in info.value.expected


def test_solver_options_left_out_keep_the_record_and_the_case_id():
    plain = Scenario.from_dict({"controller": "RMPC"})
    assert "solver_options" not in plain.to_dict()["settings"]
    numba = Scenario.from_dict({"controller": "RMPC", "settings": {"solver_options": {"core": "numba"}}})
    assert numba.to_dict()["settings"]["solver_options"] == {"core": "numba"}
    assert numba.case_id != plain.case_id
    again = Scenario.from_dict(json.loads(json.dumps(numba.to_dict())))
    assert again.case_id == numba.case_id and again == numba


class _Captured(Exception):
    """Raised by the spy once it has the constructor's keywords (the table is not designed)."""


@pytest.mark.parametrize(("family", "fields"), [("rigid", {}), ("flexible", {"saturation": "constraint"})])
def test_offline_rmpc_cost_is_reachable_and_reaches_the_constructor(family, fields, monkeypatch):
    import rmpc.mpc.offline as offline

    seen = []

    def spy(self, *args, **kwargs):
        seen.append(kwargs.get("cost"))
        raise _Captured

    (scenario,) = expand(parse_sweep(
        {"base": {"family": family, "controller": "OfflineRMPC", **fields, "settings": {"cost": "nominal"}}}
    ))
    assert scenario.to_dict()["settings"]["cost"] == "nominal"
    plain = Scenario.from_dict({"family": family, "controller": "OfflineRMPC"})
    assert "cost" not in plain.to_dict()["settings"]
    monkeypatch.setattr(offline.OfflineRMPC, "__init__", spy)
    fam = scenario.plant_family
    with pytest.raises(_Captured):
        fam.simulate(scenario, fam.effective_settings(scenario.controller, scenario.settings), False)
    assert seen == ["nominal"]


def test_offline_rmpc_nominal_cost_from_a_sweep_runs_as_the_python_controller_does():
    from benchmarks.core.metrics import compute_metrics
    from benchmarks.core.runner import run_scenario
    from rmpc import OfflineRMPC, simulate

    settings = {"cost": "nominal", "n_ellipsoids": 3}
    (scenario,) = expand(parse_sweep(
        {"base": {"controller": "OfflineRMPC", "plant": "linear", "duration": 0.03, "settings": settings}}
    ))
    record = run_scenario(scenario)
    sat = RigidSatellite.paper_p()
    poly = sat.polytope(sat.initial_state(), 0.01, 0.3, "scalar")
    d = CONTROLLER_DEFAULTS["OfflineRMPC"]

    def metrics_of(cost):
        ctrl = OfflineRMPC(poly, np.diag(d["Q_diag"]), np.diag(d["R_diag"]), u_max=1.0,
                           input_constraint="ellipsoid", n_ellipsoids=3, cost=cost)
        return compute_metrics(simulate(ctrl, poly, sat.initial_state(), duration=0.03), 1.0, 0.02)

    nominal, worst = metrics_of("nominal"), metrics_of("worst_case")
    for key in ("sum_abs_err", "max_abs_u"):
        np.testing.assert_allclose(_flat(record["metrics"][key]), _flat(nominal[key]), rtol=1e-9, atol=1e-12)
    assert not np.allclose(_flat(nominal["max_abs_u"]), _flat(worst["max_abs_u"]), rtol=1e-6)


def _flat(value):
    return [value[k] for k in sorted(value)] if isinstance(value, dict) else value


@pytest.mark.parametrize("value", ["average", 3])
def test_a_bad_offline_rmpc_cost_is_refused_naming_the_key(value):
    with pytest.raises(ConfigError) as info:
        parse_sweep({"base": {"controller": "OfflineRMPC", "settings": {"cost": value}}})
    assert info.value.argument == "base.settings.cost" and "'nominal'" in info.value.expected


@pytest.mark.parametrize(
    ("family", "fields"), [("rigid", {"plant": "linear"}), ("wheel", {"fault_kind": "none"})]
)
def test_gipc_solver_options_reach_the_constructor_and_the_case_runs(family, fields, monkeypatch):
    import rmpc.mpc.gipc as gipc
    from benchmarks.core.runner import run_scenario

    seen = []
    init = gipc.GIPC.__init__

    def spy(self, *args, **kwargs):
        init(self, *args, **kwargs)
        seen.append((kwargs.get("solver_options"), self.backend.settings.max_iter))

    monkeypatch.setattr(gipc.GIPC, "__init__", spy)
    base = {"family": family, "controller": "GIPC", **fields}
    dt = Scenario.from_dict(base).dt
    settings = {"backend": "osqp", "solver_options": {"max_iter": 1234}, "Np": 10}
    (scenario,) = expand(parse_sweep({"base": {**base, "duration": 2 * dt, "settings": settings}}))
    assert scenario.to_dict()["settings"]["solver_options"] == {"max_iter": 1234}
    record = run_scenario(scenario)
    assert seen[-1] == ({"max_iter": 1234}, 1234)
    assert record["status"] == "done", record.get("error")


#: (backend, options, the sweep's key path)
BAD_GIPC = [
    ("proxqp", {"eps": 1e-6}, "base.settings.solver_options"),
    ("proxqp", {"eps_abs": -1.0}, "base.settings.solver_options.eps_abs"),
    ("osqp", {"max_iter": 0}, "base.settings.solver_options.max_iter"),
]


@pytest.mark.parametrize("family", ["rigid", "wheel"])
@pytest.mark.parametrize(("backend", "options", "path"), BAD_GIPC, ids=[str(b[1]) for b in BAD_GIPC])
def test_a_bad_gipc_solver_option_is_refused_with_pythons_message_at_the_key_path(
    family, backend, options, path
):
    from models import PolytopicModel
    from rmpc import GIPC

    stand_in = PolytopicModel([(0.5 * np.eye(2), np.ones((2, 1)))], dt=1.0)
    with pytest.raises(ToolkitError) as in_python:
        GIPC(stand_in, Np=3, Nc=1, backend=backend, solver_options=options)
    settings = {"backend": backend, "solver_options": options}
    with pytest.raises(ConfigError) as in_sweep:
        parse_sweep({"base": {"family": family, "controller": "GIPC", "settings": settings}})
    assert in_sweep.value.argument == path
    assert in_sweep.value.expected.startswith(in_python.value.expected) and backend in in_sweep.value.expected
    assert in_sweep.value.found == in_python.value.found


@pytest.mark.parametrize("family", ["rigid", "wheel"])
def test_gipc_solver_options_left_out_keep_the_record_and_the_case_id(family):
    plain = Scenario.from_dict({"family": family, "controller": "GIPC"})
    assert "solver_options" not in plain.to_dict()["settings"]
    settings = {"solver_options": {"max_iter": 50}}
    tuned = Scenario.from_dict({"family": family, "controller": "GIPC", "settings": settings})
    assert tuned.case_id != plain.case_id
    again = Scenario.from_dict(json.loads(json.dumps(tuned.to_dict())))
    assert again.case_id == tuned.case_id and again == tuned


OFFLINE_FAMILIES = [("rigid", {}), ("flexible", {"saturation": "constraint"})]


@pytest.mark.parametrize(("family", "fields"), OFFLINE_FAMILIES)
def test_offline_rmpc_solve_options_reach_the_constructor(family, fields, monkeypatch):
    import rmpc.mpc.offline as offline

    seen = []

    def spy(self, *args, **kwargs):
        seen.append({k: kwargs.get(k) for k in ("backend", "solver_options", "certificate_tol")})
        raise _Captured

    settings = {"backend": "clarabel", "solver_options": {"max_iter": 77}, "certificate_tol": 1e-6}
    (scenario,) = expand(parse_sweep(
        {"base": {"family": family, "controller": "OfflineRMPC", **fields, "settings": settings}}
    ))
    assert {k: scenario.to_dict()["settings"][k] for k in settings} == settings
    monkeypatch.setattr(offline.OfflineRMPC, "__init__", spy)
    fam = scenario.plant_family
    with pytest.raises(_Captured):
        fam.simulate(scenario, fam.effective_settings(scenario.controller, scenario.settings), False)
    assert seen == [settings]


@pytest.mark.parametrize("family", ["rigid", "flexible"])
def test_offline_rmpc_solve_options_left_out_keep_the_record_and_the_case_id(family):
    plain = Scenario.from_dict({"family": family, "controller": "OfflineRMPC"})
    assert not {"backend", "solver_options", "certificate_tol"} & set(plain.to_dict()["settings"])
    rmpc = Scenario.from_dict({"family": family, "controller": "RMPC"})
    assert rmpc.to_dict()["settings"]["backend"] == "ipm"  # the RMPC's backend stays written
    settings = {"certificate_tol": 1e-6}
    tuned = Scenario.from_dict({"family": family, "controller": "OfflineRMPC", "settings": settings})
    assert tuned.case_id != plain.case_id
    again = Scenario.from_dict(json.loads(json.dumps(tuned.to_dict())))
    assert again.case_id == tuned.case_id and again == tuned


#: (settings, the sweep's key path)
BAD_OFFLINE = [
    ({"backend": "proxqp"}, "base.settings.backend"),
    ({"certificate_tol": -1.0}, "base.settings.certificate_tol"),
    ({"solver_options": {"core": "fortran"}}, "base.settings.solver_options.core"),
    ({"solver_options": {"bogus": 1}}, "base.settings.solver_options"),
    ({"backend": "clarabel", "solver_options": {"core": "numba"}}, "base.settings.solver_options"),
]


@pytest.mark.parametrize(("family", "fields"), OFFLINE_FAMILIES)
@pytest.mark.parametrize(("settings", "path"), BAD_OFFLINE, ids=[str(b[0]) for b in BAD_OFFLINE])
def test_a_bad_offline_rmpc_solve_option_is_refused_with_pythons_message_at_the_key_path(
    family, fields, settings, path
):
    from models import PolytopicModel
    from rmpc import OfflineRMPC

    stand_in = PolytopicModel([(0.5 * np.eye(2), np.ones((2, 1)))], dt=1.0)
    with pytest.raises(ToolkitError) as in_python:
        OfflineRMPC(stand_in, np.eye(2), np.eye(1), u_max=1.0, **settings)
    with pytest.raises(ConfigError) as in_sweep:
        parse_sweep({"base": {"family": family, "controller": "OfflineRMPC", **fields, "settings": settings}})
    assert in_sweep.value.argument == path and in_sweep.value.found == in_python.value.found
    if path == "base.settings.backend":  # the family's choices may refuse it first: OfflineRMPC's three
        assert all(f"'{name}'" in in_sweep.value.expected for name in ("ipm", "clarabel", "cvxpy"))
    else:
        assert in_sweep.value.expected.startswith(in_python.value.expected)
