"""Tutorial: a sweep from a TOML file, run in this process, its records read back and plotted."""

import json
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from benchmarks.core.sweep import run_sweep

SWEEP = """
name = "tutorial"
description = "RMPC and LQR from paper P's initial attitude scaled by 0.5, 1 and 1.3; 2 s each."

[base]
plant = "nonlinear"
saturation = "limiter"
duration = 2.0

[grid]
controller = ["RMPC", "LQR"]
ic_scale = [0.5, 1.0, 1.3]
"""

with tempfile.TemporaryDirectory() as tmp:
    config = Path(tmp) / "tutorial.toml"
    config.write_text(SWEEP)
    # the same as: rmpc bench sweep --config tutorial.toml --out OUT --workers 0
    outcome = run_sweep(config, Path(tmp) / "out", workers=0, progress=False)
    print(f"{outcome.total} cases, {outcome.ran} ran, {outcome.failed} failed;",
          "files:", sorted(f.name for f in outcome.files if f.suffix in (".json", ".md")))
    records = json.loads((Path(tmp) / "out" / "results.json").read_text())  # one record per case

fig, ax = plt.subplots(figsize=(6.4, 3.2))
for controller, marker in (("RMPC", "o"), ("LQR", "s")):
    rows = [r for r in records if r["controller"] == controller]
    scales = [r["settings"]["ic_scale"] for r in rows]
    iae = [sum(r["metrics"]["iae"].values()) for r in rows]  # integral of |error|, summed over the axes
    print(controller, "IAE (rad s):", [round(v, 4) for v in iae])
    ax.plot(scales, iae, marker=marker, label=controller)
ax.set_xlabel("initial attitude / paper P's")
ax.set_ylabel("IAE over 2 s (rad s)")
ax.legend()
fig.tight_layout()
plt.show()
