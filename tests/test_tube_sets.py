"""Tube MPC's sets against an independent construction.

The mRPI outer approximation is checked by its defining inclusions (``A_K Z + W in Z`` and
``F_inf in Z in F_inf + B_inf(epsilon)``, with ``F_inf``'s support function summed directly), the
tightenings by enumerating and sampling vertex sequences of ``W``, the terminal sets by their
invariance at their vertices. The independent side uses scipy's qhull and plain sums, not cddlib.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

from rmpc.mpc.tube import TubeMPC
from rmpc.mpc.tube_runs import double_integrator
from rmpc.sets import Polytope, mrpi_outer, reachable_tightening

A = np.array([[1.0, 1.0], [0.0, 1.0]])
B = np.array([[0.5], [1.0]])
W_CORNERS = np.array(list(itertools.product([-0.1, 0.1], repeat=2)))


def lqr_gain(a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    p = sla.solve_discrete_are(a, b, q, r)
    return -np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)


K = lqr_gain(A, B, np.eye(2), np.array([[0.01]]))
A_K = A + B @ K


def support_inf(a: np.ndarray, d: np.ndarray, terms: int = 600) -> float:
    """h_{F_inf}(d) = sum_i h_W((A^i)' d), summed until the terms vanish."""
    total, row = 0.0, d.copy()
    for _ in range(terms):
        total += np.max(W_CORNERS @ row)
        row = a.T @ row
    return total


def independent_vertices(a: np.ndarray, s: int, alpha: float) -> np.ndarray:
    """The vertices of (1 - alpha)^-1 sum_{i<s} A^i W by qhull on the pairwise sums."""
    pts = np.zeros((1, 2))
    for i in range(s):
        pts = (pts[:, None, :] + (W_CORNERS @ np.linalg.matrix_power(a, i).T)[None]).reshape(-1, 2)
        pts = pts[ConvexHull(pts).vertices]
    return pts / (1.0 - alpha)


def lp_support(H: np.ndarray, h: np.ndarray, d: np.ndarray) -> float:
    res = linprog(-d, A_ub=H, b_ub=h, bounds=[(None, None)] * H.shape[1], method="highs")
    assert res.status == 0
    return -res.fun


@pytest.fixture(scope="module", params=[1e-2, 1e-3, 1e-5])
def approx(request):
    return mrpi_outer(A_K, Polytope.box([0.1, 0.1]), epsilon=request.param)


def test_mrpi_is_robust_positively_invariant(approx) -> None:
    """A_K Z + W in Z: every A_K v + w, v a vertex of Z (independent), w a corner of W, is in Z."""
    verts = independent_vertices(A_K, approx.s, approx.alpha)
    Z = approx.Z
    images = (verts @ A_K.T)[:, None, :] + W_CORNERS[None]
    slack = Z.h - images.reshape(-1, 2) @ Z.H.T
    assert slack.min() >= -1e-12
    # the same H-representation as the independent hull: equal support in 200 directions
    dirs = np.random.default_rng(0).normal(size=(200, 2))
    lp = np.array([lp_support(Z.H, Z.h, d) for d in dirs])
    assert np.allclose(lp, (verts @ dirs.T).max(axis=0), atol=1e-12, rtol=1e-10)


def test_mrpi_is_within_epsilon_of_the_minimal_set(approx) -> None:
    """F_inf in Z in F_inf + B_inf(eps): h_Finf(d) <= h_Z(d) <= h_Finf(d) + eps |d|_1."""
    dirs = np.vstack([np.eye(2), -np.eye(2), np.random.default_rng(1).normal(size=(300, 2))])
    for d in dirs:
        h_inf = support_inf(A_K, d)
        h_z = approx.Z.support(d)
        assert h_inf <= h_z + 1e-12
        assert h_z <= h_inf + approx.epsilon * np.abs(d).sum() + 1e-12
        assert h_z <= h_inf / (1.0 - approx.alpha) + 1e-12      # relative: Z in (1 - alpha)^-1 F_inf
    assert approx.bound <= approx.epsilon


def test_mrpi_of_a_scalar_system_is_exact() -> None:
    """x+ = 0.5 x + w, |w| <= 1: F_inf = [-2, 2]; Z = (1 - 0.5^s)^-1 * 2 (1 - 0.5^s) = [-2, 2]."""
    approx = mrpi_outer(np.array([[0.5]]), Polytope.box([1.0]), epsilon=1e-6)
    assert approx.alpha == 0.5 ** approx.s
    assert np.allclose(sorted(approx.Z.vertices.ravel()), [-2.0, 2.0], atol=1e-12)


def test_rigid_tightening_is_the_support_of_Z() -> None:
    """X - Z and U - K Z: the tightening of each row is max over Z's (independent) vertices."""
    p = double_integrator()
    tube = TubeMPC((A, B), **p["controller"], kind="rigid")
    verts = independent_vertices(A_K, tube.sets.s, tube.sets.alpha)
    Hx, Hu = tube.X[0], tube.U[0]
    assert np.allclose(tube.sets.state_tightening[0], (verts @ Hx.T).max(axis=0), atol=1e-12)
    assert np.allclose(tube.sets.input_tightening[0], (verts @ (Hu @ K).T).max(axis=0), atol=1e-12)


def test_reachable_tightening_by_vertex_sequences() -> None:
    """t[i] = max over disturbance sequences of c' sum_{j<i} A_K^j w_j: all 4^i vertex sequences
    attain it exactly (i <= 5); 20000 sampled sequences of points of W never exceed it."""
    rows = np.array([[1.0, 0.0], [0.0, -1.0], [0.3, 0.7]])
    t = reachable_tightening(A_K, Polytope.box([0.1, 0.1]), rows, 9)
    assert np.all(t[0] == 0.0)
    powers = [np.linalg.matrix_power(A_K, j) for j in range(9)]
    for i in range(1, 6):
        best = np.full(3, -np.inf)
        for seq in itertools.product(range(4), repeat=i):
            e = sum(powers[j] @ W_CORNERS[seq[j]] for j in range(i))
            best = np.maximum(best, rows @ e)
        assert np.allclose(best, t[i], atol=1e-12)
    rng = np.random.default_rng(2)
    w = rng.uniform(-0.1, 0.1, size=(20000, 9, 2))
    w[::2] = W_CORNERS[rng.integers(4, size=(10000, 9))]
    e = np.zeros((20000, 2))
    for i in range(1, 10):
        e = e @ A_K.T + w[:, i - 1]          # e_i = A_K e_(i-1) + w: the same set as sum A^j w_j
        assert (e @ rows.T <= t[i] + 1e-12).all()


@pytest.mark.parametrize("kind", ["rigid", "tightening"])
def test_terminal_set_is_invariant_and_admissible(kind: str) -> None:
    p = double_integrator()
    tube = TubeMPC((A, B), **p["controller"], kind=kind)
    sets = tube.sets
    Xf = Polytope(sets.terminal_H, sets.terminal_h, "Xf")
    Hx, hx, _ = tube.X
    Hu, hu, _ = tube.U
    N = tube.N
    if kind == "rigid":
        images = Xf.vertices @ A_K.T                          # A_K Xf in Xf
        t_x, t_u = sets.state_tightening[0], sets.input_tightening[0]
    else:
        # A_K Xf + A_K^N W in Xf (the shifted plan's terminal state stays in it)
        push = W_CORNERS @ np.linalg.matrix_power(A_K, N).T
        images = ((Xf.vertices @ A_K.T)[:, None, :] + push[None]).reshape(-1, 2)
        t = reachable_tightening(A_K, tube.W, np.vstack([Hx, Hu @ K]), N)[N]
        t_x, t_u = t[: len(hx)], t[len(hx):]
    assert (images @ Xf.H.T <= Xf.h + 1e-9).all()
    assert (Xf.vertices @ Hx.T <= hx - t_x + 1e-9).all()
    assert (Xf.vertices @ (Hu @ K).T <= hu - t_u + 1e-9).all()


def test_polytope_rejects_bad_sets() -> None:
    with pytest.raises(ValueError, match="W: expected a bounded polytope"):
        Polytope(np.eye(2), np.ones(2), "W")
    with pytest.raises(ValueError, match="W: expected a non-empty polytope"):
        Polytope(np.array([[1.0], [-1.0]]), np.array([-1.0, -1.0]), "W")
    with pytest.raises(ValueError, match="K: expected a gain with A \\+ B K Schur stable"):
        mrpi_outer(A, Polytope.box([0.1, 0.1]))


def test_a_cddlib_failure_is_a_toolkit_error_naming_the_set(monkeypatch) -> None:
    """cddlib's floating-point arithmetic can give up (it did on a six-state terminal set:
    "Numerical inconsistency is found"); that surfaces as a PolytopeError naming the set."""
    import cdd

    from rmpc.sets import PolytopeError

    def give_up(*args, **kwargs):
        raise RuntimeError("*Error: Numerical inconsistency is found.")

    monkeypatch.setattr(cdd, "copy_generators", give_up)
    with pytest.raises(PolytopeError, match="could not enumerate the vertices of terminal set"):
        Polytope(np.vstack([np.eye(2), -np.eye(2)]), np.ones(4), "terminal set")


def test_a_sum_too_large_is_refused_before_it_is_built() -> None:
    with pytest.raises(ValueError, match="W: expected a Minkowski sum of at most max_vertices = 10"):
        mrpi_outer(A_K, Polytope.box([0.1, 0.1]), epsilon=1e-3, max_vertices=10)


# -- the minimal RPI set's support without a set, a flat disturbance ------------------------------
@pytest.mark.parametrize("E", [None, np.array([[0.0], [1.0]])], ids=["box W", "flat E W"])
def test_mrpi_support_bound_brackets_the_minimal_rpi_set(E) -> None:
    """``h_{F_s} <= h_{F_inf} <= bound <= h_{F_s} + epsilon``, with ``h_{F_inf}`` summed directly
    over 600 terms (``A_K^600`` is below 1e-30); a flat ``E W`` (the disturbance on the second
    state only) is taken as a full one."""
    from rmpc.sets import mrpi_support_bound

    rng = np.random.default_rng(7)
    rows = np.vstack([np.eye(2), -np.eye(2), rng.normal(size=(20, 2))])
    W = Polytope.box([0.1]) if E is not None else Polytope.box([0.1, 0.1])
    for eps in (1e-2, 1e-5):
        bound, s = mrpi_support_bound(A_K, W, rows, eps, E=E)
        sums = reachable_tightening(A_K, W, rows, 600, E=E)
        assert (sums[600] <= bound + 1e-12).all()          # an upper bound of F_inf's support
        assert (bound <= sums[s] + eps + 1e-12).all()      # within epsilon of F_s's
        assert (bound - sums[600] <= eps + 1e-12).all()
    if E is None:      # and no looser than Rakovic et al.'s outer approximation at that accuracy
        approx = mrpi_outer(A_K, W, epsilon=1e-5)
        bound, _ = mrpi_support_bound(A_K, W, rows, 1e-5)
        assert (bound <= approx.Z.support(rows) + 1e-5).all()


def test_admissible_set_by_lps_is_irredundant_bounded_or_refused() -> None:
    from rmpc.sets import admissible_set
    from toolkit_common.errors import InvalidArgumentError

    G = np.vstack([K, -K, np.eye(2), -np.eye(2)])
    g = np.concatenate([[1.0, 1.0], [10.0] * 4])
    Xf = admissible_set(A_K, G, lambda j: g)
    assert np.allclose(np.linalg.norm(Xf.H, axis=1), 1.0)
    for i in range(Xf.h.size):      # dropping any row enlarges the set
        others = np.delete(np.arange(Xf.h.size), i)
        res = linprog(-Xf.H[i], A_ub=Xf.H[others], b_ub=Xf.h[others], bounds=[(None, None)] * 2)
        assert res.status == 3 or -res.fun > Xf.h[i] + 1e-9
    # the same set as the vertex-based check: invariant and admissible at its vertices
    assert (Xf.vertices @ A_K.T @ Xf.H.T <= Xf.h + 1e-9).all()
    assert (np.abs(Xf.vertices @ K.T) <= 1.0 + 1e-9).all()
    with pytest.raises(InvalidArgumentError, match="terminal set: expected a bounded set"):
        admissible_set(0.5 * np.eye(2), np.array([[1.0, 0.0], [-1.0, 0.0]]), lambda j: np.ones(2))


def test_lyapunov_ellipsoid_is_invariant_and_fits_its_constraints() -> None:
    """The ellipsoid that stops the tightening's terminal set: ``||L' A z|| <= rate ||L' z||``
    with ``rate < 1`` on random states, and the largest radius inside the rows touches one of
    them (its support, by the ellipsoid's points, equals the bound there)."""
    from rmpc.sets import LyapunovEllipsoid

    shape = LyapunovEllipsoid.of(A_K)
    rng = np.random.default_rng(3)
    z = rng.normal(size=(500, 2))
    assert shape.rate < 1.0
    assert (np.linalg.norm(z @ A_K.T @ shape.L, axis=1)
            <= shape.rate * np.linalg.norm(z @ shape.L, axis=1) + 1e-12).all()
    G = np.vstack([K, -K, np.eye(2)])
    g = np.array([1.0, 1.0, 3.0, 0.5])
    radius = shape.largest_inside(G, g)
    angles = np.linspace(0.0, 2.0 * np.pi, 20001)
    circle = np.column_stack([np.cos(angles), np.sin(angles)])
    points = radius * np.linalg.solve(shape.L.T, circle.T).T          # ||L' z|| = radius
    reach = (points @ G.T).max(axis=0)
    assert (reach <= g + 1e-12).all() and np.isclose((reach / g).max(), 1.0, rtol=1e-6)
