"""The covering polytope: K(phi, theta) over a box of attitudes, checked by linear programming."""

import numpy as np
from scipy.optimize import linprog

from models import RigidSatellite, kinematics_matrix
from models.attitude.euler import kinematics_cover

sat = RigidSatellite.paper_p()
x0 = sat.initial_state(1.3)  # E6: paper P's initial attitude x 1.3, at rest

# The box from zero to the initial attitude, widened by 5 deg on each side (kinematics = "cover").
middle = np.concatenate((0.5 * x0[:3], np.zeros(3)))
half = 0.5 * np.abs(x0[:3]) + np.radians(5.0)
single = sat.polytope(x0, dt=0.01, spread=0.3)
cover = sat.polytope(middle, dt=0.01, spread=0.3, attitude_range=half)
print("vertices: single point", single.n_vertices, "| covering", cover.n_vertices)

phi = (middle[0] - half[0], middle[0] + half[0])
theta = (middle[1] - half[1], middle[1] + half[1])
mats = kinematics_cover(phi, theta)
corners = [kinematics_matrix(p, t) for p in phi for t in theta]


def in_hull(k_mat, vertices):
    """Whether k_mat is a convex combination of the vertices (a feasibility LP)."""
    a_eq = np.vstack([np.column_stack([v.ravel() for v in vertices]), np.ones(len(vertices))])
    b_eq = np.append(k_mat.ravel(), 1.0)
    res = linprog(np.zeros(len(vertices)), A_eq=a_eq, b_eq=b_eq, bounds=(0, None), method="highs")
    return res.status == 0


rng = np.random.default_rng(0)
samples = [kinematics_matrix(rng.uniform(*phi), rng.uniform(*theta)) for _ in range(200)]
print(f"{len(mats)} matrices; K at 200 random attitudes of the box in their hull:",
      sum(in_hull(k, mats) for k in samples))
print("the same in the hull of K at the 4 corners of the box:", sum(in_hull(k, corners) for k in samples))
print("K at the middle of the box in the hull of the 4 corners:",
      in_hull(kinematics_matrix(middle[0], middle[1]), corners))
print("roll from {:.1f} to {:.1f} deg, pitch from {:.1f} to {:.1f} deg".format(
    *np.degrees(phi), *np.degrees(theta)))
