"""Every robust MPC form of the toolkit on paper P's nonlinear satellite, 6 s from x0 at Ts = 0.05 s."""

import matplotlib.pyplot as plt
import numpy as np

from models import PAPER_P_TORQUE_LIMIT, RigidSatellite, TorqueLimiter
from rmpc import CRMPC, GIPC, RMPC, OfflineRMPC, ScheduledRMPC, simulate

sat = RigidSatellite.paper_p()
x0 = sat.initial_state()
dt, spread = 0.05, 0.3  # a coarse sample time keeps the scheduled form's 120 solves short
plant = sat.polytope(x0, dt=dt, spread=spread, mode="scalar")  # linearised at x0, 2 vertices
Q1, R = np.diag([1, 1, 1, 0.1, 0.1, 0.1]), np.eye(3)

controllers = [
    RMPC(plant, Q1, R, u_max=1.0, resolve_threshold=0.9),           # LMIs on line
    OfflineRMPC(plant, Q1, R, u_max=1.0, x_design=x0, n_ellipsoids=8),  # a table of them, off line
    ScheduledRMPC.for_satellite(sat, dt, spread, Q1, R, u_max=1.0),  # re-linearised at every step
    CRMPC(plant, Q=Q1, R=0.01 * np.eye(3), u_max=1.0),               # with paper P's adaptation
    GIPC(plant, Np=80, Nc=4, u_max=1.0, du_max=0.05),              # the incremental QP baseline
]
fig, (ax_x, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.4))
for i, ctrl in enumerate(controllers):
    traj = simulate(ctrl, sat, x0, duration=6.0, dt=dt, limiter=TorqueLimiter(PAPER_P_TORQUE_LIMIT))
    err = np.linalg.norm(traj.attitude_deg, axis=1)
    peak = np.abs(traj.u_applied).max()
    print(f"{ctrl.name:14s} |attitude| at 6 s {err[-1]:6.3f} deg, max |u_i| {peak:.3f} N m")
    ax_x.plot(traj.t, err, f"C{i}", label=ctrl.name)
    ax_u.plot(traj.t[:-1], np.abs(traj.u_applied).max(axis=1), f"C{i}")
ax_x.set_ylabel("|attitude| (deg)")
ax_x.legend(fontsize="small")
ax_u.set_ylabel("max |u_i| (N m)")
ax_u.set_xlabel("time (s)")
fig.tight_layout()
plt.show()
