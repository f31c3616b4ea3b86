""":class:`rmpc.mpc.mras.SensitivityFilter` refuses a ``columns`` that is not ``None`` or a positive
integer (a bool, zero, a negative number, a float), naming the argument, and accepts the others."""

from __future__ import annotations

import numpy as np
import pytest

from rmpc.mpc.mras import SensitivityFilter
from toolkit_common.errors import InvalidArgumentError


@pytest.mark.parametrize("columns", [0, -2, True, 2.0, "2"])
def test_a_bad_columns_is_refused(columns: object) -> None:
    with pytest.raises(InvalidArgumentError, match="columns"):
        SensitivityFilter([[0.5]], [[1.0]], columns=columns)  # type: ignore[arg-type]


@pytest.mark.parametrize(("columns", "shape"), [(None, (1,)), (1, (1, 1)), (np.int64(3), (1, 3))])
def test_a_good_columns_sets_the_shape_of_the_state(columns: object, shape: tuple[int, ...]) -> None:
    filt = SensitivityFilter([[0.5]], [[1.0]], columns=columns)  # type: ignore[arg-type]
    assert filt.output().shape == shape
