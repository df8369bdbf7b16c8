r"""The critical Froude number of broaching as a heteroclinic connection (Umeda 1999, Figs. 21-23).

Umeda (1999, "Nonlinear dynamics of ship capsizing due to broaching in following and
quartering seas", J. Mar. Sci. Technol. 4:16-26) finds the capsizing boundary where
the *upslope* branch of the one-dimensional unstable manifold of the surf-riding
saddle near the wave crest (:mod:`ship_models.analysis.upslope`) lands on the
neighbouring crest saddle, the same equilibrium one wavelength further back. Below
that Froude number the branch passes the next crest and the ship settles on a periodic
(overtaken) motion; above it the branch turns back down the slope into broaching and
capsize (or stable surf-riding when there is no roll coupling, ``chi_c = 0``).

Instead of bracketing this switch by simulations, it is solved directly: the
saddle-to-shifted-saddle heteroclinic orbit

.. math::

    \dot x = f(x; Fn, \chi_c), \qquad x(-\infty) = x_s, \qquad
    x(+\infty) = x_s + \Delta, \qquad \Delta = -1 \cdot e_{\xi_G},

with ``Fn`` unknown: ``dim W^u(x_s) + dim W^s(x_s + Delta) = 1 + 7 = n + 1 - 1``
(Beyn 1990, "The numerical computation of connecting orbits in dynamical systems",
IMA J. Numer. Anal. 10:379-405), by Gauss-Legendre collocation with projection
boundary conditions (:mod:`continuation.bvp`). Its continuation in ``chi_c`` is
:mod:`ship_models.analysis.critical_curve`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.bvp import (
    CollocationMesh,
    ConnectionResult,
    ConvergenceCheck,
    HeteroclinicProblem,
    check_convergence,
    solve_connection,
)
from continuation.errors import ContinuationError, ConvergenceError
from continuation.settings import NewtonSettings
from continuation.status import Status
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .boundary_check import boundary_refusal
from .crest_saddle import crest_saddle
from .critical_result import CriticalFn
from .fixed_points import FixedPoint
from .params import check_positive_fields, course, replace_settings, ship_model, ship_params
from .upslope import UpslopeRun, connection_guess, guess_run

log = logging.getLogger(__name__)

_DEFAULT_NEWTON = NewtonSettings(tol=1e-10, step_tol=1e-8, max_iter=40, damping=True)

#: Solve by the simplified Newton method with Broyden updates (True:
#: ``solve_connection(..., method="broyden")``) or by plain Newton (False).
_SIMPLIFIED_NEWTON = True


@dataclass(frozen=True)
class BVPSettings:
    """Settings of the connecting-orbit solve of the critical Fn (:func:`critical_fn_bvp`).

    Attributes
    ----------
    guess_bracket : (float, float)
        Fallback when the branch at ``Fn_guess`` is no usable guess (no index-1 crest
        saddle there, or the branch stays far from the shifted saddle): a coarse search
        on the upslope fate in this range, to a width of ``5e-3``
        (:func:`~ship_models.analysis.upslope.guess_run`).
    n_intervals : int or None
        Mesh intervals; default ``ceil(T / interval_length)`` (at least 10).
    degree : int
        Collocation points per interval (order ``2 degree`` at the mesh points), 1..8.
    interval_length : float
        Target length of one mesh interval (s).
    start_distance, end_distance : float
        Distances of the orbit's ends from the saddles (2-norm of the state).
    tol : float
        Newton tolerance on ``max |G|``.
    adapt : int
        Rounds of mesh equidistribution after the solve (``solve_connection``).
    mesh_from_guess : bool
        Start from a mesh that equidistributes the error monitor of the simulated
        guess (default) instead of a uniform one: for the default ship the result is
        then independent of the guess to a few 1e-8 in ``Fn`` without an adaptation
        round (a uniform mesh of the same size: a few 1e-7).

    Raises
    ------
    ValueError
        On construction, naming the bad field.
    """

    guess_bracket: tuple[float, float] = (0.2, 0.45)
    n_intervals: int | None = None
    degree: int = 4
    interval_length: float = 0.8
    start_distance: float = 3e-4
    end_distance: float = 3e-2
    tol: float = 1e-10
    adapt: int = 0
    mesh_from_guess: bool = True

    def __post_init__(self) -> None:
        check_positive_fields(self, ("interval_length", "start_distance", "end_distance", "tol"))
        n = self.n_intervals
        if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 2):
            raise ValueError(f"`n_intervals` must be an integer >= 2, got {n!r}")
        d = self.degree
        if isinstance(d, bool) or not isinstance(d, int) or not 1 <= d <= 8:
            raise ValueError(f"`degree` must be an integer in 1..8, got {d!r}")
        if isinstance(self.adapt, bool) or not isinstance(self.adapt, int) or self.adapt < 0:
            raise ValueError(f"`adapt` must be an integer >= 0, got {self.adapt!r}")

    def replace(self, **changes: Any) -> BVPSettings:
        """A copy with ``changes``; unknown names raise a ValueError naming them."""
        return replace_settings(self, "BVP", **changes)


def _pad_ends(
    t: FloatArray,
    x: FloatArray,
    x_from: FloatArray,
    x_to: FloatArray,
    pad0: float,
    pad1: float,
    h: float,
) -> tuple[FloatArray, FloatArray]:
    """Extend an orbit guess by ``pad0`` before and ``pad1`` after its ends.

    Outside the original interval the guess approaches the saddles exponentially,
    ``x_-+ + e^{-3 |s| / pad} (x_end - x_-+)`` (``s`` the time beyond the end), on a
    grid of spacing about ``h``.
    """
    t = np.asarray(t, dtype=float) - float(t[0])
    x = np.asarray(x, dtype=float)
    T = float(t[-1])
    a, b = x[0] - x_from, x[-1] - x_to
    k0 = max(int(math.ceil(pad0 / h)), 1) if pad0 > 0 else 0
    k1 = max(int(math.ceil(pad1 / h)), 1) if pad1 > 0 else 0
    s0 = np.linspace(-pad0, 0.0, k0 + 1)[:-1] if k0 else np.zeros(0)
    s1 = np.linspace(T, T + pad1, k1 + 1)[1:] if k1 else np.zeros(0)
    x0 = x_from + np.exp(3.0 * s0 / pad0)[:, None] * a if k0 else np.zeros((0, x.shape[1]))
    x1 = x_to + np.exp(-3.0 * (s1 - T) / pad1)[:, None] * b if k1 else np.zeros((0, x.shape[1]))
    return np.concatenate([s0, t, s1]), np.vstack([x0, x, x1])


def _pads(
    x: FloatArray,
    x_from: FloatArray,
    x_to: FloatArray,
    saddle: FixedPoint,
    d_start: float,
    d_end: float,
) -> tuple[float, float, float, float]:
    """Extra times before/after the orbit for end distances ``d_start``, ``d_end``.

    ``log(d / d_target) / rate`` with the unstable rate at the start and, at the end,
    the slowest stable rate among the modes present in the end offset
    (:meth:`~ship_models.analysis.eigen.EigenStructure.approach_rate`).
    """
    d0 = float(np.linalg.norm(x[0] - x_from))
    d1 = float(np.linalg.norm(x[-1] - x_to))
    pad0 = math.log(d0 / d_start) / saddle.unstable_rate if d0 > d_start else 0.0
    pad1 = math.log(d1 / d_end) / saddle.eigen.approach_rate(x[-1] - x_to) if d1 > d_end else 0.0
    return pad0, pad1, d0, d1


def _guess_mesh(t: FloatArray, x: FloatArray, n_intervals: int, degree: int) -> CollocationMesh:
    """A mesh of ``n_intervals`` that equidistributes the error monitor of the guess.

    The monitor (:meth:`CollocationMesh.equidistributed`) is evaluated on the guess
    interpolated onto a uniform mesh twice as fine; the guess of a nearby ``Fn`` has
    nearly the shape of the solution, so the solve needs no adaptation round.
    """
    T = float(t[-1] - t[0])
    fine = CollocationMesh(2 * n_intervals, degree, T)
    tau = (np.asarray(t) - t[0]) / T
    X = np.column_stack([np.interp(fine.tau, tau, x[:, i]) for i in range(x.shape[1])])
    return fine.equidistributed(X, n_intervals=n_intervals)


def _solve(
    prob: HeteroclinicProblem,
    guess: Any,
    settings: NewtonSettings,
    progress: Callable[[ConnectionResult], None] | None,
) -> ConnectionResult:
    """Solve the connection by :func:`continuation.bvp.solve_connection`.

    With ``method="broyden"`` (the default here): the collocation Jacobian of the ship
    model costs about five residuals, and from a guess simulated near the critical Fn
    one Jacobian plus a few Broyden-updated steps usually suffice (the solver falls
    back to Newton by itself when they do not).
    """
    method = "broyden" if _SIMPLIFIED_NEWTON else "newton"
    return solve_connection(prob, guess, newton=settings, progress=progress, method=method)


def critical_fn_bvp(
    chi_c: float,
    *,
    model: VesselModel | None = None,
    params: Any = None,
    guess: Any = None,
    Fn_guess: float | None = None,
    settings: BVPSettings | None = None,
    check: bool = False,
    throw: bool = False,
    progress: Callable[[ConnectionResult], None] | None = None,
    **options: Any,
) -> CriticalFn:
    r"""Critical ``Fn`` of one course as the saddle-to-shifted-saddle connection.

    Steps:

    1. Guess: simulate the upslope branch at ``Fn_guess`` (default the ``Fn`` of
       ``params``, i.e. the paper's :data:`~ship_models.paper.PAPER_FN`); if it never
       comes within 0.5 (state 2-norm) of the shifted saddle, or there is no index-1
       crest saddle at that ``Fn``, search the fate coarsely in
       ``settings.guess_bracket`` (to 5e-3) and use the closest usable branch. Cut it
       from ``start_distance`` off the saddle to its closest approach to the shifted
       saddle (:func:`~ship_models.analysis.upslope.connection_guess`) and pad the
       end with an exponential approach, ``log(d / end_distance) / mu`` longer, ``mu``
       the slowest stable rate present in the end offset
       (:meth:`~ship_models.analysis.eigen.EigenStructure.approach_rate`).
    2. Mesh: ``ceil(T / interval_length)`` intervals equidistributing the
       collocation error monitor of the guess (``mesh_from_guess``).
    3. Solve the collocation system with ``Fn`` unknown
       (:func:`continuation.bvp.solve_connection`); if the solved orbit ends more
       than 3x ``start_distance``/``end_distance`` from the saddles, pad it and solve
       again once.

    The truncation error of projection boundary conditions decays like ``d^2``
    (Beyn 1990). With the defaults, for the default ship at 0-30 deg, the result is
    within about 1.5e-7 of solves on 2.5x finer and longer meshes, independent of the
    guess ``Fn``; ``check=True`` measures this for the case at hand (``.error``).

    Parameters
    ----------
    chi_c : float
        Autopilot course (rad).
    model : Umeda4DOF, optional
        Default a new :func:`ship_models.purse_seiner` (pass it when solving many).
    params : Params or mapping, optional
        Wave and autopilot parameters (default ``model.default_params()``); ``chi_c``
        is replaced, ``Fn`` is the default guess.
    guess : ConnectionResult, CriticalFn, UpslopeRun or (t, x), optional
        Starting orbit instead of the simulation (a (t, x) pair needs ``Fn_guess``
        or uses the ``Fn`` of ``params``). A ``KeyboardInterrupt`` during the guess
        simulation propagates (nothing is finished yet); during the solve the result
        comes back with ``Status.INTERRUPTED``.
    Fn_guess : float, optional
        ``Fn`` of the simulated guess.
    settings : BVPSettings, optional
        Mesh, distances, tolerance; default ``BVPSettings()``.
    check : bool
        Also run :func:`continuation.bvp.check_convergence` (halved mesh, 1.5 T).
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` on failure.
    progress : callable, optional
        Called with every intermediate :class:`ConnectionResult`.
    **options
        Fields of :class:`BVPSettings` replaced in ``settings`` (e.g. ``degree=5``).

    Returns
    -------
    CriticalFn
        ``method="bvp"``, with ``orbit``, ``residual_norm``, ``Fn_guess`` and, with
        ``check``, ``convergence`` and ``error``.
    """
    t_start = time.perf_counter()
    chi = course(chi_c)
    m = ship_model(model)
    base = ship_params(m, params, chi_c=chi)
    cfg = (settings or BVPSettings()).replace(**options)
    if not isinstance(cfg, BVPSettings):
        raise ValueError(f"`settings` must be BVPSettings, got {type(settings).__name__}")
    guess_bracket, n_intervals, degree = cfg.guess_bracket, cfg.n_intervals, cfg.degree
    interval_length, start_distance = cfg.interval_length, cfg.start_distance
    end_distance, adapt, mesh_from_guess = cfg.end_distance, cfg.adapt, cfg.mesh_from_guess
    settings_n = dataclasses.replace(_DEFAULT_NEWTON, tol=cfg.tol)
    if isinstance(guess, CriticalFn):
        guess = guess.orbit
    Fn0 = float(base["Fn"]) if Fn_guess is None else float(Fn_guess)
    if not (math.isfinite(Fn0) and Fn0 > 0):
        raise ValueError(f"`Fn_guess` must be positive, got {Fn_guess!r}")
    Fn_guess_used = math.nan
    i_xi = m.state_index("xi_G")
    try:
        if isinstance(guess, ConnectionResult):
            wl_shift = float(np.round(guess.x_to[i_xi] - guess.x_from[i_xi]))
            Fn0 = float(guess.params["Fn"])
            start = base.replace(Fn=Fn0)
            saddle = crest_saddle(m, start)
            t_g, x_g = None, None
        else:
            start = base.replace(Fn=Fn0)
            if guess is None or isinstance(guess, UpslopeRun):
                # a loose integrator tolerance suffices for a starting guess
                if guess is None:
                    run = guess_run(m, start, guess_bracket)
                    Fn0 = float(run.params["Fn"])
                    start = base.replace(Fn=Fn0)
                else:
                    run = guess
                saddle = run.saddle
                wl_shift = run.shift
                t_g, x_g = connection_guess(run, start_distance=start_distance)
                Fn_guess_used = Fn0
            else:
                saddle = crest_saddle(m, start)
                try:
                    t_g, x_g = (np.asarray(a, dtype=float) for a in guess)
                except (TypeError, ValueError):
                    raise ValueError(
                        "`guess` must be a ConnectionResult, CriticalFn, UpslopeRun or "
                        f"(t, x) pair, got {type(guess).__name__}"
                    ) from None
                n_x = len(m.state_names)
                if x_g.ndim != 2 or x_g.shape[1] != n_x or t_g.shape != x_g[:, 0].shape:
                    raise ValueError(
                        f"`guess` (t, x) must have shapes (K,) and (K, {len(m.state_names)}), "
                        f"got {t_g.shape} and {x_g.shape}"
                    )
                wl_shift = -1.0 if x_g[-1, i_xi] < x_g[0, i_xi] else 1.0
    except ContinuationError as exc:
        # no crest saddle at this course / no usable simulated guess: nothing to solve
        exists = "does not reach" not in str(exc) and "does not exist" not in str(exc)
        if throw:
            msg = f"critical Fn at chi_c={math.degrees(chi):g} deg: {exc}"
            raise ConvergenceError(msg) from None
        return CriticalFn(
            chi_c=chi, Fn=math.nan, method="bvp",
            status=Status.NO_BRACKET if exists else Status.NO_SOLUTION,
            message=str(exc), elapsed=time.perf_counter() - t_start, Fn_guess=Fn0, tol=cfg.tol,
        )  # fmt: skip
    if t_g is not None:
        shift = np.zeros(len(m.state_names))
        shift[i_xi] = wl_shift
        pad0, pad1, _, _ = _pads(
            x_g, saddle.x, saddle.x + shift, saddle, start_distance, end_distance
        )
        t_g, x_g = _pad_ends(
            t_g, x_g, saddle.x, saddle.x + shift, pad0, pad1, 0.5 * interval_length
        )
    T0 = guess.T if isinstance(guess, ConnectionResult) else float(t_g[-1] - t_g[0])
    N0 = n_intervals or max(int(math.ceil(T0 / interval_length)), 10)
    if isinstance(guess, ConnectionResult) and n_intervals is None:
        mesh = guess.mesh
    elif t_g is not None and mesh_from_guess:
        mesh = _guess_mesh(t_g, x_g, N0, degree)
    else:
        mesh = CollocationMesh(N0, degree, T0)
    prob = HeteroclinicProblem(
        m, start, "Fn", saddle_from=saddle.x, shift={"xi_G": wl_shift}, mesh=mesh
    )
    res = _solve(prob, guess if t_g is None else (t_g, x_g), settings_n, progress)
    if res.success:
        # the solved orbit may end farther from the saddles than the guess did
        pad0, pad1, d0, d1 = _pads(
            res.x, res.x_from, res.x_to, saddle, start_distance, end_distance
        )
        if d0 > 3 * start_distance or d1 > 3 * end_distance:
            t2, x2 = _pad_ends(
                res.t, res.x, res.x_from, res.x_to, pad0, pad1, 0.5 * interval_length
            )
            T2 = float(t2[-1] - t2[0])
            N2 = n_intervals or max(int(math.ceil(T2 / interval_length)), 10)
            prob2 = res.problem.replace(mesh=CollocationMesh(N2, degree, T2), reference=None)
            log.info(
                "lengthening T from %.2f to %.2f (end distances %.2e, %.2e)", res.T, T2, d0, d1
            )
            res = _solve(prob2, (t2, x2), settings_n, progress)
    if res.success and adapt:
        res = solve_connection(res.problem, res, newton=settings_n, adapt=adapt, progress=progress)
    conv = None
    if res.success and check:
        conv = check_convergence(res, newton=settings_n)  # as check_critical_bvp does
    status = res.status
    message = res.message
    refusal = ""
    # a converged orbit is checked even when its error estimate failed: a capsize
    # is refused as such, whatever its accuracy
    if res.success or res.status in (Status.DISCRETISATION_ERROR, Status.TRUNCATION_ERROR):
        refusal = boundary_refusal(m, res.x, res.x_from, base.replace(Fn=float(res.params["Fn"])))
        if refusal:
            status, message = Status.REJECTED, f"not a capsizing boundary: {refusal}"
    if throw and status is not Status.SUCCESS:
        raise ConvergenceError(f"critical Fn at chi_c={math.degrees(chi):g} deg: {message}")
    errs = getattr(res, "errors", None)
    error = float(errs.total("Fn")) if errs is not None else None
    if conv is not None:
        dm, dT = conv.delta_mesh.get("Fn"), conv.delta_T.get("Fn")
        if dm is not None and dT is not None:
            error = max(abs(float(dm)), abs(float(dT)), error or 0.0)
    return CriticalFn(
        chi_c=chi,
        Fn=float(res.params["Fn"]),
        method="bvp",
        status=status,
        message=message,
        error=error,
        elapsed=time.perf_counter() - t_start,
        orbit=res,
        residual_norm=float(res.residual_norm),
        Fn_guess=Fn_guess_used,
        convergence=conv,
        tol=cfg.tol,
    )


def check_critical_bvp(result: CriticalFn) -> ConvergenceCheck:
    """The convergence check of ``critical_fn_bvp(..., check=True)`` for a result solved without it.

    The same re-solves (:func:`continuation.bvp.check_convergence`: the mesh halved,
    1.5 ``T``) with the same Newton settings (tolerance ``result.tol``), so
    ``check_critical_bvp(critical_fn_bvp(chi_c))`` equals
    ``critical_fn_bvp(chi_c, check=True).convergence`` without solving the connection
    twice. ``ConvergenceCheck.delta_mesh["Fn"]`` and ``.delta_T["Fn"]`` are the changes
    of the critical ``Fn``.

    Raises
    ------
    ValueError
        If ``result`` is not a converged connecting-orbit result (``method="bvp"``
        with its orbit).
    """
    orbit = getattr(result, "orbit", None)
    if not isinstance(result, CriticalFn) or result.method != "bvp" or orbit is None:
        raise ValueError("`result` must be a CriticalFn of critical_fn_bvp with its orbit")
    if not orbit.success:
        raise ValueError(f"`result` did not converge ({orbit.status.name})")
    tol = result.tol if math.isfinite(result.tol) else BVPSettings().tol
    return check_convergence(orbit, newton=dataclasses.replace(_DEFAULT_NEWTON, tol=tol))


__all__ = ["BVPSettings", "check_critical_bvp", "critical_fn_bvp"]
