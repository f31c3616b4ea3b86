"""Paper M's three backstepping controllers on the MRP satellite with the spinning disk (M2)."""

import numpy as np

from models import paper_m_scenario
from models.attitude.mrp import mrp_error_angle
from rmpc import MAB, CFBackstepping, TuningFunctionAB, simulate
from rmpc.sim.plants import SampledPlant

m2 = paper_m_scenario("M2", duration=40.0, dt=0.05)  # window [20, 40] s; the seed's is 100 s
print(f"initial error {m2.initial_error_deg:.2f} deg, window {m2.steady_window} s")
for ctrl in (
    CFBackstepping(m2.model(), target=m2.sigma_ref, dt=m2.dt),
    MAB(m2.model(), target=m2.sigma_ref, dt=m2.dt),
    TuningFunctionAB(m2.model(), target=m2.sigma_ref, dt=m2.dt),
):
    plant = SampledPlant(m2.true_satellite(), m2.dt, integrator="RK4", substep=0.01)
    traj = simulate(ctrl, plant, m2.initial_state(), duration=m2.duration, disturbance=m2.disturbance())
    phi = np.degrees([mrp_error_angle(x[:3], m2.sigma_ref) for x in traj.x])
    steady = phi[traj.t >= m2.steady_window[0]].max()
    peak = np.abs(traj.u_applied).max()
    line = f"{ctrl.name:4s}  max error {steady:.4f} deg  peak torque {peak:.2f} N m"
    if ctrl.name != "BS":
        estimate = np.array([info.extra["torque_estimate"] for info in traj.info])
        late = traj.t[:-1] >= 20.0
        line += f"  |Tdhat - Td| {np.abs(estimate[late] - traj.d[late]).max():.1e} N m"
    print(line)
