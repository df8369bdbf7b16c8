r"""One cycle: Newton solve, mesh adaptation, refinement to a tolerance.

The cycle's accuracy path is the connections' (:mod:`continuation.bvp.accuracy`):
:func:`adapt_mesh` is that loop's adaptation step
(:func:`~continuation.bvp.accuracy.adapted`: equidistribute, re-solve, stop once the
nodes settle) and the discretisation estimate of a cycle's parameter,
:math:`|p(2N) - p(N)|` at fixed period (the period limit of
:mod:`continuation.periodic.limit`), is its halving step
(:func:`~continuation.bvp.accuracy.discretisation_changes`), both with the cycle's
re-solves (:func:`cycle_resolves`) plugged in as a landing plugs in its own. A cycle has
no truncation, so it is never lengthened.

What stays the cycle's own is the criterion of its mesh size: the local error estimate
(:func:`~continuation.periodic.problem.error_estimate`, in the states' units) against
``error_tol``, with the number of intervals from the order :math:`h^{m+1}` of that
estimate (:func:`refined_intervals`): along a branch the free parameter is the
continuation parameter, not a solved one, so there is no ``p(2N) - p(N)`` to hold
against ``atol + rtol |p|``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .._threads import blas_threads_for
from ..algorithms.corrector import correct
from ..bvp.accuracy import Resolves, adapted
from ..bvp.collocation import CollocationMesh
from ..errors import ConvergenceError
from ..params import Params
from ..settings import NewtonSettings
from .orbit import PeriodicOrbit
from .problem import PeriodicOrbitProblem, error_estimate

log = logging.getLogger(__name__)


def solve_orbit(
    orbit: PeriodicOrbit,
    free: str | None = None,
    newton: NewtonSettings | None = None,
    *,
    fix_period: bool = False,
) -> PeriodicOrbit:
    """Correct a cycle guess by Newton's method at fixed parameters (or fixed period).

    Parameters
    ----------
    orbit : PeriodicOrbit
        The guess (also the first phase reference).
    free : str, optional
        Any parameter name (default the first); with ``fix_period`` the parameter
        that is solved for instead of the period.
    newton : NewtonSettings, optional
    fix_period : bool
        Keep ``T`` at ``orbit.T`` and solve for the parameter ``free`` (well
        conditioned where the period is very sensitive to the parameter, near a
        homoclinic orbit).

    Raises
    ------
    ConvergenceError
        If Newton's method does not converge.
    """
    free = free if free is not None else orbit.system.param_names[0]
    prob = PeriodicOrbitProblem.from_orbit(orbit, free)
    newton = newton if newton is not None else NewtonSettings(max_iter=40)
    p0 = orbit.param(free)
    u0 = np.append(prob.reference, p0)
    e_p = np.zeros(u0.size)
    e_p[prob.layout.T_col if fix_period else -1] = 1.0
    with blas_threads_for(u0.size, sparse=True):
        # exact=False: the factorisation at the returned point is not needed here (the
        # acceptance test of continuation steps; saves one linearisation and one
        # factorisation per solve, i.e. per mesh adaptation of a branch)
        res = correct(prob, u0, u0, e_p, 0.0, newton, exact=False)
    if not res.converged:
        raise ConvergenceError(f"the cycle did not converge at {free}={p0:.10g}: {res.message}")
    return prob.orbit(res.z, res.p)


@dataclass(frozen=True)
class CycleSolve:
    """A cycle solve as the connections' accuracy loop sees it (:class:`Resolves`).

    Attributes
    ----------
    orbit : PeriodicOrbit
        The solved cycle, or the guess whose solve failed.
    free : tuple of str
        The parameter solved for at fixed period, or the one held fixed (one name).
    success : bool
    message : str
        Why the solve failed (empty on success).
    """

    orbit: PeriodicOrbit
    free: tuple[str]
    success: bool = True
    message: str = ""

    @property
    def mesh(self) -> CollocationMesh:
        """The cycle's mesh."""
        return self.orbit.mesh

    @property
    def params(self) -> Params:
        """All parameter values of the cycle."""
        return self.orbit.params


def cycle_resolves(
    free: str,
    newton: NewtonSettings | None = None,
    *,
    fix_period: bool = False,
    n_intervals: int | None = None,
) -> Resolves:
    """The re-solves of a cycle (:class:`~continuation.bvp.accuracy.Resolves`).

    For :func:`~continuation.bvp.accuracy.adapted` and
    :func:`~continuation.bvp.accuracy.discretisation_changes`.

    ``adapt``: the mesh equidistributed (:meth:`CollocationMesh.equidistributed`, with
    ``n_intervals`` intervals, default the same) and :func:`solve_orbit` on it;
    ``refine``: :func:`solve_orbit` on the mesh with every interval halved; no
    ``extend`` (a cycle has no truncation). A solve that does not converge gives a
    :class:`CycleSolve` with ``success`` False and the reason.
    """

    def solved(guess: PeriodicOrbit) -> CycleSolve:
        try:
            return CycleSolve(solve_orbit(guess, free, newton, fix_period=fix_period), (free,))
        except ConvergenceError as exc:
            return CycleSolve(guess, (free,), False, str(exc))

    def adapt(r: CycleSolve) -> CycleSolve:
        return solved(r.orbit.on_mesh(r.mesh.equidistributed(r.orbit.X, n_intervals)))

    return Resolves(adapt=adapt, refine=lambda r: solved(r.orbit.on_mesh(r.mesh.refined())))


def adapt_mesh(
    orbit: PeriodicOrbit,
    n_intervals: int | None = None,
    *,
    rounds: int = 2,
    free: str | None = None,
    newton: NewtonSettings | None = None,
    fix_period: bool = False,
) -> PeriodicOrbit:
    """Equidistribute the mesh on ``orbit`` and re-solve, at most ``rounds`` times.

    The new nodes equidistribute the local error monitor
    (:meth:`~continuation.bvp.collocation.CollocationMesh.equidistributed`);
    ``n_intervals`` changes the number of intervals (default: the same);
    ``fix_period`` as in :func:`solve_orbit`. The rounds are those of connections and
    landings (:func:`~continuation.bvp.accuracy.adapted`): fewer once no node moves by
    more than a tenth of its neighbouring intervals.

    Raises
    ------
    ConvergenceError
        If a re-solve does not converge.
    """
    free = free if free is not None else orbit.system.param_names[0]
    how = cycle_resolves(free, newton, fix_period=fix_period, n_intervals=n_intervals)
    out = adapted(CycleSolve(orbit, (free,)), max(1, int(rounds)), how)
    if not out.success:
        raise ConvergenceError(out.message)
    return out.orbit  # type: ignore[no-any-return]


def refined_intervals(
    orb: PeriodicOrbit, error: float, error_tol: float | None, max_intervals: int
) -> int | None:
    r"""Number of intervals for the next segment (None: keep).

    From the error estimate ``error`` of ``orb`` (order ``m + 1`` in the interval
    length): :math:`N' = \lceil 1.2 N (2 e/\text{tol})^{1/(m+1)} \rceil`, at most
    ``max_intervals``.
    """
    N = orb.mesh.n_intervals
    if error_tol is None or not math.isfinite(error) or error <= error_tol or N >= max_intervals:
        return None
    # aim at half the tolerance (the estimate scales as h^(m+1)), with 20 % to spare
    factor = 1.2 * (2.0 * error / error_tol) ** (1.0 / (orb.mesh.degree + 1))
    n_new = min(max_intervals, max(N + 1, math.ceil(N * factor)))
    log.info("error estimate %.3g > error_tol %.3g: %d -> %d intervals", error, error_tol, N, n_new)
    return n_new


def refine_start(
    orb: PeriodicOrbit,
    free: str,
    error_tol: float,
    max_intervals: int,
    rounds: int = 4,
    fix_period: bool = False,
) -> PeriodicOrbit:
    """The start cycle on a mesh whose error estimate is within ``error_tol``.

    At most ``max_intervals`` intervals, ``rounds`` refinements by
    :func:`refined_intervals`, so that the first segment's rows are not left above the
    tolerance; a refinement that does not converge keeps the cycle as it was (the driver's
    start correction and the message report what follows).
    """
    for _ in range(rounds):
        n_new = refined_intervals(orb, error_estimate(orb.mesh, orb.X), error_tol, max_intervals)
        if n_new is None:
            break
        try:
            orb = adapt_mesh(orb, n_new, rounds=1, free=free, fix_period=fix_period)
        except ConvergenceError as exc:
            log.info("start cycle kept on %d intervals: %s", orb.mesh.n_intervals, exc)
            break
    return orb


__all__ = ["CycleSolve", "adapt_mesh", "cycle_resolves", "solve_orbit"]
