"""The generic stress set: seeded random Kothare problems of 8-30 states, open-loop unstable.

The plants are those of a generic robust MPC problem, not built around a known answer: a
continuous-time ``A_c`` with standard normal entries over ``sqrt(n)`` (about half of its
eigenvalues in the right half-plane) and ``B_c`` standard normal with ``m = 3`` inputs, held
(zero-order hold) at ``dt = 0.1`` s, ``Q1 = I``, ``R = I``. The polytope has ``n_vertices``
vertices: ``(A, 0.8 B)`` and ``(A, 1.2 B)`` (an uncertain input gain), and for more than two,
``(A + 0.001 E_j / sqrt(n), B diag(g_j))`` with ``E_j`` standard normal and ``g_j`` uniform in
``[0.8, 1.2]`` per input (about 1 % of ``A_c``; at 0.01, as in :mod:`dev.stress`, no
quadratic Lyapunov function held the 8 vertices of most plants of 16 states and more, with or
without a bound: every such problem was infeasible). The input bound is none, a peak bound (1 per
input) or an ellipsoid (1). Each plant gives up to three problems (``kind``):

``"generic"``
    The state is a random unit vector (the problems as a user would pose them). Whether the
    LMIs have a solution is not decided by the construction; where the witness below exists and
    satisfies the bound at that state the problem is marked ``"feasible"`` instead.
``"feasible"``
    (Bounded problems.) The witness of :func:`dev.stress.lqr_contraction` (the LQR gain of
    the vertex-mean model, with its Riccati matrix scaled until every vertex's closed loop
    contracts it) at the generic problem's state shortened until the witness needs 0.9 of the
    bound: feasible by construction, with the bound close to active.
``"infeasible"``
    (Bounded problems.) Vertex 0, ``(A, 0.8 B)``, has an eigenvalue ``lam`` with ``|lam| > 1``
    (the largest) and left eigenvector ``w`` (``w^T A = lam w^T``, complex in general); the
    generic state lengthened until ``|w^T x| (|lam| - 1)`` is ``distance`` (2) times ``reach``, an
    upper bound on ``|w^T B_0 u|`` over the admissible inputs (``sum_j |(w^T B_0)_j| u_j`` for the
    peak bound, ``||w^T B_0|| u`` for the ellipsoid). On the constant plant ``(A, 0.8 B)``
    ``|w^T x(k+1)| >= |lam| |w^T x(k)| - reach``, so ``|w^T x(k)|`` grows along every admissible
    input sequence and the Kothare LMIs have no solution (as in :mod:`dev.stress`).

:func:`run_generic` (``python -m dev.generic_stress``) solves each problem with the IPM
back-end, its Clarabel fallback off (status, gamma, iterations, time, the worst recomputed LMI
margin of :func:`lmi.certify` or the radius of the checked infeasibility certificate), and with
cvxpy + Clarabel on the textbook LMIs (Kothare's eq. (14) as printed, ``formulation="standard"``;
every back-end solves at the state scaled to unit norm, :class:`lmi.KothareProblem`), Clarabel at
its default tolerances (1e-8), and prints a Markdown table. Deterministic in its seed; imports
only numpy and scipy (and :mod:`lmi` when run).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np
from scipy.linalg import expm

from benchmarks.core.jsonable import write_json
from dev.stress import SAMPLE_TIME, StressProblem, lqr_contraction, lqr_witness, witness_bound
from toolkit_common.errors import InvalidArgumentError

__all__ = ["GENERIC_BOUNDS", "GENERIC_KINDS", "GENERIC_SIZES", "REFERENCES", "format_generic",
           "generic_problem", "generic_set", "merge_records", "run_generic"]

#: The sizes of the set (states).
GENERIC_SIZES = (8, 12, 16, 20, 24, 30)
#: The input bounds: none, a peak bound of 1 per input, an ellipsoid ``||u|| <= 1``.
GENERIC_BOUNDS = (None, "peak", "ellipsoid")
#: The kinds of problem one plant gives (see the module docstring).
GENERIC_KINDS = ("generic", "feasible", "infeasible")
#: Inputs, the uncertain input gain and the size of the other vertices' perturbation of ``A``.
INPUTS = 3
GAIN_SPREAD = 0.2
A_SPREAD = 0.001
#: How much of the bound the witness of a ``"feasible"`` problem needs, and how far beyond the slab
#: the state of an ``"infeasible"`` one is placed.
WITNESS_SHARE = 0.9
DISTANCE = 2.0


def generic_plant(n: int, n_vertices: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, x0)``: the vertices ``(N, n, n)``, ``(N, n, 3)`` and the unit state of a plant.

    Drawn from ``numpy.random.default_rng(seed)`` in the order ``A_c``, ``B_c``, ``x0``, then the
    vertices beyond two, so that the 2-vertex problems at the unit state are those the IPM was
    first measured on (with seed 0, 16 states and the peak bound it ended "insufficient_progress"
    after 55 iterations, phase one "feasible", and its Clarabel fallback "AlmostSolved")."""
    rng = np.random.default_rng(seed)
    ac = rng.normal(size=(n, n)) / np.sqrt(n)
    bc = rng.normal(size=(n, INPUTS))
    big = np.zeros((n + INPUTS, n + INPUTS))
    big[:n, :n] = ac
    big[:n, n:] = bc
    held = expm(SAMPLE_TIME * big)
    a, b = held[:n, :n], held[:n, n:]
    x0 = rng.normal(size=n)
    x0 /= np.linalg.norm(x0)
    verts_a = [a, a]
    verts_b = [(1.0 - GAIN_SPREAD) * b, (1.0 + GAIN_SPREAD) * b]
    for _ in range(n_vertices - 2):
        verts_a.append(a + A_SPREAD * rng.normal(size=(n, n)) / np.sqrt(n))
        verts_b.append(b * rng.uniform(1.0 - GAIN_SPREAD, 1.0 + GAIN_SPREAD, size=(1, INPUTS)))
    return np.array(verts_a[:n_vertices]), np.array(verts_b[:n_vertices]), x0


def slab_reach(constraint: str, wb: np.ndarray, u_max: float | np.ndarray) -> float:
    """An upper bound on ``|w^T B u|`` over the admissible inputs (``wb = w^T B``)."""
    if constraint == "peak":
        return float(np.sum(np.abs(wb) * np.broadcast_to(u_max, wb.shape)))
    return float(np.linalg.norm(wb)) * float(u_max)


def unstable_mode(a: np.ndarray) -> tuple[complex, np.ndarray]:
    """The eigenvalue of largest modulus of ``a`` and its left eigenvector ``w``: ``w^T a = lam w^T``
    (plain transpose, complex in general)."""
    eig, left = np.linalg.eig(a.T)  # a' w = lam w  <=>  w' a = lam w'
    k = int(np.argmax(np.abs(eig)))
    return complex(eig[k]), left[:, k]


def generic_problem(n: int, n_vertices: int, bound: str | None, seed: int,
                    kind: str = "generic") -> StressProblem:
    """One problem of the set (deterministic in its arguments; see the module docstring).

    ``kind`` ``"generic"`` comes back as ``"feasible"`` when the witness exists at the unit state
    and needs at most the bound; ``"feasible"`` and ``"infeasible"`` need a bound.

    Raises
    ------
    InvalidArgumentError
        For sizes out of range, an unknown bound or kind, a kind that needs a bound without one,
        or a plant without an unstable vertex 0 for ``"infeasible"``; naming the argument.
    """
    if isinstance(n, bool) or not (isinstance(n, int) and n >= 2):
        raise InvalidArgumentError("n", "an integer >= 2", repr(n))
    if isinstance(n_vertices, bool) or not (isinstance(n_vertices, int) and n_vertices >= 2):
        raise InvalidArgumentError("n_vertices", "an integer >= 2", repr(n_vertices))
    if bound not in GENERIC_BOUNDS:
        raise InvalidArgumentError("bound", "None, 'peak' or 'ellipsoid'", repr(bound))
    if kind not in GENERIC_KINDS:
        raise InvalidArgumentError("kind", "'generic', 'feasible' or 'infeasible'", repr(kind))
    if bound is None and kind != "generic":
        raise InvalidArgumentError("kind", "'generic' without an input bound", repr(kind))
    a, b, x0 = generic_plant(n, n_vertices, seed)
    q1, r = np.eye(n), np.eye(INPUTS)
    u_max: float | np.ndarray | None = None if bound is None else (
        np.ones(INPUTS) if bound == "peak" else 1.0)
    found = lqr_contraction(a, b, q1, r)
    witness = None
    x = x0
    label = "generic"
    if kind == "infeasible":
        lam, w = unstable_mode(a[0])
        if not abs(lam) > 1.0:
            raise InvalidArgumentError("kind", "'infeasible' only for a plant with |lam| > 1",
                                       f"|lam| = {abs(lam)}")
        reach = slab_reach(str(bound), w @ b[0], u_max)
        x = x0 * (DISTANCE * reach / ((abs(lam) - 1.0) * abs(complex(w @ x0))))
        label = "infeasible"
    elif found is not None:
        witness = lqr_witness(*found, x0)
        if bound is not None:
            need = np.max(np.asarray(witness_bound(bound, witness[1], witness[2])) / np.asarray(u_max))
            if kind == "feasible":
                x = x0 * (WITNESS_SHARE / need)
                witness = lqr_witness(*found, x)
                label = "feasible"
            elif need > 1.0:
                witness = None
        if witness is not None:
            label = "feasible"
    elif kind == "feasible":
        raise InvalidArgumentError("kind", "'feasible' only for a plant with an LQR witness", "none found")
    for arr in (a, b, q1, r, x):
        arr.setflags(write=False)
    known = label if label != "generic" else "unknown"
    return StressProblem(a, b, q1, r, bound, u_max, x, SAMPLE_TIME, known, seed, witness,
                         tag=f"{kind}-{bound or 'none'}")


def generic_set(sizes: Sequence[int] = GENERIC_SIZES, vertex_counts: Sequence[int] = (2, 8),
                seeds: Sequence[int] = (0, 1)) -> Iterator[StressProblem]:
    """Per size, vertex count and seed: the unbounded generic problem, then the three kinds with a
    peak bound (even seeds) or an ellipsoid (odd seeds); ``"feasible"`` only for a plant with the
    witness (:func:`has_witness`)."""
    for n in sizes:
        for count in vertex_counts:
            for seed in seeds:
                yield generic_problem(n, count, None, seed)
                bound = "peak" if seed % 2 == 0 else "ellipsoid"
                generic = generic_problem(n, count, bound, seed)
                yield generic
                if has_witness(n, count, seed):
                    yield generic_problem(n, count, bound, seed, "feasible")
                yield generic_problem(n, count, bound, seed, "infeasible")


def has_witness(n: int, n_vertices: int, seed: int) -> bool:
    """Whether the plant has the witness of :func:`dev.stress.lqr_contraction`."""
    a, b, _ = generic_plant(n, n_vertices, seed)
    return lqr_contraction(a, b, np.eye(n), np.eye(INPUTS)) is not None


# -- the benchmark ---------------------------------------------------------------------------------
#: The references: cvxpy + Clarabel on Kothare's textbook LMIs (eq. (14), ``"standard"``) and on
#: the toolkit's default form (``"delta_shared"``), each a key of the records.
REFERENCES = {"cvxpy": "standard", "cvxpy_shared": "delta_shared"}


def run_generic(problems: Sequence[StressProblem], references: Sequence[str] = tuple(REFERENCES),
                ipm: bool = True) -> list[dict]:
    """Solve every problem with the IPM alone (fallback off, cold), if ``ipm``, and with cvxpy +
    Clarabel in the forms ``references`` (keys of :data:`REFERENCES`); one record per problem."""
    import time
    import warnings

    from lmi import KothareProblem

    paths = [("ipm", {"backend": "ipm", "solver_options": {"fallback": False}})] if ipm else []
    for name in references:
        paths.append((name, {"backend": "cvxpy", "solver": "CLARABEL", "formulation": REFERENCES[name]}))
    out = []
    for prob in problems:
        rec: dict = {"label": prob.label, "kind": prob.kind, "n_states": prob.n_states,
                     "vertices": prob.n_vertices, "bound": prob.input_constraint,
                     "state_norm": float(np.linalg.norm(prob.x))}
        for name, opts in paths:
            with warnings.catch_warnings():  # cvxpy's "may be inaccurate": the status says it
                warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
                kothare = KothareProblem(**prob.kothare_kwargs(), **opts)
                start = time.perf_counter()
                sol = kothare.solve(prob.x)
                elapsed = time.perf_counter() - start
            rec[name] = {
                "status": sol.status, "solver_status": sol.solver_status, "gamma": float(sol.gamma),
                "iterations": sol.iterations, "time_s": elapsed,
                "worst_margin": None if sol.certificate is None else float(sol.certificate.worst),
                "radius": None if sol.infeasibility is None else float(sol.infeasibility.radius),
                "contradiction": (sol.status == "optimal" and prob.kind == "infeasible") or (
                    sol.status == "infeasible" and prob.kind == "feasible"),
            }
        out.append(rec)
    return out


def merge_records(*runs: Sequence[dict]) -> list[dict]:
    """Records of several runs of the same problems (e.g. the IPM and the references run apart),
    merged by label in the order of the first run, with each reference's relative difference in
    gamma to the IPM's (when the IPM is optimal and the reference optimal or inaccurate)."""
    merged: dict[str, dict] = {}
    for run in runs:
        for rec in run:
            merged.setdefault(rec["label"], {}).update(rec)
    out = []
    for rec in merged.values():
        for name in REFERENCES:
            if "ipm" in rec and name in rec:
                ipm, ref = rec["ipm"], rec[name]
                both = ipm["status"] == "optimal" and ref["status"] in ("optimal", "inaccurate")
                rec[f"rel_diff_gamma_{name}"] = abs(ipm["gamma"] / ref["gamma"] - 1.0) if both else None
        out.append(rec)
    return out


def format_generic(records: Sequence[dict]) -> str:
    """A Markdown table, one row per problem (records of :func:`merge_records`; a missing path
    reads "-")."""
    refs = [name for name in REFERENCES if any(name in r for r in records)]
    head = "| problem | known | IPM status | gamma | iterations | IPM s | margin / radius |"
    rule = "| --- | --- | --- | --- | --- | --- | --- |"
    for name in refs:
        form = "textbook" if REFERENCES[name] == "standard" else REFERENCES[name]
        head += f" {form}: cvxpy + Clarabel | gamma | s | rel diff gamma |"
        rule += " --- | --- | --- | --- |"
    lines = ["IPM: fallback off, one cold solve (s: the solve, not the build). cvxpy + Clarabel at its "
             "default tolerances (1e-8) on the textbook LMIs (Kothare's eq. (14)) and on the toolkit's "
             "default form (delta_shared); s: the first solve, cvxpy's canonicalisation included. Every "
             "back-end solves at the state scaled to unit norm. rel diff gamma: to the IPM's, when the IPM "
             "is optimal and Clarabel optimal or inaccurate.", "", head, rule]
    for r in records:
        cells = [r["label"], r["kind"]]
        if "ipm" in r:
            ipm = r["ipm"]
            proof = ipm["radius"] if ipm["status"] == "infeasible" else ipm["worst_margin"]
            cells += [ipm["status"] + (" (!)" if ipm["contradiction"] else ""), f"{ipm['gamma']:.8g}",
                      str(ipm["iterations"]), f"{ipm['time_s']:.2f}",
                      "n/a" if proof is None else f"{proof:.1e}"]
        else:
            cells += ["-"] * 5
        for name in refs:
            if name not in r:
                cells += ["-"] * 4
                continue
            c = r[name]
            diff = r.get(f"rel_diff_gamma_{name}")
            cells += [c["status"] + (" (!)" if c["contradiction"] else ""), f"{c['gamma']:.8g}",
                      f"{c['time_s']:.2f}", "n/a" if diff is None else f"{diff:.1e}"]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "(!) contradicts what is known by construction. margin: the worst recomputed relative "
              "LMI margin (lmi.certify) of an answer; radius: no solution of norm below it (the "
              "checked Farkas certificate)."]
    return "\n".join(lines)


def _warm_up(references: Sequence[str]) -> None:
    """One untimed solve of each path: the first call of a process loads the IPM's kernels (and,
    after an install, compiles them) and imports cvxpy."""
    run_generic([generic_problem(8, 2, "peak", 0, "infeasible"), generic_problem(8, 2, None, 0)],
                references=references[:1])


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m dev.generic_stress [--sizes ...] [--vertices 2 8] [--seeds 0 1]
    [--references cvxpy cvxpy_shared | --references] [--no-ipm] [--merge FILE ...] [--out FILE]``.

    ``--references`` with no name runs the IPM only; ``--no-ipm`` the references only;
    ``--merge`` prints the table of earlier ``--out`` files (records merged by problem) and
    solves nothing.
    """
    import argparse
    import json
    import os

    parser = argparse.ArgumentParser(description="the generic stress set: IPM against cvxpy + Clarabel")
    parser.add_argument("--sizes", nargs="+", type=int, default=list(GENERIC_SIZES))
    parser.add_argument("--vertices", nargs="+", type=int, default=[2, 8])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1])
    parser.add_argument("--references", nargs="*", choices=sorted(REFERENCES), default=list(REFERENCES))
    parser.add_argument("--no-ipm", action="store_true", help="the references only")
    parser.add_argument("--merge", nargs="+", metavar="FILE", help="print the table of these record files")
    parser.add_argument("--out", help="write the records as JSON to this file")
    args = parser.parse_args(argv)
    if args.merge:
        runs = []
        for name in args.merge:
            with open(name, encoding="utf-8") as fh:
                runs.append(json.load(fh))
        print(format_generic(merge_records(*runs)))
        return 0
    _warm_up(args.references)
    records: list[dict] = []
    for prob in generic_set(args.sizes, args.vertices, args.seeds):
        records += run_generic([prob], references=args.references, ipm=not args.no_ipm)
        if args.out:  # written as it goes: the large problems take minutes
            write_json(args.out, records)
    print(format_generic(merge_records(records)))
    print(f"load average {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
