"""Guide: the status words the controllers report, and what each one does with its answer."""

import numpy as np

from models import PolytopicModel
from rmpc import LQR, RMPC, OfflineRMPC, StepInputs, simulate
from toolkit_common.status import is_usable


def show(name, ctrl, u):
    """One line per step: the word, whether it is usable, the fallback flag, the applied input."""
    status = ctrl.last.status
    print(f"{name:32s} {status!s:11s} usable={is_usable(status)!s:5s} "
          f"fallback={ctrl.last.fallback!s:5s} u={float(u[0]):+.4f}")


# Kothare's example 1 (angular positioning), alpha in [0.1, 10]: a 2-vertex polytope.
A = [np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]) for alpha in (0.1, 10.0)]
B = [np.array([[0.0], [0.1 * 0.787]])] * 2
plant = PolytopicModel(vertices=list(zip(A, B, strict=True)), dt=0.1)
Q1, R = np.diag([1.0, 0.0]), np.array([[2e-5]])
x0 = np.array([0.05, 0.0])

rmpc = RMPC(plant, Q1, R, u_max=2.0, input_constraint="peak")
show("RMPC, solve at x0", rmpc, rmpc.step(x0))
show("RMPC, at the origin", rmpc, rmpc.step(np.zeros(2)))

# An unstable scalar plant, x(k+1) = 1.2 x(k) + 0.1 u(k): only |u| >= 0.2 |x| stabilises it,
# so at x = 1 a bound of 0.01 leaves the LMIs without a solution. The controller applies its
# last certified gain (here from a solve at x = 0.01 with the bound 1) and flags the step.
scalar = PolytopicModel(vertices=[(np.array([[1.2]]), np.array([[0.1]]))], dt=0.1)
tight = RMPC(scalar, np.eye(1), np.eye(1), u_max=1.0)
show("RMPC, solve at x = 0.01", tight, tight.step(np.array([0.01])))
gain = float(tight.gain[0, 0])
u = tight.step(np.array([1.0]), StepInputs(u_max=0.01))
show("RMPC, bound 0.01 at x = 1", tight, u)
print(f"  applied the kept gain {gain:.4f}: {bool(np.isclose(u[0], gain))}; "
      f"inside its ellipsoid: {tight.last.extra['inside_ellipsoid']}")

# With resolve_threshold < 1 a gain is kept while the state stays in the outer part of its
# ellipsoid: "reused" steps cost no solve.
kept = RMPC(plant, Q1, R, u_max=2.0, input_constraint="peak", resolve_threshold=0.5)
words, counts = np.unique(simulate(kept, plant, x0, n_steps=30).status, return_counts=True)
print("RMPC, resolve_threshold=0.5:", dict(zip(words.tolist(), counts.tolist(), strict=True)))

lqr = LQR(plant, Q1, R)
show("LQR", lqr, lqr.step(x0))

table = OfflineRMPC(plant, Q1, R, u_max=2.0, input_constraint="peak", x_design=x0, n_ellipsoids=5)
show("OfflineRMPC, inside its table", table, table.step(0.5 * x0))
show("OfflineRMPC, outside its table", table, table.step(3 * x0))
