"""Theory: example 1 of Kothare, Balakrishnan & Morari (1996), angular positioning."""

import matplotlib.pyplot as plt
import numpy as np

from lmi import KothareProblem
from models import PolytopicModel
from rmpc import RMPC, simulate

# x = [angle, angular rate], Ts = 0.1 s; alpha in [0.1, 10] gives a 2-vertex polytope.
A = [np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]) for alpha in (0.1, 10.0)]
B = [np.array([[0.0], [0.1 * 0.787]])] * 2
Q1, R = np.diag([1.0, 0.0]), np.array([[2e-5]])
x0 = np.array([0.05, 0.0])

prob = KothareProblem(A, B, Q=Q1, R=R, dt=0.1, input_constraint="peak", u_max=2.0)
sol = prob.solve(x0)
print("status:", sol.status)
print(f"gamma(x0) = {sol.gamma:.4g}")
print("F(x0) =", np.round(sol.F, 2))
print(f"u(0) = F x0 = {(sol.F @ x0)[0]:.4g}")

# The realised cost on each vertex plant (30 steps, |u| <= 2) stays below gamma(x0).
plant = PolytopicModel(vertices=list(zip(A, B, strict=True)), dt=0.1)
ctrl = RMPC(plant, Q=Q1, R=R, u_max=2.0, input_constraint="peak")
fig, (ax_x, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.0))
for vertex in (0, 1):
    traj = simulate(ctrl, plant, x0, n_steps=30, true_plant=vertex)
    x, u = traj.x[:-1], traj.u_applied
    cost = np.einsum("ki,ij,kj->", x, Q1, x) + np.einsum("ki,ij,kj->", u, R, u)
    print(f"vertex {vertex}: cost {cost:.4g}, max |u| {np.abs(u).max():.4g}")
    ax_x.plot(traj.t, traj.x[:, 0], label=f"vertex {vertex} (alpha = {(0.1, 10.0)[vertex]})")
    ax_u.step(traj.t[:-1], u[:, 0], where="post")
ax_x.set_ylabel("angle (rad)")
ax_x.legend()
ax_u.set_ylabel("input u")
ax_u.set_xlabel("time (s)")
fig.tight_layout()
plt.show()
