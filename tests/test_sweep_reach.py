"""Every option of every controller a sweep's scenario builds is reachable from a sweep file, with the
constructor's own checks, or refused when the file is read, saying why.

Reached: RMPC's ``solver`` and its output bounds (``output_matrix`` with ``y_max``, rigid, wheel and
MRP families), OfflineRMPC's ``solver`` and ``path``, CRMPC's ``rmpc_options``. Refused when the
file is read (not when a case runs): GIPC with an LMI back-end (``backend = "ipm"``), the RMPC or
CRMPC with a QP back-end, keywords a scenario sets itself (``x_ref``, ``Q``), the flexible family's
output bounds (its field ``modal_bound`` sets them).
"""

from __future__ import annotations

import inspect
import textwrap

import numpy as np
import pytest

from benchmarks.cli import main
from benchmarks.core.registry import get_family
from benchmarks.core.scenario import Scenario
from benchmarks.core.sweep_spec import expand, parse_sweep
from benchmarks.families import rmpc_forms
from models import RigidSatellite
from rmpc import RMPC
from toolkit_common.errors import ConfigError

_ROLL = [[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]]


def _built(family: str, controller: str, settings: dict):
    scenario = Scenario.from_dict(
        {"family": family, "controller": controller, "saturation": "constraint", "settings": settings}
    )
    poly = RigidSatellite.paper_p().polytope(np.array([0.3, -0.2, 0.25, 0, 0, 0]), 0.05, 0.3, "box")
    return get_family(family, "family").build_controller(poly, scenario).controller


def _refusal(base: dict) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        expand(parse_sweep({"base": {"saturation": "constraint", **base}}))
    return info.value


def test_rmpc_solver_and_output_bounds_reach_the_controller():
    ctrl = _built(
        "rigid", "RMPC", {"backend": "cvxpy", "solver": "SCS", "output_matrix": _ROLL, "y_max": 0.2}
    )
    assert ctrl.problem.backend == "cvxpy:SCS"
    assert np.array_equal(ctrl.problem.data.C_out, np.array(_ROLL)) and list(ctrl.problem.data.y_max) == [0.2]
    # with an output bound, soft may weigh y (refused without one)
    _built("rigid", "RMPC", {"output_matrix": _ROLL, "y_max": 0.2, "soft": {"y": 10.0}})


def test_offline_rmpc_solver_and_path_reach_the_controller():
    ctrl = _built("rigid", "OfflineRMPC", {"backend": "cvxpy", "solver": "SCS", "path": "trajectory"})
    assert ctrl.path == "trajectory" and ctrl.problem.backend == "cvxpy:SCS"


def test_crmpc_rmpc_options_reach_the_inner_rmpc_with_the_familys_own_entries():
    ctrl = _built(
        "rigid",
        "CRMPC",
        {
            "resolve_threshold": 0.9,
            "rmpc_options": {"hold_radius": 1e-5, "lyapunov": "vertex", "soft": {"u": 10.0}},
        },
    )
    assert ctrl.rmpc.form.lyapunov == "vertex" and ctrl.rmpc.form.soft == {"u": 10.0}
    assert ctrl.rmpc.resolve_threshold == 0.9 and ctrl.rmpc._arguments["hold_radius"] == 1e-5


@pytest.mark.parametrize(
    ("base", "argument", "words"),
    [
        (
            {"controller": "GIPC", "settings": {"backend": "ipm"}},
            "base.settings.backend",
            "GIPC's QP back-ends",
        ),
        (
            {"family": "wheel", "controller": "RMPC", "settings": {"backend": "proxqp"}},
            "base.settings.backend",
            "'ipm'",
        ),
        (
            {"family": "wheel", "controller": "CRMPC", "settings": {"backend": "proxqp"}},
            "base.settings.backend",
            "the RMPC inside CRMPC",
        ),
        ({"controller": "RMPC", "settings": {"solver": "SCS"}}, "base.settings.solver", "backend='ipm'"),
        (
            {"controller": "RMPC", "settings": {"output_matrix": _ROLL}},
            "base.settings.output_matrix",
            "together",
        ),
        (
            {"controller": "RMPC", "settings": {"output_matrix": [[1.0, 0.0]], "y_max": 0.1}},
            "base.settings.output_matrix",
            "shape",
        ),
        (
            {"controller": "RMPC", "settings": {"output_matrix": _ROLL, "y_max": [0.1, 0.2]}},
            "base.settings.y_max",
            "length 1",
        ),
        ({"controller": "RMPC", "settings": {"x_ref": [0.0] * 6}}, "base.settings.x_ref", "family's target"),
        ({"controller": "RMPC", "settings": {"Q": 1.0}}, "base.settings.Q", "Q_diag"),
        (
            {"family": "flexible", "controller": "RMPC", "settings": {"output_matrix": _ROLL, "y_max": 0.1}},
            "base.settings.output_matrix",
            "modal_bound",
        ),
        (
            {"controller": "OfflineRMPC", "settings": {"path": "results.txt"}},
            "base.settings.path",
            "'trajectory'",
        ),
        (
            {"controller": "OfflineRMPC", "settings": {"solver": "NOPE", "backend": "cvxpy"}},
            "base.settings.solver",
            "installed solvers",
        ),
        (
            {"controller": "CRMPC", "settings": {"rmpc_options": {"x_ref": [0.0] * 6}}},
            "base.settings.rmpc_options.x_ref",
            "family's target",
        ),
        (
            {"controller": "CRMPC", "settings": {"rmpc_options": {"resolve_threshold": 0.5}}},
            "base.settings.rmpc_options.resolve_threshold",
            "the setting resolve_threshold",
        ),
        (
            {"controller": "CRMPC", "settings": {"rmpc_options": {"soft": {"u": -1.0}}}},
            "base.settings.rmpc_options.soft.u",
            "weight",
        ),
        (
            {"controller": "CRMPC", "settings": {"rmpc_options": {"solver_options": {"max_iter": 0}}}},
            "base.settings.rmpc_options.solver_options.max_iter",
            ">= 1",
        ),
        (
            {"controller": "CRMPC", "settings": {"rmpc_options": {"input_constraint": "peak"}}},
            "base.settings.rmpc_options",
            "keys among",
        ),
        ({"controller": "CRMPC", "settings": {"rmpc_options": 5}}, "base.settings.rmpc_options", "a table"),
        (
            {"family": "mrp", "controller": "CRMPC", "settings": {"rmpc_options": {"backend": "clarabel"}}},
            "base.settings.rmpc_options.backend",
            "the setting backend",
        ),
    ],
)
def test_a_bad_option_is_refused_when_the_file_is_read_naming_its_key_path(base, argument, words):
    err = _refusal(base)
    assert err.argument == argument and words in str(err), str(err)


def test_the_default_backend_the_check_skips_is_rmpcs_own():
    assert inspect.signature(RMPC.__init__).parameters["backend"].default == rmpc_forms._RMPC_BACKEND


def test_case_ids_do_not_change_for_cases_that_set_none_of_the_new_settings():
    for family, controller in (
        ("rigid", "RMPC"),
        ("rigid", "CRMPC"),
        ("rigid", "OfflineRMPC"),
        ("wheel", "CRMPC"),
        ("mrp", "RMPC"),
    ):
        settings = Scenario.from_dict({"family": family, "controller": controller}).to_dict()["settings"]
        assert not {"solver", "path", "rmpc_options", "output_matrix", "y_max"} & set(settings), settings


def test_a_sweep_with_the_new_settings_runs(tmp_path):
    config = tmp_path / "reach.toml"
    config.write_text(
        textwrap.dedent("""
        name = "reach"
        [base]
        plant = "linear"
        saturation = "constraint"
        duration = 0.03
        [grid]
        controller = ["RMPC", "CRMPC"]
        [base.settings]
        output_matrix = [[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
        y_max = 1.0
        rmpc_options = {hold_radius = 1e-6, lyapunov = "vertex"}
    """)
    )
    status = main(
        [
            "bench",
            "sweep",
            "--config",
            str(config),
            "--out",
            str(tmp_path / "out"),
            "--workers",
            "0",
            "--no-progress",
        ]
    )
    assert status == 0
