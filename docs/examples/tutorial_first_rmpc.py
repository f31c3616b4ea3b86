"""Tutorial: robust MPC on a plant of one's own, two masses on an uncertain spring."""

import control
import matplotlib.pyplot as plt
import numpy as np

from models import PolytopicModel, zoh
from rmpc import RMPC, simulate


# Two unit masses joined by a spring of stiffness k, a force u on the first one; the states are
# the positions and the velocities [x1, x2, v1, v2]. Only k in [0.5, 10] N/m is known.
def masses(k):
    a = [[0, 0, 1, 0], [0, 0, 0, 1], [-k, k, 0, 0], [k, -k, 0, 0]]
    return control.ss(a, [[0], [0], [1], [0]], np.eye(4), np.zeros((4, 1)))


dt = 0.1
vertices = []
for k in (0.5, 10.0):
    sys = masses(k)                               # continuous time, python-control
    ad, bd = zoh(sys.A, sys.B, dt)                # exact zero-order-hold discretisation
    vertices.append(control.ss(ad, bd, sys.C, sys.D, dt))
plant = PolytopicModel.from_statespace(vertices)  # every k in [0.5, 10] lies in its hull
print(plant)

# Robust MPC: the min-max LMI problem of Kothare et al. (1996) solved at every sample,
# with |u| <= 1 N on the force.
ctrl = RMPC(plant, Q=np.eye(4), R=0.01 * np.eye(1), u_max=1.0, input_constraint="peak")
x0 = np.array([1.0, 1.0, 0.0, 0.0])              # both masses 1 m away, at rest

# 15 s in closed loop on each extreme spring.
fig, (ax_x, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.4))
for k, vertex, style in ((0.5, 0, "-"), (10.0, 1, "--")):
    traj = simulate(ctrl, plant, x0, duration=15.0, true_plant=vertex)
    print(f"k = {k:4}: final |x| = {np.linalg.norm(traj.x[-1]):.2e}, "
          f"max |u| = {np.abs(traj.u_applied).max():.3f} N, statuses {traj.status_counts()}")
    ax_x.plot(traj.t, traj.x[:, 0], "C0" + style, label=f"x1, k = {k}")
    ax_x.plot(traj.t, traj.x[:, 1], "C1" + style, label=f"x2, k = {k}")
    ax_u.step(traj.t[:-1], traj.u_applied[:, 0], "C2" + style, where="post", label=f"k = {k}")
ax_x.set_ylabel("position (m)")
ax_x.legend(ncol=2, fontsize="small")
ax_u.axhline(1.0, color="grey", lw=0.5)
ax_u.axhline(-1.0, color="grey", lw=0.5)
ax_u.set_ylabel("force u (N)")
ax_u.set_xlabel("time (s)")
ax_u.legend(fontsize="small")
fig.tight_layout()
plt.show()
