"""The SDPA sparse-format reader (:func:`lmi.sdpa.read_sdpa`).

The reference problem is the example of SDPLIB's format description (``FORMAT`` of SDPLIB 1.2):
``min 10 x1 + 20 x2`` s.t. ``F1 x1 + F2 x2 - F0 >= 0``. Its blocks are
``diag(x1 - 1, x1 + x2 - 2)`` and ``[[5 x2 - 3, 2 x2], [2 x2, 6 x2 - 4]]``; the second is
positive semidefinite exactly for ``x2 >= 1`` (its determinant ``26 x2^2 - 38 x2 + 12`` has the
roots 6/13 and 1, and ``5 x2 >= 3``), so the optimum is ``x = (1, 1)``, ``c'x = 30`` (by hand).
"""

from __future__ import annotations

import gzip

import numpy as np
import pytest

from lmi.ipm import BlockLMISolver
from lmi.sdpa import SDPAFormatError, read_sdpa
from toolkit_common.errors import InvalidArgumentError

SAMPLE = """"A sample problem.
2 =mdim
2 =nblocks
{2, 2}
10.0 20.0
0 1 1 1 1.0
0 1 2 2 2.0
0 2 1 1 3.0
0 2 2 2 4.0
1 1 1 1 1.0
1 1 2 2 1.0
2 1 2 2 1.0
2 2 1 1 5.0
2 2 1 2 2.0
2 2 2 2 6.0
"""


def _write(tmp_path, text: str | bytes, name: str = "p.dat-s"):
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return path


def test_sample_problem_is_read_in_the_solver_form(tmp_path):
    """``c`` as given, ``C_j = -F_0j``, ``A_ij = -F_ij`` (entries given once, mirrored)."""
    c, blocks = read_sdpa(_write(tmp_path, SAMPLE))
    np.testing.assert_array_equal(c, [10.0, 20.0])
    assert len(blocks) == 2
    np.testing.assert_array_equal(blocks[0][0], -np.diag([1.0, 2.0]))
    np.testing.assert_array_equal(blocks[0][1], -np.array([np.eye(2), np.diag([0.0, 1.0])]))
    np.testing.assert_array_equal(blocks[1][0], -np.diag([3.0, 4.0]))
    np.testing.assert_array_equal(blocks[1][1], -np.array([np.zeros((2, 2)), [[5.0, 2.0], [2.0, 6.0]]]))


def test_sample_problem_solves_to_its_optimum(tmp_path):
    """The solver on the reader's output finds the optimum worked out by hand, ``x = (1, 1)``."""
    c, blocks = read_sdpa(_write(tmp_path, SAMPLE))
    res = BlockLMISolver(c, blocks).solve()
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [1.0, 1.0], atol=1e-6)
    assert float(c @ res.x) == pytest.approx(30.0, rel=1e-8)


def test_diagonal_block_as_one_block_or_split(tmp_path):
    """A negative size is a diagonal block: one block with diagonal matrices, or (split) one block
    of order 1 per diagonal entry; both give the same optimum."""
    text = SAMPLE.replace("{2, 2}", "{-2, 2}")
    path = _write(tmp_path, text)
    c, whole = read_sdpa(path)
    _, split = read_sdpa(path, split_diagonal=True)
    assert [b[0].shape[0] for b in whole] == [2, 2]
    assert [b[0].shape[0] for b in split] == [1, 1, 2]
    np.testing.assert_array_equal(split[0][1][:, 0, 0], whole[0][1][:, 0, 0])
    np.testing.assert_array_equal(split[1][1][:, 0, 0], whole[0][1][:, 1, 1])
    for blocks in (whole, split):
        res = BlockLMISolver(c, blocks).solve()
        assert res.status == "optimal" and float(c @ res.x) == pytest.approx(30.0, rel=1e-8)


def test_gzip_and_the_lenient_parts_of_the_format(tmp_path):
    """A gzip file (recognised by its bytes, not its name), comments starting with ``"`` or ``*``,
    blank lines, ``c`` wrapped over two lines, integral reals as indices, Fortran exponents and an
    entry given below the diagonal read as the plain sample does."""
    want_c, want = read_sdpa(_write(tmp_path, SAMPLE))
    packed = _write(tmp_path, gzip.compress(SAMPLE.encode()), "sample.txt")
    variant = SAMPLE.replace('"A sample problem.', '"A sample problem.\n* a second comment\n')
    variant = variant.replace("10.0 20.0", "(10.0,\n 20.0)").replace("2 2 1 2 2.0", "2 2 2.0 1 0.2D+01")
    variant = variant.replace("0 1 2 2 2.0", "0 1 2 2 2.0\n")
    for path in (packed, _write(tmp_path, variant, "variant.dat-s")):
        c, blocks = read_sdpa(path)
        np.testing.assert_array_equal(c, want_c)
        for (const, coef), (want_const, want_coef) in zip(blocks, want, strict=True):
            np.testing.assert_array_equal(const, want_const)
            np.testing.assert_array_equal(coef, want_coef)


_LINES = SAMPLE.splitlines()


def _replace(line: int, text: str) -> str:
    """The sample with its line ``line`` (from 1) replaced."""
    lines = list(_LINES)
    lines[line - 1] = text
    return "\n".join(lines) + "\n"


BAD = {
    "empty": ("", None, "the number of variables m"),
    "only comments": ('"nothing\n* here\n', None, "the number of variables m"),
    "m not a number": (_replace(2, "two =mdim"), 2, "'two'"),
    "m zero": (_replace(2, "0 =mdim"), 2, "the number of variables m"),
    "blocks missing": ("2\n", None, "the number of blocks"),
    "too few sizes": (_replace(4, "{2}"), 4, "2 block sizes"),
    "size zero": (_replace(4, "{2, 0}"), 4, "size 0 for block 2"),
    "size not integral": (_replace(4, "{2, 2.5}"), 4, "'2.5'"),
    "too many c": (_replace(5, "10.0 20.0 30.0"), 5, "2 entries of c"),
    "c missing": ("2\n2\n2 2\n", None, "the 2 entries of c"),
    "c not finite": (_replace(5, "10.0 nan"), 5, "'nan'"),
    "four fields": (_replace(7, "0 1 2 2"), 7, "5 fields"),
    "matrix out of range": (_replace(7, "3 1 2 2 2.0"), 7, "a matrix number in [0, 2]"),
    "block out of range": (_replace(7, "0 3 2 2 2.0"), 7, "a block number in [1, 2]"),
    "block zero": (_replace(7, "0 0 2 2 2.0"), 7, "a block number in [1, 2]"),
    "row out of range": (_replace(7, "0 1 3 2 2.0"), 7, "a row in [1, 2]"),
    "column out of range": (_replace(7, "0 1 2 0 2.0"), 7, "a column in [1, 2]"),
    "value not a number": (_replace(7, "0 1 2 2 two"), 7, "'two'"),
    "value infinite": (_replace(7, "0 1 2 2 inf"), 7, "'inf'"),
    "entry twice": (_replace(7, "0 1 1 1 3.0"), 7, "again (first on line 6)"),
    "mirror twice": (SAMPLE + "2 2 2 1 2.0\n", 16, "again (first on line 14)"),
    "off the diagonal": (SAMPLE.replace("{2, 2}", "{2, -2}"), 14, "i = j in the diagonal block 2"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_malformed_file_is_an_error_naming_the_file_and_the_line(tmp_path, case):
    text, line, fragment = BAD[case]
    path = _write(tmp_path, text)
    with pytest.raises(SDPAFormatError) as err:
        read_sdpa(path)
    assert err.value.path == str(path) and err.value.line == line
    where = f"{path}, line {line}" if line is not None else f"{path}, at its end"
    assert str(err.value).startswith(where + ": expected ")
    assert fragment in str(err.value)


def test_non_ascii_and_broken_gzip_are_errors_naming_the_file(tmp_path):
    path = _write(tmp_path, SAMPLE.encode().replace(b"10.0 20.0", b"10.0 2\xb00"))
    with pytest.raises(SDPAFormatError, match=r"p\.dat-s, line 5: expected ASCII text, but found byte 0xb0"):
        read_sdpa(path)
    path = _write(tmp_path, gzip.compress(SAMPLE.encode())[:40], "cut.gz")
    with pytest.raises(SDPAFormatError, match=r"cut\.gz, at its end: expected a complete gzip stream"):
        read_sdpa(path)


def test_bad_arguments(tmp_path):
    with pytest.raises(InvalidArgumentError, match="split_diagonal"):
        read_sdpa(_write(tmp_path, SAMPLE), split_diagonal=1)
    with pytest.raises(FileNotFoundError, match=r"missing\.dat-s"):
        read_sdpa(tmp_path / "missing.dat-s")
