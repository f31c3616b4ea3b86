"""RMPC's reference state ``x_ref``: an equilibrium of every vertex, checked relative to its size.

``RMPC`` accepts ``x_ref`` when ``max_j |A_j x_ref - x_ref| <= 1e-9 max(1, |x_ref|_inf)``: an
equilibrium whose product ``A_j x_ref`` is off by rounding only is accepted however large it is,
and a state that is not an equilibrium is refused at every scale.
"""

from __future__ import annotations

import numpy as np
import pytest

from models import PolytopicModel
from rmpc import RMPC
from toolkit_common.errors import InvalidArgumentError

#: ``A = I + N`` with ``N [3, 1]' = 0`` in exact arithmetic (eigenvalues 1 and 0.5); in floating
#: point ``A x - x`` for ``x = s [3, 1]`` is a few units in the last place of ``s``, not zero.
A = np.eye(2) + np.array([[0.1, -0.3], [0.2, -0.6]])
B = np.array([[0.0], [0.1]])
PLANT = PolytopicModel([(A, B)], dt=0.1)
SETTINGS = {"Q": np.eye(2), "R": np.eye(1), "u_max": 1.0}
DIRECTION = np.array([3.0, 1.0])


@pytest.mark.parametrize("scale", [1.0, 1e3, 1e6, 1e9])
def test_an_equilibrium_off_by_rounding_is_accepted_at_any_size(scale: float) -> None:
    x_ref = scale * DIRECTION
    drift = float(np.max(np.abs(A @ x_ref - x_ref)))
    if scale == 1e9:
        # measured 4.8e-7: above an absolute 1e-9, so only a check relative to |x_ref| accepts it
        assert drift > 1e-9
    assert drift <= 1e-15 * float(np.max(np.abs(x_ref)))  # rounding only (measured 4.8e-16 relative)
    ctrl = RMPC(PLANT, **SETTINGS, x_ref=x_ref)
    np.testing.assert_array_equal(ctrl.x_ref, x_ref)


@pytest.mark.parametrize("scale", [1.0, 1e3, 1e6, 1e9])
def test_a_state_that_is_not_an_equilibrium_is_refused_at_any_size(scale: float) -> None:
    x_ref = scale * np.array([3.0, 1.0 + 1e-6])  # A x_ref - x_ref = 6e-7 scale: relative 2e-7 > 1e-9
    with pytest.raises(InvalidArgumentError, match="x_ref"):
        RMPC(PLANT, **SETTINGS, x_ref=x_ref)
