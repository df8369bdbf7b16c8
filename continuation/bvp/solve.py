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
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp

from ..casadi_compile import compiling
from ..errors import ConvergenceError
from ..linalg import csc_with_data
from ..newton import NewtonResult, newton
from ..settings import ContinuationSettings, NewtonSettings
from ..status import Status
from ..typing import FloatArray
from .accuracy import ConnectionAccuracy, Resolves, controlled, extended_problem, refined_problem
from .connection import HeteroclinicProblem, PinPhase, _replace_fast
from .result import ConnectionResult
from .simplified import JacobianCache, simplified_newton

log = logging.getLogger(__name__)

DEFAULT_NEWTON = NewtonSettings(tol=1e-10, step_tol=1e-8, max_iter=40, damping=True)


#: Nonlinear solvers of :func:`solve_connection` (see its ``method`` argument).
METHODS = ("newton", "broyden", "chord")


def _store_key(prob: HeteroclinicProblem) -> tuple[Any, ...]:
    """Key of a problem's Jacobian in a ``jacobians`` store: layout, ``T`` and the nodes."""
    mesh = prob.mesh
    return (prob.layout, float(mesh.T), np.asarray(mesh.nodes, dtype=float).tobytes())


def _value(prob: Any) -> float | None:
    """The value of the continuation parameter ``vary`` of a problem (None: none).

    A landing has no ``vary`` (it is continued in its start parameter, which its
    methods default to).
    """
    vary = getattr(prob, "vary", None)
    return None if vary is None else float(prob.params[vary])


@dataclass(frozen=True, eq=False)
class _Solver:
    """How a collocated orbit is solved (one value for every solve of one call).

    Attributes
    ----------
    settings : NewtonSettings
    method : str
        One of :data:`METHODS`.
    store : dict or None
        Factorised Jacobians shared between nearby solves (``jacobians`` of
        :func:`solve_connection`).
    what : str
        The kind of orbit, named in the messages ("connection", "landing").
    """

    settings: NewtonSettings = DEFAULT_NEWTON
    method: str = "newton"
    store: dict[Any, JacobianCache] | None = None
    what: str = "connection"


def _row_weights(prob: Any, z0: FloatArray) -> tuple[int, FloatArray | None]:
    r"""Row weights that make the convergence test relative to the states' magnitude.

    The collocation, continuity, equilibrium, start and projection rows are states or
    their rates (rounding floor about :math:`\epsilon_{mach} \max|X|`), the integral
    phase row a product of two (floor :math:`\epsilon_{mach} \max|X|^2`), the Riccati
    rows rates of the linearisation (independent of the states' unit). With ``S = 2^e``
    the smallest power of two at least ``max|X|`` of ``z0``'s orbit, the state rows are
    divided by ``S``, the integral phase row by ``S^2``, the Riccati rows not, so that the
    Newton tolerance (``1e-10``) holds relative to the states' scale: a problem written
    in units where the states are O(1e3) or O(1e-4) converges as the same problem in
    O(1) units does (before, at O(1e3) the residual stalled at its rounding floor above
    the tolerance; at O(1e-4) the tolerance allowed relative errors of 1e-6). Newton's
    steps are invariant under row scaling; powers of two scale exactly. ``(0, None)``
    where ``1/2 < max|X| <= 1`` (nothing changes) or the orbit is all zero.
    """
    X = prob.layout.orbit_of(np.asarray(z0, dtype=float))
    xs = float(np.max(np.abs(X))) if X.size else 0.0
    if not (math.isfinite(xs) and xs > 0.0):
        return 0, None
    e = math.ceil(math.log2(xs))
    if e == 0:
        return 0, None
    lay = prob.layout
    n, km, kp = lay.n, lay.k_minus, lay.k_plus
    w = np.full(prob.n_unknowns, 2.0**-e)
    # the boundary rows (order of continuation.bvp.casadi_backend): equilibria (and the
    # start point), then per end with conditions its Riccati rows and projections
    r = lay.boundary_row + n * (2 if lay.start_point or lay.separate_to else 1)
    for k in (km, kp):
        if k > 0:
            n_ric = (n - k) * k if k < n else 0
            w[r : r + n_ric] = 1.0
            r += n_ric + k
    if not lay.start_point and lay.pin is None:  # the integral phase row, the last one
        w[-1] = 2.0 ** (-2 * e)
    return e, w


def _newton_solve(prob: Any, z0: FloatArray, solver: _Solver) -> NewtonResult:
    """Newton (or its simplified forms, ``solver.method``) on ``prob.residual(z, p) = 0``.

    ``prob`` is a :class:`HeteroclinicProblem` or a
    :class:`~continuation.bvp.landing.LandingProblem` (the same collocation core). The
    rows are weighted by :func:`_row_weights` (the tolerance is relative to the states'
    magnitude); the result's ``residual_norm`` is the weighted one.
    """
    settings, method, store = solver.settings, solver.method, solver.store
    p = _value(prob)
    e, w = _row_weights(prob, z0)

    def res(z: FloatArray) -> FloatArray:
        g = prob.residual(z, p)
        return g if w is None else w * g

    def jac(z: FloatArray) -> Any:
        J = prob.jacobian(z, p)
        if w is None:
            return J
        if sp.issparse(J) and J.format == "csc":  # the pattern and its condensed LU kept
            return csc_with_data(J, J.data * w[J.indices])
        return sp.diags(w) @ J

    if method == "newton":
        return newton(res, jac, z0, settings)
    key = _store_key(prob) + (e,)
    cache = None if store is None else store.setdefault(key, JacobianCache())
    out = simplified_newton(res, jac, z0, settings, broyden=method == "broyden", cache=cache)
    if not out.converged:  # e.g. far from the solution: the damped Newton method
        log.info("%s iteration failed (%s); falling back to Newton", method, out.message)
        if cache is not None:
            cache.clear()
        full = newton(res, jac, z0, settings)
        return dataclasses.replace(full, iterations=full.iterations + out.iterations)
    return out


def _solved(prob: Any, z0: FloatArray, solver: _Solver) -> Any:
    """Newton from ``z0``, then a rebase at a converged solution, as a result.

    One more Newton solve follows the rebase if its residual exceeds the tolerance.
    ``prob``: a connection or a landing (``solver.what`` names it in the messages); the
    result is its ``to_result``.
    """
    res = _newton_solve(prob, z0, solver)
    p = _value(prob)
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
            message=f"converged, but the solution is not a valid {solver.what}: {exc}",
        )
    w = _row_weights(new, z)[1]
    g = new.residual(z, p)
    rn = float(np.max(np.abs(g if w is None else w * g)))
    iters = res.iterations
    if rn > solver.settings.tol:
        res2 = _newton_solve(new, z, solver)
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
        message=f"converged in {iters} {_KIND[solver.method]} iterations (|G|={rn:.2e})",
        newton_iters=iters,
        residual_norm=rn,
    )


_KIND = {"newton": "Newton", "broyden": "Newton-Broyden", "chord": "chord-Newton"}


def solve_connection(
    problem: HeteroclinicProblem,
    guess: Any,
    *,
    accuracy: ConnectionAccuracy | None = None,
    newton: NewtonSettings | None = None,
    throw: bool = False,
    adapt: int | None = None,
    progress: Callable[[ConnectionResult], None] | None = None,
    method: str = "newton",
    jacobians: dict[Any, JacobianCache] | None = None,
) -> ConnectionResult:
    r"""Solve a connecting orbit: adapted mesh, error estimates of the solved parameters.

    Steps (settings in ``accuracy``, :class:`ConnectionAccuracy`):

    1. Newton on ``problem.mesh`` from ``guess``.
    2. Mesh adaptation: ``adapt_rounds`` rounds of equidistribution of the local
       collocation error :math:`h_j^{m+1} |x^{(m+1)}|` (as AUTO-07p), each followed
       by a solve on the same number of intervals (the compiled functions are reused).
    3. Discretisation estimate: re-solve on the adapted mesh with every interval
       halved; ``safety * |p(2N) - p(N)|`` per solved parameter. Above its tolerance
       ``atol + rtol |p|`` the halved mesh becomes the mesh (at most
       ``max_refinements`` times) and step 2 repeats.
    4. Truncation estimate: re-solve on ``[0, T_factor T]`` with the same resolution;
       ``safety * |p(T_factor T) - p(T)|``. Above its tolerance the longer interval
       becomes the problem (at most ``max_extensions`` times) and steps 2-4 repeat.

    The result is the solution on the last adapted mesh (not the halved one), with
    both estimates in ``result.errors``.

    Parameters
    ----------
    problem : HeteroclinicProblem
        The connection (system, parameters, saddles, mesh, phase condition).
    guess : ConnectionResult, (t, x) pair, object with ``t``, ``x``, or ndarray
        Starting orbit, e.g. an unstable-manifold trajectory (see
        :meth:`HeteroclinicProblem.initial_vector`); ``x`` as (K, n) or SciPy's
        (n, K). It is also the reference of the integral phase condition unless
        ``problem.reference`` is set.
    accuracy : ConnectionAccuracy, optional
        Tolerances and bounds (defaults: ``rtol=1e-6``, ``atol=1e-8``, 2 adaptation
        rounds, at most 3 doublings of the intervals and 2 extensions of ``T`` by
        1.5). ``ConnectionAccuracy(estimate=False)``: a plain solve on the given mesh.
    newton : NewtonSettings, optional
        Default: ``tol=1e-10`` (max-norm of the residual, its rows divided by the
        states' magnitude: :func:`_row_weights`), ``max_iter=40``, damped.
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` when the result is not
        ``SUCCESS``.
    adapt : int, optional
        Overrides ``accuracy.adapt_rounds``; with ``accuracy.estimate=False`` it is the
        number of adaptation rounds of the plain solve (default 0).
    progress : callable, optional
        Called with each intermediate :class:`ConnectionResult` (after every solve).
    method : {"newton", "broyden", "chord"}
        ``"newton"``: damped Newton (:func:`continuation.newton.newton`), one
        Jacobian per iteration. ``"broyden"``: the Jacobian of the guess is kept
        while the residual contracts fast and corrected by Broyden rank-one updates,
        refreshed otherwise (:func:`continuation.bvp.simplified.simplified_newton`);
        ``"chord"``: the same without the updates (Shamanskii). Both fall back to
        Newton if they fail; the convergence test is the same.
    jacobians : dict, optional
        With ``"broyden"``/``"chord"``: a store (initially ``{}``) shared by the solves
        of a sequence of nearby problems (the courses of a curve). Every solve starts
        from the factorised Jacobian the last solve of the same layout, ``T`` and mesh
        nodes ended with (:class:`~continuation.bvp.simplified.JacobianCache`) and
        refreshes it only when the residual stops contracting fast; the convergence
        test is the same, so only the work changes.

    Returns
    -------
    ConnectionResult
        ``status``: ``SUCCESS`` (Newton converged and both estimates within their
        tolerances), ``DISCRETISATION_ERROR`` or ``TRUNCATION_ERROR`` (the message
        names the parameter, the estimate, the tolerance and what to change), a Newton
        failure status, or ``INTERRUPTED`` (the last finished solve is returned).
        ``result.problem`` is the problem rebased at the solution, with which
        ``result.z`` has zero residual.
    """
    if not isinstance(problem, HeteroclinicProblem):
        raise ValueError(f"`problem` must be a HeteroclinicProblem, got {type(problem).__name__}")
    if adapt is not None and (isinstance(adapt, bool) or not isinstance(adapt, int) or adapt < 0):
        raise ValueError(f"`adapt` must be an integer >= 0, got {adapt!r}")
    if newton is not None and not isinstance(newton, NewtonSettings):
        raise ValueError(f"`newton` must be a NewtonSettings, got {type(newton).__name__}")
    if accuracy is None:
        accuracy = ConnectionAccuracy()
    elif not isinstance(accuracy, ConnectionAccuracy):
        raise ValueError(f"`accuracy` must be a ConnectionAccuracy, got {type(accuracy).__name__}")
    if method not in METHODS:
        raise ValueError(f"`method` must be one of {METHODS}, got {method!r}")
    if jacobians is not None and not isinstance(jacobians, dict):
        raise ValueError(f"`jacobians` must be a dict, got {type(jacobians).__name__}")
    solver = _Solver(DEFAULT_NEWTON if newton is None else newton, method, jacobians)
    prob, z0 = problem.initial_vector(guess)
    try:
        result = _solved(prob, z0, solver)
    except KeyboardInterrupt:
        p = _value(prob)
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
        if not accuracy.estimate:
            for _ in range(adapt or 0):
                if not result.success:
                    break
                result = _adapt_once(result, solver)
                if progress is not None:
                    progress(result)
        elif result.success:
            rounds = accuracy.adapt_rounds if adapt is None else adapt
            first = 0 if _already_adapted(guess, prob) else rounds
            last = [result]
            try:
                result = controlled(
                    result,
                    accuracy,
                    _resolves(solver),
                    rounds,
                    progress,
                    last.append,
                    first,
                )
            except KeyboardInterrupt:
                result = last[-1]
                raise
    except KeyboardInterrupt:
        result = _with_status(result, Status.INTERRUPTED, Status.INTERRUPTED.value)
    if throw and not result.success:
        raise ConvergenceError(result.message)
    return result


def _already_adapted(guess: Any, prob: HeteroclinicProblem) -> bool:
    """``guess`` is an estimated result on exactly this mesh: it was adapted already."""
    return (
        isinstance(guess, ConnectionResult)
        and guess.errors is not None
        and guess.mesh.n_intervals == prob.mesh.n_intervals
        and guess.mesh.degree == prob.mesh.degree
        and guess.mesh.T == prob.mesh.T
        and bool(np.array_equal(guess.mesh.nodes, prob.mesh.nodes))
    )


def _plain(problem: HeteroclinicProblem, guess: Any, solver: _Solver) -> ConnectionResult:
    return _solved(*problem.initial_vector(guess), solver)  # type: ignore[no-any-return]


def _resolves(solver: _Solver) -> Resolves:
    """The re-solves of a connection for :func:`~continuation.bvp.accuracy.controlled`."""

    def extend(result: ConnectionResult, T_factor: float) -> ConnectionResult:
        return _plain(*extended_problem(result, T_factor), solver)

    return Resolves(
        adapt=lambda r: _adapt_once(r, solver),
        refine=lambda r: _plain(refined_problem(r), r, solver),
        extend=extend,
    )


def _with_status(result: ConnectionResult, status: Status, message: str) -> ConnectionResult:
    return dataclasses.replace(result, status=status, message=message)


def _adapt_once(result: ConnectionResult, solver: _Solver) -> ConnectionResult:
    prob: HeteroclinicProblem = result.problem
    pin = prob.layout.pin
    fixed = None
    if pin is not None and 0 < pin[1] < prob.mesh.n_intervals:
        # the pinned node keeps its index and its time (same layout: functions reused)
        fixed = (pin[1], float(prob.mesh.nodes[pin[1]]))
    new_mesh = prob.mesh.equidistributed(result.x, fixed=fixed)
    X = prob.mesh.interpolate(result.x, new_mesh.tau)
    changes: dict[str, Any] = {"mesh": new_mesh}
    if pin is not None:
        at = float(new_mesh.nodes[pin[1]])
        assert isinstance(prob.phase, PinPhase)  # (a pinned layout has a pin phase)
        changes["phase"] = dataclasses.replace(prob.phase, at=at)
    if prob.layout.pin is None:
        changes["reference"] = X
    new = _replace_fast(prob, **changes)
    parts = prob.unpack(result.z)
    z0 = new.pack(X, parts["x_from"], parts["x_to"], list(parts["params"].values()))
    return _solved(new, z0, solver)  # type: ignore[no-any-return]


@dataclass(frozen=True)
class ConvergenceCheck:
    """Changes of the solved parameters under mesh halving and under a longer ``T``.

    Attributes
    ----------
    base, refined, extended : ConnectionResult
        The solution, the solution on its mesh with every interval halved, and on
        ``[0, T_factor T]`` with the same resolution.
    delta_mesh, delta_T : dict of str to float
        ``|refined - base|`` and ``|extended - base|`` per solved parameter.
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
    r"""Re-solve ``result`` on its mesh halved and on ``T_factor T`` at the same resolution.

    The halved mesh keeps the nodes of ``result`` (an adapted mesh stays adapted), so
    ``delta_mesh`` measures the discretisation error (for order ``2 m``: the error of
    the coarser solution times ``1 - 2^{-2m}``). The longer interval keeps every
    node of ``result`` (shifted by ``(T_factor - 1) T / 2``) and adds intervals as
    long as the end intervals at both ends (:func:`~continuation.bvp.accuracy.extended_mesh`);
    its guess is the orbit continued by the linearised flow at the saddles. So the
    two solves have the same discretisation error and ``delta_T`` measures the
    truncation error, which decays exponentially with ``T`` (Beyn 1990). This is what
    :func:`solve_connection` does by default; here without the safety factor.

    Raises
    ------
    ValueError
        If ``result`` failed, has no problem attached, or ``T_factor <= 1``.
    """
    if not isinstance(result, ConnectionResult) or result.problem is None:
        raise ValueError("`result` must be a ConnectionResult with its problem attached")
    if not (
        result.success or result.status in (Status.DISCRETISATION_ERROR, Status.TRUNCATION_ERROR)
    ):
        raise ValueError(f"`result` did not converge ({result.status.name})")
    if not (math.isfinite(T_factor) and T_factor > 1):
        raise ValueError(f"`T_factor` must be > 1, got {T_factor!r}")
    solver = _Solver(DEFAULT_NEWTON if newton is None else newton)
    refined = _plain(refined_problem(result), result, solver)
    extended = _plain(*extended_problem(result, T_factor), solver)
    d_mesh = {u: abs(refined.params[u] - result.params[u]) for u in result.free}
    d_T = {u: abs(extended.params[u] - result.params[u]) for u in result.free}
    return ConvergenceCheck(result, refined, extended, d_mesh, d_T)


class ContinuedOrbit:
    """A collocated orbit problem ending at a saddle, seen by the continuation driver.

    The one adapter of connections (:class:`ContinuedConnection`) and landings
    (:class:`~continuation.bvp.landing_solve.ContinuedLanding`): the driver's protocol
    calls its continuation parameter ``free``, which is a connection's ``vary`` (its
    ``problem.free`` are the solved parameters) and a landing's start parameter. The
    equations are delegated to ``problem`` (``branch.problem`` is this object;
    ``.problem`` the orbit problem).

    Parameters
    ----------
    problem : HeteroclinicProblem or LandingProblem
    free : str
        The name of the continuation parameter.
    """

    #: ``G_z`` is a SciPy sparse (CSC) matrix (:class:`~continuation.problem.ProblemHooks`).
    sparse = True

    def __init__(self, problem: Any, free: str) -> None:
        self.problem = problem
        self._free = str(free)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the ``N`` unknowns, ``z0, z1, ...``.

        The orbit problem's ``state_names`` are those of the system's states, not of ``z``.
        """
        return tuple(f"z{k}" for k in range(self.n_unknowns))

    @property
    def free(self) -> str:
        """The continuation parameter."""
        return self._free

    @property
    def n_unknowns(self) -> int:
        """Length of ``z``."""
        return int(self.problem.n_unknowns)

    def residual(self, z: FloatArray, p: float | None = None) -> FloatArray:
        """``G(z, p)``."""
        return self.problem.residual(z, p)  # type: ignore[no-any-return]

    def jacobian(self, z: FloatArray, p: float | None = None) -> Any:
        """``dG/dz``."""
        return self.problem.jacobian(z, p)

    def dp(self, z: FloatArray, p: float | None = None) -> FloatArray:
        """``dG/dp``."""
        return self.problem.dp(z, p)  # type: ignore[no-any-return]

    def linearize(self, z: FloatArray, p: float | None = None) -> Any:
        """``(G, dG/dz, dG/dp)``."""
        return self.problem.linearize(z, p)

    def stability(self, z: FloatArray, p: float | None = None) -> None:
        """None (an orbit ending at a saddle carries no stability eigenvalues here)."""
        return None

    def record(self, z: FloatArray, p: float | None = None) -> dict[str, float]:
        """The problem's record: solved parameters, end distances, Riccati norm."""
        return self.problem.record(z, p)  # type: ignore[no-any-return]


class ContinuedConnection(ContinuedOrbit):
    """A :class:`HeteroclinicProblem` seen by the continuation driver (``free`` = ``vary``).

    See :class:`ContinuedOrbit`; attributes not found here are the connection problem's.
    """

    def __init__(self, problem: HeteroclinicProblem) -> None:
        if problem.vary is None:
            raise ValueError("`problem.vary` is None: no continuation parameter")
        super().__init__(problem, str(problem.vary))

    #: The connection's derivatives come from its CasADi trace (automatic
    #: differentiation): see :func:`~continuation.problem.exact_jacobian`.
    exact_jacobian = True

    def __getattr__(self, name: str) -> Any:
        if name in ("problem", "_free"):
            raise AttributeError(name)
        return getattr(self.problem, name)


@compiling
def continue_connection(
    result: ConnectionResult,
    vary: str,
    settings: ContinuationSettings | None = None,
    *,
    algorithm: Any = None,
    direction: Literal["forward", "backward", "both"] = "forward",
    events: Sequence[Any] = (),
    throw: bool = False,
    progress: Callable[[Any], None] | None = None,
    problem: HeteroclinicProblem | None = None,
) -> Any:
    r"""Continue a connection in a second parameter ``vary``: a curve of connections.

    The problem of ``result`` (rebased at the solution: ``R = 0``, phase reference
    = the solution) gets ``vary`` as its continuation parameter; the solved
    parameters (``free``) stay inside ``z`` and appear in ``branch.records``. The
    projection bases follow the branch through the Riccati unknowns, so the residual
    seen by the pseudo-arclength corrector is one fixed smooth function: no basis
    update ever happens between or inside steps. The integral phase condition keeps
    the start solution as its reference for the whole branch. The mesh is that of
    ``result`` (adapted by :func:`solve_connection`); branch rows carry no error
    estimates (``connection_at(branch, i)`` then :func:`solve_connection` gives them).

    Parameters
    ----------
    result : ConnectionResult
        A converged connection.
    vary : str
        The continuation parameter (not one of the solved parameters).
    settings : ContinuationSettings, optional
        Step sizes, bounds ``p_min``/``p_max`` on ``vary``, corrector settings.
    algorithm, direction, events, throw, progress
        Passed to :func:`continuation.driver.continue_branch`.
    problem : HeteroclinicProblem, optional
        Re-attach a problem to a result loaded from disk.

    Returns
    -------
    Branch
        ``branch.p`` holds ``vary`` (``branch.free`` names it, the driver's word);
        ``branch.records[name]`` the solved parameters; ``connection_at(branch, i)``
        the orbit at row ``i``.
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
    prob = prob.with_vary(vary)
    p0 = prob.params[vary]
    return continue_branch(
        ContinuedConnection(prob),
        z0,
        p0,
        algorithm,
        settings,
        events=events,
        direction=direction,
        throw=throw,
        progress=progress,
    )


def branch_row(branch: Any, index: int, kind: type, command: str) -> tuple[Any, FloatArray, float]:
    """The orbit problem of a connection's or landing's branch and its row ``index``.

    Returns ``(problem, z, p)``; raises ValueError when ``branch`` was not computed by
    ``command`` (its problem not a ``kind``) or ``index`` is out of range.
    """
    prob = getattr(branch, "problem", None)
    prob = getattr(prob, "problem", prob)  # (the driver adapter's orbit problem)
    if not isinstance(prob, kind):
        raise ValueError(f"`branch` was not computed by {command}")
    n = len(branch.p)
    if not -n <= index < n:
        raise ValueError(f"`index` {index} out of range for a branch of {n} points")
    return prob, np.asarray(branch.x[index], dtype=float), float(branch.p[index])


def connection_at(branch: Any, index: int) -> ConnectionResult:
    """The :class:`ConnectionResult` at row ``index`` of a branch from :func:`continue_connection`.

    The attached problem is rebased at that row (its ``params`` hold the row's
    parameters), so the result can be refined, checked or continued further.
    ``residual_norm`` is that of the branch's own residual at the row; ``errors``
    is None (re-solve with :func:`solve_connection` for estimates).
    """
    prob, z, p = branch_row(branch, index, HeteroclinicProblem, "continue_connection")
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
    "ContinuedConnection",
    "ContinuedOrbit",
    "ConvergenceCheck",
    "check_convergence",
    "connection_at",
    "continue_connection",
    "solve_connection",
]
