"""What a timing was measured on: the machine, its load and the package versions."""

from __future__ import annotations

import os
import platform
from importlib import metadata
from typing import Any

__all__ = ["machine_info", "package_versions", "percentiles"]

_PACKAGES = ("numpy", "scipy", "numba", "cvxpy", "clarabel", "osqp", "proxsuite", "control", "scs")


def machine_info() -> dict[str, Any]:
    """Platform, processor, CPU count and the load average at the time of the call."""
    try:
        load = os.getloadavg()
    except OSError:  # pragma: no cover - not on every platform
        load = (float("nan"),) * 3
    return {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "cpu_count": os.cpu_count(),
        "load_average": [round(v, 2) for v in load],
    }


def package_versions() -> dict[str, str]:
    """Installed versions of the numerical packages the timings depend on, and which build of the
    interior-point method's C core runs (``lmi_ccore``: the extension, or why numba runs instead;
    :func:`lmi.ccore.runtime.core_status`)."""
    from lmi.ccore.runtime import core_status

    out = {}
    for name in _PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    out["lmi_ccore"] = core_status()
    return out


def percentiles(times: Any) -> dict[str, float]:
    """``p50``, ``p95`` and ``max`` of a sequence of times (s)."""
    import numpy as np

    arr = np.asarray(times, dtype=float)
    if arr.size == 0:
        return {"p50_s": float("nan"), "p95_s": float("nan"), "max_s": float("nan")}
    return {
        "p50_s": float(np.percentile(arr, 50)),
        "p95_s": float(np.percentile(arr, 95)),
        "max_s": float(np.max(arr)),
    }
