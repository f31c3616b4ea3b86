"""A plant family of one's own: a double integrator with an LQR, run through the harness."""

import numpy as np

from benchmarks.core.family import (
    BuiltController,
    CaseResult,
    ControllerSpec,
    Field,
    PlantFamily,
    check_choice,
    check_real,
)
from benchmarks.core.registry import register_family
from benchmarks.core.runner import run_scenario
from benchmarks.core.scenario import Scenario
from models import PolytopicModel
from rmpc import LQR, simulate


def build_lqr(model, scenario, settings):
    q, r = np.diag(settings["Q_diag"]), np.diag(settings["R_diag"])
    return BuiltController(LQR(model, q, r), needs_limiter=False)


def simulate_case(scenario, settings, keep_trace):
    dt = scenario.dt
    a = np.array([[1.0, dt], [0.0, 1.0]])
    b = np.array([[0.5 * dt * dt], [dt]])
    model = PolytopicModel([(a, b), (a, scenario.gain * b)], dt)
    built = scenario.plant_family.build_controller(model, scenario)
    traj = simulate(built.controller, model, np.array([1.0, 0.0]), duration=scenario.duration)
    metrics = {"final_abs_err": float(abs(traj.x[-1, 0])), "max_abs_u": float(np.abs(traj.u_applied).max())}
    trace = {"t": traj.t, "x": traj.x} if keep_trace else {}
    return CaseResult({"n_vertices": model.n_vertices}, metrics, trace)


register_family(
    PlantFamily(
        name="double_integrator",
        description="a double integrator whose input gain is uncertain",
        fields={
            "plant": Field("linear", lambda v, w: check_choice(v, w, ("linear",))),
            "saturation": Field("none", lambda v, w: check_choice(v, w, ("none",))),
            "gain": Field(1.5, lambda v, w: check_real(v, w, low=0.0, low_open=True)),
            "duration": Field(10.0, lambda v, w: check_real(v, w, low=0.0, low_open=True)),
            "dt": Field(0.1, lambda v, w: check_real(v, w, low=0.0, low_open=True)),
        },
        controllers={"LQR": ControllerSpec(build_lqr, {"Q_diag": (1.0, 0.1), "R_diag": (0.1,)}, False)},
        simulate=simulate_case,
    )
)

scenario = Scenario.from_dict({"family": "double_integrator", "controller": "LQR", "gain": 2.0})
record = run_scenario(scenario, experiment="demo")
print(scenario.label(), "|", record["settings"]["family"], "| vertices:", record["settings"]["n_vertices"])
metrics = record["metrics"]
print(f"final |x1| = {metrics['final_abs_err']:.2e}, max |u| = {metrics['max_abs_u']:.3f}")
