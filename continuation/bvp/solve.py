"""Entry points: solve a connecting orbit once, check its convergence, continue it.

* :func:`solve_connection` — damped Newton on the collocation system with sparse LU
  (``continuation.newton``), optional mesh adaptation by equidistribution, then a
  rebase of the projection bases and the phase reference at the solution.
* :func:`check_convergence` — re-solves on the halved mesh and on a longer
  truncation interval and reports the change of the solved parameters.
* :func:`continue_connection` — a curve of connections in a second parameter
  through the pseudo-arclength driver :func:`continuation.driver.continue_branch`.
* :func:`connection_at` — the orbit stored at one point of such a branch.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ConvergenceError
from ..newton import NewtonResult, newton
from ..settings import ContinuationSettings, NewtonSettings
from ..status import Status
from ..typing import FloatArray
from .collocation import CollocationMesh
from .connection import HeteroclinicProblem, _replace_fast
from .result import ConnectionResult
from .simplified import simplified_newton

log = logging.getLogger(__name__)

DEFAULT_NEWTON = NewtonSettings(tol=1e-10, step_tol=1e-8, max_iter=40, damping=True)


#: Nonlinear solvers of :func:`solve_connection` (see its ``method`` argument).
METHODS = ("newton", "broyden", "chord")


def _newton_solve(
    prob: HeteroclinicProblem, z0: FloatArray, settings: NewtonSettings, method: str = "newton"
) -> NewtonResult:
    p = prob.params[prob.free] if prob.free is not None else None

    def res(z: FloatArray) -> FloatArray:
        return prob.residual(z, p)

    def jac(z: FloatArray) -> Any:
        return prob.jacobian(z, p)

    if method == "newton":
        return newton(res, jac, z0, settings)
    out = simplified_newton(res, jac, z0, settings, broyden=method == "broyden")
    if not out.converged:  # e.g. far from the solution: the damped Newton method
        log.info("%s iteration failed (%s); falling back to Newton", method, out.message)
        full = newton(res, jac, z0, settings)
        return dataclasses.replace(full, iterations=full.iterations + out.iterations)
    return out


def _finish(
    prob: HeteroclinicProblem, res: NewtonResult, settings: NewtonSettings, method: str = "newton"
) -> ConnectionResult:
    """Rebase at a converged solution (one more Newton if needed) and wrap as a result."""
    p = prob.params[prob.free] if prob.free is not None else None
    if not res.converged:
        return prob.to_result(
            res.z,
            p,
            status=res.status,
            message=res.message,
            newton_iters=res.iterations,
            residual_norm=res.residual_norm,
        )
    try:
        new, z = prob.rebased(res.z, p)
    except ValueError as exc:  # the equilibria lost hyperbolicity at the solution
        return prob.to_result(
            res.z,
            p,
            status=Status.NEWTON_FAILED,
            newton_iters=res.iterations,
            message=f"converged, but the solution is not a valid connection: {exc}",
        )
    rn = float(np.max(np.abs(new.residual(z, p))))
    iters = res.iterations
    if rn > settings.tol:
        res2 = _newton_solve(new, z, settings, method)
        iters += res2.iterations
        if not res2.converged:
            return new.to_result(
                res2.z,
                p,
                status=res2.status,
                message=res2.message,
                newton_iters=iters,
                residual_norm=res2.residual_norm,
            )
        z, rn = res2.z, res2.residual_norm
    return new.to_result(
        z,
        p,
        status=Status.SUCCESS,
        message=f"converged in {iters} {_KIND[method]} iterations (|G|={rn:.2e})",
        newton_iters=iters,
        residual_norm=rn,
    )


_KIND = {"newton": "Newton", "broyden": "Newton-Broyden", "chord": "chord-Newton"}


def solve_connection(
    problem: HeteroclinicProblem,
    guess: Any,
    *,
    newton: NewtonSettings | None = None,
    throw: bool = False,
    adapt: int = 0,
    progress: Callable[[ConnectionResult], None] | None = None,
    method: str = "newton",
) -> ConnectionResult:
    r"""Solve the collocation system of a connecting orbit once.

    Parameters
    ----------
    problem : HeteroclinicProblem
        The connection (system, parameters, saddles, mesh, phase condition).
    guess : ConnectionResult, (t, x) pair, object with ``t``, ``x``, or ndarray (K, n)
        Starting orbit, e.g. an unstable-manifold trajectory; mapped linearly onto
        ``[0, T]`` and interpolated onto the mesh (see
        :meth:`HeteroclinicProblem.initial_vector`). It is also the reference of the
        integral phase condition unless ``problem.reference`` is set.
    newton : NewtonSettings, optional
        Default: ``tol=1e-10`` (max-norm of the residual), ``max_iter=40``, damped.
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` when Newton fails.
    adapt : int
        Rounds of mesh adaptation after the first solve: each round moves the nodes
        to equidistribute the local error monitor
        (:meth:`CollocationMesh.equidistributed`), re-interpolates the solution and
        solves again (the compiled functions are reused: same number of intervals).
    progress : callable, optional
        Called with each intermediate :class:`ConnectionResult` (after every solve).
    method : {"newton", "broyden", "chord"}
        ``"newton"``: damped Newton (:func:`continuation.newton.newton`), one
        Jacobian per iteration. ``"broyden"``: the Jacobian of the guess is kept
        while the residual contracts fast and corrected by Broyden rank-one updates,
        refreshed otherwise (:func:`continuation.bvp.simplified.simplified_newton`);
        ``"chord"``: the same without the updates (Shamanskii). Both save time when
        the guess is good and the Jacobian costs several residuals (collocation of
        an expensive model: about five); both fall back to Newton if they fail. The
        convergence test is the same (``max |G| <= newton.tol``), so all three give
        the same solution to that tolerance.

    Returns
    -------
    ConnectionResult
        ``status`` is ``SUCCESS``, a Newton failure status, or ``INTERRUPTED`` (the
        last finished solve is returned on KeyboardInterrupt during adaptation).
        ``result.problem`` is the problem rebased at the solution (Schur bases and
        phase reference refreshed), with which ``result.z`` has zero residual.
    """
    if not isinstance(problem, HeteroclinicProblem):
        raise ValueError(f"`problem` must be a HeteroclinicProblem, got {type(problem).__name__}")
    if isinstance(adapt, bool) or not isinstance(adapt, int) or adapt < 0:
        raise ValueError(f"`adapt` must be an integer >= 0, got {adapt!r}")
    if newton is not None and not isinstance(newton, NewtonSettings):
        raise ValueError(f"`newton` must be a NewtonSettings, got {type(newton).__name__}")
    if method not in METHODS:
        raise ValueError(f"`method` must be one of {METHODS}, got {method!r}")
    settings = DEFAULT_NEWTON if newton is None else newton
    prob, z0 = problem.initial_vector(guess)
    try:
        result = _finish(prob, _newton_solve(prob, z0, settings, method), settings, method)
    except KeyboardInterrupt:
        p = prob.params[prob.free] if prob.free is not None else None
        result = prob.to_result(
            z0,
            p,
            status=Status.INTERRUPTED,
            message=(f"{Status.INTERRUPTED.value} Nothing converged: the result holds the guess."),
        )
        if throw:
            raise ConvergenceError(result.message) from None
        return result
    if progress is not None:
        progress(result)
    try:
        for _ in range(adapt):
            if not result.success:
                break
            result = _adapt_once(result, settings, method)
            if progress is not None:
                progress(result)
    except KeyboardInterrupt:
        result = _with_status(result, Status.INTERRUPTED, Status.INTERRUPTED.value)
    if throw and not result.success:
        raise ConvergenceError(result.message)
    return result


def _with_status(result: ConnectionResult, status: Status, message: str) -> ConnectionResult:
    return dataclasses.replace(result, status=status, message=message)


def _adapt_once(
    result: ConnectionResult, settings: NewtonSettings, method: str = "newton"
) -> ConnectionResult:
    prob: HeteroclinicProblem = result.problem
    new_mesh = prob.mesh.equidistributed(result.x)
    X = prob.mesh.interpolate(result.x, new_mesh.tau)
    changes: dict[str, Any] = {"mesh": new_mesh}
    if prob.layout.pin is not None:
        # keep the pinned node (same layout: the compiled functions are reused)
        at = float(new_mesh.nodes[prob.layout.pin[1]])
        changes["phase"] = dataclasses.replace(prob.phase, at=at)
    if prob.layout.pin is None:
        changes["reference"] = X
    new = _replace_fast(prob, **changes)
    parts = prob.unpack(result.z)
    z0 = new.pack(X, parts["x_from"], parts["x_to"], list(parts["params"].values()))
    return _finish(new, _newton_solve(new, z0, settings, method), settings, method)


@dataclass(frozen=True)
class ConvergenceCheck:
    """Changes of the solved parameters under mesh halving and under a longer ``T``.

    Attributes
    ----------
    base, refined, extended : ConnectionResult
        The solution, the solution on the halved mesh, and on ``[0, T_factor T]``
        (same interval length in ``t``).
    delta_mesh, delta_T : dict of str to float
        ``|refined - base|`` and ``|extended - base|`` per unknown parameter.
    """

    base: ConnectionResult
    refined: ConnectionResult
    extended: ConnectionResult
    delta_mesh: dict[str, float] = field(default_factory=dict)
    delta_T: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Both re-solves converged."""
        return self.refined.success and self.extended.success

    def converged(self, tol: float) -> bool:
        """All changes below ``tol`` (and both re-solves converged)."""
        return self.ok and max([*self.delta_mesh.values(), *self.delta_T.values(), 0.0]) <= tol


def check_convergence(
    result: ConnectionResult,
    *,
    T_factor: float = 1.5,
    newton: NewtonSettings | None = None,
) -> ConvergenceCheck:
    r"""Re-solve ``result`` on the halved mesh and with ``T`` multiplied by ``T_factor``.

    The longer interval keeps the interval length in ``t`` (``ceil(T_factor N)``
    uniform intervals); its guess is the old orbit placed in the middle and held at
    its end values outside. The truncation error of projection boundary conditions
    decays exponentially with ``T``, at a rate set by the weakest eigenvalues at the
    saddles (Beyn 1990), so ``delta_T`` measures the truncation error and
    ``delta_mesh`` the discretisation error (for order ``2 m`` it is the error of the
    coarser solution to a factor ``1 - 2^{-2m}``).

    Raises
    ------
    ValueError
        If ``result`` failed, has no problem attached, or ``T_factor <= 1``.
    """
    if not isinstance(result, ConnectionResult) or result.problem is None:
        raise ValueError("`result` must be a ConnectionResult with its problem attached")
    if not result.success:
        raise ValueError(f"`result` did not converge ({result.status.name})")
    if not (math.isfinite(T_factor) and T_factor > 1):
        raise ValueError(f"`T_factor` must be > 1, got {T_factor!r}")
    settings = DEFAULT_NEWTON if newton is None else newton
    prob: HeteroclinicProblem = result.problem
    mesh = prob.mesh
    refined = solve_connection(
        prob.replace(mesh=mesh.refined(), reference=None), result, newton=settings
    )
    T2 = mesh.T * T_factor
    mesh2 = CollocationMesh(int(math.ceil(mesh.n_intervals * T_factor)), mesh.degree, T2)
    off = 0.5 * (T2 - mesh.T)
    t2 = mesh2.t
    x2 = result.interpolate(np.clip(t2 - off, 0.0, mesh.T))
    guess = _PaddedGuess(t2, x2, result)
    extended = solve_connection(prob.replace(mesh=mesh2, reference=None), guess, newton=settings)
    d_mesh = {u: abs(refined.params[u] - result.params[u]) for u in result.unknown_params}
    d_T = {u: abs(extended.params[u] - result.params[u]) for u in result.unknown_params}
    return ConvergenceCheck(result, refined, extended, d_mesh, d_T)


@dataclass(frozen=True)
class _PaddedGuess:
    t: FloatArray
    x: FloatArray
    source: ConnectionResult


def continue_connection(
    result: ConnectionResult,
    free: str,
    settings: ContinuationSettings | None = None,
    *,
    algorithm: Any = None,
    direction: str = "forward",
    events: Sequence[Any] = (),
    throw: bool = False,
    progress: Callable[[Any], None] | None = None,
    problem: HeteroclinicProblem | None = None,
) -> Any:
    r"""Continue a connection in a second parameter ``free``: a curve of connections.

    The problem of ``result`` (rebased at the solution: ``R = 0``, phase reference
    = the solution) gets ``free`` as its continuation parameter; the unknown
    parameters stay inside ``z`` and appear in ``branch.records``. The projection
    bases follow the branch through the Riccati unknowns, so the residual seen by the
    pseudo-arclength corrector is one fixed smooth function: no basis update ever
    happens between or inside steps. The integral phase condition keeps the start
    solution as its reference for the whole branch.

    Parameters
    ----------
    result : ConnectionResult
        A converged connection.
    free : str
        The continuation parameter (not one of the unknown parameters).
    settings : ContinuationSettings, optional
        Step sizes, bounds ``p_min``/``p_max`` on ``free``, corrector settings.
    algorithm, direction, events, throw, progress
        Passed to :func:`continuation.driver.continue_branch`.
    problem : HeteroclinicProblem, optional
        Re-attach a problem to a result loaded from disk.

    Returns
    -------
    Branch
        ``branch.p`` holds ``free``; ``branch.records[name]`` the unknown parameters;
        ``connection_at(branch, i)`` gives the orbit at row ``i``.
    """
    from ..driver import continue_branch

    if not isinstance(result, ConnectionResult):
        raise ValueError(f"`result` must be a ConnectionResult, got {type(result).__name__}")
    if not result.success:
        raise ValueError(f"`result` did not converge ({result.status.name}); cannot continue")
    if problem is None:
        prob = result.problem
        if prob is None:
            raise ValueError(
                "`result` has no problem attached (loaded from disk?); pass `problem=`"
            )
        z0 = result.z
    else:
        prob, z0 = problem.initial_vector(result)
    prob = prob.with_free(free)
    p0 = prob.params[free]
    return continue_branch(
        prob,
        z0,
        p0,
        algorithm,
        settings,
        events=events,
        direction=direction,
        throw=throw,
        progress=progress,
    )


def connection_at(branch: Any, index: int) -> ConnectionResult:
    """The :class:`ConnectionResult` at row ``index`` of a branch from :func:`continue_connection`.

    The attached problem is rebased at that row (its ``params`` hold the row's
    parameters), so the result can be refined, checked or continued further.
    ``residual_norm`` is that of the branch's own residual at the row.
    """
    prob = getattr(branch, "problem", None)
    if not isinstance(prob, HeteroclinicProblem):
        raise ValueError("`branch` was not computed by continue_connection")
    n = len(branch.p)
    if not -n <= index < n:
        raise ValueError(f"`index` {index} out of range for a branch of {n} points")
    z, p = np.asarray(branch.x[index], dtype=float), float(branch.p[index])
    rn = float(np.max(np.abs(prob.residual(z, p))))
    try:
        prob, z = prob.rebased(z, p)
    except ValueError as exc:
        return prob.to_result(
            z,
            p,
            status=Status.NEWTON_FAILED,
            residual_norm=rn,
            message=f"branch row {index} is not a valid connection: {exc}",
        )
    return prob.to_result(z, p, residual_norm=rn)


__all__ = [
    "ConvergenceCheck",
    "check_convergence",
    "connection_at",
    "continue_connection",
    "solve_connection",
]
