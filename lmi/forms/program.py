"""A small LMI program: named variables, named blocks ``M(z) >= 0``, a linear objective.

The forms of :mod:`lmi.forms.lmis` are written once against a :class:`Program` and evaluated in
two ways: symbolically (each variable an :class:`~lmi.affine.AffineMatrix` in the decision vector
``z``: the data handed to :class:`lmi.BlockLMISolver`, Clarabel or cvxpy) or numerically (each
variable a given matrix, with no decision vector: the blocks' constants for a new state, or the
LMIs recomputed at a solver's answer for the certificate).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from lmi.affine import AffineMatrix, svec_index_map, svec_matrix

__all__ = ["Layout", "Program", "relative_margins"]


@dataclass(frozen=True)
class _Var:
    offset: int
    shape: tuple[int, int]
    symmetric: bool

    @property
    def size(self) -> int:
        r = self.shape[0]
        return r * (r + 1) // 2 if self.symmetric else self.shape[0] * self.shape[1]


class Layout:
    """The decision vector's variables, in the order they are declared."""

    def __init__(self) -> None:
        self._vars: dict[str, _Var] = {}
        self._gather_index: dict[str, np.ndarray] | None = None
        self.size = 0

    def symmetric(self, name: str, size: int) -> None:
        """Declare a symmetric ``size x size`` variable."""
        self._add(name, _Var(self.size, (size, size), True))

    def full(self, name: str, rows: int, cols: int) -> None:
        """Declare a ``rows x cols`` variable (a scalar is ``1 x 1``)."""
        self._add(name, _Var(self.size, (rows, cols), False))

    def _add(self, name: str, var: _Var) -> None:
        if name in self._vars:
            raise ValueError(f"variable {name!r} declared twice")
        self._vars[name] = var
        self._gather_index = None
        self.size += var.size

    def __contains__(self, name: str) -> bool:
        return name in self._vars

    @property
    def names(self) -> list[str]:
        return list(self._vars)

    def shape(self, name: str) -> tuple[int, int]:
        return self._vars[name].shape

    def index(self, name: str) -> int:
        """The position of a scalar variable in ``z``."""
        var = self._vars[name]
        if var.shape != (1, 1):
            raise ValueError(f"{name!r} is not a scalar")
        return var.offset

    def affine(self, name: str) -> AffineMatrix:
        """The variable as an affine matrix of ``z``."""
        var = self._vars[name]
        if var.symmetric:
            return AffineMatrix.symmetric_variable(var.shape[0], var.offset, self.size)
        return AffineMatrix.full_variable(*var.shape, var.offset, self.size)

    def values(self, z: np.ndarray) -> dict[str, np.ndarray]:
        """Every variable's value at ``z`` (the entries of :meth:`affine`'s value, gathered from
        ``z`` by index instead of through the ``(size + 1, rows, cols)`` coefficients)."""
        z = np.asarray(z, dtype=float)
        return {name: z[index] for name, index in self._gather().items()}

    def _gather(self) -> dict[str, np.ndarray]:
        """Per variable, the index into ``z`` of each of its entries (made once per layout)."""
        if self._gather_index is None:
            index = {}
            for name, var in self._vars.items():
                rows, cols = var.shape
                if var.symmetric:
                    full = svec_index_map(rows, var.offset)
                else:
                    full = var.offset + np.arange(rows * cols, dtype=np.int64).reshape(rows, cols)
                index[name] = full
            self._gather_index = index
        return self._gather_index

    def vector(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """The ``z`` holding the given values (missing variables are zero)."""
        z = np.zeros(self.size)
        for name, var in self._vars.items():
            if name not in values:
                continue
            val = np.asarray(values[name], dtype=float).reshape(var.shape)
            if var.symmetric:
                iu = np.triu_indices(var.shape[0])
                # the upper triangle column by column, as lmi.affine.svec_indices orders it
                order = np.lexsort((iu[0], iu[1]))
                z[var.offset : var.offset + var.size] = val[iu[0][order], iu[1][order]]
            else:
                z[var.offset : var.offset + var.size] = val.ravel()
        return z


class Program:
    """Blocks ``M_k >= 0`` written with the variables of a :class:`Layout`.

    Parameters
    ----------
    layout : Layout
    values : mapping of str to ndarray, optional
        ``None``: symbolic (every variable affine in ``z``). Otherwise numeric: each variable is
        the given matrix (a missing one is zero), and the blocks are constant matrices.
    """

    def __init__(self, layout: Layout, values: Mapping[str, np.ndarray] | None = None,
                 skip: frozenset[str] = frozenset()) -> None:
        self.layout = layout
        self.numeric = values is not None
        self.skip = skip
        self._values = dict(values or {})
        self.n_vars = 0 if self.numeric else layout.size
        self.blocks: dict[str, AffineMatrix] = {}
        self._congruences: dict[str, np.ndarray] = {}

    def var(self, name: str) -> AffineMatrix:
        if not self.numeric:
            return self.layout.affine(name)
        value = self._values.get(name)
        if value is None:
            return AffineMatrix.zeros(*self.layout.shape(name), 0)
        return AffineMatrix.constant(np.asarray(value, dtype=float).reshape(self.layout.shape(name)), 0)

    def const(self, value: np.ndarray | float) -> AffineMatrix:
        return AffineMatrix.constant(np.atleast_2d(np.asarray(value, dtype=float)), self.n_vars)

    def eye(self, size: int, scale: float = 1.0) -> AffineMatrix:
        return self.const(scale * np.eye(size))

    def zeros(self, rows: int, cols: int) -> AffineMatrix:
        return AffineMatrix.zeros(rows, cols, self.n_vars)

    def times(self, scalar: AffineMatrix, matrix: np.ndarray) -> AffineMatrix:
        """A ``1 x 1`` expression times a constant matrix."""
        return AffineMatrix(np.kron(scalar.coef, np.atleast_2d(matrix)))

    def bmat(self, rows: list[list[AffineMatrix | None]]) -> AffineMatrix:
        return AffineMatrix.bmat(rows, self.n_vars)

    def wants(self, name: str) -> bool:
        """Whether block ``name`` is to be written (``skip``: blocks the caller has already)."""
        return name not in self.skip

    def add(self, name: str, block: AffineMatrix, congruence: np.ndarray | None = None) -> None:
        """Require ``block >= 0`` (its symmetric part).

        ``congruence``: an invertible ``L``; the solvers get ``L M L'`` (the same LMI, better
        conditioned), and the certificate checks both ``M`` and ``L M L'`` (``name + "_delta"``).
        """
        if name in self.blocks:
            raise ValueError(f"block {name!r} added twice")
        self.blocks[name] = block
        if congruence is not None:
            self._congruences[name] = congruence

    def solver_coef(self, name: str) -> np.ndarray:
        """Block ``name``'s symmetric coefficients ``(n_vars + 1, k, k)`` as the solvers get them."""
        coef = self.blocks[name].coef
        lmat = self._congruences.get(name)
        if lmat is not None:
            coef = np.matmul(np.matmul(lmat, coef), lmat.T)
        return 0.5 * (coef + np.swapaxes(coef, 1, 2))

    # -- what the solvers read -----------------------------------------------------------
    def solver_blocks(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``(C_j, A_j)`` with ``M_j(z) = C_j - sum_i z_i A_ij`` (:class:`lmi.BlockLMISolver`)."""
        out = []
        for name in self.blocks:
            coef = self.solver_coef(name)
            out.append((coef[0], -coef[1:]))
        return out

    def constants(self) -> dict[str, np.ndarray]:
        """The constant part of each block as the solvers get it (a numeric program: the blocks'
        values)."""
        return {name: self.solver_coef(name)[0] for name in self.blocks}

    def conic_rows(self) -> tuple[np.ndarray, np.ndarray, list[int]]:
        """``(A, b, orders)`` with ``svec(M_j(z)) = b_j - A_j z`` stacked over the blocks
        (Clarabel's ``PSDTriangleConeT`` convention)."""
        a_rows, b_rows, orders = [], [], []
        for name, block in self.blocks.items():
            sv = svec_matrix(self.solver_coef(name))
            a_rows.append(-sv[1:].T)
            b_rows.append(sv[0])
            orders.append(block.shape[0])
        return np.vstack(a_rows), np.concatenate(b_rows), orders

    def margins(self) -> dict[str, float]:
        """Of a numeric program: each block's smallest eigenvalue relative to its largest."""
        mats = {}
        for name, block in self.blocks.items():
            mats[name] = block.coef[0]
            if name in self._congruences:
                mats[name + "_delta"] = self.solver_coef(name)[0]
        out: dict[str, float] = {}
        by_order: dict[int, list[str]] = {}
        for name, mat in mats.items():
            by_order.setdefault(mat.shape[0], []).append(name)
        for names in by_order.values():  # one batched eigenvalue call per block order
            for name, margin in zip(names, relative_margins(np.stack([mats[k] for k in names])), strict=True):
                out[name] = margin
        return {name: out[name] for name in mats}


def relative_margins(stack: np.ndarray) -> list[float]:
    """Of each matrix of a ``(count, k, k)`` stack: the smallest eigenvalue of its symmetric part
    divided by the largest absolute eigenvalue (``-inf`` for a matrix that is not finite)."""
    sym = 0.5 * (stack + np.swapaxes(stack, 1, 2))
    finite = np.all(np.isfinite(sym), axis=(1, 2))
    lam = np.linalg.eigvalsh(np.where(finite[:, None, None], sym, 0.0))
    scale = np.maximum(np.max(np.abs(lam), axis=1), np.finfo(float).tiny)
    return [float(v) if ok else -np.inf for v, ok in zip(lam[:, 0] / scale, finite, strict=True)]
