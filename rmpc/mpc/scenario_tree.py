"""The scenario tree of multi-stage MPC over a polytope's vertices, and its size.

Multi-stage (scenario-tree) MPC (Lucia, Finkler & Engell, "Multi-stage nonlinear model
predictive control applied to a semi-batch polymerization reactor under uncertainty", Journal
of Process Control 23(9), 2013) predicts over a tree: at every stage of the first
``robust_horizon`` stages each node branches into one child per vertex ``(A_j, B_j)``; after
that each branch keeps the vertex of its last branching up to the horizon. A node carries one
state and (up to the last stage) one input: the input of a node is shared by every scenario
passing through it (non-anticipativity), so the inputs form a causal policy.

With ``V`` vertices, robust horizon ``Nr`` and horizon ``N`` the stage ``k`` has
``V ** min(k, Nr)`` nodes; the tree has ``V ** Nr`` scenarios (leaves). :func:`tree_size`
counts the QP this makes before anything is built, so a tree too large is refused with its
estimate (:data:`MAX_VARIABLES`).

Examples
--------
>>> from rmpc.mpc.scenario_tree import ScenarioTree, tree_size
>>> tree = ScenarioTree(n_vertices=2, horizon=3, robust_horizon=1)
>>> tree.nodes_per_stage
(1, 2, 2, 2)
>>> tree.scenarios
2
>>> tree_size(2, 3, 1, n_states=6, n_inputs=3)["variables"]
51
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_count

__all__ = ["MAX_VARIABLES", "ScenarioTree", "check_tree_size", "tree_size"]

#: Default bound on the QP variables of a tree (inputs and states of all its nodes). Measured
#: with Clarabel on paper P's satellite (``dev/multistage_timing.py``, docs/multistage.rst): 8
#: vertices, robust horizon 3 and horizon 10 make 35 979 variables, built in about 0.6 s and
#: solved in 1.7 s per sample on a shared 2-core machine at a load of 7 (5067 variables: 0.18 s,
#: so about linear in the variables), so 50 000 variables stand for a step of 2-3 s.
#: ``MultiStageMPC(..., max_variables=N)`` lifts it.
MAX_VARIABLES = 50_000


def tree_size(
    n_vertices: int,
    horizon: int,
    robust_horizon: int,
    *,
    n_states: int,
    n_inputs: int,
    state_rows: int = 0,
) -> dict[str, int]:
    """The size of the tree and of its QP, computed without building either.

    Parameters
    ----------
    n_vertices, horizon, robust_horizon : int
        ``V``, ``N`` and ``Nr`` (``1 <= Nr <= N``).
    n_states, n_inputs : int
        ``n`` and ``m``.
    state_rows : int
        Rows of the state polytope ``H x <= h`` imposed at every predicted node.

    Returns
    -------
    dict
        ``scenarios`` (``V ** Nr``), ``input_nodes``, ``state_nodes`` (stages 1 to ``N``),
        ``variables`` (``m * input_nodes + n * state_nodes``), ``equality_rows`` (the
        dynamics, ``n * state_nodes``) and ``inequality_rows`` (``state_rows * state_nodes``).
    """
    counts = [n_vertices ** min(k, robust_horizon) for k in range(horizon + 1)]
    input_nodes = sum(counts[:-1])
    state_nodes = sum(counts[1:])
    return {
        "scenarios": n_vertices**robust_horizon,
        "input_nodes": input_nodes,
        "state_nodes": state_nodes,
        "variables": n_inputs * input_nodes + n_states * state_nodes,
        "equality_rows": n_states * state_nodes,
        "inequality_rows": state_rows * state_nodes,
    }


def check_tree_size(
    size: dict[str, int], limit: int, n_vertices: int, horizon: int, robust_horizon: int
) -> None:
    """Raise :class:`~toolkit_common.errors.InvalidArgumentError` naming ``robust_horizon`` when
    ``size["variables"]`` exceeds ``limit``, with the estimate."""
    if size["variables"] > limit:
        raise InvalidArgumentError(
            "robust_horizon",
            f"a scenario tree of at most max_variables = {limit} QP variables (pass a larger "
            "max_variables to lift it, or a smaller robust_horizon)",
            f"robust_horizon = {robust_horizon} with {n_vertices} vertices and horizon {horizon}: "
            f"{size['scenarios']} scenarios, {size['variables']} variables, "
            f"{size['equality_rows'] + size['inequality_rows']} constraint rows",
        )


@dataclass(frozen=True)
class ScenarioTree:
    """The nodes of a scenario tree over ``n_vertices`` vertices.

    Nodes of stage ``k`` are numbered ``0 .. V ** min(k, Nr) - 1``. For ``k < Nr`` node ``i``
    has the children ``i * V + j`` (vertex ``j``); for ``k >= Nr`` its one child is node
    ``i`` of the next stage, reached by vertex ``i % V`` (the vertex of the branch's last
    branching, which the branch keeps).

    Parameters
    ----------
    n_vertices, horizon, robust_horizon : int
        ``V >= 1``, ``N >= 1`` and ``1 <= Nr <= N``.
    """

    n_vertices: int
    horizon: int
    robust_horizon: int

    def __post_init__(self) -> None:
        check_count(self.n_vertices, "n_vertices")
        check_count(self.horizon, "horizon")
        check_count(self.robust_horizon, "robust_horizon")
        if self.robust_horizon > self.horizon:
            raise InvalidArgumentError(
                "robust_horizon", f"an integer in [1, horizon = {self.horizon}]", repr(self.robust_horizon)
            )

    @property
    def nodes_per_stage(self) -> tuple[int, ...]:
        """Nodes of stages ``0 .. N``."""
        return tuple(self.n_vertices ** min(k, self.robust_horizon) for k in range(self.horizon + 1))

    @property
    def scenarios(self) -> int:
        """Leaves of the tree, ``V ** Nr``."""
        return int(self.n_vertices**self.robust_horizon)

    def transitions(self, stage: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The edges from stage ``stage`` to ``stage + 1``: ``(parent, child, vertex)`` arrays.

        Examples
        --------
        >>> from rmpc.mpc.scenario_tree import ScenarioTree
        >>> t = ScenarioTree(n_vertices=2, horizon=3, robust_horizon=1)
        >>> [a.tolist() for a in t.transitions(0)], [a.tolist() for a in t.transitions(1)]
        ([[0, 0], [0, 1], [0, 1]], [[0, 1], [0, 1], [0, 1]])
        """
        if not 0 <= stage < self.horizon:
            raise InvalidArgumentError("stage", f"an integer in [0, {self.horizon - 1}]", repr(stage))
        v = self.n_vertices
        parents = np.arange(self.nodes_per_stage[stage])
        if stage < self.robust_horizon:
            parent = np.repeat(parents, v)
            vertex = np.tile(np.arange(v), parents.size)
            child = parent * v + vertex
        else:
            parent = parents
            child = parents.copy()
            vertex = parents % v
        return parent, child, vertex

    def probabilities(self) -> tuple[float, ...]:
        """The weight of one node of each stage: the share of scenarios passing through it
        (``1 / V ** min(k, Nr)``, every scenario equally likely)."""
        return tuple(1.0 / c for c in self.nodes_per_stage)
