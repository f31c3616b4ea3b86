"""A controller's design as JSON values, and the checked reading of it back.

Writing: :func:`encode` turns numbers, arrays, strings, lists and dicts into JSON values
(arrays as nested lists of floats, non-finite numbers as the strings ``"inf"``, ``"-inf"`` and
``"nan"``); :func:`plant_design` writes a :class:`~models.PolytopicModel`. Reading: a
:class:`Design` hands out each field as the type the constructor wants and raises
:class:`DesignError` naming the field for anything missing, mistyped or left unread, so a file
whose design lacks a field, or carries one this toolkit does not know, is refused rather than
half loaded.

Examples
--------
>>> import numpy as np
>>> from rmpc.io.design import Design, encode
>>> values = {"Q": encode(np.eye(2)), "u_max": encode(np.inf)}
>>> values
{'Q': [[1.0, 0.0], [0.0, 1.0]], 'u_max': 'inf'}
>>> design = Design(values)
>>> design.array("Q").shape, design.number("u_max")
((2, 2), inf)
>>> design.finish()
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NoReturn

import numpy as np

from models import PolytopicModel
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import is_integer, is_real

__all__ = ["Design", "DesignError", "encode", "plant_design", "snapshot"]

_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


class DesignError(InvalidArgumentError):
    """A field of a saved design is missing, of the wrong type or unknown (``argument``: its path)."""


def _number(value: float) -> float | str:
    value = float(value)
    if math.isfinite(value):
        return value
    return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")


def encode(value: Any, where: str = "design") -> Any:
    """``value`` as JSON values: arrays as nested lists of floats, non-finite numbers as strings.

    Raises
    ------
    InvalidArgumentError
        Naming ``where`` for a value that is not a number, string, bool, ``None``, array, list,
        tuple or dict with string keys (a saved design holds data, not objects or code).
    """
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return _number(value)
    if isinstance(value, np.ndarray):
        if value.dtype == bool:
            return value.tolist()
        if not np.issubdtype(value.dtype, np.number) or np.iscomplexobj(value):
            raise InvalidArgumentError(where, "a real array", f"an array of dtype {value.dtype}")
        return encode(value.astype(float).tolist(), where)
    if isinstance(value, list | tuple):
        return [encode(item, f"{where}[{i}]") for i, item in enumerate(value)]
    if isinstance(value, Mapping):
        bad = [key for key in value if not isinstance(key, str)]
        if bad:
            raise InvalidArgumentError(where, "a dict with string keys", f"the key {bad[0]!r}")
        return {key: encode(item, f"{where}[{key!r}]") for key, item in value.items()}
    raise InvalidArgumentError(
        where, "numbers, strings, arrays, lists or dicts (a saved design holds data)", type(value).__name__
    )


def snapshot(value: Any) -> Any:
    """A copy of the arrays, lists, tuples and dicts in ``value`` (other objects as they are): a
    constructor keeps its arguments so, for ``save``, without later changes by the caller leaking
    in and without copying (or failing on) objects a file could not hold anyway."""
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, list):
        return [snapshot(item) for item in value]
    if isinstance(value, tuple):
        return tuple(snapshot(item) for item in value)
    if isinstance(value, Mapping):
        return {key: snapshot(item) for key, item in value.items()}
    return value


def plant_design(plant: PolytopicModel) -> dict[str, Any]:
    """The fields of a :class:`~models.PolytopicModel`: vertices, sample time, nominal model, names."""
    return {
        "A": encode(plant.A), "B": encode(plant.B), "dt": encode(plant.dt),
        "nominal": [encode(plant.nominal[0]), encode(plant.nominal[1])],
        "state_names": list(plant.state_names), "input_names": list(plant.input_names),
        "attitude": plant.attitude,
    }


def _floats(value: Any, where: str) -> Any:
    if isinstance(value, list):
        return [_floats(item, where) for item in value]
    if isinstance(value, str) and value in _NON_FINITE:
        return _NON_FINITE[value]
    if not is_real(value):
        raise DesignError(where, "numbers (non-finite ones as 'inf', '-inf', 'nan')", repr(value)[:80])
    return float(value)


def _plain(value: Any) -> Any:
    """A JSON value with the strings of non-finite numbers turned back into floats."""
    if isinstance(value, list):
        return [_plain(item) for item in value]
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, str) and value in _NON_FINITE:
        return _NON_FINITE[value]
    return value


class Design:
    """The fields of a saved design, read one by one with their types checked.

    Parameters
    ----------
    values : mapping
        The JSON object of the design (or of one part of it).
    where : str
        Its path in the file, for messages (``"design"``, ``"design.table"``).

    Every getter marks its field as read; :meth:`finish` refuses fields nobody read.
    """

    def __init__(self, values: Any, where: str = "design") -> None:
        if not isinstance(values, Mapping):
            raise DesignError(where, "an object of named fields", type(values).__name__)
        self._values, self._where = values, where
        self._read: set[str] = set()

    def has(self, name: str) -> bool:
        """Whether the field is present (it is not marked as read)."""
        return name in self._values

    def value(self, name: str) -> Any:
        """The raw JSON value of a field that must be present."""
        if name not in self._values:
            raise DesignError(f"{self._where}.{name}", "a field of the design", "none (missing)")
        self._read.add(name)
        return self._values[name]

    def _where_of(self, name: str) -> str:
        return f"{self._where}.{name}"

    def plain(self, name: str) -> Any:
        """A field as plain JSON values, the strings of non-finite numbers turned into floats
        (settings dicts, whose value types the toolkit does not fix)."""
        return _plain(self.value(name))

    def text(self, name: str) -> str:
        value = self.value(name)
        if not isinstance(value, str):
            self._bad(name, "a string", value)
        return str(value)

    def optional_text(self, name: str) -> str | None:
        return None if self.value(name) is None else self.text(name)

    def number(self, name: str) -> float:
        """A number (or the string of a non-finite one)."""
        value = self.value(name)
        if isinstance(value, list):
            self._bad(name, "a number", value)
        return float(_floats(value, self._where_of(name)))

    def optional_number(self, name: str) -> float | None:
        return None if self.value(name) is None else self.number(name)

    def integer(self, name: str) -> int:
        value = self.value(name)
        if not is_integer(value):
            self._bad(name, "an integer", value)
        return int(value)

    def optional_integer(self, name: str) -> int | None:
        return None if self.value(name) is None else self.integer(name)

    def flag(self, name: str) -> bool:
        value = self.value(name)
        if not isinstance(value, bool):
            self._bad(name, "true or false", value)
        return bool(value)

    def array(self, name: str, ndim: int | None = None) -> np.ndarray:
        """A field as a float array (``ndim`` checked when given)."""
        value = self.value(name)
        try:
            arr = np.array(_floats(value, self._where_of(name)), dtype=float)
        except ValueError:
            self._bad(name, "a rectangular array of numbers", value)
        if ndim is not None and arr.ndim != ndim:
            self._bad(name, f"an array of {ndim} dimension(s)", f"{arr.ndim} dimension(s)")
        return arr

    def optional_array(self, name: str, ndim: int | None = None) -> np.ndarray | None:
        return None if self.value(name) is None else self.array(name, ndim)

    def bound(self, name: str) -> float | np.ndarray | None:
        """``None``, a number or a vector (an input or output bound as the constructor takes it)."""
        value = self.value(name)
        if value is None:
            return None
        if isinstance(value, list):
            return self.array(name, ndim=1)
        return self.number(name)

    def booleans(self, name: str) -> np.ndarray:
        value = self.value(name)
        if not isinstance(value, list) or not all(isinstance(v, bool) for v in value):
            self._bad(name, "a list of true/false", value)
        return np.array(value, dtype=bool)

    def mapping(self, name: str) -> dict[str, Any]:
        """A settings dict as plain values (see :meth:`plain`)."""
        value = self.value(name)
        if not isinstance(value, dict):
            self._bad(name, "an object", value)
        return dict(_plain(value))

    def optional_mapping(self, name: str) -> dict[str, Any] | None:
        return None if self.value(name) is None else self.mapping(name)

    def part(self, name: str) -> Design:
        """A nested design (its own fields checked by its own :meth:`finish`)."""
        return Design(self.value(name), self._where_of(name))

    def optional_part(self, name: str) -> Design | None:
        return None if self.value(name) is None else self.part(name)

    def parts(self, name: str) -> list[Design]:
        value = self.value(name)
        if not isinstance(value, list):
            self._bad(name, "a list of objects", value)
        return [Design(item, f"{self._where_of(name)}[{i}]") for i, item in enumerate(value)]

    def plant(self, name: str = "plant") -> PolytopicModel:
        """A :class:`~models.PolytopicModel` written by :func:`plant_design`."""
        part = self.part(name)
        a, b = part.array("A", ndim=3), part.array("B", ndim=3)
        nominal = part.value("nominal")
        if not isinstance(nominal, list) or len(nominal) != 2:
            part._bad("nominal", "an (A, B) pair", nominal)
        names = {key: part.value(key) for key in ("state_names", "input_names")}
        for key, value in names.items():
            if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
                part._bad(key, "a list of strings", value)
        where = part._where_of("nominal")
        plant = PolytopicModel(
            list(zip(a, b, strict=True)), dt=part.number("dt"),
            nominal=(np.array(_floats(nominal[0], where)), np.array(_floats(nominal[1], where))),
            state_names=names["state_names"], input_names=names["input_names"],
            attitude=part.optional_text("attitude"),  # type: ignore[arg-type]
        )
        part.finish()
        return plant

    def finish(self) -> None:
        """Refuse the fields no getter read (a design of a newer or another kind)."""
        unknown = sorted(set(self._values) - self._read)
        if unknown:
            raise DesignError(self._where, "only the fields this toolkit knows",
                              f"unknown field(s) {', '.join(unknown)}")

    def _bad(self, name: str, expected: str, found: Any) -> NoReturn:
        raise DesignError(self._where_of(name), expected, repr(found)[:80])
