"""Scenario fields of issue 11: initial_attitude, kinematics (single / cover / scheduled)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.core.runner import run_scenario
from benchmarks.core.scenario import Scenario
from benchmarks.families.rigid.family import initial_attitude
from toolkit_common.errors import ConfigError


def test_initial_attitude_defaults_to_paper_p_and_scales():
    paper = initial_attitude(None, 1.0)
    assert paper == pytest.approx((0.362, 0.524, -0.262), abs=1e-3)
    assert initial_attitude([60.0, 60.0, 0.0], 0.5) == pytest.approx(
        (math.radians(30), math.radians(30), 0.0)
    )


def test_bad_kinematics_fields_are_config_errors_naming_the_field():
    with pytest.raises(ConfigError, match="kinematics"):
        Scenario.from_dict({"controller": "GIPC", "kinematics": "scheduled"})
    with pytest.raises(ConfigError, match="kinematics"):
        Scenario.from_dict({"controller": "RMPC", "kinematics": "wobbly"})
    with pytest.raises(ConfigError, match="initial_attitude"):
        Scenario.from_dict({"controller": "RMPC", "initial_attitude": [1.0, 2.0]})
    with pytest.raises(ConfigError, match="initial_attitude"):
        Scenario.from_dict({"controller": "RMPC", "initial_attitude": [0.0, 95.0, 0.0]})
    with pytest.raises(ConfigError, match="ic_scale"):
        Scenario.from_dict({"controller": "RMPC", "ic_scale": 3.0})
    with pytest.raises(ConfigError, match="cover_margin"):
        Scenario.from_dict({"controller": "RMPC", "cover_margin": -1.0})


@pytest.mark.parametrize("kinematics", ["cover", "scheduled"])
def test_cover_and_scheduled_runs_keep_the_torque_inside_the_limit(kinematics):
    sc = Scenario.from_dict(
        {
            "controller": "RMPC", "plant": "nonlinear", "kinematics": kinematics,
            "initial_attitude": [40.0, -30.0, 10.0], "duration": 3.0, "dt": 0.05,
        }
    )
    rec = run_scenario(sc)
    assert rec["status"] == "done"
    assert rec["metrics"]["max_abs_u"] <= 1.0 + 1e-6
    assert rec["metrics"]["failure_count"] == 0
    if kinematics == "cover":
        assert rec["settings"]["n_vertices"] == 18
    start = np.radians([40.0, 30.0, 10.0])
    final = np.array([rec["metrics"]["final_abs_err"][a] for a in ("roll", "pitch", "yaw")])
    assert np.all(final < start)
