"""A sweep file: read, checked, and expanded into its scenarios (:mod:`benchmarks.core.sweep` runs them).

A sweep file has up to six top-level entries, all optional::

    name = "smoke"                      # used in reports
    description = "what it is for"
    max_cases = 200000                  # lifts the bound on cases (default 100000)

    [base]                              # scenario fields (benchmarks.core.scenario.Scenario)
    controller = "GIPC"
    duration = 2.0
    [base.settings]                     # controller settings (benchmarks.families.rigid.defaults)
    Np = 200

    [grid]                              # the product of these lists, over any field
    plant = ["linear", "nonlinear"]
    saturation = ["limiter", "constraint"]
    settings.R_du = [0.1, 1.0]          # a controller setting

    [montecarlo]                        # seeded draws of the true inertia in the polytope box
    n = 10
    seed = 1

Each grid point is repeated for the ``n`` draws: the true principal inertias are
``J0_i (1 + spread u_i)`` with ``u`` uniform in ``[-1, 1]^3`` (one common ``u`` in
``"scalar"`` mode), from ``numpy.random.default_rng(seed)``; every grid point gets the same
draws. Cases are keyed by :attr:`benchmarks.core.scenario.Scenario.case_id`, so re-running a sweep
skips the cases its store already holds and a grid that repeats a case runs it once. A
``settings`` table may hold settings of several controllers (each case takes those of its own
controller); grid combinations a controller cannot run (LQR with ``saturation = "constraint"``)
are left out and listed in ``results.md``.
"""

from __future__ import annotations

import itertools
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.family import PlantFamily
from benchmarks.core.registry import get_family
from benchmarks.core.scenario import DEFAULT_FAMILY, Scenario
from toolkit_common.errors import ConfigError
from toolkit_common.validation import is_integer

__all__ = [
    "SHIPPED",
    "SweepSpec",
    "expand",
    "left_out",
    "load_sweep",
    "parse_sweep",
    "resolve_config",
]

_TOP_LEVEL = ("name", "description", "max_cases", "base", "grid", "montecarlo")

MAX_CASES = 100_000
"""Default bound on a sweep's cases (grid points x draws); ``max_cases = N`` at the top of the
file lifts it (a grid of 10^6 cases used to expand silently)."""

MAX_FILE_BYTES = 2**20
"""Largest sweep file read (1 MiB; the shipped ones are under 2 KiB)."""
_MONTECARLO = ("n", "seed")


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep file: base scenario fields, grid lists (dotted field names), draws."""

    name: str
    description: str
    base: dict[str, Any]
    grid: dict[str, list[Any]]
    montecarlo: dict[str, int] | None


#: The example sweeps shipped with the package.
SHIPPED = Path(__file__).resolve().parent.parent / "sweeps"


def resolve_config(path: str | Path) -> Path:
    """``path`` itself, or a shipped sweep when ``path`` is a bare name such as ``smoke``."""
    path = Path(path)
    if not path.is_file() and path.parent == Path(".") and (SHIPPED / f"{path.stem}.toml").is_file():
        return SHIPPED / f"{path.stem}.toml"
    return path


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep file (a :class:`~toolkit_common.errors.ConfigError` names the field).

    ``path`` may also name a shipped sweep (``"smoke"``, see :func:`resolve_config`).
    """
    path = resolve_config(path)
    try:
        size = path.stat().st_size
        if path.is_file() and size > MAX_FILE_BYTES:
            raise ConfigError("--config", f"a sweep file of at most {MAX_FILE_BYTES} bytes", f"{size} bytes")
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise ConfigError("--config", "a readable TOML file", f"{str(path)!r} ({err.strerror})") from None
    except UnicodeDecodeError:
        raise ConfigError("--config", "a UTF-8 TOML file", f"{str(path)!r} (not UTF-8)") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(str(path), "valid TOML", str(err).replace("\n", " ")) from None
    except RecursionError:
        found = "arrays or tables nested too deep to read"
        raise ConfigError(str(path), "TOML nested a few levels deep", found) from None
    return parse_sweep(data, default_name=path.stem)


def _flatten_grid(table: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(_flatten_grid(value, f"{name}."))
        else:
            out[name] = value
    return out


def _with(base: Mapping[str, Any], field_name: str, value: Any) -> dict[str, Any]:
    """``base`` with one (possibly ``settings.<name>``) field replaced."""
    out = {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in base.items()}
    if field_name.startswith("settings."):
        out.setdefault("settings", {})[field_name.split(".", 1)[1]] = value
    else:
        out[field_name] = value
    return out


def parse_sweep(data: Mapping[str, Any], default_name: str = "sweep") -> SweepSpec:
    """Validate the parsed TOML of a sweep (see the module notes for the format).

    Examples
    --------
    >>> spec = parse_sweep({"base": {"controller": "GIPC"}, "grid": {"u_max": [0.5, 1.0]},
    ...                     "montecarlo": {"n": 3, "seed": 1}})
    >>> len(expand(spec))
    6
    """
    for key in data:
        if key not in _TOP_LEVEL:
            raise ConfigError(str(key), "a sweep table (" + ", ".join(_TOP_LEVEL) + ")", "an unknown field")
    name = data.get("name", default_name)
    description = data.get("description", "")
    if not isinstance(name, str) or not name.strip() or not name.isprintable():
        raise ConfigError("name", "a non-empty one-line string of printable characters", repr(name))
    if not isinstance(description, str):
        raise ConfigError("description", "a string", repr(description))
    base = data.get("base", {})
    if not isinstance(base, Mapping):
        raise ConfigError("base", "a table of scenario fields", repr(base))
    family_name = base.get("family", DEFAULT_FAMILY)
    family = get_family(family_name, "base.family")
    for key, value in base.items():
        if key != "settings":
            Scenario.check_field(str(key), value, f"base.{key}", family_name)
        elif not isinstance(value, Mapping):
            raise ConfigError("base.settings", "a table of controller settings", repr(value))
        else:
            for name_, setting in value.items():
                family.check_setting(str(name_), setting, f"base.settings.{name_}")
    grid_table = data.get("grid", {})
    if not isinstance(grid_table, Mapping):
        raise ConfigError("grid", "a table of field = [values]", repr(grid_table))
    grid = _flatten_grid(grid_table)
    known = Scenario.field_names(family_name)
    for key, values in grid.items():
        top = key.split(".", 1)[0]
        if top == "family":
            expected = "the family in [base] (its fields differ)"
            raise ConfigError("grid.family", expected, "a grid over families")
        if top not in known or (top == "settings") != (key != top):
            raise ConfigError(f"grid.{key}", "a scenario field or settings.<name>", "an unknown field")
        if not isinstance(values, list) or not values:
            raise ConfigError(f"grid.{key}", "a non-empty list of values", repr(values))
        for value in values:
            if top == "settings":
                family.check_setting(key.split(".", 1)[1], value, f"grid.{key}")
            else:
                Scenario.check_field(key, value, f"grid.{key}", family_name)
    mc = data.get("montecarlo")
    if mc is not None:
        mc = _check_montecarlo(mc, base, grid, family)
    _check_case_count(data.get("max_cases", MAX_CASES), grid, mc)
    spec = SweepSpec(name=name, description=description, base=dict(base), grid=grid, montecarlo=mc)
    _check_settings_used(spec)
    _grid_points(spec)  # the combinations: raises on one that is impossible
    return spec


def _check_case_count(limit: Any, grid: Mapping[str, list[Any]], mc: Mapping[str, int] | None) -> None:
    """Refuse a sweep of more than ``limit`` cases before any is expanded."""
    if not is_integer(limit) or limit < 1:
        raise ConfigError("max_cases", "a positive integer", repr(limit))
    points = math.prod(len(values) for values in grid.values())
    count = points * (mc["n"] if mc else 1)
    if count > limit:
        where = "montecarlo.n" if mc and mc["n"] > limit // max(points, 1) else "grid"
        raise ConfigError(
            where,
            f"at most max_cases = {limit} cases (a line max_cases = N at the top of the file lifts it)",
            f"{points} grid points x {mc['n'] if mc else 1} draws = {count} cases",
        )


def _family(spec: SweepSpec) -> PlantFamily:
    return get_family(spec.base.get("family", DEFAULT_FAMILY), "base.family")


def _check_settings_used(spec: SweepSpec) -> None:
    """Every setting given must belong to a controller the sweep runs (else it is a mistake)."""
    family = _family(spec)
    default = spec.base.get("controller", Scenario.default("controller"))
    controllers = set(spec.grid.get("controller", [default]))
    given = [(f"base.settings.{k}", k) for k in spec.base.get("settings", {})]
    given += [(f"grid.{k}", k.split(".", 1)[1]) for k in spec.grid if k.startswith("settings.")]
    for where, key in given:
        if not any(key in family.controllers[c].defaults for c in controllers if c in family.controllers):
            owners = [c for c, d in family.controllers.items() if key in d.defaults]
            raise ConfigError(
                where,
                f"a setting of a controller the sweep runs ({', '.join(sorted(controllers))})",
                f"a setting of {', '.join(owners)} only",
            )


def _check_montecarlo(
    mc: Any, base: Mapping[str, Any], grid: Mapping[str, Any], family: PlantFamily
) -> dict[str, int]:
    if not isinstance(mc, Mapping):
        raise ConfigError("montecarlo", "a table with n and seed", repr(mc))
    for key in mc:
        if key not in _MONTECARLO:
            raise ConfigError(f"montecarlo.{key}", "n or seed", "an unknown field")
    n, seed = mc.get("n"), mc.get("seed", 0)
    if not is_integer(n) or n < 1:
        raise ConfigError("montecarlo.n", "a positive integer number of draws", repr(n))
    if not is_integer(seed) or seed < 0:
        raise ConfigError("montecarlo.seed", "an integer >= 0", repr(seed))
    if family.montecarlo is None:
        raise ConfigError("montecarlo", f"no draws (family {family.name!r} has none)", "a [montecarlo] table")
    for key in family.montecarlo.sets:
        if key in base or key in grid:
            expected = f"no {key} in [base] or [grid] (the draws set it)"
            raise ConfigError("montecarlo", expected, f"{key} given")
    return {"n": int(n), "seed": int(seed)}


def _grid_points(spec: SweepSpec) -> tuple[list[Scenario], list[str]]:
    """The scenarios of the grid (before the draws) and the combinations left out.

    A combination a controller cannot run (LQR with ``saturation = "constraint"``) is left out
    and listed; if that leaves nothing, or a combination is impossible otherwise, it raises
    :class:`~toolkit_common.errors.ConfigError` naming the field (``grid.<field>`` when the grid sets it).
    """
    keys = list(spec.grid)
    points, dropped = [], []
    first_problem: ConfigError | None = None
    for combo in itertools.product(*(spec.grid[k] for k in keys)):
        data: dict[str, Any] = dict(spec.base)
        for key, value in zip(keys, combo, strict=True):
            data = _with(data, key, value)
        family = _family(spec)
        controller = data.get("controller", Scenario.default("controller"))
        saturation = data.get("saturation", family.default("saturation", controller))
        problem = family.unsupported(controller, saturation)
        if problem is not None:
            dropped.append(f"{controller} with saturation = {saturation!r}")
            if first_problem is None:
                where = "grid.saturation" if "saturation" in spec.grid else "base.saturation"
                first_problem = ConfigError(where, problem, repr(saturation))
            continue
        try:
            points.append(Scenario.from_dict(data, lenient_settings=True))
        except ConfigError as err:
            raise ConfigError(_sweep_path(err.argument, spec), err.expected, err.found) from None
    if not points and first_problem is not None:
        raise first_problem
    return points, dropped


def _sweep_path(argument: str, spec: SweepSpec) -> str:
    """The key path of a scenario's error in the sweep file: each field named by where it is set.

    ``settings.soft.u`` -> ``grid.settings.soft.u`` when the grid sets ``settings.soft``, else
    ``base.settings.soft.u``; an error naming several fields (``settings.cost, settings.lyapunov``)
    gets each its own.
    """
    parts = []
    for part in argument.split(", "):
        keys = part.split(".")
        setting = ".".join(keys[:2]) if keys[0] == "settings" else keys[0]
        parts.append(f"{'grid' if setting in spec.grid else 'base'}.{part}")
    return ", ".join(parts)


def expand(spec: SweepSpec) -> list[Scenario]:
    """Every case of the sweep, in grid order (each grid point followed by its draws), without repeats.

    Grid combinations a controller cannot run are left out (see :func:`left_out`).
    """
    points, _ = _grid_points(spec)
    draws = None
    family = _family(spec)
    if spec.montecarlo is not None and family.montecarlo is not None:
        rng = np.random.default_rng(spec.montecarlo["seed"])
        draws = rng.uniform(-1.0, 1.0, size=(spec.montecarlo["n"], family.montecarlo.dims))
    out: list[Scenario] = []
    seen: set[str] = set()
    for scenario in points:
        variants = [scenario]
        if draws is not None and family.montecarlo is not None:
            apply = family.montecarlo.apply
            variants = [Scenario.from_dict({**scenario.to_dict(), **apply(scenario, u)}) for u in draws]
        for sc in variants:
            if sc.case_id not in seen:
                seen.add(sc.case_id)
                out.append(sc)
    return out


def left_out(spec: SweepSpec) -> list[str]:
    """The grid combinations :func:`expand` leaves out, in words.

    Examples
    --------
    >>> grid = {"controller": ["LQR", "RMPC"], "saturation": ["limiter", "constraint"]}
    >>> left_out(parse_sweep({"grid": grid}))
    ["LQR with saturation = 'constraint'"]
    """
    return _grid_points(spec)[1]
