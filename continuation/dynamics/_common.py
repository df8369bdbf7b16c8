"""Argument checks and periodic-state arithmetic shared by the time-domain modules."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..params import Params
from ..typing import FloatArray


def param_vector(system: Any, params: Any) -> FloatArray:
    """Parameter vector ``(m,)`` from a Params, a mapping or an array (checked by the system)."""
    if hasattr(system, "check_params"):
        return np.asarray(system.check_params(params, "params"), dtype=float)
    if isinstance(params, Params):
        return np.array(params.values, dtype=float)
    return np.asarray(params, dtype=float).reshape(-1)


def state_period(system: Any, n: int) -> FloatArray:
    """Period of each of the ``n`` states, ``(n,)`` (``0`` where not periodic)."""
    per = getattr(system, "period", None)
    return np.zeros(n) if per is None else np.asarray(per, dtype=float).reshape(n)


def check_scale(n: int, scale: Any) -> FloatArray:
    """State scales ``(n,)`` of the distances (default ones); ValueError unless positive."""
    if scale is None:
        return np.ones(n)
    s = np.asarray(scale, dtype=float).reshape(-1)
    if s.shape != (n,) or not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise ValueError(f"`scale` must be {n} positive finite numbers, got {scale!r}")
    return s


def periodic_difference(period: FloatArray, x1: FloatArray, x2: FloatArray) -> FloatArray:
    """``x1 - x2`` with periodic components reduced to ``[-P/2, P/2)`` (any leading shape)."""
    d = np.asarray(x1, dtype=float) - np.asarray(x2, dtype=float)
    mask = period > 0
    if np.any(mask):
        per = period[mask]
        d[..., mask] = np.mod(d[..., mask] + per / 2, per) - per / 2
    return d


def period_shift(period: FloatArray, x: FloatArray, x_ref: FloatArray) -> tuple[int, ...]:
    """Integer number of periods between ``x`` and ``x_ref`` for each periodic state."""
    mask = period > 0
    if not np.any(mask):
        return ()
    k = np.rint((np.asarray(x)[mask] - np.asarray(x_ref)[mask]) / period[mask])
    return tuple(int(v) for v in k)
