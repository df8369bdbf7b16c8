"""Result types of the sensitivity analysis."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ..critical_result import CriticalFn


@dataclass(frozen=True)
class SensitivityEntry:
    """Derivative of the critical Fn with respect to one coefficient.

    Attributes
    ----------
    key : str
        Dotted vessel key, or a name of :data:`FACTORS`.
    value : float
        The coefficient at the base point (its own unit; 1 for factors).
    unit, status, source : str
        As in the vessel file (``"factor"`` status for factors).
    dFn_dtheta : float
        ``dFn*/dtheta`` per unit of ``unit``.
    elasticity : float or None
        ``theta / Fn* dFn*/dtheta`` (None when ``theta = 0``).
    step : float
        Finite-difference step of ``G_theta`` (0 for exact parameter derivatives).
    method : str
        ``"central"``, ``"forward"`` (a bound next to theta) or ``"exact"``.
    kind : str
        ``"file"`` (given/assumed/measured in the file), ``"estimated"``,
        ``"system-parameter"``, ``"numerical"`` or ``"factor"``.
    quantity : float or None
        For factors: the quantity they scale at the base point (N), else None.
    sigma : float or None
        Standard uncertainty from the vessel file (its unit), if any.
    """

    key: str
    value: float
    unit: str
    status: str
    source: str
    dFn_dtheta: float
    elasticity: float | None
    step: float
    method: str
    kind: str
    quantity: float | None = None
    sigma: float | None = None

    @property
    def contribution(self) -> float | None:
        """``|dFn*/dtheta| sigma``: this coefficient's standard uncertainty of Fn*."""
        return None if self.sigma is None else abs(self.dFn_dtheta) * self.sigma

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        d = dataclasses.asdict(self)
        d["contribution"] = self.contribution
        return d


@dataclass(frozen=True, eq=False)
class Sensitivity:
    """Sensitivities of the critical Fn of one course.

    Attributes
    ----------
    chi_c : float
        Course (rad).
    Fn : float
        Critical Fn at the base point.
    entries : tuple of SensitivityEntry
        Sorted by decreasing ``|elasticity|`` (zero-valued coefficients last, by
        ``|dFn/dtheta|``).
    connection : CriticalFn
        The converged connection that was differentiated.
    elapsed : float
        Wall time (s).
    """

    chi_c: float
    Fn: float
    entries: tuple[SensitivityEntry, ...]
    connection: CriticalFn = field(repr=False)
    elapsed: float = 0.0

    def entry(self, key: str) -> SensitivityEntry:
        """The entry of ``key``."""
        for e in self.entries:
            if e.key == key:
                return e
        raise KeyError(f"no sensitivity for {key!r}")

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary: the course, Fn and every entry (sorted)."""
        return {
            "chi_c_deg": math.degrees(self.chi_c),
            "Fn": self.Fn,
            "residual_norm": self.connection.residual_norm,
            "n_intervals": self.connection.orbit.mesh.n_intervals,
            "entries": [e.to_json() for e in self.entries],
            "elapsed_s": self.elapsed,
        }


def _sort_key(e: SensitivityEntry) -> tuple[int, float]:
    if e.elasticity is None:
        return (1, -abs(e.dFn_dtheta))
    return (0, -abs(e.elasticity))


def linear_prediction(sens: Sensitivity, changes: Mapping[str, float]) -> float:
    """``Fn* + sum dFn*/dtheta (theta - theta_0)`` for ``{key: new value}``."""
    out = sens.Fn
    for k, v in changes.items():
        e = sens.entry(k)
        out += e.dFn_dtheta * (float(v) - e.value)
    return out
