"""Invariants of the receding-horizon RMPC along closed loops (Kothare et al. 1996, lemma 2, thm 3).

At every certified solve k: the state lies in its ellipsoid, ``x(k)' Q_k^-1 x(k) <= 1``; the next
state (any plant in the polytope, even a time-varying one) stays in it,
``x(k+1)' Q_k^-1 x(k+1) <= 1``, so the old solution is feasible at k+1 and gamma cannot grow;
every recomputed LMI margin is ``>= -1e-7``.

Measured (100-step loops): ``x(k)' Q_k^-1 x(k) - 1 <= 8.4e-8`` (the state LMI is active at the
optimum, up to the certificate tolerance); ``x(k+1)' Q_k^-1 x(k+1) <= 0.821`` on Kothare's
example (fixed and random alpha) and ``<= 0.811`` on the random polytope; gamma(k+1)/gamma(k)
<= 0.821 (strict decrease; asserted: no increase beyond 1e-6 relative); worst margin -4.8e-10;
the random polytope's state falls from norm 1 to 7.4e-9 in 100 steps.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
import scipy.linalg as sla

from models import PolytopicModel
from rmpc import RMPC

LEVEL_TOL = 1e-6
GAMMA_RTOL = 1e-6
MARGIN_TOL = 1e-7


def kothare_plant(alpha: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]), np.array([[0.0], [0.1 * 0.787]])


KOTHARE = PolytopicModel([kothare_plant(0.1), kothare_plant(10.0)], dt=0.1)
KOTHARE_X0 = np.array([0.05, 0.0])


def random_polytope(seed: int = 2, n: int = 3, m: int = 2, dt: float = 0.1) -> PolytopicModel:
    """Two ZOH vertices of a random continuous system (here: both open-loop unstable)."""
    rng = np.random.default_rng(seed)
    ac = rng.normal(size=(n, n))
    ac -= (np.max(np.linalg.eigvals(ac).real) + rng.uniform(-0.3, 0.5)) * np.eye(n)
    bc = rng.normal(size=(n, m))
    verts = []
    for _ in range(2):
        d, s = 0.3 * rng.normal(size=(n, n)), rng.uniform(0.6, 1.4)
        big = sla.expm(np.block([[ac + d, bc * s], [np.zeros((m, n + m))]]) * dt)
        verts.append((big[:n, :n], big[:n, n:]))
    return PolytopicModel(verts, dt=dt)


def run(ctrl: RMPC, plant_at_step: Callable[[int], tuple[np.ndarray, np.ndarray]], x0, n_steps: int):
    """Closed loop ``x(k+1) = A_k x + B_k u``; returns the states, inputs and step infos."""
    xs, us, infos = [np.asarray(x0, dtype=float)], [], []
    for k in range(n_steps):
        u = ctrl.step(xs[-1])
        a, b = plant_at_step(k)
        us.append(u)
        infos.append(ctrl.last)
        xs.append(a @ xs[-1] + b @ u)
    return np.array(xs), np.array(us), infos


def check_invariants(xs: np.ndarray, infos: list) -> int:
    """Assert the invariants at every certified solve; returns the number of solves."""
    prev_gamma = None
    solves = 0
    for k, info in enumerate(infos):
        sol = info.extra.get("solution")
        if sol is None or info.fallback:
            continue
        solves += 1
        assert sol.status in ("optimal", "inaccurate")
        assert sol.certificate.worst >= -MARGIN_TOL, (k, sol.margins)
        q_inv = np.linalg.inv(sol.Q)
        assert xs[k] @ q_inv @ xs[k] <= 1.0 + LEVEL_TOL, k
        assert xs[k + 1] @ q_inv @ xs[k + 1] <= 1.0 + LEVEL_TOL, k
        if prev_gamma is not None:
            assert sol.gamma <= prev_gamma * (1.0 + GAMMA_RTOL), (k, sol.gamma, prev_gamma)
        prev_gamma = sol.gamma
    return solves


@pytest.mark.parametrize("alpha", [0.1, 10.0, "random"])
def test_kothare_example_invariants(alpha):
    rng = np.random.default_rng(5)
    ctrl = RMPC(KOTHARE, Q=np.diag([1.0, 0.0]), R=[[2e-5]], u_max=2.0, input_constraint="peak")

    def plant(_k: int):
        return kothare_plant(rng.uniform(0.1, 10.0) if alpha == "random" else alpha)

    xs, us, infos = run(ctrl, plant, KOTHARE_X0, 100)
    assert check_invariants(xs, infos) >= 20
    assert np.max(np.abs(us)) <= 2.0 + 1e-6
    assert np.linalg.norm(xs[-1]) < 1e-8


@pytest.mark.parametrize(
    ("input_constraint", "u_max"), [("ellipsoid", 1.0), ("peak", [1.0, 1.0]), (None, None)]
)
def test_random_polytope_invariants(input_constraint, u_max):
    poly = random_polytope()
    assert min(np.max(np.abs(np.linalg.eigvals(a))) for a in poly.A) > 1.0  # unstable vertices
    rng = np.random.default_rng(1)
    x0 = rng.normal(size=3)
    x0 /= np.linalg.norm(x0)
    ctrl = RMPC(poly, Q=np.eye(3), R=np.eye(2), u_max=u_max, input_constraint=input_constraint)

    def plant(_k: int):  # a random member of the polytope at every step
        w = rng.uniform()
        return w * poly.A[0] + (1 - w) * poly.A[1], w * poly.B[0] + (1 - w) * poly.B[1]

    xs, us, infos = run(ctrl, plant, x0, 100)
    assert check_invariants(xs, infos) == 100  # every step solved and certified
    if input_constraint == "ellipsoid":
        assert np.max(np.linalg.norm(us, axis=1)) <= 1.0 + 1e-6
    elif input_constraint == "peak":
        assert np.max(np.abs(us)) <= 1.0 + 1e-6
    assert np.linalg.norm(xs[-1]) < 1e-6 * np.linalg.norm(x0)


def test_kept_gain_keeps_the_state_in_its_ellipsoid():
    """With resolve_threshold < 1 the kept gain's ellipsoid stays invariant between re-solves."""
    ctrl = RMPC(
        KOTHARE, Q=np.diag([1.0, 0.0]), R=[[2e-5]], u_max=2.0, input_constraint="peak",
        resolve_threshold=0.5,
    )
    xs, us, infos = run(ctrl, lambda k: kothare_plant(10.0 if k % 2 else 0.1), KOTHARE_X0, 100)
    check_invariants(xs, infos)
    q_inv, reused = None, 0
    for k, info in enumerate(infos):
        sol = info.extra.get("solution")
        if sol is not None and not info.fallback:
            q_inv = np.linalg.inv(sol.Q)
        elif info.status == "reused" and info.extra.get("reason") == "inside ellipsoid":
            reused += 1
            level = xs[k] @ q_inv @ xs[k]
            assert 0.5 < level <= 1.0 + LEVEL_TOL
            assert info.extra["level"] == pytest.approx(level, rel=1e-9)
        assert xs[k + 1] @ q_inv @ xs[k + 1] <= 1.0 + LEVEL_TOL
    assert reused > 0
    assert np.max(np.abs(us)) <= 2.0 + 1e-6
