"""Tutorial: paper P's satellite, its linearisation, discretisation and inertia polytope, under RMPC."""

import matplotlib.pyplot as plt
import numpy as np

from models import PAPER_P_INERTIA, PAPER_P_TORQUE_LIMIT, RigidSatellite, TorqueLimiter
from rmpc import RMPC, simulate

sat = RigidSatellite.paper_p()      # J = diag(1.2928, 1.2928, 4.2953) kg m^2
x0 = sat.initial_state()            # roll, pitch, yaw (rad) and body rates (rad/s)

# The continuous linearisation at x0 (zero rates: A = [[0, K(phi, theta)], [0, 0]]) and its
# zero-order-hold discretisation at Ts = 0.01 s.
a, b = sat.linearize(x0)
ad, bd = sat.discretize(x0, dt=0.01)
print("K(phi, theta) =", np.round(a[:3, 3:], 4).tolist())
print("Bd[3:, :] diagonal (1/s per N m):", np.round(np.diag(bd[3:, :]), 6))

# The inertia known to +-30 %: J = c J0 with c in [0.7, 1.3] (2 vertices), or each principal
# inertia on its own (8 vertices).
scalar = sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar")
box = sat.polytope(x0, dt=0.01, spread=0.3, mode="box")
print("vertices:", scalar.n_vertices, "(scalar),", box.n_vertices, "(box)")

# Robust MPC on the 2-vertex polytope, ||u|| <= 1 N m; a solve only when the state leaves the
# outer tenth of the current invariant ellipsoid. 12 s on the nonlinear satellite, with the
# +-1 N m limiter, for the nominal satellite and one 30 % heavier.
Q1, R = np.diag([1, 1, 1, 0.1, 0.1, 0.1]), np.eye(3)
fig, (ax_x, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.4))
for scale, style in ((1.0, "-"), (1.3, "--")):
    true_sat = RigidSatellite([scale * j for j in PAPER_P_INERTIA])
    ctrl = RMPC(scalar, Q=Q1, R=R, u_max=1.0, resolve_threshold=0.9)
    traj = simulate(ctrl, true_sat, x0, duration=12.0, dt=0.01,
                    limiter=TorqueLimiter(PAPER_P_TORQUE_LIMIT))
    print(f"J x {scale}: final attitude (deg) {np.round(traj.attitude_deg[-1], 3)}, "
          f"largest |u_i| {np.abs(traj.u_applied).max():.3f} N m, statuses {traj.status_counts()}")
    for axis, name in enumerate(("roll", "pitch", "yaw")):
        ax_x.plot(traj.t, traj.attitude_deg[:, axis], f"C{axis}{style}", label=f"{name}, J x {scale}")
        ax_u.plot(traj.t[:-1], traj.u_applied[:, axis], f"C{axis}{style}")
ax_x.set_ylabel("attitude (deg)")
ax_x.legend(ncol=2, fontsize="small")
ax_u.set_ylabel("torque (N m)")
ax_u.set_xlabel("time (s)")
fig.tight_layout()
plt.show()
