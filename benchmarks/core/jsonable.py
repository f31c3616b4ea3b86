"""Values made ready for strict JSON: plain Python numbers, lists and string keys, ``None`` for NaN and inf.

Records (``results.json``, the sweep store) and the timing report (``timing.json``) are written
with ``allow_nan=False``; :func:`json_safe` is the one conversion both go through.
:func:`write_json` is the one way the stand-alone benchmark scripts write their records.

Examples
--------
>>> import numpy as np
>>> from benchmarks.core.jsonable import json_safe
>>> json_safe({1: np.float64(np.inf), "a": (np.int64(2), np.array([0.5, np.nan]))})
{'1': None, 'a': [2, [0.5, None]]}
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["json_safe", "write_json"]


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


def write_json(path: str | os.PathLike[str], value: Any, indent: int = 2) -> None:
    """Write ``value`` as JSON to ``path`` (its directory created), atomically: a run interrupted
    while writing leaves the previous file whole. NaN and inf are written as JSON's
    ``NaN``/``Infinity`` extension, which Python's ``json`` reads back (strict files go through
    :func:`json_safe`)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_name(target.name + ".partial")
    partial.write_text(json.dumps(value, indent=indent), encoding="utf-8")
    os.replace(partial, target)
