"""The pieces every C99 export shares: exact literals, arrays, the interface, the status codes.

A writer (:mod:`rmpc.export.c_gain`, :mod:`rmpc.export.c_offline`) describes its controller as a
:class:`CProgram`: its constant tables (:class:`CArray`), the fields it adds to the one static
workspace, and the body of ``rmpc_compute``, the function that maps a finite state to a command
and a status. This module turns that into ``rmpc_controller.h`` and ``rmpc_controller.c`` with
the common interface::

    #define RMPC_NX ...
    #define RMPC_NU ...
    int    rmpc_init(void);
    int    rmpc_step(const double *x, double *u);
    double rmpc_last_gamma(void);
    int    rmpc_last_iterations(void);

``rmpc_step`` checks its arguments (a null pointer, a NaN or an infinity in ``x``), calls
``rmpc_compute`` on a copy of ``x`` and checks that the command is finite; the status codes are
those of :data:`STATUS_CODES`, listed in the header. Every number is written as a C99
hexadecimal floating constant (:func:`lmi.ccore.generate.c_double`), which the compiler reads
exactly: the tables in C hold the same doubles as the Python controller.

The arithmetic is written one rounding per statement (each product is stored before it is
added) so that a compiler in a standard mode (``-std=c99``, or clang's default
``-ffp-contract=on``) cannot fuse a product and a sum into one ``fma``; only
``-ffast-math`` or ``-ffp-contract=fast`` in a GNU mode would change the results.
"""

from __future__ import annotations

import ctypes
import os
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lmi.ccore.generate import c_double
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = [
    "HEADER_NAME",
    "MAX_NU",
    "MAX_NX",
    "SOURCE_NAME",
    "STATUS_CODES",
    "ZERO_COMMAND_CODES",
    "CArray",
    "CProgram",
    "ExportResult",
    "StatusCode",
    "WorkspaceField",
    "c_double",
    "render_header",
    "render_source",
    "write_program",
]

HEADER_NAME = "rmpc_controller.h"
SOURCE_NAME = "rmpc_controller.c"

#: The largest state and input dimensions an export accepts (the tables and the stack arrays of
#: ``rmpc_step`` are sized at generation time; numpy's pairwise sum, which the off-line lookup
#: reproduces, has one branch up to 128 terms).
MAX_NX = 64
MAX_NU = 64


@dataclass(frozen=True)
class StatusCode:
    """One status code of ``rmpc_step``: its C name and value, the Python word, what ``u`` holds."""

    name: str
    value: int
    word: str
    meaning: str


#: Every code ``rmpc_step`` of any export may return (each header lists them all and says which
#: its controller returns). 0 is the only code whose command is the controller's certified answer.
STATUS_CODES: tuple[StatusCode, ...] = (
    StatusCode("RMPC_OK", 0, "optimal / ok",
               "the controller's answer: the certified gain of the ellipsoid holding x (off-line "
               "robust MPC, Python status \"optimal\"), or the fixed gain (LQR, Python status \"ok\")"),
    StatusCode("RMPC_STATUS_OUTSIDE", 1, "outside",
               "x lies outside the largest ellipsoid; u = F_1 x, the outermost gain, as the Python "
               "step applies it (no guarantee)"),
    StatusCode("RMPC_STATUS_BAD_STATE", 2, "(Python raises InvalidArgumentError)",
               "x holds a NaN or an infinity; u = 0"),
    StatusCode("RMPC_STATUS_OVERFLOW", 3, "(Python returns the non-finite command)",
               "the command computed from a finite x overflowed (an entry is not finite); u = 0"),
    StatusCode("RMPC_STATUS_NULL_ARGUMENT", 4, "(no Python counterpart)",
               "x or u is a null pointer; u = 0 when u is not null"),
    StatusCode("RMPC_STATUS_INFEASIBLE", 5, "infeasible",
               "on-line robust MPC: the LMIs are proved infeasible at x (the solver's Farkas ray); "
               "u = F_last (x - x_ref), the last certified gain (0 before any)"),
    StatusCode("RMPC_STATUS_MAX_ITERATIONS", 6, "max_iterations",
               "on-line robust MPC: the iteration limit was reached; u = F_last (x - x_ref)"),
    StatusCode("RMPC_STATUS_NUMERICAL_ERROR", 7, "numerical_error",
               "on-line robust MPC: the solver broke down or stalled; u = F_last (x - x_ref)"),
    StatusCode("RMPC_STATUS_UNCERTIFIED", 8, "uncertified",
               "on-line robust MPC: the solver converged but an LMI recomputed at its answer fails "
               "the certificate; u = F_last (x - x_ref)"),
    StatusCode("RMPC_STATUS_INACCURATE", 9, "inaccurate",
               "on-line robust MPC: the solver stalled at reduced accuracy; u = F_last (x - x_ref) "
               "(the Python controller applies such an answer when its certificate holds)"),
    StatusCode("RMPC_STATUS_HELD", 10, "reused",
               "on-line robust MPC: x is within the hold radius of x_ref, where the problem "
               "degenerates; no solve, u = F_last (x - x_ref), as the Python step"),
)
#: The codes whose command is zero (no state or command to use); every other code's ``u`` is the
#: controller's answer or the fallback its text names.
ZERO_COMMAND_CODES = ("RMPC_STATUS_BAD_STATE", "RMPC_STATUS_OVERFLOW", "RMPC_STATUS_NULL_ARGUMENT")
_CODE = {code.name: code for code in STATUS_CODES}


@dataclass(frozen=True)
class CArray:
    """A ``static const`` table of the generated source.

    Attributes
    ----------
    name : str
        The C identifier.
    values : ndarray
        The entries, written flat in C (row-major) order.
    ctype : {"double", "unsigned char"}
        The element type.
    comment : str
        One line saying what the table holds.
    """

    name: str
    values: np.ndarray
    ctype: str
    comment: str

    def __post_init__(self) -> None:
        if self.ctype not in ("double", "unsigned char"):
            raise InvalidArgumentError("ctype", "'double' or 'unsigned char'", repr(self.ctype))
        flat = np.ascontiguousarray(self.values).reshape(-1)
        if flat.size == 0:
            raise InvalidArgumentError(self.name, "at least one entry (C has no empty arrays)", "none")
        object.__setattr__(self, "values", flat)

    @property
    def nbytes(self) -> int:
        """The table's size in bytes on this machine."""
        size = ctypes.sizeof(ctypes.c_double if self.ctype == "double" else ctypes.c_ubyte)
        return int(self.values.size) * size

    def render(self, per_line: int = 3) -> str:
        """The C definition."""
        if self.ctype == "double":
            items = [c_double(v) for v in self.values]
        else:
            items = [str(int(bool(v))) for v in self.values]
            per_line = 24
        rows = [", ".join(items[k : k + per_line]) for k in range(0, len(items), per_line)]
        body = ",\n    ".join(rows)
        return (f"/* {self.comment} */\n"
                f"static const {self.ctype} {self.name}[{self.values.size}] = {{\n    {body}\n}};\n")


@dataclass(frozen=True)
class WorkspaceField:
    """A field a writer adds to the static workspace: C type, name, value after ``rmpc_init``."""

    ctype: str
    name: str
    initial: str
    comment: str


@dataclass(frozen=True)
class CProgram:
    """What a writer says about its controller; :func:`render_header` and :func:`render_source`
    turn it into the two files.

    Attributes
    ----------
    controller : str
        The Python class exported (``"OfflineRMPC"``).
    summary : tuple of str
        Lines of the header's opening comment: what the step computes.
    nx, nu : int
        State and input dimensions.
    returns : tuple of str
        The names (:data:`STATUS_CODES`) of the codes this controller's step returns.
    gamma_doc, iterations_doc : str
        What ``rmpc_last_gamma`` and ``rmpc_last_iterations`` return for this controller.
    arrays : tuple of CArray
        The constant tables.
    defines : tuple of (name, value, comment)
        Extra ``#define`` lines of the header.
    fields : tuple of WorkspaceField
        The writer's fields of the workspace (``rmpc_ws``), set to their initial values by
        ``rmpc_init`` and at the start of every step.
    helpers : str
        C definitions (``static`` functions) placed before ``rmpc_compute``.
    compute : str
        The body of ``static int rmpc_compute(const double *x, double *v)``: ``x`` is a finite
        copy of the state, ``v`` the command to fill; it returns a status code and sets
        ``rmpc_ws.gamma`` and ``rmpc_ws.iterations``.
    accessors : tuple of (prototype, comment, body)
        Extra public functions (``"int rmpc_last_index(void)"``).
    init : str
        C statements ``rmpc_init`` runs after resetting the workspace (a solver's own reset).
    helper_table_bytes : int
        The constant data the ``helpers`` hold (a solver's problem data), counted in
        :attr:`ExportResult.table_bytes`; a solver's own work arrays are not (the on-line
        export reports them through ``rmpc_solver_workspace_bytes()``).
    """

    controller: str
    summary: tuple[str, ...]
    nx: int
    nu: int
    returns: tuple[str, ...]
    gamma_doc: str
    iterations_doc: str
    arrays: tuple[CArray, ...]
    compute: str
    defines: tuple[tuple[str, str, str], ...] = ()
    fields: tuple[WorkspaceField, ...] = ()
    helpers: str = ""
    accessors: tuple[tuple[str, str, str], ...] = ()
    init: str = ""
    helper_table_bytes: int = 0

    def __post_init__(self) -> None:
        for name, value, most in (("RMPC_NX", self.nx, MAX_NX), ("RMPC_NU", self.nu, MAX_NU)):
            if not 1 <= value <= most:
                raise InvalidArgumentError(
                    "controller", f"{name} between 1 and {most} (the export's limit)", f"{name} = {value}"
                )
        unknown = [name for name in self.returns if name not in _CODE]
        if unknown:
            raise InvalidArgumentError("returns", "names of STATUS_CODES", repr(unknown))

    @property
    def table_bytes(self) -> int:
        """Bytes of the constant tables."""
        return sum(array.nbytes for array in self.arrays)

    @property
    def workspace_bytes(self) -> int:
        """``sizeof(rmpc_ws)`` on this machine (the C struct laid out as ctypes lays it out)."""
        ctypes_of = {"double": ctypes.c_double, "int": ctypes.c_int}
        members = [(f.name, ctypes_of[f.ctype]) for f in _fields(self)]
        layout = type("Workspace", (ctypes.Structure,), {"_fields_": members})
        return ctypes.sizeof(layout)


def _fields(program: CProgram) -> tuple[WorkspaceField, ...]:
    common = (
        WorkspaceField("double", "gamma", "NAN", "rmpc_last_gamma()"),
        WorkspaceField("int", "status", "RMPC_OK", "the last step's status code"),
        WorkspaceField("int", "iterations", "0", "rmpc_last_iterations()"),
    )
    fields_ = (*common, *program.fields)
    # doubles first: no padding between members on any common ABI
    return tuple(sorted(fields_, key=lambda f: f.ctype != "double"))


def _wrap(text: str, width: int = 92, indent: str = "    ") -> list[str]:
    """``text`` in lines of at most ``width`` characters, the continuation lines indented."""
    return textwrap.wrap(text, width, subsequent_indent=indent, break_on_hyphens=False) or [""]


def _comment_block(lines: Sequence[str]) -> str:
    """A C block comment, each line wrapped to fit 96 columns."""
    out = ["/*"]
    for line in lines:
        lead = line[: len(line) - len(line.lstrip())]
        out += [f" * {part}".rstrip() for part in _wrap(line, indent=lead + "    ")]
    out.append(" */")
    return "\n".join(out)


def render_header(program: CProgram) -> str:
    """The text of ``rmpc_controller.h``."""
    lines = [
        f"{HEADER_NAME}: generated by rmpc.export_c (controller: {program.controller}). Do not edit.",
        "C99, no dynamic allocation, libm only (isfinite, NAN), one static workspace;",
        "not re-entrant (one controller per program; call it from one thread).",
        "",
        *program.summary,
        "",
        "int rmpc_init(void): reset the workspace (the last step's status, gamma and counters);",
        "    returns RMPC_OK. rmpc_step also works before any call of rmpc_init.",
        "int rmpc_step(const double *x, double *u): x holds RMPC_NX states, u receives RMPC_NU",
        "    inputs (x and u may overlap). Returns RMPC_OK (0) when u is the controller's answer,",
        "    or a status code > 0 below, u then holding the fallback the code names.",
        *_wrap(f"double rmpc_last_gamma(void): {program.gamma_doc}"),
        *_wrap(f"int rmpc_last_iterations(void): {program.iterations_doc}"),
        *[line for proto, doc, _ in program.accessors for line in _wrap(f"{proto}: {doc}")],
        "",
        "Status codes (every export defines them all); this controller returns:",
        "    " + ", ".join(program.returns) + ".",
        "",
        "The arithmetic is the Python step's, one rounding per operation, dot products summed",
        "in index order (numpy's BLAS may sum them in another order: the commands then agree to",
        "the rounding of a dot product). Do not compile with -ffast-math or -ffp-contract=fast",
        "if the commands must agree with Python's.",
    ]
    guard = "RMPC_CONTROLLER_H"
    out = [_comment_block(lines), f"#ifndef {guard}", f"#define {guard}", ""]
    out += ["#ifdef __cplusplus", 'extern "C" {', "#endif", ""]
    out.append(f"#define RMPC_NX {program.nx} /* states */")
    out.append(f"#define RMPC_NU {program.nu} /* inputs */")
    for name, value, comment in program.defines:
        out.append(f"#define {name} {value} /* {comment} */")
    out.append("")
    out.append("/* status codes of rmpc_step (the Python status word in brackets) */")
    for code in STATUS_CODES:
        out.append(_comment_block([f"[{code.word}] {code.meaning}"]).replace("/*\n * ", "/* ", 1))
        out.append(f"#define {code.name} {code.value}")
    out += ["", "int rmpc_init(void);", "int rmpc_step(const double *x, double *u);",
            "double rmpc_last_gamma(void);", "int rmpc_last_iterations(void);"]
    out += [f"{proto};" for proto, _, _ in program.accessors]
    out += ["", "#ifdef __cplusplus", "}", "#endif", "", f"#endif /* {guard} */", ""]
    return "\n".join(out)


_DOT = """\
/* a[0] x[0] + ... + a[n-1] x[n-1], summed in order, each product rounded before it is added */
static double rmpc_dot(const double *a, const double *x, int n)
{
    double s = 0.0;
    int j;
    for (j = 0; j < n; ++j) {
        const double p = a[j] * x[j];
        s += p;
    }
    return s;
}
"""

_STEP = """\
static void rmpc_zero(double *u)
{
    int r;
    for (r = 0; r < RMPC_NU; ++r) {
        u[r] = 0.0;
    }
}

static int rmpc_finish(int status, double *u)
{
    rmpc_ws.status = status;
    if (@ZERO_CODES@) {
        rmpc_ws.gamma = NAN;
        rmpc_ws.iterations = 0;
        @RESET@
        if (u != NULL) {
            rmpc_zero(u);
        }
    }
    return status;
}

int rmpc_init(void)
{
    memset(&rmpc_ws, 0, sizeof rmpc_ws);
@INIT@
@SOLVER_INIT@
    return RMPC_OK;
}

int rmpc_step(const double *x, double *u)
{
    double z[RMPC_NX];
    double v[RMPC_NU];
    int status;
    int j;
    rmpc_ws.gamma = NAN;
    rmpc_ws.iterations = 0;
@RESET@
    if (x == NULL || u == NULL) {
        return rmpc_finish(RMPC_STATUS_NULL_ARGUMENT, u);
    }
    for (j = 0; j < RMPC_NX; ++j) {
        if (!isfinite(x[j])) {
            return rmpc_finish(RMPC_STATUS_BAD_STATE, u);
        }
    }
    memcpy(z, x, sizeof z);
    status = rmpc_compute(z, v);
    for (j = 0; j < RMPC_NU; ++j) {
        if (!isfinite(v[j])) {
            return rmpc_finish(RMPC_STATUS_OVERFLOW, u);
        }
    }
    memcpy(u, v, sizeof v);
    return rmpc_finish(status, u);
}

double rmpc_last_gamma(void)
{
    return rmpc_ws.gamma;
}

int rmpc_last_iterations(void)
{
    return rmpc_ws.iterations;
}
"""


def render_source(program: CProgram) -> str:
    """The text of ``rmpc_controller.c``."""
    fields_ = _fields(program)
    head = _comment_block([
        f"{SOURCE_NAME}: generated by rmpc.export_c (controller: {program.controller}). Do not edit.",
        f"Constant tables: {program.table_bytes} bytes; static workspace: "
        f"{program.workspace_bytes} bytes; see {HEADER_NAME}.",
    ])
    out = [head, "#include <math.h>", "#include <string.h>", "", f'#include "{HEADER_NAME}"', ""]
    out += [array.render() for array in program.arrays]
    out.append("/* the one static workspace */")
    out.append("static struct rmpc_workspace {")
    out += [f"    {f.ctype} {f.name}; /* {f.comment} */" for f in fields_]
    out.append("} rmpc_ws = {" + ", ".join(f.initial for f in fields_) + "};")
    out.append("")
    out.append(_DOT)
    if program.helpers:
        out.append(program.helpers)
    out.append("static int rmpc_compute(const double *x, double *v)\n{\n" + program.compute.rstrip()
               + "\n}\n")
    init = "\n".join(f"    rmpc_ws.{f.name} = {f.initial};" for f in fields_ if f.initial not in ("0", "0.0"))
    def reset(indent: str) -> str:
        return "".join(f"{indent}rmpc_ws.{f.name} = {f.initial};\n" for f in program.fields)

    solver_init = textwrap.indent(program.init.strip("\n"), "    ") if program.init else ""
    step = _STEP.replace("@SOLVER_INIT@\n", solver_init + "\n" if solver_init else "")
    step = step.replace("@INIT@", init)
    zero_codes = " || ".join(f"status == {name}" for name in ZERO_COMMAND_CODES)
    step = step.replace("@ZERO_CODES@", zero_codes).replace("        @RESET@\n", reset(" " * 8))
    out.append(step.replace("@RESET@\n", reset(" " * 4)))
    for proto, _, body in program.accessors:
        out.append(f"{proto}\n{{\n{body.rstrip()}\n}}\n")
    return "\n".join(out)


@dataclass(frozen=True)
class ExportResult:
    """What :func:`rmpc.export_c` wrote.

    Attributes
    ----------
    header, source : Path
        ``rmpc_controller.h`` and ``rmpc_controller.c``.
    sizes : dict of str to int
        Bytes of each file written, by file name.
    table_bytes : int
        The constant tables (``static const``, read-only data).
    workspace_bytes : int
        The static workspace (``sizeof rmpc_ws`` on this machine).
    controller : str
        The Python class exported.
    nx, nu : int
        ``RMPC_NX`` and ``RMPC_NU``.
    returns : tuple of int
        The status codes this controller's ``rmpc_step`` returns.
    """

    header: Path
    source: Path
    sizes: dict[str, int]
    table_bytes: int
    workspace_bytes: int
    controller: str
    nx: int
    nu: int
    returns: tuple[int, ...]

    @property
    def paths(self) -> tuple[Path, Path]:
        """``(header, source)``."""
        return self.header, self.source

    @property
    def static_bytes(self) -> int:
        """All static memory: the constant tables and the workspace."""
        return self.table_bytes + self.workspace_bytes


def _out_dir(out_dir: str | os.PathLike[str]) -> Path:
    if isinstance(out_dir, bool) or not isinstance(out_dir, str | os.PathLike):
        raise ArgumentTypeError("out_dir", "a path (str or os.PathLike)", type(out_dir).__name__)
    path = Path(out_dir)
    if path.exists() and not path.is_dir():
        raise InvalidArgumentError("out_dir", "a directory (created when missing)",
                                   f"{str(path)!r}, which is a file")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InvalidArgumentError("out_dir", "a directory that can be created",
                                   f"{str(path)!r}: {err.strerror or err}") from None
    return path


def write_program(program: CProgram, out_dir: str | os.PathLike[str]) -> ExportResult:
    """Render ``program`` and write both files into ``out_dir`` (created when missing).

    Each file is written next to its final name and then renamed over it, so a failed export
    leaves no half-written file.
    """
    folder = _out_dir(out_dir)
    texts = {HEADER_NAME: render_header(program), SOURCE_NAME: render_source(program)}
    sizes = {}
    for name, text in texts.items():
        final = folder / name
        temp = folder / f".{name}.tmp"
        data = text.encode("ascii")
        try:
            temp.write_bytes(data)
            os.replace(temp, final)
        except OSError as err:
            temp.unlink(missing_ok=True)
            raise InvalidArgumentError("out_dir", "a writable directory",
                                       f"{str(folder)!r}: {err.strerror or err}") from None
        sizes[name] = len(data)
    return ExportResult(
        header=folder / HEADER_NAME, source=folder / SOURCE_NAME, sizes=sizes,
        table_bytes=program.table_bytes + program.helper_table_bytes,
        workspace_bytes=program.workspace_bytes,
        controller=program.controller, nx=program.nx, nu=program.nu,
        returns=tuple(_CODE[name].value for name in program.returns),
    )
