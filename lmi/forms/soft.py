"""Soft bounds and soft limits: the option ``soft`` checked, and the slacks it stands for.

Two ways to soften (the page "The field's robust MPC forms" of the docs):

- one weight per family, ``soft={"u": w_u, "y": w_y}``: the hard bounds themselves softened with
  one slack per family (``u_max^2 -> u_max^2 + s_u`` in every input bound block);
- a weight per component, ``soft={"u": [w_1, ..., w_m], "y": [...]}``: one slack per component
  whose weight is ``> 0`` (a weight ``0`` keeps that component hard), softening that component's
  own bound (input bounds per component: ``input_constraint="peak"``); with
  ``"u_limit": [l_1, ..., l_m]`` (``"y_limit"`` for the outputs) the hard bounds stay hard and
  the slacks soften separate limits ``l_k`` instead, after Oravec & Bakošová's soft-constrained
  robust MPC (MUP's ``*_soft_con`` methods; ``0`` where the weight is ``0``: no soft limit).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = ["FAMILIES", "SoftSlack", "bound_slack", "check_soft", "limit_slacks", "soft_slacks"]

#: The families a weight may soften: the inputs and the outputs.
FAMILIES: tuple[str, ...] = ("u", "y")
_KEYS = ("u", "y", "u_limit", "y_limit")
_SIZE_NAMES = {"u": "inputs", "y": "outputs"}


@dataclass(frozen=True)
class SoftSlack:
    """One slack variable: its name in the LMIs (``s_u``, ``s_u1``), the family it softens, the
    component (``None``: the whole family), its weight in the objective and the soft limit it
    relaxes (``None``: the hard bound itself)."""

    name: str
    family: str
    component: int | None
    weight: float
    limit: float | None

    @property
    def key(self) -> str:
        """The slack's key in ``sol.slack``: ``"u"`` (one per family) or ``"u1"`` (component 1)."""
        return self.name[2:]


def _is_number(value: Any) -> bool:
    numeric = isinstance(value, int | float | np.floating | np.integer)
    return numeric and not isinstance(value, bool | np.bool_)


def _scalar_weight(key: str, weight: Any, max_weight: float) -> float:
    if not _is_number(weight):
        raise ArgumentTypeError(f"soft[{key!r}]", "a number > 0", type(weight).__name__)
    if not (np.isfinite(weight) and weight > 0.0):
        raise InvalidArgumentError(f"soft[{key!r}]", "a finite weight > 0", repr(weight))
    if weight > max_weight:
        raise InvalidArgumentError(
            f"soft[{key!r}]", f"a weight <= MAX_SOFT_WEIGHT = {max_weight:g} (beyond it the solvers "
            "cannot resolve the cost bound next to the penalty; see the page on the forms)", repr(weight))
    return float(weight)


def _numbers(key: str, value: Any, size: int | None, what: str) -> list[float]:
    """A list of numbers (``what`` says which), its length checked against ``size`` when known."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, list | tuple) or not all(_is_number(v) for v in value):
        raise ArgumentTypeError(f"soft[{key!r}]", f"a list of {what}", type(value).__name__)
    family = key[0]
    if size is not None and len(value) != size:
        raise InvalidArgumentError(
            f"soft[{key!r}]", f"{size} values (one per {_SIZE_NAMES[family][:-1]}: the plant has {size} "
            f"{_SIZE_NAMES[family]})", f"{len(value)} values")
    if not value:
        raise InvalidArgumentError(f"soft[{key!r}]", f"a non-empty list of {what}", "an empty list")
    return [float(v) for v in value]


def _component_weights(key: str, value: Any, size: int | None, max_weight: float) -> tuple[float, ...]:
    weights = _numbers(key, value, size, "weights >= 0, one per component")
    for k, w in enumerate(weights):
        if not (math.isfinite(w) and w >= 0.0):
            raise InvalidArgumentError(f"soft[{key!r}][{k}]", "a finite weight >= 0", repr(w))
        if w > max_weight:
            raise InvalidArgumentError(
                f"soft[{key!r}][{k}]", f"a weight <= MAX_SOFT_WEIGHT = {max_weight:g} (beyond it the "
                "solvers cannot resolve the cost bound next to the penalty; see the page on the forms)",
                repr(w))
    if not any(w > 0.0 for w in weights):
        raise InvalidArgumentError(f"soft[{key!r}]", "at least one weight > 0 (0 keeps a component hard)",
                                   repr(list(weights)))
    return tuple(weights)


def _limits(key: str, value: Any, weights: tuple[float, ...]) -> tuple[float, ...]:
    limits = _numbers(key, value, len(weights), "soft limits > 0 (0 where the weight is 0)")
    for k, (limit, w) in enumerate(zip(limits, weights, strict=True)):
        if w > 0.0 and not (math.isfinite(limit) and limit > 0.0):
            raise InvalidArgumentError(f"soft[{key!r}][{k}]", "a finite soft limit > 0 (its weight is > 0)",
                                       repr(limit))
        if w == 0.0 and limit != 0.0:
            raise InvalidArgumentError(
                f"soft[{key!r}][{k}]", "0 (its weight is 0: no soft limit on that component)", repr(limit))
    return tuple(limits)


def check_soft(
    soft: Any, *, input_constraint: str | None, has_output: bool, n_inputs: int | None,
    n_outputs: int | None, max_weight: float,
) -> dict[str, float | tuple[float, ...]] | None:
    """The option ``soft`` checked; ``None`` or the weights (and limits) as floats and tuples.

    ``n_inputs``/``n_outputs``: the lengths a list must have (``None``: not known here, checked
    where they are).

    Raises
    ------
    InvalidArgumentError, ArgumentTypeError
        Naming ``soft`` or the entry (``soft['u']``, ``soft['u_limit'][1]``).
    """
    if soft is None:
        return None
    if not isinstance(soft, Mapping):
        raise ArgumentTypeError("soft", 'None or a dict of weights {"u": w_u, "y": w_y}', type(soft).__name__)
    unknown = sorted(str(k) for k in soft if k not in _KEYS)
    if unknown:
        raise InvalidArgumentError(
            "soft", 'weights for "u" and/or "y" (and the soft limits "u_limit", "y_limit")',
            f"unknown keys {unknown}")
    if not any(k in soft for k in FAMILIES):
        raise InvalidArgumentError("soft", 'at least one weight ("u" or "y")',
                                   "an empty dict" if not soft else f"only {sorted(soft)}")
    for family in FAMILIES:
        if f"{family}_limit" in soft and family not in soft:
            raise InvalidArgumentError(f"soft[{family + '_limit'!r}]",
                                       f"the per-component weights soft[{family!r}] beside it", "none")
    sizes = {"u": n_inputs, "y": n_outputs}
    out: dict[str, float | tuple[float, ...]] = {}
    for family in [key for key in soft if key in FAMILIES]:  # in the order given
        weight = soft[family]
        limit_key = f"{family}_limit"
        if _is_number(weight):
            out[family] = _scalar_weight(family, weight, max_weight)
        elif not isinstance(weight, list | tuple | np.ndarray):
            expected = "a number > 0 (or a list of weights >= 0, one per component)"
            raise ArgumentTypeError(f"soft[{family!r}]", expected, type(weight).__name__)
        if family == "u" and input_constraint is None:
            expected = 'no "u" weight without an input bound (u_max)'
            raise InvalidArgumentError("soft", expected, repr(dict(soft)))
        if family == "y" and not has_output:
            raise InvalidArgumentError(
                "soft", 'no "y" weight without output bounds (output_matrix, y_max)', repr(dict(soft)))
        if _is_number(weight):
            if limit_key in soft:
                raise InvalidArgumentError(
                    f"soft[{family!r}]", f"a list of weights, one per component, with soft[{limit_key!r}]",
                    repr(weight))
            continue
        weights = _component_weights(family, weight, sizes[family], max_weight)
        out[family] = weights
        if limit_key in soft:
            out[limit_key] = _limits(limit_key, soft[limit_key], weights)
        elif family == "u" and input_constraint != "peak":
            raise InvalidArgumentError(
                "soft, input_constraint",
                "input_constraint='peak' with per-component weights soft['u'] (the ellipsoid bound has "
                "no components; or give soft limits soft['u_limit'])",
                f"input_constraint={input_constraint!r}")
    return {key: out[key] for key in soft if key in out}  # in the order given (a sweep's records)


def soft_slacks(soft: Mapping[str, Any] | None) -> tuple[SoftSlack, ...]:
    """The slacks of a checked ``soft`` (:func:`check_soft`), inputs first, in component order."""
    slacks: list[SoftSlack] = []
    for family in FAMILIES:
        weight = (soft or {}).get(family)
        if weight is None:
            continue
        if isinstance(weight, float):
            slacks.append(SoftSlack(f"s_{family}", family, None, weight, None))
            continue
        limits = (soft or {}).get(f"{family}_limit")
        for k, w in enumerate(weight):
            if w > 0.0:
                limit = None if limits is None else limits[k]
                slacks.append(SoftSlack(f"s_{family}{k}", family, k, w, limit))
    return tuple(slacks)


def bound_slack(soft: Mapping[str, Any] | None, family: str, component: int | None) -> str | None:
    """The slack that softens the hard bound of ``family``'s ``component`` (``None``: the
    ellipsoid bound), or ``None`` where that bound stays hard."""
    for slack in soft_slacks(soft):
        if slack.family == family and slack.limit is None and slack.component in (None, component):
            return slack.name
    return None


def limit_slacks(soft: Mapping[str, Any] | None, family: str) -> tuple[SoftSlack, ...]:
    """The slacks of ``family``'s soft limits (``soft[family + "_limit"]``), in component order."""
    return tuple(s for s in soft_slacks(soft) if s.family == family and s.limit is not None)
