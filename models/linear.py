"""Linear models: zero-order-hold discretisation and polytopic discrete-time models.

:func:`zoh` turns ``x' = A x + B u`` into ``x(k+1) = Ad x(k) + Bd u(k)``;
:class:`PolytopicModel` holds ``x(k+1) = A x(k) + B u(k)`` with ``[A B] in Co{[A_j B_j]}``.
:func:`operating_point` and :func:`sample_time` read the ``x_op`` and ``dt`` arguments of every
satellite's ``linearize``, ``discretize``, ``linear_model`` and ``polytope``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import expm

from models.attitude.quaternion import quat_to_euler321
from models.protocols import map_states
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_choice, check_positive

if TYPE_CHECKING:  # python-control is imported where it is used
    import control

__all__ = [
    "ATTITUDE_FORMS",
    "AttitudeCoordinates",
    "PolytopicModel",
    "operating_point",
    "relative_spread",
    "sample_time",
    "unreachable_modes",
    "zoh",
]

#: What the first three states of a :class:`PolytopicModel` may hold (``None``: no attitude).
AttitudeCoordinates = Literal["euler321", "quaternion_vector"]
ATTITUDE_FORMS: tuple[str, ...] = ("euler321", "quaternion_vector")


def operating_point(x_op: ArrayLike | None, size: int, default: Any = None) -> np.ndarray:
    """The ``x_op`` argument of a linearisation: ``size`` finite values, or ``default`` for ``None``.

    A single number is refused with a message naming ``dt``: ``x_op`` comes first in every
    family's ``discretize``, ``linear_model`` and ``polytope``, and a sample time passed in its
    place is the likely mistake.

    Examples
    --------
    >>> from models.linear import operating_point
    >>> operating_point(None, 3).tolist()
    [0.0, 0.0, 0.0]
    >>> operating_point(0.04, 6)
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: x_op: expected an operating point of 6 states (the \
sample time comes after it: dt=...), but found the number 0.04
    """
    if x_op is None:
        return np.zeros(size) if default is None else as_vector(default, "x_op", size)
    if np.ndim(x_op) == 0 and not isinstance(x_op, str | bytes):
        raise InvalidArgumentError(
            "x_op", f"an operating point of {size} states (the sample time comes after it: dt=...)",
            f"the number {x_op!r}",
        )
    return as_vector(x_op, "x_op", size)


def sample_time(dt: Any) -> float:
    """The ``dt`` argument of a discretisation: a number > 0 (s); ``None`` (left out) is an error.

    Examples
    --------
    >>> from models.linear import sample_time
    >>> sample_time(None)
    Traceback (most recent call last):
    ...
    toolkit_common.errors.ArgumentTypeError: dt: expected a sample time > 0 (s), but found nothing \
(dt is required)
    """
    if dt is None:
        raise ArgumentTypeError("dt", "a sample time > 0 (s)", "nothing (dt is required)")
    return check_positive(dt, "dt")


def relative_spread(spread: Any, name: str = "spread") -> float:
    """The relative half-width ``s`` in ``[0, 1)`` of an inertia uncertainty ``J in [(1 - s) J, (1 + s) J]``.

    ``None`` (left out) is an error naming the argument.

    Examples
    --------
    >>> from models.linear import relative_spread
    >>> relative_spread(0.3)
    0.3
    >>> relative_spread(1.2)
    Traceback (most recent call last):
    ...
    toolkit_common.errors.InvalidArgumentError: spread: expected a relative spread in [0, 1), but found 1.2
    """
    if spread is None:
        raise ArgumentTypeError(name, "a relative spread in [0, 1)", f"nothing ({name} is required)")
    s = check_positive(spread, name, allow_zero=True)
    if s >= 1.0:
        raise InvalidArgumentError(name, "a relative spread in [0, 1)", repr(s))
    return s


def zoh(a: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Discretise ``x' = A x + B u`` with a zero-order hold on ``u`` over ``dt``.

    Uses the exponential of the block matrix ``[[A, B], [0, 0]] dt`` (Van Loan), which gives
    ``Ad = e^{A dt}`` and ``Bd = int_0^dt e^{A s} ds B`` exactly, also for singular ``A``.

    Parameters
    ----------
    a : (n, n) array_like
    b : (n, m) array_like
    dt : float
        Sample time in seconds, > 0.

    Returns
    -------
    ad, bd : ndarray
        The discrete-time matrices.

    Examples
    --------
    >>> import numpy as np
    >>> from models import zoh
    >>> ad, bd = zoh([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], 0.1)
    >>> np.allclose(bd.ravel(), [0.005, 0.1])
    True
    """
    a = as_matrix(a, "a")
    n = a.shape[0]
    a = as_matrix(a, "a", (n, n))
    b = as_matrix(b, "b", (n, None))
    dt = check_positive(dt, "dt")
    m = b.shape[1]
    block = np.zeros((n + m, n + m))
    block[:n, :n] = a
    block[:n, n:] = b
    phi = expm(block * dt)
    return phi[:n, :n], phi[:n, n:]


class PolytopicModel:
    """A discrete-time linear model whose ``[A B]`` lies in the convex hull of vertices.

    Parameters
    ----------
    vertices : sequence of (A, B) pairs
        Each ``A`` is ``(n, n)`` and each ``B`` is ``(n, m)``, all of the same sizes.
        At least one vertex.
    dt : float
        Sample time in seconds (> 0). The model is discrete-time.
    nominal : (A, B) pair, optional
        The nominal model (for prediction, reference models, reports). Defaults to the mean
        of the vertices, which lies inside the polytope.
    state_names, input_names : sequence of str, optional
        Names used in reports and in python-control conversions.
    attitude : {"euler321", "quaternion_vector"} or None
        What the first three states hold: 3-2-1 Euler angles (rad), the vector part of a unit
        quaternion with non-negative scalar part, or no attitude (``None``, the default). It
        tells :meth:`attitude_euler` (and the reports of a run on this model) how to read them.

    Examples
    --------
    >>> import numpy as np
    >>> from models import PolytopicModel
    >>> A = np.array([[1.0, 0.1], [0.0, 1.0]])
    >>> plant = PolytopicModel([(A, [[0.0], [0.1]]), (A, [[0.0], [0.2]])], dt=0.1)
    >>> plant.n_states, plant.n_inputs, plant.n_vertices
    (2, 1, 2)
    >>> plant.nominal[1].ravel().tolist()
    [0.0, 0.15000000000000002]
    """

    def __init__(
        self,
        vertices: Sequence[tuple[Any, Any]],
        dt: float,
        nominal: tuple[Any, Any] | None = None,
        state_names: Sequence[str] | None = None,
        input_names: Sequence[str] | None = None,
        attitude: AttitudeCoordinates | None = None,
    ) -> None:
        if isinstance(vertices, np.ndarray) or not isinstance(vertices, Sequence):
            raise ArgumentTypeError(
                "vertices", "a sequence of (A, B) pairs", type(vertices).__name__
            )
        if len(vertices) == 0:
            raise InvalidArgumentError("vertices", "at least one (A, B) pair", "an empty sequence")
        a_list: list[np.ndarray] = []
        b_list: list[np.ndarray] = []
        n = m = None
        for j, pair in enumerate(vertices):
            if not isinstance(pair, Sequence) or len(pair) != 2:
                raise InvalidArgumentError(
                    f"vertices[{j}]", "an (A, B) pair", f"{type(pair).__name__}"
                )
            a = as_matrix(pair[0], f"vertices[{j}] A")
            if n is None:
                n = a.shape[0]
                if n == 0:
                    raise InvalidArgumentError(f"vertices[{j}] A", "at least one state", "shape (0, 0)")
            a = as_matrix(a, f"vertices[{j}] A", (n, n))
            b = as_matrix(pair[1], f"vertices[{j}] B", (n, m))
            if m is None:
                m = b.shape[1]
                if m == 0:
                    raise InvalidArgumentError(f"vertices[{j}] B", "at least one input", f"shape {b.shape}")
            a_list.append(a)
            b_list.append(b)
        assert n is not None and m is not None
        self._a = np.stack(a_list)
        self._b = np.stack(b_list)
        self._a.setflags(write=False)
        self._b.setflags(write=False)
        self._dt = check_positive(dt, "dt")
        if nominal is None:
            a_nom, b_nom = self._a.mean(axis=0), self._b.mean(axis=0)
        else:
            if not isinstance(nominal, Sequence) or len(nominal) != 2:
                raise InvalidArgumentError("nominal", "an (A, B) pair", type(nominal).__name__)
            a_nom = as_matrix(nominal[0], "nominal A", (n, n))
            b_nom = as_matrix(nominal[1], "nominal B", (n, m))
        a_nom.setflags(write=False)
        b_nom.setflags(write=False)
        self._nominal = (a_nom, b_nom)
        self.state_names = self._names(state_names, "state_names", n, "x")
        self.input_names = self._names(input_names, "input_names", m, "u")
        if attitude is not None:
            check_choice(attitude, "attitude", (*ATTITUDE_FORMS, None))
            if n < 3:
                raise InvalidArgumentError(
                    "attitude", "None for a model with fewer than 3 states", f"{attitude!r} with {n} states"
                )
        self._attitude: AttitudeCoordinates | None = attitude

    @staticmethod
    def _names(names: Sequence[str] | None, arg: str, size: int, prefix: str) -> tuple[str, ...]:
        if names is None:
            return tuple(f"{prefix}[{i}]" for i in range(size))
        names = tuple(str(s) for s in names)
        if len(names) != size:
            raise InvalidArgumentError(arg, f"{size} names", f"{len(names)}")
        return names

    # -- sizes and data ----------------------------------------------------------------
    @property
    def n_states(self) -> int:
        """Number of states ``n``."""
        return int(self._a.shape[1])

    @property
    def n_inputs(self) -> int:
        """Number of inputs ``m``."""
        return int(self._b.shape[2])

    @property
    def n_vertices(self) -> int:
        """Number of vertices of the polytope."""
        return int(self._a.shape[0])

    @property
    def dt(self) -> float:
        """Sample time in seconds."""
        return self._dt

    @property
    def A(self) -> np.ndarray:
        """Vertex state matrices, shape ``(n_vertices, n, n)`` (read-only)."""
        return self._a

    @property
    def B(self) -> np.ndarray:
        """Vertex input matrices, shape ``(n_vertices, n, m)`` (read-only)."""
        return self._b

    @property
    def vertices(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The vertices as a list of ``(A, B)`` pairs."""
        return [(self._a[j], self._b[j]) for j in range(self.n_vertices)]

    @property
    def nominal(self) -> tuple[np.ndarray, np.ndarray]:
        """The nominal ``(A, B)``."""
        return self._nominal

    @property
    def attitude(self) -> AttitudeCoordinates | None:
        """What the first three states hold: ``"euler321"``, ``"quaternion_vector"`` or ``None``."""
        return self._attitude

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:
        """Roll, pitch and yaw (rad, 3-2-1) of the attitude in the first three states of ``x``.

        Parameters
        ----------
        x : array_like, shape (n_states,) or (k, n_states)
            One state or ``k`` states as rows; the result has shape ``(3,)`` or ``(k, 3)``.

        Raises
        ------
        InvalidArgumentError
            Naming ``attitude`` when the model holds no attitude (``attitude=None``); naming
            ``x`` when a quaternion vector part has norm above 1.

        Examples
        --------
        >>> import numpy as np
        >>> from models import PolytopicModel
        >>> a, b = np.eye(6), np.zeros((6, 3))
        >>> PolytopicModel([(a, b)], dt=0.1, attitude="euler321").attitude_euler(np.arange(6.0)).tolist()
        [0.0, 1.0, 2.0]
        >>> qv = np.sin(0.25) * np.array([1.0, 0.0, 0.0])   # 0.5 rad about x
        >>> model = PolytopicModel([(a, b)], dt=0.1, attitude="quaternion_vector")
        >>> bool(np.allclose(model.attitude_euler(np.r_[qv, np.zeros(3)]), [0.5, 0.0, 0.0]))
        True
        """
        if self._attitude is None:
            raise InvalidArgumentError(
                "attitude",
                "'euler321' or 'quaternion_vector' to read an attitude (this model was built with "
                "attitude=None: its states hold none)",
                "None",
            )
        if self._attitude == "euler321":
            return map_states(lambda s: s[:3].copy(), x, self.n_states)
        return map_states(_quaternion_vector_to_euler, x, self.n_states)

    def vertex(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Return vertex ``index`` as an ``(A, B)`` pair."""
        n_vertices = self.n_vertices
        if isinstance(index, bool) or not isinstance(index, int | np.integer) or not 0 <= index < n_vertices:
            raise InvalidArgumentError(
                "index", f"an integer in [0, {self.n_vertices - 1}]", repr(index)
            )
        return self._a[index], self._b[index]

    def combination(self, weights: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Return ``sum_j w_j (A_j, B_j)`` for convex weights ``w`` (non-negative, sum 1)."""
        w = as_vector(weights, "weights", self.n_vertices)
        if np.any(w < -1e-12) or abs(w.sum() - 1.0) > 1e-9:
            raise InvalidArgumentError(
                "weights", "non-negative weights that sum to 1", f"{w.tolist()} (sum {w.sum():.6g})"
            )
        return np.tensordot(w, self._a, axes=1), np.tensordot(w, self._b, axes=1)

    # -- python-control ----------------------------------------------------------------
    def to_statespace(self, vertex: int | None = None) -> control.StateSpace:
        """Return a python-control ``StateSpace`` (full-state output) of a vertex or the nominal.

        Parameters
        ----------
        vertex : int, optional
            Vertex index; ``None`` gives the nominal model.
        """
        import control

        a, b = self.nominal if vertex is None else self.vertex(vertex)
        n, m = self.n_states, self.n_inputs
        return control.ss(
            a, b, np.eye(n), np.zeros((n, m)), self.dt,
            states=list(self.state_names), inputs=list(self.input_names),
            outputs=[f"y_{s}" for s in self.state_names],
        )

    def to_statespace_list(self) -> list[control.StateSpace]:
        """Return every vertex as a python-control ``StateSpace``."""
        return [self.to_statespace(j) for j in range(self.n_vertices)]

    @classmethod
    def from_statespace(
        cls,
        systems: control.StateSpace | Sequence[control.StateSpace],
        nominal: control.StateSpace | None = None,
        attitude: AttitudeCoordinates | None = None,
    ) -> PolytopicModel:
        """Build a polytope from python-control discrete-time ``StateSpace`` vertices.

        Parameters
        ----------
        systems : StateSpace or sequence of StateSpace
            Discrete-time systems with a common, positive ``dt`` and equal sizes. Only ``A``
            and ``B`` are used (the polytope is in the state equation); the state and input
            names are the first system's signal labels (python-control's ``x[0]``, ``u[0]``,
            ... unless the system was built with its own ``states=`` / ``inputs=``).
        nominal : StateSpace, optional
            The nominal system; defaults to the mean of the vertices.
        attitude : {"euler321", "quaternion_vector"} or None
            What the first three states hold (see :class:`PolytopicModel`).
        """
        import control

        if isinstance(systems, control.StateSpace):
            systems = [systems]
        if not isinstance(systems, Sequence) or len(systems) == 0:
            raise InvalidArgumentError(
                "systems", "a StateSpace or a non-empty sequence of them", type(systems).__name__
            )
        dts = []
        for j, sys in enumerate(systems):
            if not isinstance(sys, control.StateSpace):
                raise ArgumentTypeError(f"systems[{j}]", "a control.StateSpace", type(sys).__name__)
            if sys.dt is None or sys.dt is True or not sys.dt > 0:
                raise InvalidArgumentError(
                    f"systems[{j}].dt", "a discrete-time system with a numeric dt > 0", repr(sys.dt)
                )
            dts.append(float(sys.dt))
        if max(dts) - min(dts) > 1e-12 * max(dts):
            raise InvalidArgumentError("systems", "a common dt", f"dt values {dts}")
        nom = None if nominal is None else (nominal.A, nominal.B)
        first = systems[0]
        return cls(
            [(s.A, s.B) for s in systems], dt=dts[0], nominal=nom, attitude=attitude,
            state_names=list(getattr(first, "state_labels", None) or []) or None,
            input_names=list(getattr(first, "input_labels", None) or []) or None,
        )

    def __repr__(self) -> str:
        return (
            f"PolytopicModel(n_states={self.n_states}, n_inputs={self.n_inputs}, "
            f"n_vertices={self.n_vertices}, dt={self.dt:g})"
        )


def _quaternion_vector_to_euler(state: np.ndarray) -> np.ndarray:
    """3-2-1 Euler angles of the unit quaternion ``[sqrt(1 - |q_v|^2), q_v]``, ``q_v = state[:3]``."""
    qv = state[:3]
    norm2 = float(qv @ qv)
    if norm2 > 1.0 + 1e-12:
        raise InvalidArgumentError(
            "x", "a quaternion vector part with |q_v| <= 1 in the first three states (attitude="
            "'quaternion_vector')", f"|q_v| = {np.sqrt(norm2):.6g}",
        )
    q0 = np.sqrt(max(0.0, 1.0 - norm2))
    return quat_to_euler321(np.concatenate(([q0], qv)) / np.sqrt(q0 * q0 + norm2))


def unreachable_modes(a: np.ndarray, b: np.ndarray, *, only_unstable: bool = False,
                      tol: float = 1e-9) -> list[complex]:
    """The eigenvalues of ``a`` that the input matrix ``b`` cannot move (the PBH test).

    ``rank [a - lambda I, b] < n``, the rank read from the singular values relative to the
    largest; with ``only_unstable`` only modes with ``|lambda| >= 1 - tol`` are tested. By
    duality, ``unreachable_modes(a.T, c.T)`` are the modes of ``a`` that ``c`` does not see.
    """
    n = a.shape[0]
    found = []
    for lam in np.linalg.eigvals(a):
        if only_unstable and abs(lam) < 1.0 - tol:
            continue
        sv = np.linalg.svd(np.hstack([a - lam * np.eye(n), b]), compute_uv=False)
        if sv[-1] <= 1e-9 * max(1.0, sv[0]):
            found.append(complex(lam))
    return found
