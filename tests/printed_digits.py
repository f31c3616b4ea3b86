"""How precise a published number is: half a unit in the last digit it is printed with.

A value printed as ``9.716e-3`` stands for any number in ``[9.7155e-3, 9.7165e-3]``; comparing a
computed value with it to a fixed relative tolerance (say 1e-3) is 20 times looser than what the
digits say. :func:`half_unit` reads the bound from the printed text itself.
"""

from __future__ import annotations

from decimal import Decimal

import numpy as np


def half_unit(printed: str) -> float:
    """Half a unit in the last printed digit: ``"9.716e-3"`` gives ``5e-7``, ``"-33.21"`` ``0.005``.

    Parameters
    ----------
    printed : str
        The number as the source prints it (trailing zeros count: ``"1.50"`` gives ``0.005``).

    Returns
    -------
    float
        The largest distance between the printed value and the number it was rounded from.
    """
    exponent = Decimal(printed).as_tuple().exponent
    if not isinstance(exponent, int):
        raise ValueError(f"not a finite number: {printed!r}")
    return 0.5 * 10.0**exponent


def assert_rounds_to(value: float | np.ndarray, printed: str | tuple[str, ...]) -> None:
    """Assert that ``value`` lies within half a unit of the last digit of each ``printed`` number.

    Parameters
    ----------
    value : float or ndarray
        The computed value(s), one per printed number.
    printed : str or tuple of str
        The published value(s) as printed.
    """
    texts = (printed,) if isinstance(printed, str) else printed
    values = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    assert values.shape == (len(texts),), (values, texts)
    for got, text in zip(values, texts, strict=True):
        assert abs(got - float(text)) <= half_unit(text), f"{got!r} does not round to the published {text}"
