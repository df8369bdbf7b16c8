r"""The critical Froude number of broaching as a heteroclinic connection (Umeda 1999, Figs. 21-23).

Umeda (1999, "Nonlinear dynamics of ship capsizing due to broaching in following and
quartering seas", J. Mar. Sci. Technol. 4:16-26) finds the capsizing boundary where
the *upslope* branch of the one-dimensional unstable manifold of the surf-riding
saddle near the wave crest (the branch heading to ``0 < xi_G/lambda < 0.5``: the ship
falls behind the crest and the wave overtakes it) lands on the neighbouring crest
saddle, the same equilibrium one wavelength further back. Below that Froude number
the branch passes the next crest and the ship settles on a periodic (overtaken)
motion; above it the branch turns back down the slope into broaching and capsize
(or stable surf-riding when there is no roll coupling, ``chi_c = 0``).

Instead of bracketing this switch by simulations, it is solved directly: the
saddle-to-shifted-saddle heteroclinic orbit

.. math::

    \dot x = f(x; Fn, \chi_c), \qquad x(-\infty) = x_s, \qquad
    x(+\infty) = x_s + \Delta, \qquad \Delta = -1 \cdot e_{\xi_G},

with ``Fn`` unknown: ``dim W^u(x_s) + dim W^s(x_s + Delta) = 1 + 7 = n + 1 - 1``
(Beyn 1990, "The numerical computation of connecting orbits in dynamical systems",
IMA J. Numer. Anal. 10:379-405), by Gauss-Legendre collocation with projection
boundary conditions (:mod:`continuation.bvp`). Its continuation in ``chi_c`` is the
paper's Fig. 23 line.

Public names
------------
:func:`critical_fn_bvp` — one course: critical ``Fn``, orbit, residual, status.
:func:`critical_curve` — critical ``Fn`` over a range of courses by continuation.
:func:`critical_fn_bisection` — the brute-force reference: bisection of ``Fn`` on
the fate of the upslope branch (simulations), for checks and benchmarks.
:func:`upslope_branch` — one simulation of the upslope branch and its fate.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from continuation.bvp import (
    CollocationMesh,
    ConnectionResult,
    ConvergenceCheck,
    HeteroclinicProblem,
    check_convergence,
    continue_connection,
    solve_connection,
)
from continuation.bvp.simplified import JacobianCache, simplified_newton
from continuation.errors import ContinuationError, ConvergenceError
from continuation.newton import newton
from continuation.params import Params
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.simulate import SimEvent, Simulator, Trajectory
from continuation.status import Status
from continuation.typing import FloatArray

from .events import capsize_event

log = logging.getLogger(__name__)

#: Shift of ``xi_G/lambda`` from the crest saddle to the saddle the upslope branch meets.
UPSLOPE_SHIFT = -1.0
#: Fates of the upslope branch.
PERIODIC, CAPTURED, UNDECIDED = "periodic", "captured", "undecided"

_DEFAULT_NEWTON = NewtonSettings(tol=1e-10, step_tol=1e-8, max_iter=40, damping=True)


# ----------------------------------------------------------------------------- helpers
def _model(model: Any) -> Any:
    if model is None:
        from ship_models import purse_seiner

        return _default_model(purse_seiner)
    if not (hasattr(model, "state_names") and hasattr(model, "find_equilibrium")):
        raise ValueError(
            "`model` must be an Umeda4DOF-like System (with `find_equilibrium`), "
            f"got {type(model).__name__}"
        )
    return model


_CACHE: dict[str, Any] = {}


def _default_model(factory: Callable[[], Any]) -> Any:
    if "default" not in _CACHE:
        _CACHE["default"] = factory()
    return _CACHE["default"]


def _params(model: Any, params: Any, **changes: float) -> Params:
    if params is None:
        p = model.default_params()
    elif isinstance(params, Params):
        p = params
    else:
        try:
            p = model.params(**dict(params)) if hasattr(params, "keys") else None
        except (TypeError, ValueError) as exc:
            raise ValueError(f"`params` is not valid for this model: {exc}") from None
        if p is None:
            p = Params(tuple(model.param_names), np.asarray(params, dtype=float))
    if tuple(p.names) != tuple(model.param_names):
        raise ValueError(f"`params` must name {tuple(model.param_names)}, got {tuple(p.names)}")
    for k, v in changes.items():
        if not math.isfinite(v):
            raise ValueError(f"`{k}` must be finite, got {v!r}")
    return p.replace(**changes) if changes else p


def _chi_c(value: Any, name: str = "chi_c") -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a number (rad), got {value!r}") from None
    if not (math.isfinite(v) and abs(v) < math.pi / 2):
        raise ValueError(f"`{name}` must be a finite course in (-pi/2, pi/2) rad, got {value!r}")
    return v


@dataclass(frozen=True)
class CrestSaddle:
    """The surf-riding saddle near the crest and its upslope unstable direction.

    Attributes
    ----------
    x : ndarray, shape (8,)
        The equilibrium.
    rate : float
        Its unstable eigenvalue ``lambda_u > 0`` (1/s).
    direction : ndarray, shape (8,)
        Unit unstable eigenvector, oriented so that ``xi_G`` decreases (upslope).
    weakest_stable : float
        ``min |Re lambda|`` over the stable eigenvalues (1/s): the slowest approach.
    n_unstable : int
        Number of eigenvalues with positive real part (1 for a saddle of index 1).
    eigenvalues : ndarray, shape (8,), complex
    eigenvectors : ndarray, shape (8, 8), complex
        Columns are the eigenvectors of ``f_x`` at the saddle.
    """

    x: FloatArray
    rate: float
    direction: FloatArray
    weakest_stable: float
    n_unstable: int
    eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros(0, complex), repr=False)
    eigenvectors: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), complex), repr=False)

    def approach_rate(self, offset: FloatArray, rel: float = 1e-3) -> float:
        """Slowest stable decay rate present in ``offset`` (a state minus the saddle).

        The offset is expanded in the eigenvectors; modes whose coefficient is below
        ``rel`` times the largest are ignored (e.g. the lateral modes at ``chi_c = 0``,
        which the symmetric motion never excites). Falls back to ``weakest_stable``.
        """
        if self.eigenvectors.size == 0:
            return self.weakest_stable
        try:
            c = np.abs(np.linalg.solve(self.eigenvectors, np.asarray(offset, dtype=complex)))
        except np.linalg.LinAlgError:
            return self.weakest_stable
        stable = self.eigenvalues.real < 0
        present = stable & (c > rel * np.max(c[stable], initial=0.0))
        if not np.any(present):
            return self.weakest_stable
        return float(np.min(-self.eigenvalues.real[present]))


def _crest_equilibrium(model: Any, params: Params) -> FloatArray:
    """The crest equilibrium followed from ``chi_c = 0`` (where it is the surge root):
    ``model.find_equilibrium`` continues it in ``chi_c`` (a guess with zero lateral
    states alone can converge to another root at large courses); fails if the branch
    folds before the course."""
    settings = NewtonSettings(tol=1e-11, max_iter=30, damping=True)
    res = model.find_equilibrium(params, "crest", settings=settings)
    if not res.converged:
        raise ContinuationError(
            f"no crest equilibrium at {dict(params.items())} (followed from chi_c = 0): "
            f"{res.message}"
        )
    return np.asarray(res.z, dtype=float)


def crest_saddle(model: Any, params: Params) -> CrestSaddle:
    """Solve the crest equilibrium and orient its unstable eigenvector upslope.

    Raises
    ------
    ContinuationError
        If no crest equilibrium is found or it is not a saddle of index 1.
    """
    pv = np.asarray(params.values, dtype=float)
    x = _crest_equilibrium(model, params)
    w, V = np.linalg.eig(model.jacobian(x, pv))
    n_unst = int(np.sum(w.real > 0))
    if n_unst != 1:
        raise ContinuationError(
            f"the crest equilibrium has {n_unst} unstable eigenvalues (need a saddle of "
            f"index 1 for the upslope connection) at {dict(params.items())}"
        )
    k = int(np.argmax(w.real))
    v = np.real(V[:, k])
    v = v / np.linalg.norm(v)
    i_xi = model.state_index("xi_G")
    if v[i_xi] > 0:
        v = -v
    stable = w.real[w.real < 0]
    return CrestSaddle(x, float(w[k].real), v, float(np.min(-stable)), n_unst, w, V)


@dataclass(frozen=True)
class UpslopeRun:
    """One simulation of the upslope branch of the crest saddle's unstable manifold.

    Attributes
    ----------
    trajectory : Trajectory
        From ``x_s + eps v_u`` (``xi_G`` unwrapped).
    saddle : CrestSaddle
    fate : str
        ``"periodic"`` (passed the next crest: ``xi_G < xi_s - 1.5``), ``"captured"``
        (capsized, turned back down the slope of the next wave: ``xi_G`` rose again
        above ``xi_s - 0.8``, or went down the slope of the same wave:
        ``xi_G > xi_s + 0.2``), or ``"undecided"`` (``t_max`` reached first, or failure).
    """

    trajectory: Trajectory
    saddle: CrestSaddle
    fate: str

    @property
    def shift(self) -> float:
        """Shift of ``xi_G`` to the neighbouring saddle the branch passes closest to.

        ``-1`` (one wavelength back, :data:`UPSLOPE_SHIFT`) for the upslope branch of
        the paper; ``+1`` would mean the branch heads for the saddle ahead instead.
        """
        x = np.asarray(self.trajectory.x, dtype=float)
        i = list(self.trajectory.state_names).index("xi_G")
        d = {}
        for k in (-1.0, 1.0):
            target = self.saddle.x.copy()
            target[i] += k
            d[k] = float(np.min(np.linalg.norm(x - target, axis=1)))
        return -1.0 if d[-1.0] <= d[1.0] else 1.0


def upslope_branch(
    model: Any,
    params: Params,
    *,
    eps: float = 1e-6,
    t_max: float = 600.0,
    dt: float = 0.05,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    saddle: CrestSaddle | None = None,
) -> UpslopeRun:
    r"""Simulate the upslope branch ``x_s + eps v_u`` and classify its fate.

    Terminal events: capsize (``|phi|`` beyond the angle of vanishing stability,
    :func:`~ship_models.analysis.events.capsize_event`), ``xi_G`` falling below
    ``xi_s - 1.5`` (beyond the neighbouring crest saddle: periodic motion), and
    ``xi_G`` rising back through ``xi_s - 0.8`` (the branch came down the slope of
    the next wave: surf-riding or broaching).
    """
    if not (math.isfinite(eps) and 0 < eps < 1e-2):
        raise ValueError(f"`eps` must be in (0, 1e-2), got {eps!r}")
    if not (math.isfinite(t_max) and t_max > 0):
        raise ValueError(f"`t_max` must be positive, got {t_max!r}")
    s = crest_saddle(model, params) if saddle is None else saddle
    i_xi = model.state_index("xi_G")
    xi_s = float(s.x[i_xi])
    passed = SimEvent(
        "passed",
        lambda t, x: x[..., i_xi] - (xi_s - 1.5),
        terminal=True,
        direction=-1,
        vectorized=True,
    )
    returned = SimEvent(
        "returned",
        lambda t, x: x[..., i_xi] - (xi_s - 0.8),
        terminal=True,
        direction=1,
        vectorized=True,
    )
    downslope = SimEvent(
        "downslope",
        lambda t, x: x[..., i_xi] - (xi_s + 0.2),
        terminal=True,
        direction=1,
        vectorized=True,
    )
    sim = Simulator(model, np.asarray(params.values, dtype=float), rtol=rtol, atol=atol)
    traj = sim.run(
        s.x + eps * s.direction,
        (0.0, t_max),
        events=[capsize_event(model), passed, returned, downslope],
        dt=dt,
    )
    if traj.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    if traj.terminal_event == "passed":
        fate = PERIODIC
    elif traj.terminal_event in ("capsize", "returned", "downslope"):
        fate = CAPTURED
    else:
        fate = UNDECIDED
    return UpslopeRun(traj, s, fate)


# ----------------------------------------------------------------------------- bisection
@dataclass(frozen=True)
class BisectionCritical:
    """Critical ``Fn`` bracketed by the fate of the upslope branch.

    Attributes
    ----------
    chi_c : float
        Course (rad).
    Fn : float
        Midpoint of the final bracket.
    bracket : (float, float)
        ``(Fn_periodic, Fn_captured)``: the upslope branch passes the next crest at the
        first and is captured at the second.
    n_runs : int
        Simulations used.
    elapsed : float
        Wall time (s).
    status : Status
    message : str
    """

    chi_c: float
    Fn: float
    bracket: tuple[float, float]
    n_runs: int
    elapsed: float
    status: Status
    message: str

    @property
    def success(self) -> bool:
        """True when the bracket is narrower than the requested tolerance."""
        return self.status is Status.SUCCESS


def critical_fn_bisection(
    chi_c: float,
    *,
    model: Any = None,
    params: Any = None,
    bracket: tuple[float, float] = (0.28, 0.33),
    tol: float = 1e-6,
    eps: float = 1e-6,
    t_max: float = 600.0,
    throw: bool = False,
    progress: Callable[[float, str], None] | None = None,
) -> BisectionCritical:
    r"""Critical ``Fn`` by bisection on the fate of the upslope branch (simulations).

    The brute-force reference for :func:`critical_fn_bvp`: every step simulates the
    upslope branch (:func:`upslope_branch`) at the midpoint and keeps the half whose
    ends have different fates, until the bracket is narrower than ``tol``. The
    accuracy is also limited by ``eps`` (the manifold is started on its tangent:
    an ``O(eps^2)`` error in its position) and the integrator tolerances.

    Parameters
    ----------
    chi_c : float
        Autopilot course (rad).
    model, params
        The ship (default :func:`ship_models.purse_seiner`) and the other parameters.
    bracket : (float, float)
        ``(Fn_lo, Fn_hi)``; the branch must be periodic at ``Fn_lo`` and captured at
        ``Fn_hi`` (both are simulated first).
    tol : float
        Final bracket width.
    progress : callable, optional
        ``progress(Fn, fate)`` after every simulation.

    Returns
    -------
    BisectionCritical
        ``status`` ``SUCCESS``, ``NO_BRACKET`` (the bracket ends do not have the
        fates above), ``UNDECIDED`` (a run reached ``t_max`` undecided) or
        ``INTERRUPTED``.
    """
    chi = _chi_c(chi_c)
    lo, hi = (float(b) for b in bracket)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise ValueError(f"`bracket` must be (Fn_lo, Fn_hi) with 0 < Fn_lo < Fn_hi, got {bracket}")
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"`tol` must be positive, got {tol!r}")
    m = _model(model)
    base = _params(m, params, chi_c=chi)
    t0 = time.perf_counter()
    n = 0

    def fate(Fn: float) -> str:
        nonlocal n
        n += 1
        try:
            f = upslope_branch(m, base.replace(Fn=Fn), eps=eps, t_max=t_max).fate
        except ContinuationError:
            f = UNDECIDED
        if progress is not None:
            progress(Fn, f)
        return f

    def done(status: Status, message: str) -> BisectionCritical:
        if throw and status is not Status.SUCCESS:
            raise ConvergenceError(message)
        return BisectionCritical(
            chi, 0.5 * (lo + hi), (lo, hi), n, time.perf_counter() - t0, status, message
        )

    try:
        f_lo, f_hi = fate(lo), fate(hi)
        if f_lo != PERIODIC or f_hi != CAPTURED:
            return done(
                Status.NO_BRACKET,
                f"`bracket` {bracket} does not bracket the switch: fates {f_lo!r} at Fn={lo} "
                f"and {f_hi!r} at Fn={hi} (need 'periodic' then 'captured')",
            )
        while hi - lo > tol:
            mid = 0.5 * (lo + hi)
            f = fate(mid)
            if f == PERIODIC:
                lo = mid
            elif f == CAPTURED:
                hi = mid
            else:
                return done(Status.UNDECIDED, f"undecided fate at Fn={mid}")
    except KeyboardInterrupt:
        return done(Status.INTERRUPTED, Status.INTERRUPTED.value)
    return done(Status.SUCCESS, f"bracket width {hi - lo:.2e} after {n} simulations")


# ----------------------------------------------------------------------------- BVP
@dataclass(frozen=True, eq=False)
class CriticalConnection:
    """The heteroclinic connection at the critical ``Fn`` for one course.

    Attributes
    ----------
    chi_c : float
        Course (rad).
    Fn : float
        Critical nominal Froude number (solved).
    residual_norm : float
        ``max |G|`` of the collocation equations at the solution.
    orbit : ConnectionResult
        The connecting orbit ``t (M,)``, ``x (M, 8)`` from the crest saddle ``x_from``
        to the shifted saddle ``x_to`` (``xi_G`` one wavelength back).
    status : Status
    message : str
    guess_Fn : float
        ``Fn`` of the simulated manifold used as the starting guess (nan if given).
    convergence : ConvergenceCheck or None
        Mesh-halving and longer-``T`` re-solves (``check=True``).
    elapsed : float
        Wall time (s).
    """

    chi_c: float
    Fn: float
    residual_norm: float
    orbit: ConnectionResult
    status: Status
    message: str
    guess_Fn: float = math.nan
    convergence: ConvergenceCheck | None = field(default=None, repr=False)
    elapsed: float = 0.0

    @property
    def success(self) -> bool:
        """True when the collocation system converged."""
        return self.status is Status.SUCCESS

    @property
    def chi_c_deg(self) -> float:
        """Course in degrees."""
        return math.degrees(self.chi_c)

    @property
    def saddle(self) -> FloatArray:
        """The crest saddle ``x_-``, shape (8,)."""
        return self.orbit.x_from

    @property
    def end_distances(self) -> tuple[float, float]:
        """``|x(0) - x_-|`` and ``|x(T) - x_+|`` (2-norm)."""
        o = self.orbit
        return (
            float(np.linalg.norm(o.x[0] - o.x_from)),
            float(np.linalg.norm(o.x[-1] - o.x_to)),
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (no orbit samples)."""
        d: dict[str, Any] = {
            "chi_c_deg": self.chi_c_deg,
            "Fn": self.Fn,
            "residual_norm": self.residual_norm,
            "status": self.status.name,
            "message": self.message,
            "guess_Fn": None if math.isnan(self.guess_Fn) else self.guess_Fn,
            "T": self.orbit.T,
            "n_intervals": self.orbit.mesh.n_intervals,
            "degree": self.orbit.mesh.degree,
            "end_distances": list(self.end_distances),
            "saddle": self.saddle.tolist(),
            "elapsed_s": self.elapsed,
        }
        if self.convergence is not None:
            d["delta_Fn_mesh"] = self.convergence.delta_mesh.get("Fn")
            d["delta_Fn_T"] = self.convergence.delta_T.get("Fn")
        return d


def connection_guess(
    run: UpslopeRun, *, start_distance: float = 1e-3
) -> tuple[FloatArray, FloatArray]:
    """Cut an upslope-branch simulation into a guess of the connecting orbit.

    Starts where the branch is ``start_distance`` from the saddle and ends where it
    passes closest to the shifted saddle ``x_s + Delta``.

    Returns
    -------
    t : ndarray, shape (K,)
    x : ndarray, shape (K, 8)
    """
    tr = run.trajectory
    x = np.asarray(tr.x, dtype=float)
    shift = np.zeros(x.shape[1])
    shift[list(tr.state_names).index("xi_G")] = run.shift
    d0 = np.linalg.norm(x - run.saddle.x, axis=1)
    d1 = np.linalg.norm(x - (run.saddle.x + shift), axis=1)
    i1 = int(np.argmin(d1))
    far = np.nonzero(d0 >= start_distance)[0]
    i0 = int(far[0]) if far.size else 0
    if i1 - i0 < 4:
        raise ContinuationError(
            "the upslope branch does not travel towards the neighbouring crest saddle; "
            "no connection guess"
        )
    return np.asarray(tr.t[i0 : i1 + 1]), x[i0 : i1 + 1]


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
    saddle: CrestSaddle,
    d_start: float,
    d_end: float,
) -> tuple[float, float, float, float]:
    """Extra times before/after the orbit for end distances ``d_start``, ``d_end``.

    ``log(d / d_target) / rate`` with the unstable rate at the start and, at the end,
    the slowest stable rate among the modes present in the end offset
    (:meth:`CrestSaddle.approach_rate`).
    """
    d0 = float(np.linalg.norm(x[0] - x_from))
    d1 = float(np.linalg.norm(x[-1] - x_to))
    pad0 = math.log(d0 / d_start) / saddle.rate if d0 > d_start else 0.0
    pad1 = math.log(d1 / d_end) / saddle.approach_rate(x[-1] - x_to) if d1 > d_end else 0.0
    return pad0, pad1, d0, d1


#: Largest distance (2-norm of the state) of a usable guess from the shifted saddle.
_GUESS_REACH = 0.5


def _try_guess(model: Any, params: Params) -> tuple[UpslopeRun | None, str]:
    """The upslope branch at ``params`` and its fate; the run is None if unusable as a guess."""
    try:
        # a guess needs no accuracy: start 1e-4 off the saddle (integrator errors
        # ~1e-6 stay well below that), sample every 0.1 s
        run = upslope_branch(model, params, eps=1e-4, rtol=1e-7, atol=1e-9, dt=0.1)
    except ContinuationError:
        return None, UNDECIDED
    x = np.asarray(run.trajectory.x, dtype=float)
    target = run.saddle.x.copy()
    target[model.state_index("xi_G")] += run.shift
    if run.fate == UNDECIDED or np.min(np.linalg.norm(x - target, axis=1)) > _GUESS_REACH:
        return None, run.fate
    return run, run.fate


def _guess_run(model: Any, params: Params, bracket: tuple[float, float]) -> UpslopeRun:
    """A simulated upslope branch near the critical ``Fn`` (see :func:`critical_fn_bvp`)."""
    run, _ = _try_guess(model, params)
    if run is not None:
        return run
    lo, hi = (float(b) for b in bracket)
    if not (0 < lo < hi and math.isfinite(hi)):
        raise ValueError(f"`guess_bracket` must be (Fn_lo, Fn_hi) with 0 < lo < hi, got {bracket}")
    best: UpslopeRun | None = None
    while hi - lo > 5e-3:
        mid = 0.5 * (lo + hi)
        r, fate = _try_guess(model, params.replace(Fn=mid))
        best = r or best
        if fate == PERIODIC:
            lo = mid
        elif fate == CAPTURED:
            hi = mid
        else:
            break
    if best is None:
        raise ContinuationError(
            f"no usable guess of the connection at {dict(params.items())}: the upslope "
            f"branch does not approach the shifted crest saddle for Fn in {bracket}"
        )
    return best


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


#: Solve by the simplified Newton method with Broyden updates (True:
#: ``solve_connection(..., method="broyden")``) or by plain Newton (False).
_SIMPLIFIED_NEWTON = True


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
    model: Any = None,
    params: Any = None,
    guess: Any = None,
    Fn_guess: float | None = None,
    guess_bracket: tuple[float, float] = (0.2, 0.45),
    n_intervals: int | None = None,
    degree: int = 4,
    interval_length: float = 0.8,
    start_distance: float = 3e-4,
    end_distance: float = 3e-2,
    tol: float = 1e-10,
    adapt: int = 0,
    mesh_from_guess: bool = True,
    check: bool = False,
    throw: bool = False,
    progress: Callable[[ConnectionResult], None] | None = None,
) -> CriticalConnection:
    r"""Critical ``Fn`` of one course as the saddle-to-shifted-saddle connection.

    Steps:

    1. Guess: simulate the upslope branch at ``Fn_guess`` (default the ``Fn`` of
       ``params``, i.e. the paper's 0.3248); if it never comes within 0.5 (state
       2-norm) of the shifted saddle, or there is no index-1 crest saddle at that
       ``Fn``, bisect the fate coarsely in ``guess_bracket`` (to 5e-3) and use the
       closest usable branch. Cut it from ``start_distance`` off the saddle to its
       closest approach to the shifted saddle (:func:`connection_guess`) and pad the
       end with an exponential approach, ``log(d / end_distance) / mu`` longer, ``mu``
       the slowest stable rate present in the end offset
       (:meth:`CrestSaddle.approach_rate`).
    2. Mesh: ``ceil(T / interval_length)`` intervals equidistributing the
       collocation error monitor of the guess (``mesh_from_guess``).
    3. Solve the collocation system with ``Fn`` unknown
       (:func:`continuation.bvp.solve_connection`); if the solved orbit ends more
       than 3x ``start_distance``/``end_distance`` from the saddles, pad it and solve
       again once.

    The truncation error of projection boundary conditions decays like ``d^2``
    (Beyn 1990). With the defaults, for the default ship at 0-30 deg, the result is
    within about 1.5e-7 of solves on 2.5x finer and longer meshes, independent of the
    guess ``Fn``; ``check=True`` measures this for the case at hand.

    Parameters
    ----------
    chi_c : float
        Autopilot course (rad).
    model : Umeda4DOF, optional
        Default :func:`ship_models.purse_seiner` (built once and cached).
    params : Params or mapping, optional
        Wave and autopilot parameters (default ``model.default_params()``); ``chi_c``
        is replaced, ``Fn`` is the default guess.
    guess : ConnectionResult, CriticalConnection, UpslopeRun or (t, x), optional
        Starting orbit instead of the simulation (a (t, x) pair needs ``Fn_guess``
        or uses the ``Fn`` of ``params``). A ``KeyboardInterrupt`` during the guess
        simulation propagates (nothing is finished yet); during the solve the result
        comes back with ``Status.INTERRUPTED``.
    Fn_guess : float, optional
        ``Fn`` of the simulated guess.
    guess_bracket : (float, float)
        Fallback when the branch at ``Fn_guess`` is no usable guess (no index-1 crest
        saddle there, or the branch stays far from the shifted saddle): a coarse
        bisection on the upslope fate in this range, to a width of ``5e-3``; the last
        usable branch it simulated gives the guess.
    n_intervals : int, optional
        Mesh intervals; default ``ceil(T / interval_length)``.
    degree : int
        Collocation points per interval (order ``2 degree`` at the mesh points).
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
    check : bool
        Also run :func:`continuation.bvp.check_convergence` (halved mesh, 1.5 T).
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` on failure.
    progress : callable, optional
        Called with every intermediate :class:`ConnectionResult`.

    Returns
    -------
    CriticalConnection
    """
    t_start = time.perf_counter()
    chi = _chi_c(chi_c)
    m = _model(model)
    base = _params(m, params, chi_c=chi)
    for name, v in (
        ("interval_length", interval_length),
        ("start_distance", start_distance),
        ("end_distance", end_distance),
        ("tol", tol),
    ):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"`{name}` must be a positive number, got {v!r}")
    if n_intervals is not None and (
        isinstance(n_intervals, bool) or not isinstance(n_intervals, int) or n_intervals < 2
    ):
        raise ValueError(f"`n_intervals` must be an integer >= 2, got {n_intervals!r}")
    if isinstance(degree, bool) or not isinstance(degree, int) or not 1 <= degree <= 8:
        raise ValueError(f"`degree` must be an integer in 1..8, got {degree!r}")
    settings = dataclasses.replace(_DEFAULT_NEWTON, tol=tol)
    if isinstance(guess, CriticalConnection):
        guess = guess.orbit
    Fn0 = float(base["Fn"]) if Fn_guess is None else float(Fn_guess)
    if not (math.isfinite(Fn0) and Fn0 > 0):
        raise ValueError(f"`Fn_guess` must be positive, got {Fn_guess!r}")
    guess_Fn = math.nan
    i_xi = m.state_index("xi_G")
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
                run = _guess_run(m, start, guess_bracket)
                Fn0 = float(run.trajectory.params[m.param_index("Fn")])
                start = base.replace(Fn=Fn0)
            else:
                run = guess
            saddle = run.saddle
            wl_shift = run.shift
            t_g, x_g = connection_guess(run, start_distance=start_distance)
            guess_Fn = Fn0
        else:
            saddle = crest_saddle(m, start)
            try:
                t_g, x_g = (np.asarray(a, dtype=float) for a in guess)
            except (TypeError, ValueError):
                raise ValueError(
                    "`guess` must be a ConnectionResult, CriticalConnection, UpslopeRun or "
                    f"(t, x) pair, got {type(guess).__name__}"
                ) from None
            if x_g.ndim != 2 or x_g.shape[1] != len(m.state_names) or t_g.shape != x_g[:, 0].shape:
                raise ValueError(
                    f"`guess` (t, x) must have shapes (K,) and (K, {len(m.state_names)}), "
                    f"got {t_g.shape} and {x_g.shape}"
                )
            wl_shift = -1.0 if x_g[-1, i_xi] < x_g[0, i_xi] else 1.0
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
    res = _solve(prob, guess if t_g is None else (t_g, x_g), settings, progress)
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
            res = _solve(prob2, (t2, x2), settings, progress)
    if res.success and adapt:
        res = solve_connection(res.problem, res, newton=settings, adapt=adapt, progress=progress)
    conv = None
    if res.success and check:
        conv = check_convergence(res, newton=settings)
    status = res.status
    message = res.message
    if throw and not res.success:
        raise ConvergenceError(f"critical Fn at chi_c={math.degrees(chi):g} deg: {message}")
    return CriticalConnection(
        chi_c=chi,
        Fn=float(res.params["Fn"]),
        residual_norm=float(res.residual_norm),
        orbit=res,
        status=status,
        message=message,
        guess_Fn=guess_Fn,
        convergence=conv,
        elapsed=time.perf_counter() - t_start,
    )


# ----------------------------------------------------------------------------- curve
@dataclass(frozen=True, eq=False)
class CriticalCurve:
    """Critical ``Fn`` against the course: the paper's Fig. 23 line.

    Attributes
    ----------
    chi_c : ndarray, shape (K,)
        Requested courses (rad).
    Fn : ndarray, shape (K,)
        Critical ``Fn`` at each course (nan where not computed).
    residual_norm : ndarray, shape (K,)
        ``max |G|`` of the connection at each course.
    converged : ndarray of bool, shape (K,)
        Whether the point was corrected to the requested course.
    n_unstable : ndarray of int, shape (K,)
        Unstable eigenvalues of the crest saddle at each course (1 for a valid
        codimension-one connection; -1 where not computed).
    branch : Branch or None
        The pseudo-arclength branch of connections in ``chi_c``.
    start : CriticalConnection
        The one-shot solve the branch started from.
    status : Status
    message : str
    elapsed : float
        Wall time (s), the start solve included.
    """

    chi_c: FloatArray
    Fn: FloatArray
    residual_norm: FloatArray
    converged: np.ndarray
    n_unstable: np.ndarray
    branch: Any
    start: CriticalConnection
    status: Status
    message: str
    elapsed: float = 0.0
    orbits: tuple[FloatArray, ...] = field(default=(), repr=False)

    @property
    def success(self) -> bool:
        """True when every requested course converged."""
        return self.status is Status.SUCCESS

    @property
    def chi_c_deg(self) -> FloatArray:
        """Courses in degrees."""
        return np.degrees(self.chi_c)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "chi_c_deg": [round(float(c), 9) for c in self.chi_c_deg],
            "Fn": [None if not np.isfinite(f) else float(f) for f in self.Fn],
            "residual_norm": [float(r) for r in self.residual_norm],
            "converged": [bool(c) for c in self.converged],
            "n_unstable": [int(k) for k in self.n_unstable],
            "status": self.status.name,
            "message": self.message,
            "elapsed_s": self.elapsed,
            "start": self.start.to_json(),
        }

    def to_csv(self, path: str | Path) -> Path:
        """Write ``chi_c_deg, Fn_critical, residual_norm, converged`` rows."""
        path = Path(path)
        rows = ["chi_c_deg,Fn_critical,residual_norm,converged"]
        for c, f, r, ok in zip(
            self.chi_c_deg, self.Fn, self.residual_norm, self.converged, strict=True
        ):
            rows.append(f"{c:.6g},{f:.10f},{r:.3e},{int(bool(ok))}")
        path.write_text("\n".join(rows) + "\n")
        return path


def critical_curve(
    chi_c_values: Sequence[float] | FloatArray | None = None,
    *,
    model: Any = None,
    params: Any = None,
    start: CriticalConnection | None = None,
    ds: float = 0.02,
    ds_max: float = 0.1,
    tol: float = 1e-9,
    keep_orbits: bool = False,
    throw: bool = False,
    progress: Callable[[Any], None] | None = None,
    **bvp_options: Any,
) -> CriticalCurve:
    r"""Critical ``Fn`` over a range of courses by continuing the connection in ``chi_c``.

    One connection is solved at the course of the requested range closest to its
    middle (:func:`critical_fn_bvp`, or ``start``), then continued with
    pseudo-arclength (:func:`continuation.bvp.continue_connection`, both directions)
    across the range with ``Fn`` an unknown of the boundary-value problem. Every
    requested course is then corrected exactly: the two branch rows around it give a
    linear predictor in ``chi_c`` and Newton solves the connection at that fixed
    course (same mesh, same compiled functions).

    Parameters
    ----------
    chi_c_values : array_like, shape (K,), optional
        Courses (rad); default 0, 1, ..., 30 degrees.
    model, params
        As for :func:`critical_fn_bvp`.
    start : CriticalConnection, optional
        A converged connection at one course inside the range.
    ds, ds_max : float
        Pseudo-arclength step (initial and largest).
    tol : float
        Newton tolerance of the continuation corrector and of the corrections.
    keep_orbits : bool
        Store the orbit ``x (M, 8)`` of every corrected course in ``orbits``.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` if a course fails.
    progress : callable, optional
        Called with every accepted branch point.
    **bvp_options
        Passed to :func:`critical_fn_bvp` for the start solve.

    Returns
    -------
    CriticalCurve
        ``status`` ``SUCCESS``, a failure status (some courses nan) or ``INTERRUPTED``.
    """
    t_start = time.perf_counter()
    if chi_c_values is None:
        chis = np.radians(np.arange(0.0, 31.0))
    else:
        chis = np.atleast_1d(np.asarray(chi_c_values, dtype=float))
        if chis.ndim != 1 or chis.size == 0:
            raise ValueError("`chi_c_values` must be a non-empty 1-D array of courses (rad)")
        for c in chis:
            _chi_c(c, "chi_c_values")
    if not (math.isfinite(ds) and ds > 0 and math.isfinite(ds_max) and ds_max >= ds):
        raise ValueError(f"`ds` and `ds_max` must satisfy 0 < ds <= ds_max, got {ds}, {ds_max}")
    m = _model(model)
    lo_c, hi_c = float(chis.min()), float(chis.max())
    if start is None:
        mid = chis[np.argmin(np.abs(chis - 0.5 * (lo_c + hi_c)))]
        start = critical_fn_bvp(float(mid), model=m, params=params, **bvp_options)
    elif not isinstance(start, CriticalConnection):
        raise ValueError(f"`start` must be a CriticalConnection, got {type(start).__name__}")
    nan = np.full(chis.size, np.nan)
    if not start.success:
        msg = f"the start connection did not converge: {start.message}"
        if throw:
            raise ContinuationError(msg)
        return CriticalCurve(
            chis, nan, nan.copy(), np.zeros(chis.size, bool), np.full(chis.size, -1), None, start,
            start.status, msg, time.perf_counter() - t_start,
        )  # fmt: skip
    margin = max(0.25 * (hi_c - lo_c) / max(chis.size - 1, 1), 1e-3)
    settings = ContinuationSettings(
        ds=ds,
        ds_max=ds_max,
        p_min=min(lo_c, start.chi_c) - margin,
        p_max=max(hi_c, start.chi_c) + margin,
        max_steps=400,
        newton=NewtonSettings(tol=tol, step_tol=1e-8, max_iter=8),
    )
    direction = (
        "both" if lo_c < start.chi_c < hi_c else ("forward" if start.chi_c <= lo_c else "backward")
    )
    branch = continue_connection(
        start.orbit, "chi_c", settings, direction=direction, progress=progress
    )
    prob = branch.problem
    P = np.asarray(branch.p, dtype=float)
    Z = np.asarray(branch.x, dtype=float)
    Fn = nan.copy()
    res_n = nan.copy()
    ok = np.zeros(chis.size, dtype=bool)
    n_unst = np.full(chis.size, -1, dtype=int)
    orbits: list[FloatArray] = []
    status = branch.status if branch.status is Status.INTERRUPTED else Status.SUCCESS
    corr = NewtonSettings(tol=tol, step_tol=1e-8, max_iter=15, damping=True)
    chord_settings = NewtonSettings(tol=tol, step_tol=1e-8, max_iter=12)
    jac_cache = JacobianCache()
    try:
        for k, c in enumerate(chis):
            z0 = _predict(P, Z, float(c))
            if z0 is None:
                continue
            # one factorised Jacobian serves neighbouring courses while it contracts fast
            r = simplified_newton(
                lambda z, c=c: prob.residual(z, c),
                lambda z, c=c: prob.jacobian(z, c),
                z0,
                chord_settings,
                cache=jac_cache,
            )
            if not r.converged:
                jac_cache.clear()
                r = newton(
                    lambda z, c=c: prob.residual(z, c), lambda z, c=c: prob.jacobian(z, c), z0, corr
                )
            if not r.converged:
                log.warning("course %.3g deg did not converge: %s", math.degrees(c), r.message)
                continue
            parts = prob.unpack(r.z)
            pv = prob.param_vector(r.z, float(c))
            n_unst[k] = int(np.sum(np.linalg.eigvals(m.jacobian(parts["x_from"], pv)).real > 0))
            if n_unst[k] != 1:
                log.warning(
                    "course %.3g deg: the crest saddle has %d unstable eigenvalues",
                    math.degrees(c),
                    n_unst[k],
                )
                continue
            Fn[k] = float(parts["params"]["Fn"])
            res_n[k] = float(r.residual_norm)
            ok[k] = True
            if keep_orbits:
                orbits.append(np.asarray(parts["X"], dtype=float))
    except KeyboardInterrupt:
        status = Status.INTERRUPTED
    n_ok = int(ok.sum())
    if status is Status.SUCCESS and n_ok < chis.size:
        status = Status.NEWTON_FAILED if branch.status.ok else branch.status
    message = f"{n_ok}/{chis.size} courses; branch: {branch.status.name} ({len(P)} points)"
    if throw and status is not Status.SUCCESS and status is not Status.INTERRUPTED:
        raise ContinuationError(f"critical curve incomplete: {message}")
    return CriticalCurve(
        chis, Fn, res_n, ok, n_unst, branch, start, status, message,
        time.perf_counter() - t_start, tuple(orbits),
    )  # fmt: skip


def _predict(P: FloatArray, Z: FloatArray, c: float) -> FloatArray | None:
    """Linear interpolation of the branch rows ``Z`` at ``chi_c = c`` (first bracketing pair)."""
    if P.size == 0:
        return None
    for i in range(P.size - 1):
        a, b = P[i], P[i + 1]
        if min(a, b) <= c <= max(a, b) and a != b:
            w = (c - a) / (b - a)
            return (1 - w) * Z[i] + w * Z[i + 1]
    j = int(np.argmin(np.abs(P - c)))
    if abs(P[j] - c) < 1e-12:
        return Z[j].copy()
    return None


__all__ = [
    "CAPTURED",
    "PERIODIC",
    "UNDECIDED",
    "UPSLOPE_SHIFT",
    "BisectionCritical",
    "CrestSaddle",
    "CriticalConnection",
    "CriticalCurve",
    "UpslopeRun",
    "connection_guess",
    "crest_saddle",
    "critical_curve",
    "critical_fn_bisection",
    "critical_fn_bvp",
    "upslope_branch",
]
