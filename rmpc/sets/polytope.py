"""Bounded polytopes in both representations: cddlib for inequalities, qhull for point sets.

A :class:`Polytope` is ``{x : H x <= h}``, bounded and full-dimensional, with its vertices.
Given by inequalities (a user's ``W``, ``X``, ``U``, a terminal set), its vertices and its
irredundant rows come from cddlib through ``pycddlib-standalone``, which also tells an empty or
an unbounded set (a ray) apart; given by points (a Minkowski sum, a hull), its vertices and
facets come from scipy's qhull (:meth:`Polytope.from_vertices`). Support functions are evaluated
on the vertices, so a Pontryagin difference ``X - Z`` with ``X`` given by inequalities is ``{x :
H x <= h - h_Z(H)}`` without any set operation, and a Minkowski sum is the hull of the pairwise
vertex sums.

The choice, measured on the mRPI outer approximation of the double integrator of the tube
literature (seven Minkowski sums, then the inequalities): ``pycddlib-standalone`` 3.0.0 took
9 ms, ``polytope`` 0.2.5 (pure Python on scipy's LPs) 46-65 ms, scipy's qhull 0.45 ms;
``pycddlib`` and ``pytope`` did not install from PyPI without a system cddlib. In four
dimensions cddlib's floating-point LPs reported cycling on the sums and ``polytope`` took 26 s
for three terms; qhull took 0.1-0.7 s. And cddlib's canonical form of a point set, in floating
point, dropped extreme points within its tolerance of the hull (the 34 vertices of the
``epsilon = 1e-5`` approximation became 17, the set lost up to 5.6e-6 and no longer contained
the minimal RPI set): point sets go to qhull, inequalities to cddlib.

Examples
--------
>>> import numpy as np
>>> from rmpc.sets import Polytope
>>> box = Polytope.box([0.1, 0.1])
>>> box.vertices.shape, box.support([1.0, 1.0])
((4, 2), 0.2)
>>> (box + box).support([1.0, 0.0])
0.2
"""

from __future__ import annotations

from typing import Any

import cdd
import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import ConvexHull, QhullError

from toolkit_common.errors import InvalidArgumentError, SolverError
from toolkit_common.validation import as_matrix, as_vector

__all__ = ["Polytope", "PolytopeError"]

#: Relative tolerance of the geometric checks (a vertex on a facet, the origin inside).
TOL = 1e-9


class PolytopeError(SolverError):
    """cddlib failed on a representation (e.g. its floating-point LPs report cycling)."""


def _canonical_rows(h_mat: np.ndarray, h_vec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The irredundant rows of ``H x <= h`` (cddlib's canonicalisation), normalised to unit rows."""
    mat = cdd.matrix_from_array(np.hstack([h_vec[:, None], -h_mat]), rep_type=cdd.RepType.INEQUALITY)
    try:
        cdd.matrix_canonicalize(mat)
    except RuntimeError as err:      # cddlib's floating-point arithmetic gave up
        raise PolytopeError(f"cddlib could not remove the redundant inequalities: {err}") from None
    arr = np.array(mat.array, dtype=float).reshape(-1, h_mat.shape[1] + 1)
    if mat.lin_set:  # equality rows: the set is not full-dimensional
        raise InvalidArgumentError("H, h", "a full-dimensional polytope", "implicit equalities")
    rows, rhs = -arr[:, 1:], arr[:, 0]
    scale = np.linalg.norm(rows, axis=1)
    keep = scale > 0
    return rows[keep] / scale[keep, None], rhs[keep] / scale[keep]


class Polytope:
    """A bounded, full-dimensional polytope ``{x : H x <= h}``.

    Parameters
    ----------
    H : (p, n) array_like
        Inequality rows.
    h : (p,) array_like
        Right-hand sides.
    name : str
        The argument name used in error messages (``"W"``, ``"state_constraints"``).

    Raises
    ------
    InvalidArgumentError
        Naming ``name``: wrong shapes, non-finite values, an empty set, an unbounded set (a ray
        of the recession cone is reported) or one that is not full-dimensional.
    """

    def __init__(self, H: ArrayLike, h: ArrayLike, name: str = "polytope") -> None:
        h_mat = as_matrix(H, f"{name} (H)")
        h_vec = as_vector(h, f"{name} (h)", h_mat.shape[0])
        n = h_mat.shape[1]
        try:
            poly = cdd.polyhedron_from_matrix(
                cdd.matrix_from_array(np.hstack([h_vec[:, None], -h_mat]), rep_type=cdd.RepType.INEQUALITY)
            )
            gen = np.array(cdd.copy_generators(poly).array, dtype=float).reshape(-1, n + 1)
        except RuntimeError as err:      # cddlib's floating-point arithmetic gave up
            raise PolytopeError(f"cddlib could not enumerate the vertices of {name} "
                                f"({h_mat.shape[0]} inequalities in R^{n}): {err}") from None
        if gen.shape[0] == 0:
            raise InvalidArgumentError(name, "a non-empty polytope", "inequalities no point satisfies")
        rays = gen[gen[:, 0] == 0, 1:]
        if rays.shape[0]:
            raise InvalidArgumentError(
                name, "a bounded polytope",
                f"an unbounded set (it contains the ray {np.round(rays[0], 6).tolist()})",
            )
        vertices = gen[:, 1:]
        spread = vertices - vertices.mean(axis=0)
        if vertices.shape[0] < n + 1 or np.linalg.matrix_rank(spread, tol=1e-10) < n:
            raise InvalidArgumentError(name, f"a full-dimensional polytope in R^{n}", "a flat set")
        self.H, self.h = _canonical_rows(h_mat, h_vec)
        self._vertices: np.ndarray | None = vertices
        self.name = name
        for arr in (self.H, self.h, vertices):
            arr.setflags(write=False)

    # -- constructors --------------------------------------------------------------------
    @classmethod
    def box(cls, upper: ArrayLike, lower: ArrayLike | None = None, name: str = "box") -> Polytope:
        """The box ``lower <= x <= upper`` (``lower = -upper`` by default).

        Examples
        --------
        >>> from rmpc.sets import Polytope
        >>> Polytope.box([1.0, 2.0]).h.tolist()
        [1.0, 2.0, 1.0, 2.0]
        """
        up = as_vector(upper, name)
        lo = -up if lower is None else as_vector(lower, name, up.size)
        if not np.all(lo < up):
            raise InvalidArgumentError(name, "lower < upper in every component",
                                       f"{lo.tolist()}, {up.tolist()}")
        n = up.size
        return cls(np.vstack([np.eye(n), -np.eye(n)]), np.concatenate([up, -lo]), name)

    @classmethod
    def from_vertices(cls, points: ArrayLike, name: str = "polytope") -> Polytope:
        """The convex hull of ``points`` (rows), by scipy's qhull: its extreme points are the
        vertices, its facets (coplanar ones merged) the rows, each right-hand side the exact
        support ``max_v H_i v`` of the vertices. No tolerance merges nearly parallel facets or
        drops nearly redundant vertices (cddlib's canonical form does, see the module's notes)."""
        pts = as_matrix(points, name)
        n = pts.shape[1]
        if n == 1:
            verts = np.array([[pts.min()], [pts.max()]])
            rows = np.array([[1.0], [-1.0]])
        else:
            try:
                hull = ConvexHull(pts)
            except QhullError as err:
                found = f"qhull: {str(err).splitlines()[0]}"
                raise InvalidArgumentError(name, f"points spanning R^{n}", found) from None
            verts = pts[hull.vertices]
            rows = np.unique(np.round(hull.equations[:, :n], 12), axis=0)
            rows /= np.linalg.norm(rows, axis=1, keepdims=True)
        if verts[0, 0] == verts[-1, 0] and n == 1:
            raise InvalidArgumentError(name, "points spanning R^1", "a single point")
        poly = cls.__new__(cls)
        poly.H, poly.h, poly._vertices, poly.name = rows, (verts @ rows.T).max(axis=0), verts, name
        for arr in (poly.H, poly.h, verts):
            arr.setflags(write=False)
        return poly

    @classmethod
    def from_irredundant(cls, H: ArrayLike, h: ArrayLike, name: str = "polytope") -> Polytope:
        """A polytope from rows its caller has already made irredundant and whose set it knows
        to be bounded and full-dimensional (an admissible set built by LPs): nothing is checked
        and the vertices are enumerated by cddlib only when asked for. In six or more dimensions
        with hundreds of rows that enumeration is what is slow (or where cddlib's floating point
        gives up), and the tube's QP needs only the rows."""
        poly = cls.__new__(cls)
        poly.H = np.array(as_matrix(H, f"{name} (H)"), dtype=float)
        poly.h = np.array(as_vector(h, f"{name} (h)", poly.H.shape[0]), dtype=float)
        poly._vertices, poly.name = None, name
        for arr in (poly.H, poly.h):
            arr.setflags(write=False)
        return poly

    # -- what a polytope answers -----------------------------------------------------------
    @property
    def vertices(self) -> np.ndarray:
        """The vertices, one per row (enumerated by cddlib on first use where not known)."""
        if self._vertices is None:
            self._vertices = Polytope(self.H, self.h, self.name)._vertices
        return self._vertices

    @property
    def dim(self) -> int:
        """The dimension ``n`` of the space."""
        return int(self.H.shape[1])

    def support(self, direction: ArrayLike) -> float | np.ndarray:
        """``h(d) = max_{x in P} d'x`` for one direction ``(n,)`` or each row of ``(k, n)``."""
        d = np.asarray(direction, dtype=float)
        values = self.vertices @ d.T
        return float(values.max()) if d.ndim == 1 else values.max(axis=0)

    def contains(self, points: ArrayLike, tol: float = TOL) -> bool | np.ndarray:
        """Whether each point (a row) lies in the polytope, to ``tol`` times the row's scale."""
        p = np.asarray(points, dtype=float)
        inside = (p @ self.H.T <= self.h + tol * np.maximum(1.0, np.abs(self.h))).all(axis=-1)
        return bool(inside) if p.ndim == 1 else inside

    def contains_origin_inside(self) -> bool:
        """Whether the origin is an interior point (every ``h_i > 0``)."""
        return bool(np.all(self.h > TOL * np.max(np.abs(self.h))))

    def linear_map(self, matrix: ArrayLike) -> Polytope:
        """``M P = {M x : x in P}`` for an invertible-image ``M`` (hull of the mapped vertices)."""
        m = as_matrix(matrix, "matrix", (None, self.dim))
        return Polytope.from_vertices(self.vertices @ m.T, self.name)

    def __add__(self, other: Any) -> Polytope:
        """The Minkowski sum: the hull of the pairwise vertex sums."""
        if not isinstance(other, Polytope):
            return NotImplemented
        return Polytope.from_vertices(minkowski_vertices(self.vertices, other.vertices), self.name)

    def scaled(self, factor: float) -> Polytope:
        """``factor * P`` (``factor > 0``)."""
        if not factor > 0:
            raise InvalidArgumentError("factor", "a number > 0", repr(factor))
        return Polytope(self.H, factor * self.h, self.name)

    def __repr__(self) -> str:
        return f"Polytope({self.name!r}, dim={self.dim}, facets={self.h.size}, vertices={len(self.vertices)})"


def minkowski_vertices(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The vertices of ``conv(first) + conv(second)``: the extreme pairwise sums (scipy's qhull).

    qhull, not cddlib: cddlib's floating-point canonicalisation of a point set dropped extreme
    points of the tube's Minkowski sums that lie within its tolerance of the hull (34 of the 34
    vertices of the double integrator's ``F_11`` became 17), which shrank the set below the
    minimal RPI set it must contain; qhull keeps them.
    """
    sums = (first[:, None, :] + second[None, :, :]).reshape(-1, first.shape[1])
    if sums.shape[1] == 1:
        return np.array([[sums.min()], [sums.max()]])
    try:
        return sums[ConvexHull(sums).vertices]
    except QhullError as err:
        raise PolytopeError(f"qhull could not reduce a Minkowski sum's vertices: {err}") from None
