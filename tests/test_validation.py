"""The shared argument checks of toolkit_common.validation: one reading, one message per kind."""

from __future__ import annotations

import numpy as np
import pytest

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import (
    as_array,
    as_inertia,
    as_matrix,
    as_optional_limits,
    as_positive_values,
    as_square_matrix,
    as_vector,
    check_bool,
    check_positive,
    renamed_arguments,
)


def test_check_bool_accepts_python_and_numpy_bools_only() -> None:
    assert check_bool(True, "flag") is True
    assert check_bool(np.bool_(False), "flag") is False
    assert type(check_bool(np.bool_(True), "flag")) is bool
    for bad in (1, 0, "yes", None, 1.0):
        with pytest.raises(ArgumentTypeError, match="flag: expected True or False"):
            check_bool(bad, "flag")


def test_positive_values_broadcast_a_scalar_and_check_each_component() -> None:
    np.testing.assert_array_equal(as_positive_values(2.0, "k", 3), [2.0, 2.0, 2.0])
    np.testing.assert_array_equal(as_positive_values([1, 2], "k", 2), [1.0, 2.0])
    assert as_positive_values(0.5, "k", None).tolist() == [0.5]
    assert as_positive_values([1.0, 2.0, 3.0, 4.0], "k", None).shape == (4,)
    with pytest.raises(InvalidArgumentError, match=r"k: expected values > 0, but found \[1.0, 0.0\]"):
        as_positive_values([1.0, 0.0], "k", 2)
    assert as_positive_values([1.0, 0.0], "k", 2, allow_zero=True).tolist() == [1.0, 0.0]
    with pytest.raises(InvalidArgumentError, match="values >= 0"):
        as_positive_values(-1.0, "k", 2, allow_zero=True)
    with pytest.raises(InvalidArgumentError, match=r"one number per wheel \(4 of them\)"):
        as_positive_values([1.0, 2.0], "k", 4, per="wheel")
    with pytest.raises(InvalidArgumentError, match="finite values > 0"):
        as_positive_values([1.0, np.inf], "k", 2)
    assert as_positive_values([1.0, np.inf], "k", 2, allow_inf=True, what="limits")[1] == np.inf
    with pytest.raises(InvalidArgumentError, match=r"limits > 0 \(inf for none\)"):
        as_positive_values([np.nan, 1.0], "k", 2, allow_inf=True, what="limits")
    for bad in ("1", True, object()):
        with pytest.raises(ArgumentTypeError, match="k: expected a number or one number per axis"):
            as_positive_values(bad, "k", 3, per="axis")


def test_optional_limits() -> None:
    assert as_optional_limits(None, "u_max", 3) is None
    np.testing.assert_array_equal(as_optional_limits(np.float64(0.5), "u_max", 2), [0.5, 0.5])
    with pytest.raises(InvalidArgumentError, match="u_max: expected None or limits > 0"):
        as_optional_limits([1.0, -1.0], "u_max", 2)
    with pytest.raises(InvalidArgumentError, match="u_max: expected None or limits > 0"):
        as_optional_limits(0.0, "u_max", 2)
    with pytest.raises(InvalidArgumentError, match="None or finite limits > 0"):
        as_optional_limits(np.inf, "u_max", 2)
    with pytest.raises(ArgumentTypeError, match="u_max: expected None, a number"):
        as_optional_limits("1", "u_max", 2)


def test_square_matrix_reads_a_scalar_a_diagonal_or_a_full_matrix() -> None:
    np.testing.assert_array_equal(as_square_matrix(2.0, "G", 3), 2.0 * np.eye(3))
    np.testing.assert_array_equal(as_square_matrix([1.0, 2.0, 3.0], "G", 3), np.diag([1.0, 2.0, 3.0]))
    full = np.array([[2.0, 0.5], [0.5, 1.0]])
    np.testing.assert_array_equal(as_square_matrix(full, "G", 2), full)
    with pytest.raises(InvalidArgumentError, match="G: expected a number > 0"):
        as_square_matrix(0.0, "G", 3)
    assert np.all(as_square_matrix(0.0, "G", 3, allow_zero=True, definite="psd") == 0.0)
    with pytest.raises(InvalidArgumentError, match="G: expected positive diagonal entries"):
        as_square_matrix([1.0, 0.0, 1.0], "G", 3)
    with pytest.raises(InvalidArgumentError, match="G: expected a positive definite matrix"):
        as_square_matrix([[1.0, 2.0], [2.0, 1.0]], "G", 2)
    with pytest.raises(InvalidArgumentError, match="positive semidefinite"):
        as_square_matrix([[1.0, 2.0], [2.0, 1.0]], "G", 2, definite="psd")
    with pytest.raises(InvalidArgumentError, match="symmetric"):
        as_square_matrix([[1.0, 2.0], [0.0, 1.0]], "G", 2)
    skewed = np.array([[1.0, 2.0], [0.0, 1.0]])  # any finite matrix without a definiteness check
    np.testing.assert_array_equal(as_square_matrix(skewed, "G", 2, definite=None), skewed)
    with pytest.raises(InvalidArgumentError, match=r"G: expected shape \(3, 3\)"):
        as_square_matrix(np.eye(2), "G", 3)
    with pytest.raises(InvalidArgumentError, match="G"):
        as_square_matrix(np.ones((3, 3, 3)), "G", 3)
    with pytest.raises(ArgumentTypeError, match="G"):
        as_square_matrix("eye", "G", 3)


def test_inertia_is_a_diagonal_or_a_full_positive_definite_matrix() -> None:
    np.testing.assert_array_equal(as_inertia([1.0, 2.0, 3.0]), np.diag([1.0, 2.0, 3.0]))
    j = np.array([[2.0, 0.1, 0.0], [0.1, 3.0, 0.0], [0.0, 0.0, 4.0]])
    np.testing.assert_array_equal(as_inertia(j), j)
    wanted = r"inertia: expected positive principal inertias \(kg m\^2\), but found \[1.0, -1.0, 1.0\]"
    with pytest.raises(InvalidArgumentError, match=wanted):
        as_inertia([1.0, -1.0, 1.0])
    with pytest.raises(InvalidArgumentError, match="J0"):
        as_inertia(5.0, "J0")  # a scalar is not an inertia
    with pytest.raises(InvalidArgumentError, match="positive definite"):
        as_inertia(-np.eye(3))


def test_renamed_arguments_name_the_new_argument() -> None:
    @renamed_arguments(inertia_spread="spread", scale="factor")
    def polytope(dt: float, *, spread: float | None = None, factor: float = 1.0) -> tuple:
        """Doc."""
        return dt, spread, factor

    assert polytope(0.1, spread=0.2) == (0.1, 0.2, 1.0)
    assert polytope.__doc__ == "Doc." and polytope.__name__ == "polytope"
    with pytest.raises(ArgumentTypeError, match=r"inertia_spread: expected the argument 'spread' \(renamed"):
        polytope(0.1, inertia_spread=0.2)
    with pytest.raises(ArgumentTypeError, match="'factor'"):
        polytope(0.1, scale=2.0)


@pytest.mark.parametrize(
    "check",
    [
        lambda: as_vector([1.0, 2.0 + 1.0j], "x"),
        lambda: as_matrix(np.diag([1.0, 1.0 + 1.0j]), "Q"),
        lambda: as_array([[1.0j]], "M"),
    ],
)
def test_complex_values_are_refused_not_cast(check) -> None:
    """numpy would drop the imaginary part with only a ComplexWarning; the checks refuse it and say where."""
    with pytest.raises(ArgumentTypeError, match=r"expected real values, but found complex .*1j\)? at index"):
        check()


def test_complex_with_zero_imaginary_parts_is_its_real_part() -> None:
    values = np.linalg.eigvals(np.diag([1.0, 2.0])).astype(complex)
    np.testing.assert_array_equal(as_vector(values, "x"), [1.0, 2.0])


@pytest.mark.parametrize("check", [lambda: as_vector(None, "x"), lambda: as_matrix(None, "Q"),
                                   lambda: check_positive(None, "dt")])
def test_none_is_named_as_none(check) -> None:
    """``None`` used to become NaN or a 1 x 1 matrix and was reported as 'shape (1, 1)'."""
    with pytest.raises(ArgumentTypeError, match=r"but found None$"):
        check()
