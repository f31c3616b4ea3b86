"""What the sections of ``rmpc timing`` share: paper P's timing problem, its polytopes, record helpers.

The problem: paper P's satellite, ``Ts = 0.01`` s, inertia spread :data:`SPREAD`,
``Q1 = diag(1, 1, 1, 0.1, 0.1, 0.1)``, ``R = I``, ``||u|| <= 1``. :func:`polytope` gives its
2-, 4- and 8-vertex polytopes; the small helpers below make the records (``finite``, ``rel_err``,
...) and the report's numbers (``ms``, ``us``, ...). Light on purpose: nothing here imports a
solver or a controller, so the ``rmpc`` command line can load it at start-up.

Examples
--------
>>> from benchmarks.timing.common import ms, rel_err
>>> rel_err([1.0, 2.2, float("nan")], [1.0, 2.0, 3.0])
0.10000000000000009
>>> ms(0.0123), ms(None)
('12.30', 'n/a')
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from toolkit_common.errors import InvalidArgumentError

if TYPE_CHECKING:
    from models import PolytopicModel

__all__ = [
    "POLYTOPE_NAMES",
    "Q1",
    "SCS_OPTIONS",
    "SPREAD",
    "U_MAX",
    "R",
    "finite",
    "machine_line",
    "median_int",
    "ms",
    "polytope",
    "rel_err",
    "sample_key",
    "sci",
    "tally",
    "us",
    "write_result",
]

#: The state weight of paper P's timing problem.
Q1 = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
#: The input weight.
R = np.eye(3)
#: The input bound ``||u||_2 <= U_MAX`` (N m).
U_MAX = 1.0
#: The inertia spread of the polytopes.
SPREAD = 0.3
#: SCS at its own default tolerances: the toolkit's defaults (1e-9, 100 000 iterations) take
#: 25-80 s per solve here; this row shows what a user who just picks SCS gets.
SCS_OPTIONS: dict[str, Any] = {"eps_abs": 1e-4, "eps_rel": 1e-4}
#: The polytope of each vertex count, by the name ``RigidSatellite.polytope`` gives its mode.
POLYTOPE_NAMES = {2: "scalar", 4: "axisymmetric", 8: "box"}


# -- plants ---------------------------------------------------------------------------------------
def polytope(n_vertices: int, spread: float = SPREAD) -> PolytopicModel:
    """Paper P's linearisation over an inertia polytope with 2, 4 or 8 vertices.

    2: ``J = c J0`` with ``c`` in ``1 +- s`` (``RigidSatellite.polytope`` mode ``"scalar"``);
    8: each principal inertia in ``(1 +- s) J_i`` independently (mode ``"box"``);
    4: ``Ixx = Iyy`` scaled together by ``1 +- s``, ``Izz`` independently (4 of the box's corners:
    the satellite stays axisymmetric). ``B`` is linear in ``J^-1`` at zero rates, so the corners in
    ``J`` span the exact set (see :meth:`models.RigidSatellite.inertia_vertices`).
    """
    from models import INPUT_NAMES, PAPER_P_SAMPLE_TIME, STATE_NAMES, PolytopicModel, RigidSatellite

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    if n_vertices == 2:
        return sat.polytope(x0, PAPER_P_SAMPLE_TIME, spread, "scalar")
    if n_vertices == 8:
        return sat.polytope(x0, PAPER_P_SAMPLE_TIME, spread, "box")
    if n_vertices != 4:
        raise InvalidArgumentError("n_vertices", "2, 4 or 8", repr(n_vertices))
    j0 = np.diag(sat.inertia)
    verts = [
        RigidSatellite(j0 * np.array([a, a, c])).discretize(x0, PAPER_P_SAMPLE_TIME)
        for a in (1.0 + spread, 1.0 - spread)
        for c in (1.0 + spread, 1.0 - spread)
    ]
    return PolytopicModel(verts, PAPER_P_SAMPLE_TIME, nominal=sat.discretize(x0, PAPER_P_SAMPLE_TIME),
                          state_names=STATE_NAMES, input_names=INPUT_NAMES, attitude="euler321")


# -- records --------------------------------------------------------------------------------------
def finite(value: Any) -> float | None:
    """A float for JSON (NaN and inf become ``None``)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def tally(counts: dict[str, int], word: str) -> None:
    """Count one more ``word`` in ``counts``."""
    counts[word] = counts.get(word, 0) + 1


def rel_err(values: Sequence[float], refs: Sequence[float], floor: float = 0.0) -> float | None:
    """Largest ``|value / ref - 1|`` over the pairs where both are finite (``|ref|`` at least ``floor``)."""
    vals, ref = np.asarray(values, dtype=float), np.asarray(refs, dtype=float)
    ok = np.isfinite(vals) & np.isfinite(ref)
    if not np.any(ok):
        return None
    return float(np.max(np.abs(vals[ok] - ref[ok]) / np.maximum(np.abs(ref[ok]), floor)))


def median_int(values: Sequence[int | None]) -> float | None:
    """Median of the known, non-negative counts (iterations); ``None`` if there is none."""
    vals = [v for v in values if v is not None and v >= 0]
    return float(np.median(vals)) if vals else None


def sample_key(rec: dict[str, Any]) -> str:
    """The key of a record's per-step times in ``timing_samples.npz``."""
    return f"{rec['problem']}|{rec['backend']}|{rec['formulation']}|{rec['vertices']}"


# -- numbers in the report ------------------------------------------------------------------------
def ms(value: float | None, digits: int = 2) -> str:
    """Seconds as milliseconds, ``n/a`` for ``None``."""
    return "n/a" if value is None else f"{1e3 * value:.{digits}f}"


def us(value: float | None) -> str:
    """Seconds as microseconds, ``n/a`` for ``None``."""
    return "n/a" if value is None else f"{1e6 * value:.1f}"


def sci(value: float | None) -> str:
    """Two significant digits in scientific notation, ``n/a`` for ``None``."""
    return "n/a" if value is None else f"{value:.1e}"


def machine_line(machine: dict[str, Any]) -> str:
    """The stand-alone scripts' last line: the machine and its load, as the run recorded them."""
    m = machine
    return (f"machine: {m['platform']}, {m['processor']}, {m['cpu_count']} CPUs (os.cpu_count), "
            f"load average {m['load_average']} (os.getloadavg), Python {m['python']}")


def write_result(result: dict[str, Any], table: str, out: str | None) -> None:
    """Print a stand-alone script's table and, with ``out``, write its result as JSON there."""
    import json

    print(table)
    if out:
        with open(out, "w", encoding="utf-8") as fh:
            json.dump(result, fh, indent=2)
