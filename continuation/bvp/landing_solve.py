r"""Solve a landing orbit (:class:`~continuation.bvp.landing.LandingProblem`) and continue it.

* :func:`solve_landing` -- damped Newton on the collocation system, mesh
  equidistribution, and the error estimates of the solved parameters by the
  connections' own loop (:func:`~continuation.bvp.accuracy.controlled`, settings
  :class:`~continuation.bvp.accuracy.ConnectionAccuracy`):
  discretisation by a re-solve on the mesh with every interval halved, truncation by a
  re-solve on ``[0, T_factor T]`` (extended at the end only, the added part guessed by
  the linearised flow onto the equilibrium). ``SUCCESS`` only when both are within
  ``atol + rtol |p|``.
* :func:`continue_landing` -- the curve of landings in the start parameter ``s`` by the
  pseudo-arclength driver :func:`continuation.driver.continue_branch`.
* :func:`landing_at` -- the orbit at one row of such a branch.

Example (closed form; ``u' = u - p + y^2``, ``y' = -y``: the saddle ``(p, 0)`` has the
stable manifold ``u = p - y^2 / 3``, so the orbit from ``(s, c)`` lands on it for
``p = s + c^2 / 3``; with the end on the eigenspace at ``T``,
``p(T) = s + c^2 (1 - e^{-3T}) / 3``)::

    sys = System(lambda x, p, ops: ops.stack([x[0] - p[0] + x[1] ** 2, -x[1]]),
                 ("u", "y"), ("p",))
    prob = LandingProblem(sys, {"p": 0.3}, "p", start=lambda s: [s, 1.0],
                          saddle=[0.3, 0.0], T=8.0, s=0.0, start_name="s")
    res = solve_landing(prob, (np.linspace(0, 8, 50), np.zeros((50, 2))))
    res.value("p"), res.error("p")        # 0.33333..., its bound
    br = continue_landing(res, ContinuationSettings(p_min=-1, p_max=1))
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal

import numpy as np

from ..errors import ConvergenceError
from ..settings import ContinuationSettings, NewtonSettings
from ..typing import FloatArray
from .accuracy import ConnectionAccuracy, Resolves, controlled, extended_mesh, extended_orbit
from .landing import LandingProblem
from .result import LandingResult
from .solve import ContinuedOrbit, _solved, _Solver, branch_row

DEFAULT_NEWTON = NewtonSettings(tol=1e-10, step_tol=1e-8, max_iter=40, damping=True)


def _plain(prob: LandingProblem, z0: FloatArray, settings: NewtonSettings) -> LandingResult:
    """One Newton solve, then a rebase (Schur basis at the solution) and a polish.

    The connections' own steps (:func:`continuation.bvp.solve._solved`).
    """
    return _solved(prob, z0, _Solver(settings, what="landing"))  # type: ignore[no-any-return]


def _adapt(result: LandingResult, settings: NewtonSettings) -> LandingResult:
    prob = result.problem
    new_mesh = prob.mesh.equidistributed(result.x)
    X = prob.mesh.interpolate(result.x, new_mesh.tau)
    new = prob.replace(mesh=new_mesh)
    parts = prob.unpack(result.z)
    return _plain(new, new.pack(X, parts["x_eq"], list(parts["params"].values())), settings)


def _refined(result: LandingResult, settings: NewtonSettings) -> LandingResult:
    prob = result.problem
    new = prob.replace(mesh=prob.mesh.refined())
    return _plain(new, new.initial_vector(result), settings)


def extended_landing(result: LandingResult, T_factor: float) -> tuple[LandingProblem, FloatArray]:
    """The problem on ``[0, T_factor T]`` (same nodes, end intervals added) and its ``z``.

    :func:`~continuation.bvp.accuracy.extended_mesh` with ``start=False`` (the start is a
    point, not a saddle); beyond ``T`` the guess is the linearised flow from ``x(T)``
    onto the equilibrium along its stable eigenspace (exact to first order in the end
    distance).
    """
    prob = result.problem
    mesh2, off, _ = extended_mesh(prob.mesh, T_factor, start=False)
    new = prob.replace(mesh=mesh2)
    pvec = np.array(result.params.values, dtype=float)
    x = extended_orbit(prob.system, pvec, prob.mesh, result.x, mesh2, off, None, result.x_eq)
    parts = prob.unpack(result.z)
    return new, new.pack(x, parts["x_eq"], list(parts["params"].values()))


def _resolves(settings: NewtonSettings) -> Resolves:
    """The re-solves of a landing for :func:`~continuation.bvp.accuracy.controlled`."""
    return Resolves(
        adapt=lambda r: _adapt(r, settings),
        refine=lambda r: _refined(r, settings),
        extend=lambda r, f: _plain(*extended_landing(r, f), settings),
        keep_on_adapt_failure=True,
    )


def solve_landing(
    problem: LandingProblem,
    guess: Any,
    *,
    accuracy: ConnectionAccuracy | None = None,
    newton: NewtonSettings | None = None,
    throw: bool = False,
    progress: Callable[[LandingResult], None] | None = None,
) -> LandingResult:
    r"""Solve a landing orbit with error estimates of the solved parameters.

    1. Newton from ``guess`` on ``problem.mesh``; ``adapt_rounds`` equidistribution
       rounds (:meth:`CollocationMesh.equidistributed`).
    2. Discretisation estimate ``safety |p(2N) - p(N)|``; above ``atol + rtol |p|`` the
       halved mesh becomes the mesh (at most ``max_refinements`` times).
    3. Truncation estimate ``safety |p(T_factor T) - p(T)|`` (:func:`extended_landing`);
       above the tolerance the longer problem is adopted (at most ``max_extensions``
       times) and 1-3 repeat.

    Parameters
    ----------
    problem : LandingProblem
    guess : LandingResult, (t, x) pair, object with ``t`` and ``x``/``y``, or ndarray
        Starting orbit (see :meth:`LandingProblem.initial_vector`).
    accuracy : ConnectionAccuracy, optional
        ``ConnectionAccuracy(estimate=False)``: one plain solve (``SUCCESS`` then means
        only that Newton converged; ``errors`` is None).
    newton : NewtonSettings, optional
        Default ``tol=1e-10`` (max-norm of the residual, relative to the states'
        magnitude), damped, 40 iterations.
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` unless ``SUCCESS``.
    progress : callable, optional
        Called with every intermediate result.

    Returns
    -------
    LandingResult
        ``SUCCESS``, ``DISCRETISATION_ERROR``, ``TRUNCATION_ERROR`` (message with the
        estimate and the tolerance) or a Newton failure status.
    """
    if not isinstance(problem, LandingProblem):
        raise ValueError(f"`problem` must be a LandingProblem, got {type(problem).__name__}")
    acc = ConnectionAccuracy() if accuracy is None else accuracy
    if not isinstance(acc, ConnectionAccuracy):
        raise ValueError(f"`accuracy` must be a ConnectionAccuracy, got {type(acc).__name__}")
    settings = DEFAULT_NEWTON if newton is None else newton
    if not isinstance(settings, NewtonSettings):
        raise ValueError(f"`newton` must be a NewtonSettings, got {type(settings).__name__}")
    result = _plain(problem, problem.initial_vector(guess), settings)
    if progress is not None:
        progress(result)
    if acc.estimate and result.success:
        result = controlled(result, acc, _resolves(settings), progress=progress)
    if throw and not result.success:
        raise ConvergenceError(result.message)
    return result


class ContinuedLanding(ContinuedOrbit):
    """A :class:`LandingProblem` seen by the driver (``free`` = ``start_name``).

    See :class:`~continuation.bvp.solve.ContinuedOrbit`, the adapter of connections too.
    """

    def __init__(self, problem: LandingProblem) -> None:
        if not callable(problem.start):
            raise ValueError("the problem has a fixed start point: nothing to continue in")
        super().__init__(problem, problem.start_name)


def continue_landing(
    result: LandingResult,
    settings: ContinuationSettings | None = None,
    *,
    direction: Literal["forward", "backward", "both"] = "forward",
    throw: bool = False,
    progress: Callable[[Any], None] | None = None,
) -> Any:
    """Continue a landing orbit in its start parameter ``s`` (pseudo-arclength).

    The mesh and ``T`` are those of ``result``; the Schur basis follows the branch
    through the Riccati unknowns. Branch rows carry no error estimates (re-solve a
    row with :func:`solve_landing` via :func:`landing_at` for them).

    Parameters
    ----------
    result : LandingResult
        A converged landing whose problem has a start callable.
    settings : ContinuationSettings, optional
        ``p_min``/``p_max`` bound ``s``; step sizes are in ``s`` and the unknowns.
    direction, throw, progress
        As :func:`continuation.driver.continue_branch`.

    Returns
    -------
    Branch
        ``branch.p`` holds ``s``; ``branch.records[name]`` the solved parameters and
        ``end_distance``; folds in ``s`` are reported as special points.
    """
    from ..driver import continue_branch

    if not isinstance(result, LandingResult) or result.problem is None:
        raise ValueError("`result` must be a LandingResult with its problem attached")
    if not result.success and result.errors is None:
        raise ValueError(f"`result` did not converge ({result.status.name}); cannot continue")
    prob = result.problem
    return continue_branch(
        ContinuedLanding(prob),
        result.z,
        prob.s,
        None,
        settings,
        direction=direction,
        throw=throw,
        progress=progress,
    )  # type: ignore[arg-type]


def landing_at(branch: Any, index: int) -> LandingResult:
    """The :class:`LandingResult` at row ``index`` of a :func:`continue_landing` branch."""
    prob, z, s = branch_row(branch, index, LandingProblem, "continue_landing")
    new, z = prob.replace(s=s).rebased(z, s)
    return new.to_result(z, s, message=f"branch row {index}")


__all__ = [
    "ContinuedLanding",
    "LandingResult",
    "continue_landing",
    "extended_landing",
    "landing_at",
    "solve_landing",
]
