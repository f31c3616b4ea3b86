"""The metrics of one benchmark case: a 10 s LQR run on the nonlinear satellite with a limiter."""

from benchmarks.core.runner import simulate_scenario
from benchmarks.core.scenario import Scenario

# Every field not given takes its default (benchmarks.families.rigid.defaults): paper P's satellite and
# initial attitude, Ts = 0.01 s, u_max = 1 N m, the toolkit's weights Q1 and R.
scenario = Scenario.from_dict(
    {"controller": "LQR", "plant": "nonlinear", "saturation": "limiter", "duration": 10.0}
)
record, trace = simulate_scenario(scenario, experiment="example", keep_trace=True)
m = record["metrics"]  # what results.json holds for this case

print(record["label"], "| steps:", m["n_steps"], "| samples:", trace["t"].size)
for name in ("sum_abs_err", "iae", "ise", "settling_time", "overshoot"):
    print(f"{name:14s}", {axis: round(value, 4) for axis, value in m[name].items()})
print("final_abs_err ", {axis: f"{value:.2e}" for axis, value in m["final_abs_err"].items()})
print("max_abs_u", round(m["max_abs_u"], 4), "| max_abs_u_cmd", round(m["max_abs_u_cmd"], 4))
print("saturated_fraction", round(m["saturated_fraction"], 4),
      "| constraint_violation", m["constraint_violation"])
print("status_counts", m["status_counts"], "| fallbacks", m["fallback_count"],
      "| gamma values", m["gamma"]["count"])
