"""The forms' ``"ipm"`` back-end checks its ``solver_options`` values with the check Kothare's
problem uses (:func:`lmi.backends.ipm.check_ipm_values`): ``max_iter = 0`` is refused in both."""

from __future__ import annotations

import numpy as np
import pytest

from models import PolytopicModel
from rmpc import RMPC
from toolkit_common.errors import InvalidArgumentError

_PLANT = PolytopicModel([(0.5 * np.eye(2), np.ones((2, 1)))], dt=1.0)


@pytest.mark.parametrize("form", [{}, {"lyapunov": "vertex"}, {"cost": "nominal"}, {"soft": {"u": 10.0}}])
@pytest.mark.parametrize(
    ("options", "name", "expected"),
    [
        ({"max_iter": 0}, "solver_options['max_iter']", "an integer >= 1"),
        ({"warm_max_iter": -3}, "solver_options['warm_max_iter']", "an integer >= 1"),
        ({"max_iter": 2.5}, "solver_options['max_iter']", "an integer >= 1"),
        ({"tol_feas": 0.0}, "solver_options['tol_feas']", "a number > 0"),
        ({"phase_one": 1}, "solver_options['phase_one']", "True or False"),
    ],
)
def test_a_bad_ipm_setting_is_refused_by_kothare_and_the_forms_alike(form, options, name, expected):
    with pytest.raises(InvalidArgumentError) as info:
        RMPC(_PLANT, np.eye(2), np.eye(1), u_max=[1.0], input_constraint="peak", solver_options=options,
             **form)
    assert info.value.argument == name and info.value.expected == expected


def test_a_form_takes_good_ipm_settings_as_numbers_of_the_right_kind():
    ctrl = RMPC(_PLANT, np.eye(2), np.eye(1), u_max=[1.0], input_constraint="peak", lyapunov="vertex",
                solver_options={"max_iter": np.int64(40), "tol_feas": 1e-9})
    settings = ctrl.problem._settings
    assert settings["max_iter"] == 40 and type(settings["max_iter"]) is int
    assert ctrl.step(np.array([0.3, -0.1])).shape == (1,)
