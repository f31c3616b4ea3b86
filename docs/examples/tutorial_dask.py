"""Tutorial: the sweep of the previous page on a local Dask cluster of two worker processes."""

import json
import tempfile
from pathlib import Path

from dask.distributed import LocalCluster

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

if __name__ == "__main__":  # the workers are new processes: they must not run this part again
    with tempfile.TemporaryDirectory() as tmp, LocalCluster(
        n_workers=2, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        config = Path(tmp) / "tutorial.toml"
        config.write_text(SWEEP)
        # the same as: rmpc bench sweep --config tutorial.toml --out OUT --scheduler ADDRESS
        outcome = run_sweep(config, Path(tmp) / "out", scheduler=cluster.scheduler_address, progress=False)
        print(f"{outcome.total} cases, {outcome.ran} ran, {outcome.failed} failed")
        records = json.loads((Path(tmp) / "out" / "results.json").read_text())
    for controller in ("RMPC", "LQR"):
        iae = [sum(r["metrics"]["iae"].values()) for r in records if r["controller"] == controller]
        print(controller, "IAE (rad s):", [round(v, 4) for v in iae])
