"""Connecting orbits by Gauss-Legendre collocation, built once in CasADi.

This package is also the one collocation core of every orbit the engine computes by
collocation -- connections, landings and the periodic orbits of
:mod:`continuation.periodic` (design: :mod:`continuation.bvp.layout`): one mesh and
local error estimate (:mod:`~continuation.bvp.collocation`), one layout of the orbit's
unknowns and rows with the integral phase condition (:mod:`~continuation.bvp.layout`),
one condensation of the stage unknowns (:mod:`~continuation.bvp.condense`). A landing
is a connection whose start condition is a point: the same CasADi functions, the same
accuracy loop (:mod:`~continuation.bvp.accuracy`), the same result
(:class:`OrbitResult`, one ``to_result``) and driver adapter. A cycle's mesh adaptation
and halved-mesh estimate are steps of that accuracy loop too.

Names follow :func:`~continuation.equilibria.continue_equilibria`: ``free`` are the
*solved* parameters, ``vary`` is the continuation parameter.

Public names:

* :class:`CollocationMesh` — nodes, degree, truncation time ``T``;
* :class:`HeteroclinicProblem`, :class:`PinPhase` — the connection and its phase condition;
* :class:`ConnectionResult` — orbit, equilibria, parameters, status; ``save``/``load``/``plot``
  (:class:`OrbitResult`, shared with :class:`LandingResult`);
* :func:`find_connection` — from a saddle alone: its unstable manifold, cut at the
  closest approach to the target, ``T`` from the eigenvalues, solve and check;
* :func:`solve_connection` (adaptive mesh and error estimates by default,
  :class:`ConnectionAccuracy`, :class:`ErrorEstimates`), :func:`check_convergence`,
  :func:`continue_connection`, :func:`connection_at`;
* :class:`LandingProblem`, :func:`solve_landing`, :class:`LandingResult`,
  :func:`continue_landing`, :func:`landing_at` — an orbit from a given start point
  ``x0(s)`` onto a saddle's stable manifold, one system parameter solved per unstable
  direction, continued in ``s`` (:mod:`continuation.bvp.landing`);
* :func:`simplified_newton`, :class:`JacobianCache` — Newton with few Jacobians (chord
  steps with Broyden updates; one factorisation shared between nearby solves), behind
  ``solve_connection(..., method="broyden" | "chord")``.

Example: the Nagumo front ``u'' + c u' + u (1 - u)(u - a) = 0`` from ``u = 1`` to
``u = 0`` has ``c = sqrt(2) (1/2 - a)`` (McKean 1970)::

    def rhs(x, p, ops):
        return ops.stack([x[1], -p[1] * x[1] - x[0] * (1 - x[0]) * (x[0] - p[0])])

    s = System(rhs, ("u", "v"), ("a", "c"))
    prob = HeteroclinicProblem(s, s.params(a=0.25, c=0.2), free="c",
                               saddle_from=[1, 0], saddle_to=[0, 0], T=40.0)
    t = np.linspace(0, 40, 200)
    u = 1 / (1 + np.exp(t - 20))
    res = solve_connection(prob, (t, np.column_stack([u, np.gradient(u, t)])))
    res.value("c"), res.error("c")                   # 0.35355339059..., its error bound
    check_convergence(res).delta_mesh                # change of c on the halved mesh
    br = continue_connection(res, "a", ContinuationSettings(p_min=0.1, p_max=0.4))
    br.records["c"]                                  # c along the branch

From the saddle alone (branch -1 of its unstable manifold heads for ``u = 0``)::

    res = find_connection(s, s.params(a=0.25, c=0.2), "c", source=[1, 0],
                          target=[0, 0], branch=-1)

A connection to the same equilibrium shifted by a period (a front on a circle, the
ship's wave-relative position ``xi_G`` with period 1) uses ``shift={"xi_G": -1.0}``
instead of ``saddle_to``; the state must be declared periodic in the System.
``shift=0`` gives a homoclinic orbit (``x_+ = x_-``).
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _EXPORTS is what runs (names imported on first use)
    from .accuracy import ConnectionAccuracy
    from .collocation import CollocationMesh
    from .connection import HeteroclinicProblem, PinPhase
    from .find import find_connection
    from .landing import LandingProblem
    from .landing_solve import continue_landing, landing_at, solve_landing
    from .result import ConnectionResult, ErrorEstimates, LandingResult, OrbitResult
    from .simplified import JacobianCache, simplified_newton
    from .solve import (
        ContinuedConnection,
        ConvergenceCheck,
        check_convergence,
        connection_at,
        continue_connection,
        solve_connection,
    )

#: Sub-module -> the public names it defines (imported on first use: issue 27).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "accuracy": ("ConnectionAccuracy",),
    "collocation": ("CollocationMesh",),
    "connection": ("HeteroclinicProblem", "PinPhase"),
    "find": ("find_connection",),
    "landing": ("LandingProblem",),
    "landing_solve": ("continue_landing", "landing_at", "solve_landing"),
    "result": ("ConnectionResult", "ErrorEstimates", "LandingResult", "OrbitResult"),
    "simplified": ("JacobianCache", "simplified_newton"),
    "solve": (
        "ContinuedConnection",
        "ConvergenceCheck",
        "check_convergence",
        "connection_at",
        "continue_connection",
        "solve_connection",
    ),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = [
    "CollocationMesh",
    "ConnectionAccuracy",
    "ConnectionResult",
    "ContinuedConnection",
    "ConvergenceCheck",
    "ErrorEstimates",
    "HeteroclinicProblem",
    "JacobianCache",
    "LandingProblem",
    "LandingResult",
    "OrbitResult",
    "PinPhase",
    "check_convergence",
    "connection_at",
    "find_connection",
    "continue_connection",
    "continue_landing",
    "landing_at",
    "simplified_newton",
    "solve_connection",
    "solve_landing",
]
