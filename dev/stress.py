"""A seeded stress set of random Kothare problems whose feasibility is known by construction.

Each problem is a polytope of discrete-time models ``(A_j, B_j)``, weights ``Q1``, ``R``, a
peak or ellipsoid input bound and a state ``x``. Two kinds:

``"feasible"``
    A point ``(Q, Y, gamma)`` that satisfies every LMI is built alongside the problem and
    returned with it (``witness``), so feasibility is proved, not assumed: the LQR gain ``F``
    and Riccati matrix ``P`` of the vertex-mean model (state weight ``b Q1``, ``b`` the first of
    1, 10, 100 that works) give ``Q = gamma (c P)^-1``, ``Y = F Q`` with the smallest ``c`` in
    ``1, 2, 4, ..., 64`` for which every vertex's closed loop satisfies
    ``Acl_j' (c P) Acl_j - c P + Q1 + F'RF <= 0`` (drawn again otherwise), ``gamma``
    such that ``x`` lies on the boundary of the ellipsoid scaled by 0.9, and the input bound
    set 10 % above what ``F`` needs on that ellipsoid. :func:`lmi.certify` checks it.
``"infeasible"``
    The vertex-mean plant has a real eigenvalue ``lam`` in ``[1.1, 1.5]`` with left
    eigenvector ``w`` (the other vertices are perturbations of it) and ``x`` is drawn so that
    ``|w'x| (lam - 1)`` is ``distance`` (2 unless given) times the largest ``|w' B_0 u|`` the
    input bound allows: the state is ``distance`` times as far along ``w`` as the edge of the
    slab ``|w'x| (lam - 1) <= max |w' B_0 u|`` that holds every state the input can keep. On the
    constant plant ``(A_0, B_0)``, which is in the polytope, ``|w'x(k)|`` then grows for every
    admissible input sequence (``|w'x(k+1)| >= lam |w'x(k)| - |w'B_0 u(k)|``), so no
    controller keeps the cost finite and the Kothare LMIs have no solution. Here ``A_0`` is
    the vertex-mean model itself (it is one of the vertices).

:func:`run_stress` (``python -m dev.stress``) solves the set with the IPM back-end (with
and without its Clarabel fallback) and with cvxpy + Clarabel at tight tolerances, and flags any
answer that contradicts what is known by construction.

The generator is deterministic in its seed (``numpy.random.default_rng``) and imports only
numpy and scipy, so both the tests and the benchmarks use it.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy.linalg import expm, solve_discrete_are

from benchmarks.core.jsonable import write_json
from toolkit_common.errors import InvalidArgumentError

__all__ = ["StressProblem", "make_problem", "stress_set"]

Kind = Literal["feasible", "infeasible", "unknown"]
#: Relative size of the vertex perturbations of ``A`` (Frobenius, per entry scale) and of ``B``.
A_SPREAD = 0.01
B_SPREAD = 0.2
SAMPLE_TIME = 0.1
MAX_DRAWS = 50


@dataclass(frozen=True)
class StressProblem:
    """One random Kothare problem and what is known about it.

    Attributes
    ----------
    A, B : ndarray
        Vertices ``(N, n, n)`` and ``(N, n, m)``.
    Q1, R : ndarray
        Weights.
    input_constraint : {"peak", "ellipsoid"} or None
    u_max : float or ndarray or None
    x : ndarray
        The state.
    dt : float
        Sample time (for the delta formulations).
    kind : {"feasible", "infeasible", "unknown"}
        Known by construction (see the module docstring); ``"unknown"`` only for the generic
        problems of :mod:`dev.generic_stress`.
    seed : int
    witness : tuple or None
        For feasible problems ``(gamma, Q, Y)``, a point satisfying every LMI.
    tag : str
        Names the problem in :attr:`label` instead of ``kind`` when given.
    """

    A: np.ndarray
    B: np.ndarray
    Q1: np.ndarray
    R: np.ndarray
    input_constraint: str | None
    u_max: float | np.ndarray | None
    x: np.ndarray
    dt: float
    kind: Kind
    seed: int
    witness: tuple[float, np.ndarray, np.ndarray] | None = field(default=None, repr=False)
    tag: str = ""

    @property
    def n_states(self) -> int:
        return int(self.A.shape[1])

    @property
    def n_vertices(self) -> int:
        return int(self.A.shape[0])

    @property
    def label(self) -> str:
        """A short name, e.g. ``"n14-v2-feasible-s3"``."""
        return f"n{self.n_states}-v{self.n_vertices}-{self.tag or self.kind}-s{self.seed}"

    def kothare_kwargs(self) -> dict:
        """Keyword arguments of :class:`lmi.KothareProblem` (besides the back-end)."""
        return {"A": self.A, "B": self.B, "Q": self.Q1, "R": self.R, "dt": self.dt,
                "input_constraint": self.input_constraint, "u_max": self.u_max}


def _vertices(rng: np.random.Generator, a0: np.ndarray, b0: np.ndarray,
              count: int) -> tuple[np.ndarray, np.ndarray]:
    """``count`` vertices; vertex 0 is ``(a0, b0)``, the others perturbations of it."""
    n, m = b0.shape
    a = [a0]
    b = [b0]
    for _ in range(count - 1):
        a.append(a0 + A_SPREAD * rng.normal(size=(n, n)) / np.sqrt(n))
        b.append(b0 * (1.0 + B_SPREAD * rng.uniform(-1.0, 1.0, size=(1, m))))
    return np.array(a), np.array(b)


def lqr_contraction(a: np.ndarray, b: np.ndarray, q1: np.ndarray,
                    r: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``(c P, F)``: the LQR gain ``F`` and Riccati matrix ``P`` of the vertex-mean model (state
    weight ``b Q1``, ``b`` the first of 1, 10, 100 that works) with the smallest ``c`` in ``1, 2,
    4, ..., 64`` for which every vertex's closed loop satisfies ``Acl_j' (c P) Acl_j - c P + Q1 +
    F'RF <= 0``; ``None`` if there is none (or the Riccati equation has no solution)."""
    am, bm = a.mean(axis=0), b.mean(axis=0)
    for boost in (1.0, 10.0, 100.0):  # a more aggressive gain contracts more robustly
        try:
            p = solve_discrete_are(am, bm, boost * q1, r)
        except (np.linalg.LinAlgError, ValueError):
            return None
        f = -np.linalg.solve(r + bm.T @ p @ bm, bm.T @ p @ am)
        stage = q1 + f.T @ r @ f
        for c in (1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0):
            pc = c * p
            worst = max(float(np.linalg.eigvalsh((aj + bj @ f).T @ pc @ (aj + bj @ f) - pc + stage)[-1])
                        for aj, bj in zip(a, b, strict=True))
            if worst < 0.0:
                return pc, f
    return None


def lqr_witness(pc: np.ndarray, f: np.ndarray, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The witness ``(gamma, Q, Y)`` of :func:`lqr_contraction`'s ``(c P, F)`` at the state ``x``:
    ``Q = gamma (c P)^-1``, ``Y = F Q`` with ``gamma`` such that ``x`` lies on the boundary of the
    ellipsoid scaled by 0.9 (``x' Q^-1 x = 0.9``)."""
    gamma = float(x @ pc @ x) / 0.9
    q = gamma * np.linalg.inv(pc)
    return gamma, q, f @ q


def witness_bound(constraint: str, q: np.ndarray, y: np.ndarray) -> float | np.ndarray:
    """The input bound the witness ``(Q, Y)`` needs: per input ``sqrt((Y Q^-1 Y')_jj)`` (peak) or
    ``sqrt(lambda_max(Y Q^-1 Y'))`` (ellipsoid)."""
    yqy = y @ np.linalg.solve(q, y.T)
    if constraint == "peak":
        return np.sqrt(np.diag(yqy))
    return float(np.sqrt(np.linalg.eigvalsh(yqy)[-1]))


def _feasible(rng: np.random.Generator, n: int, m: int, count: int, constraint: str):
    """One draw of a feasible problem with its witness, or None if the draw is rejected."""
    ac = rng.normal(size=(n, n)) / np.sqrt(n)
    ac -= (np.max(np.linalg.eigvals(ac).real) + rng.uniform(-0.2, 0.3)) * np.eye(n)
    a0 = expm(SAMPLE_TIME * ac)
    b0 = SAMPLE_TIME * rng.normal(size=(n, m))
    a, b = _vertices(rng, a0, b0, count)
    q1 = np.diag(10.0 ** rng.uniform(-1.0, 1.0, size=n))
    r = np.eye(m)
    found = lqr_contraction(a, b, q1, r)
    if found is None:
        return None
    x = rng.normal(size=n)
    x /= np.linalg.norm(x)
    gamma, q, y = lqr_witness(*found, x)
    u_max = 1.1 * witness_bound(constraint, q, y)
    return a, b, q1, r, u_max, x, (gamma, q, y)


def _infeasible(rng: np.random.Generator, n: int, m: int, count: int, constraint: str,
                distance: float = 2.0):
    """One draw of an infeasible problem (see the module docstring)."""
    lam = rng.uniform(1.1, 1.5)
    rest = rng.normal(size=(n - 1, n - 1)) / np.sqrt(n - 1)
    rest *= rng.uniform(0.5, 0.95) / max(np.max(np.abs(np.linalg.eigvals(rest))), 1e-12)
    core = np.zeros((n, n))
    core[0, 0] = lam
    core[1:, 1:] = rest
    core[1:, 0] = 0.3 * rng.normal(size=n - 1)  # e_0' core = lam e_0': e_0 is a left eigenvector
    s = np.eye(n) + 0.3 * rng.normal(size=(n, n)) / np.sqrt(n)
    a0 = s @ core @ np.linalg.inv(s)
    b0 = rng.normal(size=(n, m)) / np.sqrt(n)
    a, b = _vertices(rng, a0, b0, count)
    # left eigenvector of a0 for lam: w' a0 = lam w'  (w' = e_0' s^-1 since e_0' core = lam e_0')
    w = np.linalg.inv(s)[0]
    q1 = np.diag(10.0 ** rng.uniform(-1.0, 1.0, size=n))
    r = np.eye(m)
    wb = w @ b0
    if constraint == "peak":
        u_max = rng.uniform(0.5, 2.0, size=m)
        reach = float(np.sum(np.abs(wb) * u_max))
    else:
        u_max = float(rng.uniform(0.5, 2.0))
        reach = float(np.linalg.norm(wb)) * u_max
    x = rng.normal(size=n)
    x *= distance * reach / ((lam - 1.0) * abs(float(w @ x)))
    return a, b, q1, r, u_max, x, None


def make_problem(n: int, m: int, n_vertices: int, kind: Kind, seed: int,
                 input_constraint: str = "peak", distance: float = 2.0) -> StressProblem:
    """One stress problem (deterministic in its arguments).

    ``distance`` (infeasible problems only, > 1) places the state that many times beyond the
    slab of states the input can hold (see the module docstring); the data do not depend on it,
    only the state's length.

    Raises
    ------
    InvalidArgumentError
        For sizes out of range or an unknown kind or constraint, naming the argument.
    """
    if not (isinstance(n, int) and n >= 2):
        raise InvalidArgumentError("n", "an integer >= 2", repr(n))
    if not (isinstance(m, int) and 1 <= m <= n):
        raise InvalidArgumentError("m", f"an integer in [1, {n}]", repr(m))
    if not (isinstance(n_vertices, int) and n_vertices >= 1):
        raise InvalidArgumentError("n_vertices", "an integer >= 1", repr(n_vertices))
    if kind not in ("feasible", "infeasible"):
        raise InvalidArgumentError("kind", "'feasible' or 'infeasible'", repr(kind))
    if input_constraint not in ("peak", "ellipsoid"):
        raise InvalidArgumentError("input_constraint", "'peak' or 'ellipsoid'", repr(input_constraint))
    if isinstance(distance, bool) or not (isinstance(distance, int | float) and 1.0 < distance < np.inf):
        raise InvalidArgumentError("distance", "a finite number > 1", repr(distance))
    rng = np.random.default_rng([seed, n, m, n_vertices, kind == "feasible",
                                 input_constraint == "peak"])
    for _ in range(MAX_DRAWS):
        if kind == "feasible":
            out = _feasible(rng, n, m, n_vertices, input_constraint)
        else:
            out = _infeasible(rng, n, m, n_vertices, input_constraint, float(distance))
        if out is not None:
            a, b, q1, r, u_max, x, witness = out
            for arr in (a, b, q1, r, x):
                arr.setflags(write=False)
            return StressProblem(a, b, q1, r, input_constraint, u_max, x, SAMPLE_TIME, kind, seed, witness)
    raise RuntimeError(f"no {kind} problem found in {MAX_DRAWS} draws (seed {seed})")  # pragma: no cover


def stress_set(sizes: Sequence[int] = (6, 10, 14), vertex_counts: Sequence[int] = (2, 8),
               seeds: Sequence[int] = (0, 1, 2), m: int = 3,
               kinds: Sequence[Kind] = ("feasible", "infeasible")) -> Iterator[StressProblem]:
    """Every combination of size, vertex count, kind and seed, peak and ellipsoid bounds alternating."""
    for n in sizes:
        for count in vertex_counts:
            for kind in kinds:
                for seed in seeds:
                    constraint = "peak" if seed % 2 == 0 else "ellipsoid"
                    yield make_problem(n, m, count, kind, seed, constraint)


# -- the benchmark ---------------------------------------------------------------------------------
def run_stress(problems: Sequence[StressProblem], tight: float = 1e-9) -> list[dict]:
    """Solve every problem with the IPM back-end (defaults: Clarabel fallback on), the IPM alone
    and cvxpy + Clarabel at ``tight`` tolerances; one record per problem (statuses, times,
    iterations, gamma's relative difference when both are optimal, times of the build plus one
    cold solve, and whether each answer
    contradicts what is known by construction: ``"optimal"`` on an infeasible problem, or
    ``"infeasible"`` on one with a witness)."""
    import time
    import warnings

    from lmi import KothareProblem

    tol = {"tol_feas": tight, "tol_gap_abs": tight, "tol_gap_rel": tight}
    paths = (("ipm", {"backend": "ipm"}),
             ("ipm-alone", {"backend": "ipm", "solver_options": {"fallback": False}}),
             ("cvxpy:CLARABEL", {"backend": "cvxpy", "solver": "CLARABEL", "solver_options": tol}))
    out = []
    for prob in problems:
        rec: dict = {"label": prob.label, "kind": prob.kind, "n_states": prob.n_states,
                     "vertices": prob.n_vertices, "input_constraint": prob.input_constraint}
        gammas = {}
        for name, opts in paths:
            start = time.perf_counter()
            with warnings.catch_warnings():  # cvxpy's "may be inaccurate": the status says it
                warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
                sol = KothareProblem(**prob.kothare_kwargs(), **opts).solve(prob.x)
            rec[name] = {"status": sol.status, "solver_status": sol.solver_status,
                         "time_s": time.perf_counter() - start, "iterations": sol.iterations}
            rec[name]["contradiction"] = (sol.status == "optimal" and prob.kind == "infeasible") or (
                sol.status == "infeasible" and prob.kind == "feasible")
            gammas[name] = sol.gamma if sol.ok else float("nan")
        ref = gammas["cvxpy:CLARABEL"]
        both = np.isfinite(ref * gammas["ipm"])
        rec["rel_diff_gamma_ipm"] = float(abs(gammas["ipm"] / ref - 1.0)) if both else None
        out.append(rec)
    return out


def format_stress(records: Sequence[dict]) -> str:
    """A Markdown table: one row per problem."""
    lines = ["Times: build + one cold solve.", "",
             "| problem | ipm | ipm alone | cvxpy + Clarabel | ipm ms | ipm-alone ms | cvxpy ms "
             "| rel diff gamma |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in records:
        cells = [f"{r[p]['status']}{' (!)' if r[p]['contradiction'] else ''}"
                 for p in ("ipm", "ipm-alone", "cvxpy:CLARABEL")]
        times = [f"{1e3 * r[p]['time_s']:.0f}" for p in ("ipm", "ipm-alone", "cvxpy:CLARABEL")]
        diff = "n/a" if r["rel_diff_gamma_ipm"] is None else f"{r['rel_diff_gamma_ipm']:.1e}"
        lines.append(f"| {r['label']} | {' | '.join(cells)} | {' | '.join(times)} | {diff} |")
    lines.append("")
    lines.append("(!) contradicts what is known by construction.")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m dev.stress [--sizes 6 10 14] [--vertices 2 8] [--seeds 0 1 2] [--out FILE]``."""
    import argparse
    import os

    parser = argparse.ArgumentParser(description="the seeded stress set: IPM against cvxpy + Clarabel")
    parser.add_argument("--sizes", nargs="+", type=int, default=[6, 10, 14])
    parser.add_argument("--vertices", nargs="+", type=int, default=[2, 8])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--out", help="write the records as JSON to this file")
    args = parser.parse_args(argv)
    records = run_stress(list(stress_set(args.sizes, args.vertices, args.seeds)))
    print(format_stress(records))
    print(f"load average {os.getloadavg()}")
    if args.out:
        write_json(args.out, records)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
