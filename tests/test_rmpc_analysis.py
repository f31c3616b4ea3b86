"""rmpc.analysis: the certified region along directions and the ellipsoid's projection, checked
against closed forms (a scalar plant's boundary, an ellipse's support function)."""

from __future__ import annotations

import numpy as np
import pytest

from models import PolytopicModel
from rmpc import RMPC
from rmpc.analysis import ellipse_points, feasible_region, plot_ellipsoid
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError


def scalar(u_max: float | None) -> RMPC:
    """``x+ = 2 x + u``: a certified gain needs ``|2 + F| < 1`` (``|F| > 1``) and, with a bound,
    ``|F x| <= u_max``: the region is ``|x| < u_max``."""
    plant = PolytopicModel([(np.array([[2.0]]), np.array([[1.0]]))], dt=1.0)
    return RMPC(plant, Q=np.eye(1), R=np.eye(1), u_max=u_max)


@pytest.mark.parametrize("u_max", [0.5, 3.0])
def test_the_boundary_of_a_scalar_plant_is_its_closed_form(u_max: float) -> None:
    region = feasible_region(scalar(u_max), [[1.0], [-2.0]], rel_tol=1e-4)
    np.testing.assert_allclose(np.abs(region.points[:, 0]), u_max, rtol=2e-4)
    assert not region.capped.any() and region.limits[0] != "cap"
    assert sum(region.status_counts.values()) > 10 and region.status_counts.get("optimal", 0) > 0


def test_a_region_without_bounds_is_capped_not_bounded() -> None:
    region = feasible_region(scalar(None), [[1.0]], t_max=64.0)
    assert region.capped.all() and region.t[0] == 64.0 and region.limits == ("cap",)


def test_the_projection_has_the_support_function_of_the_ellipsoid() -> None:
    """``max over {x' Q^-1 x <= 1}`` of ``c' x_dims`` is ``sqrt(c' Q_dims c)``: the drawn ellipse
    reaches it in every direction (to its sampling) and never exceeds it."""
    rng = np.random.default_rng(3)
    g = rng.normal(size=(4, 4))
    q = g @ g.T + 0.1 * np.eye(4)
    pts = ellipse_points(q, dims=(1, 3), n_points=4000)
    block = q[np.ix_([1, 3], [1, 3])]
    for angle in np.linspace(0.0, np.pi, 7):
        c = np.array([np.cos(angle), np.sin(angle)])
        support = np.sqrt(c @ block @ c)
        assert (pts @ c).max() <= support * (1 + 1e-12) + 1e-12
        assert (pts @ c).max() >= support * (1 - 1e-6)


def test_plot_ellipsoid_takes_a_solution_and_draws_its_projection() -> None:
    import matplotlib

    matplotlib.use("Agg")
    sol = scalar(3.0).solve([1.0])
    plant = PolytopicModel([(np.eye(2), np.eye(2))], dt=1.0)
    two = RMPC(plant, Q=np.eye(2), R=np.eye(2), u_max=1.0).solve([0.5, 0.2])
    ax = plot_ellipsoid(two, names=("a", "b"), color="k")
    line = ax.lines[0]
    np.testing.assert_allclose(np.c_[line.get_xdata(), line.get_ydata()], ellipse_points(two.Q))
    assert ax.get_xlabel() == "a" and sol.Q.shape == (1, 1)


def test_bad_input_names_the_argument() -> None:
    ctrl = scalar(1.0)
    with pytest.raises(InvalidArgumentError, match="directions: expected non-zero rows"):
        feasible_region(ctrl, [[0.0]])
    with pytest.raises(InvalidArgumentError, match=r"directions: expected a finite \(k, 1\)"):
        feasible_region(ctrl, [[1.0, 2.0]])
    with pytest.raises(InvalidArgumentError, match="t_max: expected a cap > 1"):
        feasible_region(ctrl, [[1.0]], t_max=0.5)
    with pytest.raises(InvalidArgumentError, match="budget_s: expected seconds > 0"):
        feasible_region(ctrl, [[1.0]], budget_s="soon")
    assert feasible_region(ctrl, [[1.0]], budget_s=np.int64(60)).t.shape == (1,)
    with pytest.raises(ArgumentTypeError, match="ctrl"):
        feasible_region(object(), [[1.0]])
    with pytest.raises(InvalidArgumentError, match="Q: expected a positive definite"):
        ellipse_points(-np.eye(2))
    with pytest.raises(InvalidArgumentError, match="dims"):
        ellipse_points(np.eye(2), dims=(0, 0))


def test_a_certified_inaccurate_answer_counts_as_inside_and_an_uncertified_one_does_not():
    """The region is where a certified gain exists: the controller applies an "inaccurate" answer
    whose certificate holds, so the search must count it (and stop at one whose certificate fails)."""
    from types import SimpleNamespace

    from rmpc.analysis import boundary_along

    class Fake:
        def __init__(self, edge: float, ok_beyond: bool) -> None:
            self.edge, self.ok_beyond = edge, ok_beyond

        def solve(self, x):
            t = float(np.linalg.norm(x))
            if t <= self.edge:
                return SimpleNamespace(status="optimal", certificate=SimpleNamespace(ok=True))
            if t <= 3.0 * self.edge:
                return SimpleNamespace(status="inaccurate", certificate=SimpleNamespace(ok=self.ok_beyond))
            return SimpleNamespace(status="infeasible", certificate=None)

    t_cert, why = boundary_along(Fake(2.0, True), np.array([1.0, 0.0]))
    assert t_cert == pytest.approx(6.0, rel=2e-3) and why == "infeasible"
    t_uncert, why = boundary_along(Fake(2.0, False), np.array([1.0, 0.0]))
    assert t_uncert == pytest.approx(2.0, rel=2e-3) and why == "inaccurate"
