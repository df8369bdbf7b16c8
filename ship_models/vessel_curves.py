"""Measured curves in a vessel file: the ``[curves]`` section.

A vessel file may give measured propulsion curves instead of estimating them::

    [curves]
    resistance = { x = [2.0, 3.0, 4.0], y = [3.1, 7.0, 12.9], x_unit = "m/s",
                   y_unit = "kN", source = "tank test report ...", status = "measured" }
    K_T = { x = [0.0, 0.2, 0.4], y = [0.34, 0.29, 0.22], x_unit = "-", y_unit = "-",
            source = "...", status = "measured" }
    K_T = { coefficients = [0.34, -0.27, -0.14], source = "...", status = "measured" }
    w_P = { x = [...], y = [...], x_unit = "kn", y_unit = "-", source = "...", status = "..." }
    t_P = { ... }

``resistance`` is R(u) (force against speed), ``K_T`` the open-water thrust
coefficient against the advance ratio J (a table, or polynomial coefficients
``c_0, c_1, ...`` of ``K_T = sum c_i J^i`` with an optional ``J_range``), ``w_P`` and
``t_P`` the wake and thrust-deduction fractions against speed. Tables are
interpolated by C2 cubic splines (:mod:`ship_models.hydro.curves`); the speed range
(or J range) of a table is its validity range.

Validation names the field: ``curves.resistance.x`` must be strictly increasing and
non-negative, values finite, resistance non-negative, fractions in [0, 0.9).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

#: curve name -> (x dimension, y dimension, description)
CURVES: dict[str, tuple[str, str, str]] = {
    "resistance": ("speed", "force", "calm-water resistance R(u)"),
    "K_T": ("none", "none", "open-water thrust coefficient K_T(J)"),
    "w_P": ("speed", "none", "effective wake fraction w_P(u)"),
    "t_P": ("speed", "none", "thrust deduction fraction t_P(u)"),
}

_UNITS: dict[str, dict[str, float]] = {
    "speed": {"m/s": 1.0, "kn": 1852.0 / 3600.0},
    "force": {"N": 1.0, "kN": 1000.0},
    "none": {"-": 1.0},
}

_STATUSES = ("given", "measured", "estimated", "assumed", "calibrated")


class CurveError(ValueError):
    """A ``[curves]`` entry is malformed (the message names the field)."""


@dataclass(frozen=True)
class CurveData:
    """One measured curve in SI units.

    Attributes
    ----------
    name : str
        ``resistance``, ``K_T``, ``w_P`` or ``t_P``.
    x, y : tuple of float
        Table in SI (empty for a polynomial).
    coefficients : tuple of float
        Polynomial coefficients ``c_0, c_1, ...`` (empty for a table).
    x_range : tuple of float
        Validity interval of the abscissa (the table's span, or ``J_range``).
    source, status : str
        Where it comes from and its status (as for coefficients).
    raw : tuple
        The entry as written (for writing the file back), as sorted ``(key, value)``.
    """

    name: str
    x: tuple[float, ...]
    y: tuple[float, ...]
    coefficients: tuple[float, ...]
    x_range: tuple[float, float]
    source: str
    status: str
    raw: tuple[tuple[str, Any], ...]

    @property
    def is_table(self) -> bool:
        """True for a table, False for a polynomial."""
        return len(self.x) > 0

    def as_dict(self) -> dict[str, Any]:
        """The entry as written in the file."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.raw}


def _numbers(where: str, raw: Any, min_len: int) -> list[float]:
    if not isinstance(raw, list) or len(raw) < min_len:
        raise CurveError(f"`{where}` must be a list of at least {min_len} numbers")
    out = []
    for i, v in enumerate(raw):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise CurveError(f"`{where}[{i}]` must be a finite number, got {v!r}")
        out.append(float(v))
    return out


def _unit(where: str, dim: str, unit: Any) -> float:
    units = _UNITS[dim]
    if unit not in units:
        raise CurveError(f"`{where}`: unit {unit!r} not accepted; use one of {sorted(units)}")
    return units[unit]


def parse_curve(name: str, raw: Any) -> CurveData:
    """Validate one ``[curves]`` entry and convert it to SI.

    Raises
    ------
    CurveError
        Naming the field (``curves.<name>.<key>``).
    """
    where = f"curves.{name}"
    if name not in CURVES:
        raise CurveError(f"`{where}`: unknown curve {name!r}; curves are {list(CURVES)}")
    if not isinstance(raw, Mapping):
        raise CurveError(f"`{where}` must be a table")
    xdim, ydim, _ = CURVES[name]
    for k in ("source", "status"):
        if not isinstance(raw.get(k), str) or not raw[k].strip():
            raise CurveError(f"`{where}.{k}` must be a non-empty string")
    if raw["status"] not in _STATUSES:
        raise CurveError(f"`{where}.status` must be one of {_STATUSES}, got {raw['status']!r}")
    if "coefficients" in raw:
        if name != "K_T":
            raise CurveError(f"`{where}`: only K_T may be given as polynomial coefficients")
        extra = sorted(set(raw) - {"coefficients", "J_range", "source", "status"})
        if extra:
            raise CurveError(f"`{where}` has unknown key(s) {extra}")
        c = _numbers(f"{where}.coefficients", raw["coefficients"], 2)
        if c[0] <= 0:
            raise CurveError(f"`{where}.coefficients[0]` (K_T at J = 0) must be > 0, got {c[0]}")
        rng = _numbers(f"{where}.J_range", raw.get("J_range", [0.0, math.inf]), 2)
        if len(rng) != 2 or not 0 <= rng[0] < rng[1]:
            raise CurveError(f"`{where}.J_range` must be [J_lo, J_hi] with 0 <= J_lo < J_hi")
        return CurveData(
            name, (), (), tuple(c), (rng[0], rng[1]), raw["source"], raw["status"],
            tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in raw.items())),
        )  # fmt: skip
    extra = sorted(set(raw) - {"x", "y", "x_unit", "y_unit", "source", "status"})
    if extra:
        raise CurveError(f"`{where}` has unknown key(s) {extra}")
    for k in ("x", "y", "x_unit", "y_unit"):
        if k not in raw:
            raise CurveError(f"`{where}` is missing `{k}`")
    x = _numbers(f"{where}.x", raw["x"], 3)
    y = _numbers(f"{where}.y", raw["y"], 3)
    if len(x) != len(y):
        raise CurveError(f"`{where}.x` and `{where}.y` must have the same length")
    if any(b <= a for a, b in zip(x, x[1:], strict=False)) or x[0] < 0:
        raise CurveError(f"`{where}.x` must be non-negative and strictly increasing")
    fx = _unit(f"{where}.x_unit", xdim, raw["x_unit"])
    fy = _unit(f"{where}.y_unit", ydim, raw["y_unit"])
    x = [v * fx for v in x]
    y = [v * fy for v in y]
    if name == "resistance" and min(y) < 0:
        raise CurveError(f"`{where}.y` must be >= 0 (a resistance)")
    if name in ("w_P", "t_P") and not all(0 <= v < 0.9 for v in y):
        raise CurveError(f"`{where}.y` must lie in [0, 0.9)")
    return CurveData(
        name, tuple(x), tuple(y), (), (x[0], x[-1]), raw["source"], raw["status"],
        tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in raw.items())),
    )  # fmt: skip


def parse_curves(raw: Any) -> dict[str, CurveData]:
    """Validate the whole ``[curves]`` section."""
    if not isinstance(raw, Mapping):
        raise CurveError("`curves` must be a table of curves")
    return {str(k): parse_curve(str(k), v) for k, v in raw.items()}


def curves_to_toml(curves: Mapping[str, CurveData]) -> list[str]:
    """Lines of a ``[curves]`` section (empty when there are no curves)."""
    import json

    if not curves:
        return []

    def val(v: Any) -> str:
        if isinstance(v, (tuple, list)):
            return "[" + ", ".join(repr(float(x)) for x in v) + "]"
        if isinstance(v, str):
            return json.dumps(v, ensure_ascii=True)
        return repr(float(v))

    lines = ["", "[curves]"]
    for name, c in curves.items():
        body = ", ".join(f"{k} = {val(v)}" for k, v in c.raw)
        lines.append(f"{name} = {{ {body} }}")
    return lines


__all__ = ["CURVES", "CurveData", "CurveError", "curves_to_toml", "parse_curve", "parse_curves"]
