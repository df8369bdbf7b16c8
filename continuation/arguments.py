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


__all__ = ["finite_number"]
