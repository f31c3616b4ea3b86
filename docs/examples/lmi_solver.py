"""The LMI solver: the default back-end "ipm" against "clarabel" on paper P's 2-vertex problem."""

import numpy as np

from lmi import KothareProblem
from lmi.ipm import BlockLMISolver
from models import RigidSatellite

sat = RigidSatellite.paper_p()
x0 = sat.initial_state()
poly = sat.polytope(x0, 0.01, 0.3, "scalar")  # 2 vertices, (1 +- 0.3) J
Q1 = np.diag([1, 1, 1, 0.1, 0.1, 0.1])
R = np.eye(3)
settings = dict(dt=poly.dt, u_max=1.0)

ipm = KothareProblem(poly.A, poly.B, Q1, R, **settings)  # backend="ipm", the default
cold = KothareProblem(poly.A, poly.B, Q1, R, solver_options={"warm_start": False}, **settings)
clarabel = KothareProblem(poly.A, poly.B, Q1, R, backend="clarabel", **settings)

# 20 steps of the closed loop on vertex 0 with the IPM's gain; all three solve at every state.
a0, b0 = poly.vertex(0)
x = x0
iterations = {"ipm": [], "cold": [], "clarabel": []}
worst_rel_diff = 0.0
for k in range(21):
    sol, sol_cold, ref = ipm.solve(x), cold.solve(x), clarabel.solve(x)
    for name, s in (("ipm", sol), ("cold", sol_cold), ("clarabel", ref)):
        iterations[name].append(s.iterations)
    worst_rel_diff = max(worst_rel_diff, abs(sol.gamma / ref.gamma - 1))
    if k % 5 == 0:
        # the IPM's answer is strictly feasible up to rounding; Clarabel's within its tolerance
        ipm_ok = sol.certificate.worst >= -1e-12
        ref_ok = ref.certificate.worst >= -1e-7
        print(f"state {k:2d}: ipm {sol.status} {sol.gamma:.6g}, clarabel {ref.status} {ref.gamma:.6g};"
              f" margins ok {ipm_ok} {ref_ok}")
    x = a0 @ x + b0 @ (sol.F @ x)
print("iterations at state 0:", {name: its[0] for name, its in iterations.items()})
print("median iterations, states 1-20:", {name: int(np.median(its[1:])) for name, its in iterations.items()})
print(f"largest relative difference in gamma below 1e-6: {worst_rel_diff < 1e-6}")

# A problem without a solution: Kothare's example 1 with |x1(k+i)| <= 0.01 at x1 = 0.05.
# The IPM proves it infeasible from its own run (a Farkas ray, checked on the conic data).
A = [np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]) for alpha in (0.1, 10.0)]
B = [np.array([[0.0], [0.1 * 0.787]])] * 2
bad = KothareProblem(A, B, Q=np.diag([1.0, 0.0]), R=[[2e-5]], dt=0.1, input_constraint="peak",
                     u_max=2.0, output_matrix=[[1.0, 0.0]], y_max=0.01)
sol = bad.solve([0.05, 0.0])
print("infeasible problem:", sol.status, "| solver_status:", sol.solver_status, "| proof checked:",
      sol.infeasibility.ok)

# BlockLMISolver directly: the largest eigenvalue of M is min t subject to t I - M >= 0.
M = np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 1.0], [0.0, 1.0, 2.0]])
res = BlockLMISolver([1.0], [(-M, -np.eye(3)[None])]).solve()
print(f"lambda_max: {res.status} {res.x[0]:.6f} (eigvalsh: {np.linalg.eigvalsh(M)[-1]:.6f})")
