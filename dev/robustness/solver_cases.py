"""The LMI solver's edges and its front ends' validation: bad and edge inputs of the solver family.

:func:`solver_probes` tries :class:`lmi.BlockLMISolver` with more variables than its blocks have
entries, degenerate blocks, objectives far beyond the data's scale and data that are not real
numbers; the forms' soft weights from 1e3 to the largest finite float; array-valued options;
complex data in the front ends (:class:`lmi.KothareProblem`, :class:`lmi.forms.FormProblem`,
:class:`rmpc.RMPC`); :func:`lmi.sdpa.read_sdpa` with sizes it must refuse before allocating and
arguments that are not paths; NumPy integers where an integer is expected.

An edge input that may be accepted (``expect="either"``) is checked here, not only run: the call
raises ``AssertionError`` (a ``crash`` verdict) when its answer is not what the status says: an
``"optimal"`` or ``"unbounded"`` ``x`` that violates the LMIs, an ``"infeasible"`` ray that is no
ray, a form called ``"unbounded"``, a slack below zero beyond tolerance in an ``"optimal"`` answer.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from dev.robustness.probe import Probe

#: Relative tolerance of the checks of a claimed answer (the solver's own is 1e-8).
CHECK_TOL = 1e-6


# --- checked solves ---------------------------------------------------------------------------------


def _slacks(x: np.ndarray, blocks: list[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
    return [c_j - np.einsum("i,ikl->kl", x, a_j) for c_j, a_j in blocks]


def _lowest(mat: np.ndarray) -> float:
    """The smallest eigenvalue relative to the largest absolute one (1 for a zero matrix)."""
    lam = np.linalg.eigvalsh(0.5 * (mat + mat.T))
    scale = float(np.max(np.abs(lam)))
    return 1.0 if scale == 0.0 else float(lam[0]) / scale


def checked_solve(c: Any, blocks: list[tuple[Any, Any]], **kwargs: Any) -> dict[str, Any]:
    """Solve with :class:`lmi.BlockLMISolver` and check the claim of the status in numpy.

    ``"optimal"``, ``"inaccurate"`` and ``"unbounded"``: every ``C_j - sum_i x_i A_ij`` positive
    semidefinite to :data:`CHECK_TOL` relative (and, for ``"unbounded"``, ``c'x`` below ``-1e6
    max(1, ||c||)``); ``"infeasible"``: ``Z`` positive semidefinite, ``sum_j <A_ij, Z_j>`` about
    zero and ``sum_j <C_j, Z_j> < 0``. Other words claim nothing and pass.
    """
    from lmi import BlockLMISolver

    res = BlockLMISolver(c, blocks, **kwargs).solve()
    data = [(np.asarray(c_j, dtype=float), np.asarray(a_j, dtype=float)) for c_j, a_j in blocks]
    cvec = np.asarray(c, dtype=float)
    status = str(res.status)
    if status in ("optimal", "inaccurate", "unbounded"):
        worst = min(_lowest(s) for s in _slacks(res.x, data))
        if worst < -CHECK_TOL:
            raise AssertionError(f"{status}: x violates an LMI (relative eigenvalue {worst:.2e})")
    if status == "unbounded" and not float(cvec @ res.x) <= -1e6 * max(1.0, float(np.linalg.norm(cvec))):
        raise AssertionError(f"unbounded with c'x = {float(cvec @ res.x):.3e} only")
    if status == "infeasible":
        z_blocks = res.Z
        if min(_lowest(z) for z in z_blocks) < -CHECK_TOL:
            raise AssertionError("infeasible: the ray is not positive semidefinite")
        a_z = sum(np.einsum("ikl,kl->i", a_j, z) for (_, a_j), z in zip(data, z_blocks, strict=True))
        c_z = sum(float(np.sum(c_j * z)) for (c_j, _), z in zip(data, z_blocks, strict=True))
        if not c_z < 0.0 or float(np.linalg.norm(a_z)) > CHECK_TOL * abs(c_z):
            norm = float(np.linalg.norm(a_z))
            raise AssertionError(f"infeasible: no ray (<C, Z> = {c_z:.2e}, ||A'Z|| = {norm:.2e})")
    objective = float(cvec @ res.x) if res.x.size else 0.0
    return {"status": status, "objective": objective if np.isfinite(objective) else "overflow"}


def _symmetric(rng: np.random.Generator, *shape: int) -> np.ndarray:
    a = rng.standard_normal(shape)
    return a + np.swapaxes(a, -1, -2)


def _more_variables(seed: int, n: int, order: int, objective_in_range: bool) -> dict[str, Any]:
    """``n`` variables on one ``order x order`` block and a ``1 x 1`` block (``n`` above their
    ``order (order + 1) / 2 + 1`` entries), random data."""
    rng = np.random.default_rng(seed)
    coef = _symmetric(rng, n, order, order)
    if objective_in_range:  # c orthogonal to the directions that move no block
        iu = np.triu_indices(order)
        c = coef[:, iu[0], iu[1]] @ rng.standard_normal(iu[0].size)
    else:
        c = rng.standard_normal(n)
    blocks = [(2.0 * np.eye(order), coef), (np.array([[3.0]]), rng.standard_normal((n, 1, 1)))]
    out = checked_solve(c, blocks)
    from lmi import BlockLMISolver

    one = BlockLMISolver(c, blocks).phase_one()
    if one.status == "feasible" and min(_lowest(s) for s in _slacks(one.x, blocks)) <= 0.0:
        raise AssertionError("phase one: its 'feasible' point is not strictly feasible")
    out["phase_one"] = one.status
    return out


def _lambda_max(scale: float) -> dict[str, Any]:
    """``min scale t`` s.t. ``t I - M >= 0``: ``t = 3`` at any positive scale."""
    m = np.array([[2.0, 1.0], [1.0, 2.0]])
    out = checked_solve([scale], [(-m, -np.eye(2)[None])])
    if out["status"] != "optimal":
        raise AssertionError(f"the largest eigenvalue at objective scale {scale:g}: {out['status']}")
    return out


def _degenerate(kind: str) -> dict[str, Any]:
    eye = np.eye(2)
    cases: dict[str, tuple[Any, list[tuple[Any, Any]]]] = {
        "zero coefficients": ([1.0, 1.0], [(eye, np.stack([np.zeros((2, 2)), -eye]))]),
        "all coefficients zero": ([1.0], [(eye, np.zeros((1, 2, 2)))]),
        "1x1 blocks": ([1.0, -1.0], [(np.ones((1, 1)), -np.ones((2, 1, 1))),
                                     (np.ones((1, 1)), np.ones((2, 1, 1)))]),
        "zero objective": ([0.0, 0.0], [(eye, _symmetric(np.random.default_rng(3), 2, 2, 2))]),
        "zero constant": ([1.0], [(np.zeros((2, 2)), -eye[None])]),
    }
    c, blocks = cases[kind]
    return checked_solve(c, blocks)


# --- the forms ------------------------------------------------------------------------------------


def _plant() -> Any:
    from models import PolytopicModel

    a1 = np.array([[1.0, 0.1], [0.0, 1.0]])
    a2 = np.array([[1.0, 0.1], [0.0, 0.95]])
    b = np.array([[0.005], [0.1]])
    return PolytopicModel(vertices=[(a1, b), (a2, b)], dt=0.1)


def _rmpc(**kw: Any) -> Any:
    from rmpc import RMPC

    args: dict[str, Any] = {"plant": _plant(), "Q": np.eye(2), "R": np.eye(1), "u_max": 1.0}
    args.update(kw)
    return RMPC(**args)


def _soft_solve(weight: float, backend: str = "ipm", lyapunov: str = "common") -> dict[str, Any]:
    """A softened solve at a state where the hard input bound does not hold: never ``"unbounded"``
    (the objective is >= 0), never a negative slack beyond tolerance in an ``"optimal"`` answer."""
    ctrl = _rmpc(soft={"u": weight}, backend=backend, lyapunov=lyapunov)
    sol = ctrl.solve(np.array([30.0, 0.0]))
    status = str(sol.status)
    if status == "unbounded":
        raise AssertionError(f"soft weight {weight:g}: 'unbounded', but the objective is >= 0")
    slack = float((sol.slack or {}).get("u", 0.0))
    if status == "optimal" and slack < -CHECK_TOL * max(1.0, abs(slack)):
        raise AssertionError(f"soft weight {weight:g}: optimal with the slack {slack:.3e}")
    return {"status": status, "gamma": sol.gamma, "slack": slack}


def _kothare(**kw: Any) -> Any:
    from lmi import KothareProblem

    a = np.array([[[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.1], [0.0, 0.95]]])
    b = np.array([[[0.005], [0.1]]] * 2)
    args: dict[str, Any] = {"A": a, "B": b, "Q": np.eye(2), "R": np.eye(1), "u_max": 1.0}
    args.update(kw)
    return KothareProblem(**args)


def _form(**kw: Any) -> Any:
    from lmi.forms import FormProblem

    a = np.array([[[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.1], [0.0, 0.95]]])
    b = np.array([[[0.005], [0.1]]] * 2)
    args: dict[str, Any] = {"A": a, "B": b, "Q": np.eye(2), "R": np.eye(1), "u_max": 1.0,
                            "lyapunov": "vertex"}
    args.update(kw)
    return FormProblem(**args)


def _kothare_solve(**kw: Any) -> dict[str, Any]:
    sol = _kothare(**kw).solve(np.array([1.0, 0.0]))
    return {"status": str(sol.status), "gamma": sol.gamma}


# --- SDPA files -----------------------------------------------------------------------------------


def _sdpa_text(text: str, **kw: Any) -> Any:
    import os
    import tempfile

    from lmi.sdpa import read_sdpa

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "probe.dat-s")
        with open(path, "w") as handle:
            handle.write(text)
        return read_sdpa(path, **kw)


def _sdpa_gzip_bomb() -> Any:
    """A compressed file of a few kB that expands to 64 MB (above ``max_bytes`` = 1 MB)."""
    import gzip
    import os
    import tempfile

    from lmi.sdpa import read_sdpa

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bomb.dat-s.gz")
        with open(path, "wb") as handle:
            handle.write(gzip.compress(b'"' + b" " * (64 * 2**20)))
        return read_sdpa(path, max_bytes=2**20)


def _read_sdpa(path: Any) -> Any:
    from lmi.sdpa import read_sdpa

    return read_sdpa(path)


# --- the catalogue --------------------------------------------------------------------------------


def _probe(pid: str, names: tuple[str, ...], call: Callable[[], Any], kind: str, *,
           found: tuple[str, ...] = (), expect: str = "error") -> Probe:
    return Probe(pid, "api", names, found=found, call=call, expect=expect, kind=kind)  # type: ignore[arg-type]


def _solver(c: Any, blocks: Any, **kw: Any) -> Any:
    from lmi import BlockLMISolver

    return BlockLMISolver(c, blocks, **kw)


def solver_probes() -> list[Probe]:
    """Every probe of the solver family (group ``"api"``)."""
    eye = np.eye(2)
    coef = -eye[None]
    probes: list[Probe] = []
    for seed in range(3):
        for n, order in ((5, 2), (8, 3)):
            for in_range in (False, True):
                tag = "c in range" if in_range else "random c"
                probes.append(_probe(
                    f"BlockLMISolver.blocks:{n} variables, {order}x{order} block, {tag}, seed {seed}",
                    ("blocks",), lambda s=seed, n=n, o=order, r=in_range: _more_variables(s, n, o, r),
                    "more variables", expect="either"))
    kinds = ("zero coefficients", "all coefficients zero", "1x1 blocks", "zero objective", "zero constant")
    for kind in kinds:
        probes.append(_probe(f"BlockLMISolver.blocks:{kind}", ("blocks",), lambda k=kind: _degenerate(k),
                             "degenerate", expect="either"))
    for scale in (1e20, 1e60, 1e200, float(np.finfo(float).max)):
        probes.append(_probe(f"BlockLMISolver.c:{scale:.3g}", ("c",), lambda s=scale: _lambda_max(s),
                             "huge objective", expect="either"))
    bad_data: dict[str, tuple[tuple[str, ...], tuple[str, ...], Callable[[], Any]]] = {
        "c:empty": (("c",), ("empty",), lambda: _solver([], [(eye, np.zeros((1, 2, 2)))])),
        "c:complex": (("c",), ("complex",), lambda: _solver([1.0 + 1.0j], [(eye, coef)])),
        "blocks C:complex": (("blocks[0] C",), ("complex",),
                             lambda: _solver([1.0], [(eye * (1 + 1j), coef)])),
        "blocks A:complex": (("blocks[0] A",), ("complex",), lambda: _solver([1.0], [(eye, coef * 1j)])),
        "blocks C:nan": (("blocks[0] C",), ("nan",), lambda: _solver([1.0], [(eye * np.nan, coef)])),
        "blocks A:inf": (("blocks[0] A",), ("inf",), lambda: _solver([1.0], [(eye, coef * np.inf)])),
        "blocks C:string": (("blocks[0] C",), ("str",), lambda: _solver([1.0], [("eye", coef)])),
        "blocks:int": (("blocks",), ("int",), lambda: _solver([1.0], 5)),
        "blocks:string": (("blocks",), ("str",), lambda: _solver([1.0], "blocks")),
        "blocks:not pairs": (("blocks[0]",), ("ndarray",), lambda: _solver([1.0], [eye])),
        "blocks:triples": (("blocks[0]",), ("3 items",), lambda: _solver([1.0], [(eye, coef, coef)])),
        "blocks:empty": (("blocks",), ("none",), lambda: _solver([1.0], [])),
        "max_iter:float": (("max_iter",), (), lambda: _solver([1.0], [(eye, coef)], max_iter=10.5)),
    }
    for pid, (names, found, call) in bad_data.items():
        probes.append(_probe(f"BlockLMISolver.{pid}", names, call, pid.split(":")[1], found=found))
    probes.append(_probe("BlockLMISolver.max_iter:np.int64(10)", ("max_iter",),
                         lambda: checked_solve([1.0], [(eye, coef)], max_iter=np.int64(10)),
                         "numpy integer", expect="either"))
    # the forms' soft weights: refused above the documented limit, a true status below it
    big = float(np.finfo(float).max)
    for weight in (1e9, 1e13, 1e15, 1e100, 1e200, big):
        probes.append(_probe(f"RMPC.soft:{weight:.3g}", ("soft",), lambda w=weight: _rmpc(soft={"u": w}),
                             "huge weight", found=("e+",)))
    for weight in (1e3, 1e6, 1e8):
        for backend in ("ipm", "clarabel"):
            probes.append(_probe(f"RMPC.soft:{weight:.3g} ({backend})", ("soft",),
                                 lambda w=weight, b=backend: _soft_solve(w, b), "soft weight",
                                 expect="either"))
    probes.append(_probe("RMPC.soft:1e8 (vertex)", ("soft",), lambda: _soft_solve(1e8, lyapunov="vertex"),
                         "soft weight", expect="either"))
    # array-valued and other-typed options
    options: dict[str, Any] = {
        "free_moves:array": np.array([1, 0]), "free_moves:float": 1.0, "free_moves:string": "1",
        "free_moves:two": 2, "free_moves:bool": True, "lyapunov:array": np.array(["common"]),
        "cost:array": np.array(["nominal"]), "saturation:array": np.array(["auxiliary"]),
        "soft:array weight": {"u": np.array([1e3, 1e3])}, "soft:list": [("u", 1e3)],
    }
    for pid, value in options.items():
        option = pid.split(":")[0]
        probes.append(_probe(f"RMPC.{pid}", (option,), lambda o=option, v=value: _rmpc(**{o: v}),
                             pid.split(":")[1]))
    probes.append(_probe("RMPC.free_moves:np.int64(1)", ("free_moves",),
                         lambda: _rmpc(free_moves=np.int64(1)).solve(np.array([1.0, 0.0])).gamma,
                         "numpy integer", expect="either"))
    # complex data in the front ends
    a_c = np.array([[[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.1], [0.0, 0.95]]]) * (1 + 1j)
    complex_inputs: dict[str, tuple[tuple[str, ...], Callable[[], Any]]] = {
        "KothareProblem.A:complex": (("A",), lambda: _kothare(A=a_c)),
        "KothareProblem.B:complex": (("B",), lambda: _kothare(B=np.array([[[0.005], [0.1j]]] * 2))),
        "KothareProblem.output_matrix:complex": (("output_matrix",), lambda: _kothare(
            output_matrix=np.array([[1.0j, 0.0]]), y_max=1.0)),
        "FormProblem.A:complex": (("A",), lambda: _form(A=a_c)),
        "FormProblem.disturbance E:complex": (("disturbance E",), lambda: _form(
            disturbance=(np.array([[0.1j], [0.0]]), 0.01))),
        "FormProblem.nominal:complex": (("nominal A",), lambda: _form(
            cost="nominal", lyapunov="common", nominal=(a_c[0], np.array([[0.005], [0.1]])))),
        "RMPC.disturbance E:complex": (("disturbance E",), lambda: _rmpc(
            disturbance=(np.array([[0.1j], [0.0]]), 0.01))),
    }
    for pid, (names, call) in complex_inputs.items():
        probes.append(_probe(pid, names, call, "complex", found=("complex",)))
    probes.append(_probe("KothareProblem.solver_options:max_iter np.int64(50)", ("solver_options",),
                         lambda: _kothare_solve(solver_options={"max_iter": np.int64(50)}), "numpy integer",
                         expect="either"))
    probes.append(_probe("KothareProblem.solver_options:tol_feas np.float32", ("solver_options",),
                         lambda: _kothare_solve(solver_options={"tol_feas": np.float32(1e-8)}), "numpy float",
                         expect="either"))
    # SDPA files: sizes refused before anything is allocated, arguments that are not paths
    sdpa_sizes = {
        "30000x30000 block": "1\n1\n30000\n1.0\n",
        "10^12 variables": "1000000000000\n1\n2\n1.0\n",
        "10^6 blocks of 1000": "1\n1000000\n" + " ".join(["1000"] * 1000000) + "\n1.0\n",
    }
    for label, text in sdpa_sizes.items():
        probes.append(_probe(f"read_sdpa.path:{label}", ("probe.dat-s", "max_bytes"),
                             lambda t=text: _sdpa_text(t), "size", found=("bytes",)))
    probes.append(_probe("read_sdpa.path:gzip expanding past max_bytes", ("bomb.dat-s.gz", "max_bytes"),
                         _sdpa_gzip_bomb, "size"))
    not_paths = {"int": 5, "None": None, "bytes": b"x.dat-s", "list": ["x.dat-s"], "float": 1.5}
    for label, value in not_paths.items():
        probes.append(_probe(f"read_sdpa.path:{label}", ("path",), lambda v=value: _read_sdpa(v), label,
                             found=(type(value).__name__.lower(),)))
    probes.append(_probe("read_sdpa.max_bytes:string", ("max_bytes",),
                         lambda: _sdpa_text("1\n1\n2\n1.0\n", max_bytes="1GB"), "string"))
    return probes
