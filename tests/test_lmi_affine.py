""":class:`lmi.affine.AffineMatrix`, the matrices affine in the decision vector ``z`` from which the
conic back-end builds its LMIs: evaluated at ``z`` they give the constant term plus each variable
times its coefficient. Integer data, so every comparison is exact."""

from __future__ import annotations

import numpy as np

from lmi.affine import AffineMatrix

N_VARS = 5
Z = np.array([2.0, -3.0, 5.0, 7.0, -1.0])
C = np.array([[1.0, 4.0], [4.0, -2.0]])
K = np.array([[0.0, 3.0], [3.0, 1.0]])


def test_value_is_the_constant_plus_the_variables_times_their_coefficients() -> None:
    # z[0:3] is a symmetric 2 x 2 variable (upper triangle column by column), z[4] scales K
    m = (AffineMatrix.constant(C, N_VARS) + AffineMatrix.symmetric_variable(2, 0, N_VARS)
         + AffineMatrix.scalar_variable_times(K, 4, N_VARS))
    want = C + np.array([[Z[0], Z[1]], [Z[1], Z[2]]]) + Z[4] * K
    np.testing.assert_array_equal(m.value(Z), want)
    np.testing.assert_array_equal(AffineMatrix.constant(C, N_VARS).value(Z), C)
    np.testing.assert_array_equal(AffineMatrix.full_variable(1, 2, 3, N_VARS).value(Z), [[Z[3], Z[4]]])


def test_the_algebra_commutes_with_evaluation() -> None:
    m = AffineMatrix.constant(C, N_VARS) - AffineMatrix.symmetric_variable(2, 1, N_VARS) * 2.0
    left, right = np.array([[1.0, 2.0], [0.0, -1.0], [3.0, 1.0]]), np.array([[2.0], [-1.0]])
    np.testing.assert_array_equal(m.lmul(left).value(Z), left @ m.value(Z))
    np.testing.assert_array_equal(m.rmul(right).value(Z), m.value(Z) @ right)
    np.testing.assert_array_equal(m.T.value(Z), m.value(Z).T)
    np.testing.assert_array_equal((-m).value(Z), -m.value(Z))


def test_svec_index_map_places_each_entry_where_the_symmetric_variable_reads_it():
    """Entry ``(i, j)`` of ``svec_index_map(size, offset)`` is the index of ``z`` whose coefficient
    in ``AffineMatrix.symmetric_variable(size, offset, n)`` is one at ``(i, j)`` (both triangles)."""
    from lmi.affine import svec_index_map

    size, offset, n = 4, 3, 15
    index = svec_index_map(size, offset)
    coef = AffineMatrix.symmetric_variable(size, offset, n).coef
    for i in range(size):
        for j in range(size):
            assert coef[1 + index[i, j], i, j] == 1.0
            assert np.count_nonzero(coef[1:, i, j]) == 1
