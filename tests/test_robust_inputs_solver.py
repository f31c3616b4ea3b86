"""The LMI solver's edges and its front ends' validation, one test per family of inputs.

Each answer is checked against what it claims, in numpy or against Clarabel through cvxpy (an
independent solver), not against stored digits: an ``"optimal"`` ``x`` satisfies the LMIs and
reaches the reference optimum, an ``"unbounded"`` one satisfies them far down the objective, a
refusal names the argument.
"""

from __future__ import annotations

import gzip
import time

import cvxpy as cp
import numpy as np
import pytest

from lmi import BlockLMISolver, KothareProblem
from lmi.forms import MAX_SOFT_WEIGHT, FormProblem
from lmi.sdpa import SDPAFormatError, read_sdpa
from models import PolytopicModel
from rmpc import RMPC
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_count, is_integer

A_VERTICES = np.array([[[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.1], [0.0, 0.95]]])
B_VERTICES = np.array([[[0.005], [0.1]]] * 2)


def _plant() -> PolytopicModel:
    return PolytopicModel([(a, b) for a, b in zip(A_VERTICES, B_VERTICES, strict=True)], dt=0.1)


def _lowest(mats: list[np.ndarray]) -> float:
    """The smallest eigenvalue of the blocks, relative to each block's largest."""
    out = np.inf
    for mat in mats:
        lam = np.linalg.eigvalsh(0.5 * (mat + mat.T))
        out = min(out, float(lam[0] / max(np.max(np.abs(lam)), 1e-300)))
    return out


def _slacks(x: np.ndarray, blocks: list) -> list[np.ndarray]:
    return [c_j - np.einsum("i,ikl->kl", x, a_j) for c_j, a_j in blocks]


def _reference(c: np.ndarray, blocks: list) -> tuple[str, float]:
    """Clarabel through cvxpy on the same LMIs."""
    x = cp.Variable(c.size)
    cons = []
    for c_j, a_j in blocks:
        s = c_j - sum(x[i] * a_j[i] for i in range(c.size))
        cons.append(0.5 * (s + s.T) >> 0)
    prob = cp.Problem(cp.Minimize(c @ x), cons)
    prob.solve(solver="CLARABEL")
    return str(prob.status), float(prob.value)


def _random_problem(seed: int, n: int, order: int, in_range: bool) -> tuple[np.ndarray, list]:
    rng = np.random.default_rng(seed)
    coef = rng.standard_normal((n, order, order))
    coef = coef + coef.transpose(0, 2, 1)
    iu = np.triu_indices(order)
    c = coef[:, iu[0], iu[1]] @ rng.standard_normal(iu[0].size) if in_range else rng.standard_normal(n)
    blocks = [(2.0 * np.eye(order), coef), (np.array([[3.0]]), rng.standard_normal((n, 1, 1)))]
    return c, blocks


@pytest.mark.parametrize("seed", range(4))
def test_more_variables_than_entries_and_degenerate_blocks(seed):
    """More variables than the blocks have entries (5 on a 2 x 2 and a 1 x 1 block, 8 on a 3 x 3 and
    a 1 x 1): before, ``ValueError: unable to broadcast`` inside the kernels (solve and phase one).
    ``c`` in the span of the coefficients: the optimum of Clarabel; otherwise the objective is
    unbounded along a direction that moves no block. Degenerate blocks (a variable in no block, 1 x 1
    blocks, a zero objective, a zero constant) give the true answer too."""
    for n, order in ((5, 2), (8, 3)):
        for in_range in (True, False):
            c, blocks = _random_problem(seed, n, order, in_range)
            res = BlockLMISolver(c, blocks).solve()
            ref_status, ref_value = _reference(c, blocks)
            assert _lowest(_slacks(res.x, blocks)) >= -1e-7, (n, in_range, res.status)
            if in_range and ref_status == "optimal":
                assert res.status == "optimal"
                assert float(c @ res.x) == pytest.approx(ref_value, rel=1e-6, abs=1e-6)
            else:
                assert ref_status == "unbounded" and res.status == "unbounded", (ref_status, res.status)
                assert float(c @ res.x) <= -1e8 * max(1.0, float(np.linalg.norm(c)))
            one = BlockLMISolver(c, blocks).phase_one()
            assert one.status == "feasible"
            assert _lowest(_slacks(one.x, blocks)) > 0.0
    if seed == 0:
        eye = np.eye(2)
        # four copies of t in min t s.t. t I - M >= 0 (3 entries): bounded in the span (sum t_i = 3,
        # the largest eigenvalue of M), unbounded as soon as c weighs the copies differently
        m = np.array([[2.0, 1.0], [1.0, 2.0]])
        copies = [(-m, -np.stack([eye] * 4))]
        res = BlockLMISolver(np.ones(4), copies).solve()
        assert res.status == "optimal" and res.x.sum() == pytest.approx(3.0, rel=1e-7)
        res = BlockLMISolver([1.0, 2.0, 1.0, 1.0], copies).solve()
        assert res.status == "unbounded" and _lowest(_slacks(res.x, copies)) >= -1e-7
        assert float(res.x @ [1.0, 2.0, 1.0, 1.0]) <= -1e8
        # a variable in no block with a cost: unbounded; 1x1 blocks: -1 <= x1 - x2 <= 1 ...
        res = BlockLMISolver([1.0, 1.0], [(eye, np.stack([np.zeros((2, 2)), -eye]))]).solve()
        assert res.status == "unbounded" and _lowest(_slacks(res.x, [(eye, np.stack([0 * eye, -eye]))])) >= 0
        one_by_one = [(np.ones((1, 1)), np.array([[[1.0]], [[-1.0]]])),
                      (np.ones((1, 1)), np.array([[[-1.0]], [[1.0]]])),
                      (np.zeros((1, 1)), -np.eye(2)[:, :1, None])]
        res = BlockLMISolver([-1.0, 1.0], one_by_one).solve()
        assert res.status == "optimal" and float(res.x @ [-1.0, 1.0]) == pytest.approx(-1.0, abs=1e-7)
        res = BlockLMISolver([0.0], [(np.zeros((2, 2)), -eye[None])]).solve()  # zero objective and constant
        assert res.status == "optimal" and res.x[0] >= -1e-7


def test_empty_objective_names_c():
    """``c=[]`` with a block of one variable: before, the error blamed ``blocks[0] A``; with a
    block of no variable it was accepted."""
    with pytest.raises(InvalidArgumentError, match=r"^c: expected at least one variable"):
        BlockLMISolver([], [(np.eye(2), np.zeros((1, 2, 2)))])
    with pytest.raises(InvalidArgumentError, match=r"^c: "):
        BlockLMISolver([], [(np.eye(2), np.zeros((0, 2, 2)))])
    with pytest.raises(InvalidArgumentError, match=r"^blocks: expected a sequence"):
        BlockLMISolver([1.0], 5)
    with pytest.raises(InvalidArgumentError, match=r"^blocks\[0\]: expected a pair"):
        BlockLMISolver([1.0], [np.eye(2)])


def test_complex_data_is_refused_naming_the_argument():
    """Complex ``C_j``, ``A_j``, ``A``, ``E``: before, accepted with numpy's ComplexWarning and the
    imaginary part dropped."""
    eye = np.eye(2)
    cases = [
        (r"^blocks\[0\] C: expected real values",
         lambda: BlockLMISolver([1.0], [(eye * (1 + 1j), -eye[None])])),
        (r"^blocks\[0\] A: expected real values", lambda: BlockLMISolver([1.0], [(eye, -1j * eye[None])])),
        (r"^A: expected real values", lambda: KothareProblem(A_VERTICES * (1 + 1j), B_VERTICES, np.eye(2),
                                                             np.eye(1), u_max=1.0)),
        (r"^B: expected real values", lambda: FormProblem(A_VERTICES, B_VERTICES * 1j, np.eye(2), np.eye(1),
                                                          u_max=1.0, lyapunov="vertex")),
        (r"^disturbance E: expected real values", lambda: RMPC(
            _plant(), np.eye(2), np.eye(1), u_max=1.0, disturbance=(np.array([[0.1j], [0.0]]), 0.01))),
    ]
    for pattern, call in cases:
        with pytest.raises(ArgumentTypeError, match=pattern):
            call()


@pytest.mark.parametrize("scale", [1e60, 1e200, float(np.finfo(float).max)])
def test_objective_far_beyond_the_data(scale):
    """``min scale t`` s.t. ``t I - M >= 0``: the largest eigenvalue of ``M`` (3) at any scale. Before,
    ``"numerical_error"`` at the largest float (overflow in the norms); 1e60 and 1e200 passed and
    guard the scaling (a soft weight of 1e200 in a form's objective, ``[1, ..., 1e200]``, ended in
    ``ZeroDivisionError`` inside the kernels)."""
    m = np.array([[2.0, 1.0], [1.0, 2.0]])
    res = BlockLMISolver([scale], [(-m, -np.eye(2)[None])]).solve()
    assert res.status == "optimal"
    assert res.x[0] == pytest.approx(3.0, rel=1e-7)


@pytest.mark.filterwarnings("ignore:Solution may be inaccurate")  # cvxpy's, on the far state
def test_soft_weights_up_to_the_largest_float():
    """Above :data:`lmi.forms.MAX_SOFT_WEIGHT` (1e8) a weight is refused naming ``soft``; before, it
    was accepted: phase-one points (``"inaccurate"``) from 1e10 on paper W's satellite and from 1e15
    here, ``ZeroDivisionError`` at 1e200, Clarabel's ``"unbounded"`` at 1e12 at ``x = (30, 0)``.
    At the limit the answer is the hard problem's where that is feasible, certified with its slack;
    where it is not, no back-end's ``"unbounded"`` reaches a form's answer (its objective is >= 0)."""
    for weight in (np.nextafter(MAX_SOFT_WEIGHT, np.inf), 1e15, 1e200, float(np.finfo(float).max)):
        with pytest.raises(InvalidArgumentError, match=r"^soft\['u'\]: expected a weight <= MAX_SOFT_WEIGHT"):
            RMPC(_plant(), np.eye(2), np.eye(1), u_max=1.0, soft={"u": weight})
    x = np.array([1.0, 0.0])
    hard = RMPC(_plant(), np.eye(2), np.eye(1), u_max=1.0).solve(x)
    for lyapunov in ("common", "vertex"):
        sol = RMPC(_plant(), np.eye(2), np.eye(1), u_max=1.0, soft={"u": MAX_SOFT_WEIGHT},
                   lyapunov=lyapunov).solve(x)
        assert sol.status == "optimal" and sol.certificate.ok
        assert sol.certificate.margins["slack_u"] >= -sol.certificate.tol
        assert abs(sol.slack["u"]) <= 1e-9
        if lyapunov == "common":
            assert sol.gamma == pytest.approx(hard.gamma, rel=1e-6)
    # where the hard bound cannot hold, every back-end: a true status, never "unbounded"
    far = np.array([30.0, 0.0])
    for backend in ("ipm", "clarabel", "cvxpy"):
        sol = RMPC(_plant(), np.eye(2), np.eye(1), u_max=1.0, soft={"u": MAX_SOFT_WEIGHT},
                   backend=backend).solve(far)
        assert sol.status != "unbounded", backend
        if sol.status == "optimal":
            assert sol.slack["u"] > 0.0


def test_a_back_end_saying_unbounded_is_not_believed(monkeypatch):
    """A form's objective is >= 0: a solver's "unbounded" becomes "numerical_error" with the reason
    (made here by Clarabel's word for every solve; before, the form answered "unbounded")."""
    import lmi.forms.problem as problem

    monkeypatch.setitem(problem.CLARABEL_STATUS_MAP, "Solved", "unbounded")
    sol = FormProblem(A_VERTICES, B_VERTICES, np.eye(2), np.eye(1), u_max=1.0, soft={"u": 1e3},
                      backend="clarabel").solve(np.array([1.0, 0.0]))
    assert sol.status == "numerical_error"
    assert "not believed" in sol.solver_status


@pytest.mark.parametrize("value", [np.array([1, 0]), np.array(1), 1.0, "1", [1]])
def test_array_valued_free_moves_is_refused_naming_it(value):
    """Before: ``ValueError: The truth value of an array ... is ambiguous`` from numpy."""
    with pytest.raises(ArgumentTypeError, match=r"^free_moves: expected the integer 0 or 1"):
        RMPC(_plant(), np.eye(2), np.eye(1), u_max=1.0, free_moves=value)
    sol = RMPC(_plant(), np.eye(2), np.eye(1), u_max=1.0, free_moves=np.int64(1)).solve(np.array([1.0, 0.0]))
    assert sol.status == "optimal" and sol.u0 is not None


def test_read_sdpa_refuses_sizes_before_allocating(tmp_path):
    """A 14-byte file declaring a 30000 x 30000 block (14.4 GB of dense data): refused at once,
    naming the file and the bytes (before, it allocated them); a compressed file that expands
    past ``max_bytes`` likewise; arguments that are not paths name ``path``."""
    big = tmp_path / "big.dat-s"
    big.write_text("1\n1\n30000\n1.0\n")
    start = time.perf_counter()
    with pytest.raises(SDPAFormatError, match=r"big\.dat-s, line 3: expected sizes whose dense data fit in "
                                             r"max_bytes = 2147483648 bytes.* 14400000000 bytes"):
        read_sdpa(big)
    assert time.perf_counter() - start < 1.0
    bomb = tmp_path / "bomb.dat-s.gz"
    bomb.write_bytes(gzip.compress(b'"' + b" " * 2**20))
    with pytest.raises(SDPAFormatError, match=r"bomb\.dat-s\.gz.*expands to at most max_bytes = 100000"):
        read_sdpa(bomb, max_bytes=np.int64(100_000))
    for value in (5, None, b"x.dat-s", [str(big)]):
        with pytest.raises(ArgumentTypeError, match=r"^path: expected a file path"):
            read_sdpa(value)
    with pytest.raises(InvalidArgumentError, match=r"^max_bytes"):
        read_sdpa(big, max_bytes="1GB")


def test_numpy_integers_are_integers():
    """``np.int64(10)`` wherever an integer is: before, the IPM's settings refused it as "an integer >
    0" (``solver_options={"max_iter": np.int64(50)}``)."""
    assert is_integer(np.int64(10)) and is_integer(10) and not is_integer(True) and not is_integer(10.0)
    assert check_count(np.int64(10), "n") == 10
    options = {"max_iter": np.int64(50), "tol_feas": np.float32(1e-8)}
    sol = KothareProblem(A_VERTICES, B_VERTICES, np.eye(2), np.eye(1), u_max=1.0,
                         solver_options=options).solve([1.0, 0.0])
    assert sol.status == "optimal"
    res = BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])], max_iter=np.int64(10)).solve()
    assert res.status == "optimal" and res.x[0] == pytest.approx(1.0)
