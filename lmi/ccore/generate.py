"""Write the problem header of the C core for one Kothare problem (:mod:`lmi.ccore`).

:func:`problem_header` turns the data the Python path solves (the blocks ``C_j``, ``A_ij`` of
:class:`lmi.backends.ipm.IPMKothare` in its state coordinates, the bound-scaled entries, the
solver's settings, and the original :class:`lmi.KothareData` for the certificate) into
``rmpc_problem.h``: sizes as macros (``RMPC_NX``, ``RMPC_NU``, ``RMPC_NV``, the block orders...)
and the data as ``static const`` arrays of exact C99 hexadecimal literals (``float.hex``: every
double round-trips bit for bit). ``ipm.c`` includes it, so one source serves every size.
:func:`write_solver` writes that header next to copies of the C sources.

The coefficient entries are the non-zero upper-triangle entries of each block, ordered by block,
then packed position (row by row, as ``numpy.triu_indices``), then variable: the order in which
:func:`lmi.ipm.kernels.scaling_and_schur_rows` accumulates each row of ``P'``.
"""

from __future__ import annotations

import ctypes
import math
import re
import shutil
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from toolkit_common.errors import InvalidArgumentError

__all__ = [
    "CORE_DOUBLE_TABLES", "CORE_INT_TABLES", "LIMITS", "SOURCES", "STATUS_CODES", "CoreTables", "c_double",
    "check_controller", "core_tables", "problem_header", "solver_source", "write_solver",
]

#: The C sources the header goes with (package data of :mod:`lmi.ccore`).
SOURCES = ("ipm.c", "ipm.h", "dense.c", "dense.h")

#: The status codes of ``kothare_solve`` (``ipm.h`` defines them as ``KOTHARE_STATUS_*``; an
#: exported controller maps them to its own ``RMPC_STATUS_*`` codes).
STATUS_CODES: dict[str, int] = {
    "optimal": 0,
    "infeasible": 1,
    "max_iterations": 2,
    "numerical_error": 3,
    "certificate_failed": 4,
    "nonfinite_x": 5,
    "inaccurate": 6,
    "zero_state": 7,
    "held": 8,
}

#: Sizes the C core accepts: variables, block order, blocks (the workspace grows as
#: ``variables x packed size``; the certificate's vertex LMI has order ``2 n + p + m``).
LIMITS = {"variables": 600, "order": 64, "blocks": 64}


def c_double(value: float, *, infinite: bool = False, name: str = "value") -> str:
    """``value`` as a C99 hexadecimal floating constant, exact bit for bit (``float.hex``).

    With ``infinite``, an infinity is written ``HUGE_VAL`` (``<math.h>``); otherwise it is an
    error, as NaN always is (naming ``name``). The one writer of numbers into generated C: the
    problem header here and the exports of :mod:`rmpc.export`.

    Examples
    --------
    >>> c_double(0.1), c_double(-2.0), c_double(0.0)
    ('0x1.999999999999ap-4', '-0x1.0000000000000p+1', '0x0.0p+0')
    >>> float.fromhex(c_double(0.1)) == 0.1, c_double(float("inf"), infinite=True)
    (True, 'HUGE_VAL')
    """
    number = float(value)
    if math.isnan(number) or (math.isinf(number) and not infinite):
        expected = "a number that is not NaN" if infinite else "a finite number to write as a C constant"
        raise InvalidArgumentError(name, expected, repr(number))
    if math.isinf(number):
        return "HUGE_VAL" if number > 0 else "(-HUGE_VAL)"
    return number.hex()


def _lit(value: float) -> str:
    return c_double(value, infinite=True, name="problem data")


def _doubles(name: str, values: Any) -> str:
    flat = np.asarray(values, dtype=float).ravel()
    if flat.size == 0:
        flat = np.zeros(1)
    body = ",\n    ".join(", ".join(_lit(v) for v in flat[i:i + 4]) for i in range(0, flat.size, 4))
    return f"static const double {name}[{flat.size}] = {{\n    {body}\n}};\n"


def _ints(name: str, values: Any) -> str:
    flat = np.asarray(values, dtype=np.int64).ravel()
    if flat.size == 0:
        flat = np.zeros(1, dtype=np.int64)
    body = ",\n    ".join(", ".join(str(int(v)) for v in flat[i:i + 16]) for i in range(0, flat.size, 16))
    return f"static const int {name}[{flat.size}] = {{\n    {body}\n}};\n"


def _is_ipm_backend(obj: Any) -> bool:
    """Whether ``obj`` holds what an :class:`~lmi.backends.ipm.IPMKothare` holds for the C core."""
    held = ("_base_blocks", "_scaled_blocks", "conic", "_solver", "original_data", "nesting")
    return all(hasattr(obj, name) for name in held)


def _backend(problem: Any) -> Any:
    """The :class:`~lmi.backends.ipm.IPMKothare` of ``problem`` (a :class:`lmi.KothareProblem`,
    an :class:`rmpc.RMPC` of Kothare's form, or the back-end itself), checked. Recognised by what
    it holds (:func:`_is_ipm_backend`), not imported: the back-end imports this module."""
    backend = problem
    for attr in ("problem", "_backend"):
        if not _is_ipm_backend(backend) and hasattr(backend, attr):
            backend = getattr(backend, attr)
    if not _is_ipm_backend(backend):
        raise InvalidArgumentError(
            "problem", "a KothareProblem with backend='ipm' (or an RMPC of Kothare's form, or IPMKothare)",
            type(problem).__name__ if backend is problem else type(backend).__name__)
    if backend.nesting:
        raise InvalidArgumentError("problem", "the on-line problem (no nesting block)", "nesting=True")
    if backend._t.ndim != 1:
        raise InvalidArgumentError("problem", "diagonal state coordinates (no rebalanced retry yet)",
                                   "a rebalanced (full) coordinate change")
    return backend


#: The integer and real tables of the interior-point method (``runtime.h``'s ``kothare_problem_t``
#: fields and the export's ``rmpc_*`` arrays of the same names; ``cnst`` is ``rmpc_const``).
CORE_INT_TABLES = ("order", "offset", "copies", "ent_off", "ent_var", "ent_pos", "ent_t", "ent_bound",
                   "pos_off", "pos_row", "pos_col")
CORE_DOUBLE_TABLES = ("cnst", "ent_val", "c")


@dataclass(frozen=True)
class CoreTables:
    """What the C core's interior-point method reads of one problem (:func:`core_tables`).

    Attributes
    ----------
    sizes : dict
        ``nv, nb, kmax, size, nent, basis, nbound, degree, max_iter, warm_max_iter``.
    reals : dict
        ``tol_feas, tol_gap_abs, tol_gap_rel, warm_gap, warm_feas, inf_radius, qr_switch``.
    tables : dict
        :data:`CORE_INT_TABLES` (int arrays) and :data:`CORE_DOUBLE_TABLES` (float arrays).
    n_ub, n_yb : int
        Input and output bounds (the bound vector is ``[u_max, y_max]``).
    """

    sizes: dict[str, int]
    reals: dict[str, float]
    tables: dict[str, np.ndarray]
    n_ub: int
    n_yb: int


def core_tables(backend: Any) -> CoreTables:
    """The C core's data of an :class:`~lmi.backends.ipm.IPMKothare` in its current coordinates.

    The coefficient entries are the non-zero upper-triangle entries of each block, ordered by
    block, then packed position (row by row), then variable; an entry's bound index (``-1``: none)
    picks the bound that divides it at each solve, as ``IPMKothare._update_blocks`` scales it.
    One computation for the export's header (:func:`problem_header`) and the run-time core
    (:mod:`lmi.ccore.runtime`).
    """
    data = backend.data
    solver = backend._solver
    blocks = backend._base_blocks
    orders = [c.shape[0] for c, _ in blocks]
    n_ub = int(data.u_max.size)
    n_yb = int(data.y_max.size)
    # bound index of every entry: -1 none, else into [u bounds, y bounds]
    bound_of: dict[int, np.ndarray] = {}
    for j, parts in backend._scaled_blocks:
        idx = np.full((orders[j], orders[j]), -1, dtype=np.int64)
        for mask, b_idx, kind in parts:
            if kind == "u":
                idx[mask] = 0 if n_ub == 1 else int(b_idx)
            else:
                idx[mask] = n_ub + (0 if n_yb == 1 else int(b_idx))
        bound_of[j] = idx
    offsets = [0]
    const_vals: list[float] = []
    ent_off, ent_var, ent_pos, ent_val, ent_bound = [0], [], [], [], []
    pos_off, pos_row, pos_col = [0], [], []
    for j, (const, coef) in enumerate(blocks):
        k = orders[j]
        iu0, iu1 = np.triu_indices(k)
        offsets.append(offsets[-1] + iu0.size)
        const_vals.extend(const[iu0, iu1].tolist())
        for a, b in zip(iu0, iu1, strict=True):
            nz = np.flatnonzero(coef[:, a, b] != 0.0)
            if nz.size:
                pos_row.append(int(a))
                pos_col.append(int(b))
            for i in nz:
                ent_var.append(int(i))
                ent_pos.append(len(pos_row) - 1)
                ent_val.append(float(coef[i, a, b]))
                ent_bound.append(int(bound_of[j][a, b]) if j in bound_of else -1)
        ent_off.append(len(ent_var))
        pos_off.append(len(pos_row))
    ent_t = []  # the packed row of each entry
    for j in range(len(blocks)):
        for e in range(ent_off[j], ent_off[j + 1]):
            a, b = pos_row[ent_pos[e]], pos_col[ent_pos[e]]
            k = orders[j]
            ent_t.append(offsets[j] + a * k - (a * (a - 1)) // 2 + (b - a))
    max_pos_size = max((pos_off[j + 1] - pos_off[j]) * (offsets[j + 1] - offsets[j])
                       for j in range(len(blocks)))
    opts = backend._solver_options
    sizes = {
        "nv": int(solver.n), "nb": len(blocks), "kmax": max(orders), "size": offsets[-1],
        "nent": len(ent_var), "basis": max_pos_size, "nbound": max(1, n_ub + n_yb),
        "degree": int(sum(orders)), "max_iter": int(opts["max_iter"]),
        "warm_max_iter": int(opts["warm_max_iter"]),
    }
    reals = {
        "tol_feas": solver.tol_feas, "tol_gap_abs": solver.tol_gap_abs, "tol_gap_rel": solver.tol_gap_rel,
        "warm_gap": solver.warm_gap, "warm_feas": solver.warm_feas,
        "inf_radius": solver.infeasibility_radius, "qr_switch": solver.qr_switch(),
    }
    ints = {"order": orders, "offset": offsets, "copies": solver._copies(), "ent_off": ent_off,
            "ent_var": ent_var, "ent_pos": ent_pos, "ent_t": ent_t, "ent_bound": ent_bound,
            "pos_off": pos_off, "pos_row": pos_row, "pos_col": pos_col}
    tables = {name: np.asarray(values, dtype=np.int64) for name, values in ints.items()}
    tables["cnst"] = np.asarray(const_vals, dtype=float)
    tables["ent_val"] = np.asarray(ent_val, dtype=float)
    tables["c"] = np.asarray(backend.conic.objective, dtype=float)
    return CoreTables(sizes, {k: float(v) for k, v in reals.items()}, tables, n_ub, n_yb)


def problem_header(problem: Any) -> str:
    """The text of ``rmpc_problem.h`` for ``problem``.

    Parameters
    ----------
    problem : KothareProblem, RMPC or IPMKothare
        A Kothare problem solved by the ``"ipm"`` back-end (with an :class:`rmpc.RMPC` of
        Kothare's form, its problem; the state is the deviation ``x - x_ref``, here ``x``).

    Returns
    -------
    str

    Raises
    ------
    InvalidArgumentError
        Naming ``problem``: another back-end or form, the nesting block of the off-line design,
        a rebalanced coordinate change, or sizes beyond :data:`LIMITS`.
    """
    backend = _backend(problem)
    cert_tol = float(getattr(getattr(problem, "problem", problem), "certificate_tol", 1e-7))
    data = backend.original_data
    solver = backend._solver
    conic = backend.conic
    blocks = backend._base_blocks
    n, m, nv = data.n, data.m, solver.n
    orders = [c.shape[0] for c, _ in blocks]
    kmax = max(orders)
    p_rows = data.Q1h.shape[0]
    cert_k = 2 * n + p_rows + m
    for label, value, limit in (("variables", nv, LIMITS["variables"]),
                                ("order", max(kmax, cert_k), LIMITS["order"]),
                                ("blocks", len(blocks), LIMITS["blocks"])):
        if value > limit:
            raise InvalidArgumentError("problem", f"at most {limit} {label} for the C core", f"{value}")
    if orders[0] != n + 1 or np.any(blocks[0][0] != 0.0):
        raise InvalidArgumentError("problem", "the state LMI as its first block", f"order {orders[0]}")
    core = core_tables(backend)
    n_ub, n_yb = core.n_ub, core.n_yb
    tab = core.tables
    offsets, ent_var, pos_row = tab["offset"], tab["ent_var"], tab["pos_row"]

    def affine_map(aff: Any) -> tuple[list[int], list[int], list[float]]:
        coef = aff.coef  # (nv + 1, r, c)
        cells, var, val = [], [], []
        cols = coef.shape[2]
        for i, a, b in zip(*np.nonzero(coef[1:]), strict=True):
            cells.append(int(a) * cols + int(b))
            var.append(int(i))
            val.append(float(coef[1 + i, a, b]))
        if np.any(coef[0] != 0.0):
            raise InvalidArgumentError("problem", "Q and Y linear in the variables", "a constant part")
        return cells, var, val

    q_cells, q_var, q_val = affine_map(conic.q_affine)
    y_cells, y_var, y_val = affine_map(conic.y_affine)
    kind = {None: 0, "ellipsoid": 1, "peak": 2}[data.input_constraint]
    p_out = 0 if data.C_out is None else data.C_out.shape[0]
    t = backend._t
    scaled = bool(np.any(t != 1.0))
    gamma_div = 1.0 if data.formulation == "standard" else float(data.dt)
    if not (np.array_equal(conic.objective[:1], [1.0]) and not np.any(conic.objective[1:])):
        raise InvalidArgumentError("problem", "the objective gamma_s (the first variable)",
                                   "another objective")
    opts = backend._solver_options
    macros = {
        "RMPC_NX": n, "RMPC_NU": m, "RMPC_NV": nv, "RMPC_NB": len(blocks), "RMPC_KMAX": kmax,
        "RMPC_SIZE": int(offsets[-1]), "RMPC_NENT": len(ent_var), "RMPC_NPOS": len(pos_row),
        "RMPC_BASIS": core.sizes["basis"], "RMPC_NUB": n_ub, "RMPC_NYB": n_yb,
        "RMPC_NBOUND": max(1, n_ub + n_yb), "RMPC_NQMAP": len(q_var), "RMPC_NYMAP": len(y_var),
        "RMPC_NVERT": data.n_vertices, "RMPC_P1": p_rows, "RMPC_POUT": p_out, "RMPC_CERT_K": cert_k,
        "RMPC_INPUT_KIND": kind, "RMPC_SCALED": int(scaled), "RMPC_DEGREE": int(sum(orders)),
        "RMPC_MAX_ITER": int(opts["max_iter"]), "RMPC_WARM_MAX_ITER": int(opts["warm_max_iter"]),
        "RMPC_WARM_START": int(backend._warm_start),
    }
    reals = {
        **{f"RMPC_{key.upper()}": value for key, value in core.reals.items()},
        "RMPC_GAMMA_DIV": gamma_div, "RMPC_DT": float(data.dt),
        "RMPC_CERT_TOL": cert_tol,
    }
    out = [
        "/* Generated by lmi.ccore.generate: the data of one Kothare problem for ipm.c. Do not edit. */\n",
        "#ifndef RMPC_PROBLEM_H\n#define RMPC_PROBLEM_H\n\n#include <math.h>\n\n",
    ]
    out += [f"#define {key} {value}\n" for key, value in macros.items()]
    out += [f"#define {key} ({_lit(value)})\n" for key, value in reals.items()]
    out.append("\n")
    for name in CORE_INT_TABLES:
        out.append(_ints(f"rmpc_{name}", tab[name]))
    for name in CORE_DOUBLE_TABLES:
        out.append(_doubles(f"rmpc_{'const' if name == 'cnst' else name}", tab[name]))
    out.append("#if RMPC_SCALED /* used only then: an unused table is a warning in one translation unit */\n"
               + _doubles("rmpc_t", t) + "#endif\n")
    out.append(_doubles("rmpc_bound", np.concatenate([data.u_max, data.y_max]) if n_ub + n_yb else [1.0]))
    out.append(_ints("rmpc_q_cell", q_cells))
    out.append(_ints("rmpc_q_var", q_var))
    out.append(_doubles("rmpc_q_val", q_val))
    out.append(_ints("rmpc_y_cell", y_cells))
    out.append(_ints("rmpc_y_var", y_var))
    out.append(_doubles("rmpc_y_val", y_val))
    # the certificate's data (lmi.certificate.certify), in the original coordinates
    out.append(_doubles("rmpc_cert_a", data.A))
    out.append(_doubles("rmpc_cert_b", data.B))
    out.append(_doubles("rmpc_cert_q1h", data.Q1h))
    out.append(_doubles("rmpc_cert_rh", data.Rh))
    c_out = data.C_out if data.C_out is not None else []
    out.append("#if RMPC_POUT > 0\n" + _doubles("rmpc_cert_cout", c_out) + "#endif\n")
    out.append("\n#endif\n")
    return "".join(out)


def check_controller(controller: Any) -> None:
    """Refuse an :class:`rmpc.RMPC` whose step the C core does not carry.

    The core solves Kothare's problem at ``z = x - x_ref`` and applies ``u = F z``: a
    set-point's input ``u_s``, offset-free action or a kept gain (``resolve_threshold < 1``) are
    not in it; nor is another form or back-end (:func:`problem_header` says which).

    Raises
    ------
    InvalidArgumentError
        Naming ``controller``.
    """
    # duck-typed: lmi does not import rmpc (the dependency runs rmpc -> lmi)
    needed = ("problem", "x_ref", "u_ref", "hold_radius", "resolve_threshold", "offset_free")
    if not all(hasattr(controller, name) for name in needed):
        raise InvalidArgumentError("controller", "an rmpc.RMPC", type(controller).__name__)
    if controller.offset_free or np.any(controller.u_ref != 0.0):
        raise InvalidArgumentError("controller", "no set-point input and no offset-free action",
                                   "a target input u_s" if not controller.offset_free else "offset_free=True")
    if controller.resolve_threshold < 1.0:
        raise InvalidArgumentError("controller", "resolve_threshold = 1 (a solve at every step)",
                                   repr(controller.resolve_threshold))


_LOCAL_INCLUDE = re.compile(r'^#include "(rmpc_problem|dense|ipm)\.h"\n', re.MULTILINE)


def solver_source(problem: Any, omit_macros: tuple[str, ...] = ()) -> tuple[str, int]:
    """The C core for ``problem`` as one text (one translation unit) and its constant data's bytes.

    The problem header (:func:`problem_header`, without the ``#define`` lines of
    ``omit_macros``: an including file defines them), ``dense.h``, ``ipm.h``, ``dense.c`` and
    ``ipm.c`` in that order, their includes of each other removed. The bytes count the
    ``static const`` arrays of the problem header (doubles and ints as this machine sizes them).
    """
    header = problem_header(problem)
    for name in omit_macros:
        header = re.sub(rf"^#define {name} [^\n]*\n", "", header, flags=re.MULTILINE)
    package = resources.files("lmi.ccore")
    parts = [header]
    for name in ("dense.h", "ipm.h", "dense.c", "ipm.c"):
        text = (package / name).read_text(encoding="ascii")
        parts.append(f"/* ---- lmi/ccore/{name} ---- */\n" + _LOCAL_INCLUDE.sub("", text))
    sizes = {"double": ctypes.sizeof(ctypes.c_double), "int": ctypes.sizeof(ctypes.c_int)}
    macros = dict(re.findall(r"^#define (RMPC_SCALED|RMPC_POUT) (\d+)$", header, re.MULTILINE))
    compiled = {"rmpc_t": macros.get("RMPC_SCALED") != "0", "rmpc_cert_cout": macros.get("RMPC_POUT") != "0"}
    arrays = re.findall(r"static const (double|int) (\w+)\[(\d+)\]", header)
    table = sum(sizes[kind] * int(count) for kind, name, count in arrays if compiled.get(name, True))
    return "\n".join(parts), table


def write_solver(problem: Any, out_dir: str | Path) -> list[Path]:
    """Write ``rmpc_problem.h`` for ``problem`` and copies of :data:`SOURCES` into ``out_dir``.

    Compile ``ipm.c`` and ``dense.c`` together (``cc -std=c99 -O2 ipm.c dense.c -lm``); ``ipm.h``
    declares ``kothare_solve`` and the status codes. The controller interface around it
    (``rmpc_init``, ``rmpc_step``...) is :func:`rmpc.export_c`'s, which writes the core and the
    interface as one source.

    Parameters
    ----------
    problem : KothareProblem, RMPC or IPMKothare
        See :func:`problem_header`.
    out_dir : str or Path
        A folder (made if missing).

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    InvalidArgumentError
        Naming ``out_dir`` when it is a file or cannot be written, or ``problem`` (see
        :func:`problem_header`).
    """
    text = problem_header(problem)
    folder = Path(out_dir)
    if folder.exists() and not folder.is_dir():
        raise InvalidArgumentError("out_dir", "a folder", f"the file {folder}")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        written = [folder / "rmpc_problem.h"]
        written[0].write_text(text)
        package = resources.files("lmi.ccore")
        for name in SOURCES:
            with resources.as_file(package / name) as src:
                shutil.copyfile(src, folder / name)
            written.append(folder / name)
    except OSError as err:
        raise InvalidArgumentError("out_dir", "a writable folder", f"{folder}: {err.strerror}") from None
    return written
