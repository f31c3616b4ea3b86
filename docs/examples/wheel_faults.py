"""Paper W's wheel satellite: geometry, redundancy, the compensator's first command, a short
S1 run with its fault metrics, and robust MPC on the wheel-effectiveness polytope."""

import numpy as np

from benchmarks.families.wheel.metrics import fault_metrics
from benchmarks.families.wheel.plant import scenario_plant
from models import WheelArray, WheelSatellite, paper_w_scenario, rank_deficient_windows
from rmpc import RMPC, AdaptiveBacksteppingFTC, simulate

wheels = WheelArray.paper_w()
skew = np.degrees(np.arccos(wheels.D[:, 3]))
print("skew wheel to each axis (deg):", skew.round(4))
print("rank with one wheel out:", [wheels.rank(1.0 - np.eye(4)[j]) for j in range(4)])
print("rank with wheels 1 and 4 out:", wheels.rank([0, 1, 1, 0]))
for w in rank_deficient_windows(paper_w_scenario("S3").schedule(), wheels):
    print(f"S3 rank {w.rank} on [{w.t_start:g}, {w.t_end:g}) s, wheels {w.wheels} lost")

sat = WheelSatellite.paper_w()
s1 = paper_w_scenario("S1")
ftc = AdaptiveBacksteppingFTC(sat)
nu0 = ftc.step(s1.initial_state())
print("S1 first command (N m):", nu0.round(3), f"= {np.abs(nu0).max() / 0.123:.1f} x the limit")

ftc.reset()
run = simulate(ftc, scenario_plant(s1), s1.initial_state(), duration=12.0)  # S1's first 12 s
metrics = fault_metrics(run, s1.schedule(), wheels)
print(f"max |u| commanded {metrics['max_abs_u_cmd']:.3f}, applied {metrics['max_abs_u']:.3f} N m")
print(f"saturated fraction {metrics['sat_fraction']['any']:.3f}")
print("max |h| (N m s):", np.round(metrics["max_abs_h"], 3))
print("stuck wheel 2 applies (N m):", np.unique(run.stage_log["u_fault"][run.t[:-1] >= 8.0, 1]))

poly_w = sat.polytope(dt=0.04, effectiveness="single_outage")
Q, R = np.diag([1.0, 1, 1, 0.1, 0.1, 0.1]), np.eye(4)
x0 = np.radians([10.0, -5.0, 15.0, 0, 0, 0])
sol = RMPC(poly_w, Q, R, u_max=0.123, input_constraint="peak").solve(x0)
print(f"polytope: {poly_w.n_vertices} vertices; RMPC {sol.status}, certified {sol.certificate.ok}")
print("max |F x0| (N m):", f"{np.abs(sol.F @ x0).max():.4f}")
