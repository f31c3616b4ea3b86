"""Sparse QPs in the QP layer: ``QP`` keeps scipy.sparse ``H`` and ``C`` sparse and checks them as
the dense ones; OSQP and Clarabel solve them to the dense problem's answer."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from rmpc.qp import QP, kkt_residuals, make_backend
from rmpc.qp.problem import SPARSE_PSD_CHECK_LIMIT
from toolkit_common.errors import InvalidArgumentError


def _problem(seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    n, m = 12, 6
    f = rng.normal(size=(n, n))
    h = f @ f.T / n + 0.1 * np.eye(n)
    c = rng.normal(size=(m, n)) * (rng.random((m, n)) < 0.4)
    return {"H": h, "g": rng.normal(size=n), "C": c, "l": np.r_[np.zeros(2), -np.ones(4)],
            "u": np.r_[np.zeros(2), np.ones(4)], "lb": -0.5 * np.ones(n), "ub": 0.5 * np.ones(n)}


def test_sparse_matrices_stay_sparse_and_read_only() -> None:
    data = _problem()
    qp = QP(**{**data, "H": sp.csr_matrix(data["H"]), "C": sp.coo_matrix(data["C"])})
    assert qp.is_sparse and sp.isspmatrix_csc(qp.H) and sp.isspmatrix_csc(qp.C)
    assert not QP(**data).is_sparse
    with pytest.raises(ValueError, match="read-only"):
        qp.H.data[0] = 1.0
    assert (qp.n_vars, qp.n_cons) == (12, 6)
    # a dense C with a sparse H is taken sparse too
    assert sp.issparse(QP(**{**data, "H": sp.csc_matrix(data["H"])}).C)


@pytest.mark.parametrize("backend", ["osqp", "clarabel"])
def test_a_sparse_qp_has_the_dense_qps_answer(backend: str) -> None:
    data = _problem(1)
    dense = make_backend(backend)
    dense.setup(QP(**data))
    ref = dense.solve()
    sparse_qp = QP(**{**data, "H": sp.csc_matrix(data["H"]), "C": sp.csc_matrix(data["C"])})
    be = make_backend(backend)
    be.setup(sparse_qp)
    res = be.solve()
    assert ref.status == res.status == "optimal"
    np.testing.assert_allclose(res.x, ref.x, atol=1e-7)
    assert kkt_residuals(sparse_qp, res).max() < 1e-6
    be.update(g=np.zeros(12), l=-np.ones(6), u=np.ones(6))  # vectors change, the matrices stay
    again = be.solve()
    assert again.status == "optimal" and np.allclose(again.x, 0.0, atol=1e-7)


def test_a_sparse_h_is_checked_for_symmetry_and_definiteness() -> None:
    data = _problem()
    bad = data["H"].copy()
    bad[0, 1] += 1.0
    with pytest.raises(InvalidArgumentError, match="H: expected a symmetric matrix"):
        QP(**{**data, "H": sp.csc_matrix(bad)})
    with pytest.raises(InvalidArgumentError, match="H"):
        QP(**{**data, "H": sp.csc_matrix(-data["H"])})
    with pytest.raises(InvalidArgumentError, match="C: expected a matrix with 12 columns"):
        QP(**{**data, "H": sp.csc_matrix(data["H"]), "C": sp.csc_matrix(np.ones((2, 5)))})
    nan = sp.csc_matrix(data["H"])
    nan.data[0] = np.nan
    with pytest.raises(InvalidArgumentError, match="H: expected finite values"):
        QP(**{**data, "H": nan})
    assert SPARSE_PSD_CHECK_LIMIT >= 1000
