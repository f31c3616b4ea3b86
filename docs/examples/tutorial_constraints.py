"""Tutorial: input bounds (ellipsoid or peak), the true plant inside the polytope, a disturbance."""

import matplotlib.pyplot as plt
import numpy as np

from models import RigidSatellite
from rmpc import RMPC, StepDisturbance, simulate

sat = RigidSatellite.paper_p()
x0 = sat.initial_state()
plant = sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar")  # vertex 0: 1.3 J, vertex 1: 0.7 J
Q1, R = np.diag([1, 1, 1, 0.1, 0.1, 0.1]), np.eye(3)

runs = {
    # ||u||_2 <= 1 N m: one ellipsoidal bound on the torque vector (the default with u_max)
    "ellipsoid, nominal": (dict(u_max=1.0, input_constraint="ellipsoid"), None, None),
    # |u_i| <= 1 N m on each axis: the peak bounds, a box
    "peak, nominal": (dict(u_max=1.0, input_constraint="peak"), None, None),
    # the same controller on the heavy vertex (1.3 J), with 0.02 N m on the roll axis from 4 s
    "peak, 1.3 J, disturbed": (dict(u_max=1.0, input_constraint="peak"), 0,
                               StepDisturbance([0.02, 0.0, 0.0], t_start=4.0)),
}
fig, (ax_x, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.4))
for i, (label, (bounds, true_plant, disturbance)) in enumerate(runs.items()):
    ctrl = RMPC(plant, Q=Q1, R=R, resolve_threshold=0.9, **bounds)
    traj = simulate(ctrl, plant, x0, duration=8.0, true_plant=true_plant, disturbance=disturbance)
    u, solves = traj.u_applied, traj.status_counts().get("optimal", 0)
    norm, peak = np.linalg.norm(u, axis=1).max(), np.abs(u).max()
    print(f"{label:23s} max ||u|| {norm:.3f}, max |u_i| {peak:.3f} N m, "
          f"final roll {traj.attitude_deg[-1, 0]:+.3f} deg, solves {solves}")
    ax_x.plot(traj.t, traj.attitude_deg[:, 0], f"C{i}", label=label)
    ax_u.plot(traj.t[:-1], np.abs(u).max(axis=1), f"C{i}")
ax_x.set_ylabel("roll (deg)")
ax_x.legend(fontsize="small")
ax_u.set_ylabel("max |u_i| (N m)")
ax_u.set_xlabel("time (s)")
fig.tight_layout()
plt.show()
