"""Read semidefinite programs in SDPA's sparse format (``.dat-s``), the format of SDPLIB.

SDPA (K. Fujisawa et al.) and SDPLIB (B. Borchers, "SDPLIB 1.2, a library of semidefinite
programming test problems", Optimization Methods and Software 11(1-4), 1999) state the primal
problem as ::

    minimise  sum_i c_i x_i   subject to   X = sum_i x_i F_i - F_0 >= 0

with symmetric block-diagonal ``F_0, ..., F_m``; the optima SDPLIB publishes are values of
this ``c'x``. :class:`lmi.ipm.BlockLMISolver` solves ``min c'x`` s.t.
``C_j - sum_i x_i A_ij >= 0``, so :func:`read_sdpa` returns ``c`` unchanged, ``C_j = -F_0j`` and
``A_ij = -F_ij`` for every block ``j``: the same ``x`` and the same objective value.

The file (SDPA's sparse format, as in the SDPA and SDPLIB manuals):

1. comment lines, starting with ``"`` or ``*``, before the data;
2. ``m``, the number of variables (anything after the first number is ignored, e.g. ``=mdim``);
3. the number of blocks (likewise);
4. the block sizes, a negative size ``-d`` for a diagonal block of order ``d``;
5. the ``m`` entries of ``c``;
6. one line per non-zero entry: ``matrix block i j value`` (matrix ``0`` is ``F_0``; block, ``i``
   and ``j`` count from 1), each entry of a symmetric matrix given once, on either side of the
   diagonal.

Numbers on lines 4 and 5 may be separated by commas, braces and parentheses as well as blanks.
A file compressed with gzip is read as it is (recognised by its first bytes, not its name).
"""

from __future__ import annotations

import gzip
import io
import math
import os
import re

import numpy as np

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_count

__all__ = ["MAX_SDPA_BYTES", "SDPAFormatError", "read_sdpa"]

_SEPARATORS = re.compile(r"[\s,{}()]+")


class SDPAFormatError(InvalidArgumentError):
    """An SDPA file is malformed; the message names the file and the line.

    Attributes
    ----------
    path : str
        The file.
    line : int or None
        The line (counting from 1), ``None`` when the file ends too early.
    """

    def __init__(self, path: str, line: int | None, expected: str, found: str) -> None:
        self.path = path
        self.line = line
        where = f"{path}, line {line}" if line is not None else f"{path}, at its end"
        super().__init__(where, expected, found)


#: The default ``max_bytes`` of :func:`read_sdpa`: the most memory the dense data it returns may
#: take (``8 (m + 1) sum_j k_j^2`` bytes for ``m`` variables and blocks of order ``k_j``; a
#: diagonal block read split counts ``k_j`` blocks of order 1), and the most a compressed file may
#: expand to. Checked from the header, before anything is allocated: a 22-byte file declaring a
#: 30000 x 30000 block asked for 2 x 7.2 GB. SDPLIB's control4 takes 21 MB, its largest
#: problems (``equalG51``, ``maxG60``, ...) many gigabytes, beyond what the dense solver handles.
MAX_SDPA_BYTES = 2 * 2**30


def read_sdpa(
    path: str | os.PathLike[str], *, split_diagonal: bool = False, max_bytes: int = MAX_SDPA_BYTES
) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """Read an SDPA sparse file as ``(c, blocks)`` for :class:`lmi.ipm.BlockLMISolver`.

    Parameters
    ----------
    path : str or path-like
        The ``.dat-s`` file, plain or compressed with gzip.
    split_diagonal : bool
        Return a diagonal block of order ``d`` as ``d`` blocks of order 1 (equivalent; the
        solver pads every block to the largest order, so a long diagonal block is cheaper split).
        By default it is one block of order ``d`` with diagonal ``C_j`` and ``A_ij``, and
        ``blocks[j]`` is the file's block ``j + 1``.
    max_bytes : int
        The most memory the returned arrays may take, and the most a compressed file may expand
        to (:data:`MAX_SDPA_BYTES`, 2 GiB); a file that declares more is refused before anything
        is allocated.

    Returns
    -------
    c : (m,) ndarray
        The objective.
    blocks : list of (C_j, A_j)
        ``C_j = -F_0j`` of shape ``(k, k)`` and ``A_j`` of shape ``(m, k, k)`` with
        ``A_j[i] = -F_(i+1)j``: the problem is ``min c'x`` s.t. ``C_j - sum_i x_i A_j[i] >= 0``.

    Raises
    ------
    SDPAFormatError
        For a malformed file: a missing or non-numeric header, a block size of zero, a value
        that is not finite, an entry with the wrong number of fields, out of range, off the
        diagonal of a diagonal block, or given twice; or one whose sizes need more than
        ``max_bytes``. The message names the file and the line.
    ArgumentTypeError
        When ``path`` is not a path (``str`` or path-like) or ``max_bytes`` not an integer.
    OSError
        When the file cannot be read.

    Examples
    --------
    The largest eigenvalue of ``[[2, 1], [1, 2]]`` is ``min t`` s.t. ``t I - M >= 0``
    (``F_1 = I``, ``F_0 = M``):

    >>> import pathlib, tempfile
    >>> from lmi.ipm import BlockLMISolver
    >>> text = '''"lambda_max of [[2, 1], [1, 2]]
    ... 1 =mdim
    ... 1 =nblocks
    ... {2}
    ... 1.0
    ... 0 1 1 1 2.0
    ... 0 1 1 2 1.0
    ... 0 1 2 2 2.0
    ... 1 1 1 1 1.0
    ... 1 1 2 2 1.0
    ... '''
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     file = pathlib.Path(tmp, "lambda_max.dat-s")
    ...     _ = file.write_text(text)
    ...     c, blocks = read_sdpa(file)
    >>> [(b[0].shape, b[1].shape) for b in blocks]
    [((2, 2), (1, 2, 2))]
    >>> res = BlockLMISolver(c, blocks).solve()
    >>> res.status, round(float(res.x[0]), 6)
    ('optimal', 3.0)
    """
    if not isinstance(split_diagonal, bool):
        raise InvalidArgumentError("split_diagonal", "True or False", repr(split_diagonal))
    limit = check_count(max_bytes, "max_bytes", expected="a number of bytes (an integer >= 1)")
    if not isinstance(path, str | os.PathLike):
        found = f"{type(path).__name__} {path!r}"[:80]
        raise ArgumentTypeError("path", "a file path (str or os.PathLike)", found)
    name = os.fspath(path)
    if not isinstance(name, str):
        raise ArgumentTypeError("path", "a file path (str or os.PathLike of str)", type(name).__name__)
    with open(name, "rb") as handle:
        raw = handle.read(limit + 1)
    if len(raw) > limit:
        raise SDPAFormatError(name, None, f"a file of at most max_bytes = {limit} bytes", "a larger file")
    if raw[:2] == b"\x1f\x8b":
        try:
            with gzip.GzipFile(fileobj=io.BytesIO(raw)) as stream:
                raw = stream.read(limit + 1)
        except (OSError, EOFError) as err:
            raise SDPAFormatError(name, None, "a complete gzip stream", repr(err)) from None
        if len(raw) > limit:
            raise SDPAFormatError(name, None, f"a file that expands to at most max_bytes = {limit} bytes",
                                  "a compressed file that expands to more")
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError as err:
        raise SDPAFormatError(name, _text_line(raw, err.start), "ASCII text",
                              f"byte {raw[err.start]:#04x}") from None
    return _parse(name, text.splitlines(), split_diagonal, limit)


def _text_line(raw: bytes, offset: int) -> int:
    """The line (from 1) of byte ``offset`` of ``raw``."""
    return raw.count(b"\n", 0, offset) + 1


def _parse(name: str, lines: list[str], split_diagonal: bool, limit: int) -> tuple[np.ndarray, list]:
    numbered = [(k + 1, line) for k, line in enumerate(lines)]
    pos = 0
    while pos < len(numbered) and (not numbered[pos][1].strip() or numbered[pos][1].lstrip()[0] in "\"*"):
        pos += 1
    rows = [(k, line) for k, line in numbered[pos:] if line.strip()]

    def tokens(line: str) -> list[str]:
        return [t for t in _SEPARATORS.split(line) if t]

    def header(index: int, what: str) -> tuple[int, list[str]]:
        if index >= len(rows):
            raise SDPAFormatError(name, None, what, "the end of the file")
        return rows[index][0], tokens(rows[index][1])

    line_m, tok = header(0, "the number of variables m")
    m = _integer(name, line_m, tok[0].split("=")[0] if tok else "", "the number of variables m", low=1)
    line_nb, tok = header(1, "the number of blocks")
    nblocks = _integer(name, line_nb, tok[0].split("=")[0] if tok else "", "the number of blocks", low=1)
    line_sz, tok = header(2, f"{nblocks} block sizes")
    if len(tok) < nblocks:
        raise SDPAFormatError(name, line_sz, f"{nblocks} block sizes", f"{len(tok)} values")
    sizes = [_integer(name, line_sz, t, "a block size (non-zero integer)") for t in tok[:nblocks]]
    if 0 in sizes:
        raise SDPAFormatError(name, line_sz, "non-zero block sizes", f"size 0 for block {sizes.index(0) + 1}")
    # the dense arrays to be allocated, from the header alone (Python integers: no overflow)
    need = 8 * (m + 1) * sum(-k if k < 0 and split_diagonal else k * k for k in sizes)
    if need > limit:
        raise SDPAFormatError(
            name, line_sz, f"sizes whose dense data fit in max_bytes = {limit} bytes (pass a larger "
            "max_bytes to lift it)", f"m = {m} and blocks of orders up to {max(abs(k) for k in sizes)}: "
            f"{need} bytes")
    # c: m numbers, on one line or wrapped over several
    c_vals: list[float] = []
    index = 3
    while len(c_vals) < m:
        line_c, tok = header(index, f"the {m} entries of c")
        if len(c_vals) + len(tok) > m:
            raise SDPAFormatError(name, line_c, f"{m} entries of c", f"{len(c_vals) + len(tok)} values")
        c_vals.extend(_real(name, line_c, t, "an entry of c") for t in tok)
        index += 1
    c = np.array(c_vals)
    orders = [abs(k) for k in sizes]
    consts = [np.zeros((k, k)) for k in orders]
    coefs = [np.zeros((m, k, k)) for k in orders]
    seen: dict[tuple[int, int, int, int], int] = {}
    for line_no, line in rows[index:]:
        tok = line.split()
        if len(tok) != 5:
            tok = tokens(line)
            if len(tok) != 5:
                raise SDPAFormatError(name, line_no, "5 fields 'matrix block i j value'",
                                      f"{len(tok)}: {line.strip()!r}")
        try:  # the common case; the checks below name what is wrong
            mat, blk, i, j, value = int(tok[0]), int(tok[1]), int(tok[2]), int(tok[3]), float(tok[4])
            k = orders[blk - 1]
            ok = (0 <= mat <= m and 1 <= blk <= nblocks and 1 <= i <= k and 1 <= j <= k
                  and math.isfinite(value))
        except (ValueError, IndexError):
            ok = False
        if not ok:
            mat = _integer(name, line_no, tok[0], f"a matrix number in [0, {m}]", 0, m)
            blk = _integer(name, line_no, tok[1], f"a block number in [1, {nblocks}]", 1, nblocks)
            k = orders[blk - 1]
            i = _integer(name, line_no, tok[2], f"a row in [1, {k}] (block {blk})", 1, k)
            j = _integer(name, line_no, tok[3], f"a column in [1, {k}] (block {blk})", 1, k)
            value = _real(name, line_no, tok[4], "a finite value")
        if sizes[blk - 1] < 0 and i != j:
            raise SDPAFormatError(name, line_no, f"i = j in the diagonal block {blk}", f"entry ({i}, {j})")
        key = (mat, blk, min(i, j), max(i, j))
        if key in seen:
            raise SDPAFormatError(name, line_no, "each entry once", f"matrix {mat} block {blk} entry "
                                  f"({i}, {j}) again (first on line {seen[key]})")
        seen[key] = line_no
        target = consts[blk - 1] if mat == 0 else coefs[blk - 1][mat - 1]
        target[i - 1, j - 1] = target[j - 1, i - 1] = -value
    blocks: list[tuple[np.ndarray, np.ndarray]] = []
    for size, const, coef in zip(sizes, consts, coefs, strict=True):
        if size > 0 or not split_diagonal:
            blocks.append((const, coef))
        else:
            blocks.extend((const[d:d + 1, d:d + 1].copy(), coef[:, d:d + 1, d:d + 1].copy())
                          for d in range(-size))
    return c, blocks


def _integer(name: str, line: int, token: str, what: str, low: int | None = None,
             high: int | None = None) -> int:
    """``token`` as an integer (an integral real such as ``2.0`` too) in ``[low, high]``."""
    try:
        value = int(token)
    except ValueError:
        try:
            real = float(token.replace("D", "E").replace("d", "e"))
        except ValueError:
            raise SDPAFormatError(name, line, what, repr(token)) from None
        if not (math.isfinite(real) and real.is_integer()):
            raise SDPAFormatError(name, line, what, repr(token)) from None
        value = int(real)
    if (low is not None and value < low) or (high is not None and value > high):
        raise SDPAFormatError(name, line, what, str(value))
    return value


def _real(name: str, line: int, token: str, what: str) -> float:
    """``token`` as a finite real (Fortran's ``1.0D+00`` too)."""
    try:
        value = float(token.replace("D", "E").replace("d", "e"))
    except ValueError:
        raise SDPAFormatError(name, line, what, repr(token)) from None
    if not math.isfinite(value):
        raise SDPAFormatError(name, line, what, repr(token))
    return value
