r"""Periodic orbits: collocation, Floquet multipliers, continuation, bifurcations of cycles.

A cycle is collocated on the core it shares with connections and landings
(:mod:`continuation.bvp.layout`): the same mesh, layout of unknowns and rows, integral
phase condition, condensation and local error estimate, and the steps of the accuracy
loop of connections (mesh adaptation, the re-solve on the halved mesh:
:mod:`continuation.periodic.solve`); periodicity and the phase condition are its
boundary conditions. Its residual and Jacobian values are filled by the compiled kernel
connections and landings use for their collocation and continuity rows
(:mod:`continuation.bvp._collocation_jit`), with the cycle's own rows beside them.

Modules: :mod:`~continuation.periodic.problem` (the collocation system),
:mod:`~continuation.periodic.solve` (one cycle: Newton, mesh adaptation, refinement),
:mod:`~continuation.periodic.continuation` (:func:`continue_periodic`),
:mod:`~continuation.periodic.segments` (one driver run per mesh and the segments of an
adapted branch), :mod:`~continuation.periodic.rows` (the rows of a branch and their
meshes), :mod:`~continuation.periodic.limit` (the period's blow-up end).

* :class:`PeriodicOrbitProblem` -- the collocation system (Gauss-Legendre, degree
  ``m``, ``N`` intervals on ``[0, 1]``, period unknown, integral phase condition,
  rotation orbits by a winding number per periodic state) as a continuation problem;
* :func:`continue_periodic` -- its branch by the pseudo-arclength driver, with LPC,
  BPC, PD and NS located; :func:`continue_from_hopf`, :func:`continue_period_doubled`
  start at a Hopf point or at a PD point, :func:`continue_from_branch_point` (or
  ``switch_branch``) on the branch crossing at a BPC; ``period_max`` ends a branch whose
  period grows without bound (``Status.PERIOD_UNBOUNDED``; :func:`period_limit` fits the limit
  and gives a guess of the connecting orbit);
* starts: :func:`periodic_orbit_from_hopf`, :func:`orbit_from_trajectory`,
  :func:`orbit_from_array`; :func:`solve_orbit`, :func:`adapt_mesh`;
* :func:`multipliers`, :func:`orbit_at`, :func:`problem_at`, :func:`special_problem`
  along a branch (whose mesh adapts to ``error_tol`` by default).

Example (the van der Pol oscillator, period 6.6632868593 at ``mu = 1``)::

    def rhs(x, p, ops):
        return ops.stack([x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0]])

    s = System(rhs, ("x", "y"), ("mu",))
    tr = simulate(s, [2.0, 0.0], {"mu": 1.0}, (0.0, 60.0), dt=0.01)
    orb = orbit_from_trajectory(s, {"mu": 1.0}, tr, mesh=CollocationMesh(60, 4, 1.0))
    orb.T                                            # 6.66328685932...
    br = continue_periodic(s, orb, {"mu": 1.0}, "mu", ContinuationSettings(p_max=5.0))
    br.records["T"], multipliers(br)

A rotation orbit of a circle coordinate (the ship's ``xi_G`` with period 1, advancing
one wavelength per cycle) is declared by ``System(..., periodic={"xi_G": 1.0})`` and
``winding={"xi_G": 1}`` (or ``-1``) in the start.
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _EXPORTS is what runs (names imported on first use)
    from .branch_point import continue_from_branch_point
    from .collocation import CollocationLayout, monodromy_factors
    from .continuation import continue_periodic
    from .doubling import continue_period_doubled, doubled_orbit, switch_period_doubling
    from .floquet import FloquetResult, floquet, ns_test, pd_test
    from .hopf import first_lyapunov_coefficient, periodic_orbit_from_hopf
    from .limit import PeriodLimit, period_limit
    from .orbit import PeriodicOrbit, orbit_from_array
    from .problem import PeriodicOrbitProblem, error_estimate
    from .rows import CycleSegments, multipliers, orbit_at, problem_at, special_problem
    from .solve import adapt_mesh, solve_orbit
    from .starts import continue_from_hopf, orbit_from_trajectory

#: Sub-module -> the public names it defines (imported on first use: issue 27).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "branch_point": ("continue_from_branch_point",),
    "collocation": ("CollocationLayout", "monodromy_factors"),
    "continuation": ("continue_periodic",),
    "limit": ("PeriodLimit", "period_limit"),
    "rows": ("CycleSegments", "multipliers", "orbit_at", "problem_at", "special_problem"),
    "solve": ("adapt_mesh", "solve_orbit"),
    "doubling": ("continue_period_doubled", "doubled_orbit", "switch_period_doubling"),
    "floquet": ("FloquetResult", "floquet", "ns_test", "pd_test"),
    "hopf": ("first_lyapunov_coefficient", "periodic_orbit_from_hopf"),
    "orbit": ("PeriodicOrbit", "orbit_from_array"),
    "problem": ("PeriodicOrbitProblem", "error_estimate"),
    "starts": ("continue_from_hopf", "orbit_from_trajectory"),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = [
    "CycleSegments",
    "CollocationLayout",
    "FloquetResult",
    "PeriodLimit",
    "PeriodicOrbit",
    "PeriodicOrbitProblem",
    "adapt_mesh",
    "continue_from_branch_point",
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
    "special_problem",
    "switch_period_doubling",
]
