"""Periodic orbits: collocation, Floquet multipliers, continuation and bifurcations of
cycles (see :mod:`continuation.periodic.continuation`)."""

from .collocation import CollocationLayout, monodromy_factors
from .continuation import (
    CycleSegments,
    PeriodLimit,
    adapt_mesh,
    continue_periodic,
    multipliers,
    orbit_at,
    period_limit,
    problem_at,
    solve_orbit,
)
from .doubling import continue_period_doubled, doubled_orbit, switch_period_doubling
from .floquet import FloquetResult, floquet, ns_test, pd_test
from .hopf import first_lyapunov_coefficient, periodic_orbit_from_hopf
from .orbit import PeriodicOrbit, orbit_from_array
from .problem import PeriodicOrbitProblem, error_estimate
from .starts import continue_from_hopf, orbit_from_trajectory

__all__ = [
    "CycleSegments",
    "CollocationLayout",
    "FloquetResult",
    "PeriodLimit",
    "PeriodicOrbit",
    "PeriodicOrbitProblem",
    "adapt_mesh",
    "continue_from_hopf",
    "continue_period_doubled",
    "continue_periodic",
    "doubled_orbit",
    "error_estimate",
    "first_lyapunov_coefficient",
    "floquet",
    "monodromy_factors",
    "multipliers",
    "ns_test",
    "orbit_at",
    "orbit_from_array",
    "orbit_from_trajectory",
    "pd_test",
    "period_limit",
    "periodic_orbit_from_hopf",
    "problem_at",
    "solve_orbit",
    "switch_period_doubling",
]
