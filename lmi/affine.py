"""Affine matrix expressions ``M(z) = M_0 + sum_k z_k M_k`` and their conic (svec) data.

A small, dense tool used to write LMIs once and hand them to a conic solver as
``A z + s = b, s in PSD`` without a modelling layer in the loop. Coefficients are stored as an
array ``c`` of shape ``(n_vars + 1, rows, cols)``; ``c[0]`` is the constant part.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["AffineMatrix", "smat_matrix", "svec_index_map", "svec_indices", "svec_matrix"]


class AffineMatrix:
    """A matrix affine in the decision vector ``z`` (length ``n_vars``)."""

    __slots__ = ("coef",)

    def __init__(self, coef: np.ndarray) -> None:
        self.coef = coef

    # -- constructors ------------------------------------------------------------------
    @classmethod
    def constant(cls, value: np.ndarray, n_vars: int) -> AffineMatrix:
        value = np.atleast_2d(np.asarray(value, dtype=float))
        coef = np.zeros((n_vars + 1, *value.shape))
        coef[0] = value
        return cls(coef)

    @classmethod
    def zeros(cls, rows: int, cols: int, n_vars: int) -> AffineMatrix:
        return cls(np.zeros((n_vars + 1, rows, cols)))

    @classmethod
    def symmetric_variable(cls, size: int, offset: int, n_vars: int) -> AffineMatrix:
        """A symmetric ``size x size`` variable stored in ``z[offset : offset + size(size+1)/2]``.

        The entries are ordered like :func:`svec_indices` (upper triangle, column by column).
        """
        coef = np.zeros((n_vars + 1, size, size))
        for k, (i, j) in enumerate(zip(*svec_indices(size), strict=True)):
            coef[1 + offset + k, i, j] = 1.0
            coef[1 + offset + k, j, i] = 1.0
        return cls(coef)

    @classmethod
    def full_variable(cls, rows: int, cols: int, offset: int, n_vars: int) -> AffineMatrix:
        """A ``rows x cols`` variable stored row-major in ``z[offset : offset + rows cols]``."""
        coef = np.zeros((n_vars + 1, rows, cols))
        for k in range(rows * cols):
            coef[1 + offset + k, k // cols, k % cols] = 1.0
        return cls(coef)

    @classmethod
    def scalar_variable_times(cls, matrix: np.ndarray, index: int, n_vars: int) -> AffineMatrix:
        """``z[index] * matrix``."""
        matrix = np.atleast_2d(np.asarray(matrix, dtype=float))
        coef = np.zeros((n_vars + 1, *matrix.shape))
        coef[1 + index] = matrix
        return cls(coef)

    # -- algebra -----------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        return self.coef.shape[1], self.coef.shape[2]

    @property
    def T(self) -> AffineMatrix:
        return AffineMatrix(np.swapaxes(self.coef, 1, 2))

    def __add__(self, other: AffineMatrix) -> AffineMatrix:
        return AffineMatrix(self.coef + other.coef)

    def __sub__(self, other: AffineMatrix) -> AffineMatrix:
        return AffineMatrix(self.coef - other.coef)

    def __neg__(self) -> AffineMatrix:
        return AffineMatrix(-self.coef)

    def __mul__(self, scalar: float) -> AffineMatrix:
        return AffineMatrix(self.coef * float(scalar))

    __rmul__ = __mul__

    def lmul(self, matrix: np.ndarray) -> AffineMatrix:
        """``matrix @ self``."""
        return AffineMatrix(np.einsum("ij,kjl->kil", matrix, self.coef))

    def rmul(self, matrix: np.ndarray) -> AffineMatrix:
        """``self @ matrix``."""
        return AffineMatrix(np.einsum("kij,jl->kil", self.coef, matrix))

    def value(self, z: np.ndarray) -> np.ndarray:
        """Evaluate at ``z``."""
        return self.coef[0] + np.tensordot(z, self.coef[1:], axes=1)

    @staticmethod
    def bmat(blocks: Sequence[Sequence[AffineMatrix | None]], n_vars: int) -> AffineMatrix:
        """Assemble a block matrix; ``None`` is a zero block sized by its row and column."""
        rows = [next(b.shape[0] for b in row if b is not None) for row in blocks]
        cols = [
            next(blocks[i][j].shape[1] for i in range(len(blocks)) if blocks[i][j] is not None)
            for j in range(len(blocks[0]))
        ]
        coef = np.zeros((n_vars + 1, sum(rows), sum(cols)))
        r0 = 0
        for i, row in enumerate(blocks):
            c0 = 0
            for j, block in enumerate(row):
                if block is not None:
                    coef[:, r0 : r0 + rows[i], c0 : c0 + cols[j]] = block.coef
                c0 += cols[j]
            r0 += rows[i]
        return AffineMatrix(coef)


def svec_indices(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices of the upper triangle, column by column (Clarabel's order)."""
    rows, cols = [], []
    for j in range(size):
        for i in range(j + 1):
            rows.append(i)
            cols.append(j)
    return np.asarray(rows), np.asarray(cols)


def svec_index_map(size: int, offset: int) -> np.ndarray:
    """The ``(size, size)`` map of a symmetric variable's entries to their places in ``z``: entry
    ``(i, j)`` and ``(j, i)`` at ``offset + k``, ``k`` the entry's place in :func:`svec_indices`."""
    rows, cols = svec_indices(size)
    out = np.empty((size, size), dtype=np.int64)
    out[rows, cols] = offset + np.arange(rows.size)
    out[cols, rows] = offset + np.arange(rows.size)
    return out


def svec_matrix(stack: np.ndarray) -> np.ndarray:
    """Scaled half-vectorisation of a stack of symmetric matrices, shape ``(k, s(s+1)/2)``.

    Off-diagonal entries are multiplied by ``sqrt(2)`` so that ``<svec(X), svec(Y)> = tr(X Y)``
    (Clarabel's ``PSDTriangleConeT`` convention).
    """
    size = stack.shape[-1]
    rows, cols = svec_indices(size)
    scale = np.where(rows == cols, 1.0, np.sqrt(2.0))
    return stack[..., rows, cols] * scale


def smat_matrix(vecs: np.ndarray, size: int) -> np.ndarray:
    """Inverse of :func:`svec_matrix`: a stack ``(..., s(s+1)/2)`` -> ``(..., s, s)``."""
    rows, cols = svec_indices(size)
    vals = vecs / np.where(rows == cols, 1.0, np.sqrt(2.0))
    out = np.zeros((*vecs.shape[:-1], size, size))
    out[..., rows, cols] = vals
    out[..., cols, rows] = vals
    return out
