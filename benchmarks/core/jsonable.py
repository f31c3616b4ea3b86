"""Values made ready for strict JSON: plain Python numbers, lists and string keys, ``None`` for NaN and inf.

Records (``results.json``, the sweep store) and the timing report (``timing.json``) are written
with ``allow_nan=False``; :func:`json_safe` is the one conversion both go through.

Examples
--------
>>> import numpy as np
>>> from benchmarks.core.jsonable import json_safe
>>> json_safe({1: np.float64(np.inf), "a": (np.int64(2), np.array([0.5, np.nan]))})
{'1': None, 'a': [2, [0.5, None]]}
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["json_safe"]


def json_safe(value: Any) -> Any:
    """``value`` with dict keys as strings, tuples and arrays as lists, numpy scalars as Python
    numbers and non-finite floats as ``None``, recursively; anything else unchanged."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
