"""Connecting orbits by Gauss-Legendre collocation, built once in CasADi.

Public names:

* :class:`CollocationMesh` — nodes, degree, truncation time ``T``;
* :class:`HeteroclinicProblem`, :class:`PinPhase` — the connection and its phase condition;
* :class:`ConnectionResult` — orbit, equilibria, parameters, status; ``save``/``load``/``plot``;
* :func:`solve_connection`, :func:`check_convergence`, :func:`continue_connection`,
  :func:`connection_at`.
"""

from .collocation import CollocationMesh
from .connection import HeteroclinicProblem, PinPhase
from .result import ConnectionResult
from .solve import (
    ConvergenceCheck,
    check_convergence,
    connection_at,
    continue_connection,
    solve_connection,
)

__all__ = [
    "CollocationMesh",
    "ConnectionResult",
    "ConvergenceCheck",
    "HeteroclinicProblem",
    "PinPhase",
    "check_convergence",
    "connection_at",
    "continue_connection",
    "solve_connection",
]
