"""Periodic orbits: collocation, Floquet multipliers, continuation and bifurcations of
cycles (see :mod:`continuation.periodic.continuation`)."""

from .collocation import CollocationLayout, monodromy_factors
from .continuation import (
    PeriodLimit,
    adapt_mesh,
    continue_periodic,
    multipliers,
    orbit_at,
    period_limit,
    solve_orbit,
)
from .floquet import FloquetResult, floquet, ns_test, pd_test
from .orbit import PeriodicOrbit, orbit_from_array
from .problem import PeriodicOrbitProblem, error_estimate

__all__ = [
    "CollocationLayout",
    "FloquetResult",
    "PeriodLimit",
    "PeriodicOrbit",
    "PeriodicOrbitProblem",
    "adapt_mesh",
    "continue_periodic",
    "error_estimate",
    "floquet",
    "monodromy_factors",
    "multipliers",
    "ns_test",
    "orbit_at",
    "orbit_from_array",
    "pd_test",
    "period_limit",
    "solve_orbit",
]
