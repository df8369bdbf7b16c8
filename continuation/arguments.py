"""Checks of scalar arguments shared across the engine (and open to the vessel plugins).

Bad input raises :class:`ValueError` at once with a one-line message that names the
argument (the project's rule for library errors, :mod:`continuation.errors`).
"""

from __future__ import annotations

import math
from typing import Any


def finite_number(name: str, value: Any, *, meaning: str = "") -> float:
    """``float(value)``, checked to be a finite number.

    Parameters
    ----------
    name : str
        The argument's name, as the user wrote it (quoted in the message).
    value : object
        Anything ``float()`` accepts: a Python or NumPy scalar, a numeric string.
    meaning : str, optional
        What the number is, shown in brackets after "finite number" (e.g. a unit).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        ``"`name` must be a finite number, got ..."`` when ``value`` is not a number
        or is NaN or infinite.
    """
    what = f"a finite number ({meaning})" if meaning else "a finite number"
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be {what}, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"`{name}` must be {what}, got {x}")
    return x


def positive(name: str, value: Any) -> float:
    """``float(value)``, checked to be a positive finite number.

    Unlike :func:`finite_number`, only a Python ``int`` or ``float`` passes (a NumPy
    floating scalar is a ``float``); a string or another type is refused, with the
    message ``"`name` must be a positive finite number, got ..."`` (a ValueError), as
    is a value that is not in ``(0, inf)``.

    Parameters
    ----------
    name : str
    value : int or float

    Returns
    -------
    float
    """
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise ValueError(f"`{name}` must be a positive finite number, got {value!r}")
    return float(value)


def integer_at_least(name: str, value: Any, low: int) -> int:
    """``value``, checked to be a Python ``int`` (``bool`` included) of at least ``low``.

    Anything else raises ValueError ``"`name` must be an integer >= low, got ..."``.

    Parameters
    ----------
    name : str
    value : int
    low : int

    Returns
    -------
    int
    """
    if not (isinstance(value, int) and value >= low):
        raise ValueError(f"`{name}` must be an integer >= {low}, got {value!r}")
    return value


__all__ = ["finite_number", "integer_at_least", "positive"]
