"""Quickstart: LQR on the nonlinear rigid satellite of paper P."""

import matplotlib.pyplot as plt
import numpy as np

from models import RigidSatellite
from rmpc import LQR, simulate

# Paper P's satellite, diag(1.2928, 1.2928, 4.2953) kg m^2, and its initial state
# (roll 0.362, pitch 0.524, yaw -0.262 rad, zero body rates).
sat = RigidSatellite.paper_p()
x0 = sat.initial_state()

# Linearise at x0, discretise with a zero-order hold at Ts = 0.01 s, and wrap a +-30 %
# inertia uncertainty into a polytope: "scalar" mode gives 2 vertices.
plant = sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar")
print(plant)

# A discrete LQR gain designed on the polytope's nominal model (u = F x).
lqr = LQR(plant, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]), R=np.eye(3))

# 20 s in closed loop on the nonlinear satellite (not on the linear model).
traj = simulate(lqr, sat, x0, duration=20.0, dt=0.01)

print("final attitude (deg):", np.round(traj.attitude_deg[-1], 4))
print("largest torque (N m):", round(float(np.abs(traj.u_applied).max()), 4))
print("step statuses:", traj.status_counts())

# The attitude and the torques over the run (plt.show() opens a window).
fig, (ax_x, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.4))
for axis, name in enumerate(("roll", "pitch", "yaw")):
    ax_x.plot(traj.t, traj.attitude_deg[:, axis], label=name)
    ax_u.plot(traj.t[:-1], traj.u_applied[:, axis], label=name)
ax_x.set_ylabel("attitude (deg)")
ax_x.legend()
ax_u.set_ylabel("torque (N m)")
ax_u.set_xlabel("time (s)")
fig.tight_layout()
plt.show()
