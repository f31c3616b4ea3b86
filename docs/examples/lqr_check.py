"""Theory: with one vertex and no constraint, robust MPC is LQR (u = F x, F = -K)."""

import control
import numpy as np

from models import RigidSatellite
from rmpc import RMPC

sat = RigidSatellite.paper_p()
x0 = sat.initial_state()
nominal = sat.linear_model(x0, 0.01)  # a PolytopicModel with one vertex
A, B = nominal.A[0], nominal.B[0]
Q1, R = np.diag([1, 1, 1, 0.1, 0.1, 0.1]), np.eye(3)

K, P, _ = control.dlqr(A, B, Q1, R)  # python-control: u = -K x
sol = RMPC(nominal, Q=Q1, R=R).solve(x0)  # no u_max: no input constraint
print("status:", sol.status)
print(f"gamma = {sol.gamma:.7g}, x0' P x0 = {x0 @ P @ x0:.7g}")
print("F close to -K (max |F + K| < 0.1):", bool(np.abs(sol.F + K).max() < 0.1))
print("F close to +K:", bool(np.abs(sol.F - K).max() < 0.1))
