r"""From a saddle alone to its connecting orbit: :func:`find_connection`.

Steps:

1. Newton-refine the source saddle :math:`x_-` (and the target :math:`x_+`, or set
   :math:`x_+ = x_- + \text{shift}`); the source must have a one-dimensional unstable
   manifold.
2. Integrate the chosen branch of :math:`W^u(x_-)` from :math:`x_- \pm \delta v_u`,
   :math:`\delta` = ``end_distance``, default ``1e-4`` or less in small units
   (:func:`_linear_distance`; :func:`continuation.dynamics.manifolds.unstable_manifold`,
   CVODES), in segments until the window of step 3 has closed, at most ``t_max``.
3. Cut it at its closest approach to :math:`x_+`: for a heteroclinic target the
   nearest sample after the orbit has left :math:`x_-` (half its largest distance
   from :math:`x_-`); for a homoclinic one the first local minimum of the distance
   to :math:`x_+` below a quarter of that excursion.
4. Close the gap: the stable part :math:`d_s` of the remaining offset is continued
   by the linearised flow :math:`x_+ + \mathrm{Re}\,V e^{\Lambda s} c_s` for
   :math:`S = \ln(|d_s| / \delta) / \mu_s` (:math:`\mu_s` the weakest stable rate at
   :math:`x_+`), so that both ends lie within about :math:`\delta` of the saddles:
   ``T`` follows from the eigenvalues (the start leaves :math:`x_-` at rate
   :math:`\lambda_u`, so :math:`\ln(D/\delta)/\lambda_u` of it is spent near the saddle).
5. A mesh equidistributing the collocation error monitor of this guess, then
   :func:`~continuation.bvp.solve.solve_connection` (adaptive mesh, discretisation and
   truncation estimates, which lengthen ``T`` if needed).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from typing import Any

import numpy as np

from ..dynamics.manifolds import unstable_manifold
from ..dynamics.simulate import Simulator
from ..settings import NewtonSettings
from ..status import Status
from ..system import as_params
from ..typing import FloatArray
from .accuracy import ConnectionAccuracy, _linear_flow
from .collocation import CollocationMesh
from .connection import (
    DEFAULT_N_INTERVALS,
    HeteroclinicProblem,
    PinPhase,
    _refine_equilibrium,
    _shift_vector,
)
from .result import ConnectionResult
from .solve import solve_connection

log = logging.getLogger(__name__)


def _window_min(d: FloatArray, i_low: int, level: float) -> int:
    """Argmin of ``d`` from ``i_low`` until ``d`` rises above ``level`` again."""
    above = np.flatnonzero(d[i_low:] > level)
    end = d.size if above.size == 0 else i_low + int(above[0])
    return i_low + int(np.argmin(d[i_low:end]))


def cut_at_closest_approach(
    t: FloatArray, x: FloatArray, x_from: FloatArray, x_to: FloatArray
) -> tuple[int, float]:
    """Index of the first close approach to ``x_to`` after the orbit has left ``x_from``.

    Heteroclinic (``x_to != x_from``, distance ``L``): the first time the distance to
    ``x_to`` falls below ``L / 4`` opens a window that closes when it rises above
    ``L / 2`` again; the nearest sample in it. Homoclinic: the first local maximum
    ``d_peak`` of the distance (at least ten times the start distance) after which
    the distance falls below ``d_peak / 2`` before exceeding ``d_peak`` opens the
    window (closed when the distance exceeds ``d_peak / 2`` again). Fallback: the
    nearest sample after the orbit has first gone half its largest distance away.

    Returns ``(k, d)``: the sample index and its distance to ``x_to``.
    """
    d_to = np.linalg.norm(x - x_to, axis=1)
    L = float(np.linalg.norm(x_to - x_from))
    if L > 1e-12 * (1.0 + float(np.linalg.norm(x_from))):
        near = np.flatnonzero(d_to < 0.25 * L)
        if near.size:
            k = _window_min(d_to, int(near[0]), 0.5 * L)
            return k, float(d_to[k])
    else:
        d = d_to
        d0 = max(float(d[0]), 1e-300)
        for k in range(1, d.size - 1):
            if not (d[k] >= d[k - 1] and d[k] >= d[k + 1] and d[k] >= 10 * d0):
                continue
            after = d[k + 1 :]
            low = np.flatnonzero(after < 0.5 * d[k])
            high = np.flatnonzero(after > d[k])
            if low.size and (high.size == 0 or low[0] < high[0]):
                j = _window_min(d, k + 1 + int(low[0]), 0.5 * d[k])
                return j, float(d[j])
    d_from = np.linalg.norm(x - x_from, axis=1)
    i_far = int(np.argmax(d_from >= 0.5 * float(np.max(d_from))))
    k = i_far + int(np.argmin(d_to[i_far:]))
    return k, float(d_to[k])


class _ReturnWatch:
    """Whether the window of :func:`cut_at_closest_approach` has closed, sample by sample.

    Called on consecutive pieces of the sampled orbit, in time order, it returns
    whether the distance to ``x_to`` has risen out of the cut's window again, after
    which the cut no longer depends on the rest of the orbit. Homoclinic: the window
    opens at the first sample below half the running maximum of the distance (once
    that maximum is at least ten times the start distance) and closes above half that
    maximum. Heteroclinic (distance ``L`` between the saddles): it opens below
    ``L / 4`` and closes above ``L / 2``. ``level`` is None until the window opens.
    """

    def __init__(self, x_from: FloatArray, x_to: FloatArray, d0: float) -> None:
        self.x_to = x_to
        L = float(np.linalg.norm(x_to - x_from))
        self.hetero = L > 1e-12 * (1.0 + float(np.linalg.norm(x_from)))
        self.L = L
        self.d0 = max(d0, 1e-300)
        self.peak = 0.0
        self.level: float | None = None

    def closed(self, x: FloatArray) -> bool:
        """Feed the next samples ``x`` (K, n); True once the window has closed."""
        d = np.linalg.norm(x - self.x_to, axis=1)
        if self.level is None:
            if self.hetero:
                opened = np.flatnonzero(d < 0.25 * self.L)
                level = 0.5 * self.L
            else:
                m = np.maximum(np.maximum.accumulate(d), self.peak)
                opened = np.flatnonzero((m >= 10.0 * self.d0) & (d < 0.5 * m))
                self.peak = float(m[-1])
                level = 0.5 * float(m[opened[0]]) if opened.size else 0.0
            if opened.size == 0:
                return False
            self.level = level
            d = d[int(opened[0]) :]
        return bool(np.any(d > self.level))


#: Largest and smallest number of samples per integration segment of
#: :func:`_manifold_to_return`.
_SEGMENT_SAMPLES = (100, 5)
#: Local error tolerances (relative, absolute) of the manifold integration: the guess
#: only starts Newton's method, which converges to the same discrete solution.
_MANIFOLD_TOL = (1e-10, 1e-12)
#: Largest stiffness ratio of the saddles' spectra, ``max |lambda| / min |Re lambda|``,
#: at which the manifold is integrated by CVODES's Adams method (no Jacobian
#: factorisations: 10-30 % faster on the HomCont demos at this tolerance) instead of
#: BDF; a stiffer flow, or an Adams run that fails before the return, uses BDF.
_ADAMS_MAX_STIFFNESS = 1e3


def _manifold_method(system: Any, lam_m: Any, lam_p: Any) -> str | None:
    """``"cvodes_adams"`` where both saddles' spectra are non-stiff, else None.

    The spectra ``lam_m``, ``lam_p`` are the eigenvalues of the Jacobians there; non-stiff:
    ratio at most :data:`_ADAMS_MAX_STIFFNESS`. None: the simulator's default (BDF, or
    SciPy's DOP853 without a CasADi trace).
    """
    if not getattr(system, "has_casadi", False):
        return None
    lam = np.concatenate((np.asarray(lam_m), np.asarray(lam_p)))
    re = np.abs(lam.real)
    if not np.all(np.isfinite(lam)) or not np.any(re > 0):
        return None
    ratio = float(np.max(np.abs(lam)) / np.min(re[re > 0]))
    return "cvodes_adams" if ratio <= _ADAMS_MAX_STIFFNESS else None


def _manifold_to_return(
    system: Any,
    pvec: FloatArray,
    x_m: FloatArray,
    x_p: FloatArray,
    branch: int,
    end_distance: float,
    t_max: float,
    method: str | None = None,
) -> tuple[FloatArray, FloatArray, bool]:
    """Branch ``branch`` of ``W^u(x_m)`` sampled every ``t_max / 1000``.

    Integrated in segments until the window of :func:`cut_at_closest_approach` has closed
    (:class:`_ReturnWatch`) or to ``t_max``; ``(t, x, complete)`` of shapes (K,), (K, n),
    and False where the integration failed before the window closed.

    Segments are 100 samples long until the window opens. Inside it, where the orbit
    at distance ``d`` from ``x_+`` leaves at most at the rate ``mu`` of the fastest
    unstable eigenvalue of ``x_+`` (linearised flow), a segment spans the time
    ``ln(level / d) / mu`` the orbit needs to reach the closing level, at least 5
    samples: beyond the window the orbit may blow up, and a failing CVODES call
    costs its whole step budget (san: 0.15 s against 10 ms for the orbit).
    """
    dt = t_max / 1000.0
    watch = _ReturnWatch(x_m, x_p, end_distance)
    lam = np.linalg.eigvals(np.asarray(system.jacobian(x_p, pvec), dtype=float)).real
    mu = max(float(np.max(lam)), 1e-6)
    lo, hi = _SEGMENT_SAMPLES[1], _SEGMENT_SAMPLES[0]
    t1 = min(t_max, hi * dt)
    rtol, atol = _MANIFOLD_TOL
    man = unstable_manifold(
        system, pvec, x_m, eps=end_distance, t_max=t1, dt=dt, branches=(branch,),
        refine=False, rtol=rtol, atol=atol, method=method,
    )  # fmt: skip
    traj = man.branch(branch).trajectory
    ts, xs = [np.asarray(traj.t, dtype=float)], [np.asarray(traj.x, dtype=float)]
    sim = Simulator(system, pvec, rtol=rtol, atol=atol, method=method)
    closed = False
    while traj.status is Status.SUCCESS and t1 < t_max * (1.0 - 1e-12):
        closed = watch.closed(xs[-1])
        if closed:
            break
        t0 = t1
        k = hi
        if watch.level is not None:
            d = float(np.linalg.norm(xs[-1][-1] - x_p))
            k = int(min(hi, max(lo, math.log(watch.level / max(d, 1e-300)) / mu / dt)))
        t1 = min(t_max, t0 + k * dt)
        traj = sim.run(xs[-1][-1], (t0, t1), dt=dt)
        ts.append(np.asarray(traj.t, dtype=float)[1:])
        xs.append(np.asarray(traj.x, dtype=float)[1:])
    complete = traj.status is Status.SUCCESS or closed or watch.closed(xs[-1])
    return np.concatenate(ts), np.vstack(xs), complete


def _end_pad(
    A: FloatArray, x_to: FloatArray, x_end: FloatArray, end_distance: float, n_samples: int = 60
) -> tuple[FloatArray, FloatArray]:
    """Times ``s`` (K,) and states (K, n) of the linear approach to ``x_to`` from ``x_end``."""
    lam = np.linalg.eigvals(A)
    stable = lam.real < 0
    mu = float(np.min(-lam.real[stable]))
    d = x_end - x_to
    d_s = float(np.linalg.norm(_linear_flow(A, d, np.array([0.0]), unstable=False)[0]))
    if d_s <= end_distance:
        return np.zeros(0), np.zeros((0, x_to.size))
    S = math.log(d_s / end_distance) / mu
    s = np.linspace(0.0, S, n_samples + 1)[1:]
    return s, x_to + _linear_flow(A, d, s, unstable=False)


#: Default distance of the guess's ends from the saddles (states' 2-norm), and the
#: largest relative defect of the linearised flow there (:func:`_linear_distance`).
_END_DISTANCE, _LINEAR_DEFECT = 1e-4, 1e-2
#: A default end distance is reduced to ``1e-4`` of the manifold's excursion when that
#: excursion is less than this many end distances (states in small units).
_SMALL_ORBIT = 1e3


def _linear_distance(system: Any, pvec: FloatArray, x_eq: FloatArray, A: FloatArray,
                     v: FloatArray) -> float:  # fmt: skip
    r"""The default end distance at ``x_eq`` along the eigendirection ``v`` (unit).

    :data:`_END_DISTANCE`, divided by 10 (at most 8 times) while the flow there departs
    from its linearisation by more than :data:`_LINEAR_DEFECT` of the distance, measured
    as a displacement, :math:`|A^{-1} (f(x + \delta v) - f(x) - \delta A v)| > 10^{-2}
    \delta` (the defect of the velocity, mapped back through the linear flow, so that a
    fast slaved direction, whose defect is large in ``f`` but small in position, does
    not count): where the saddle's linear neighbourhood is small in the states' units (a
    problem written in units where the orbit is 1e-4 across) a fixed 1e-4 would start
    the guess off the manifold, or outside the orbit.
    """
    v = np.real(np.asarray(v))
    v = v / max(float(np.linalg.norm(v)), 1e-300)
    f0 = np.asarray(system.f(x_eq, pvec), dtype=float)
    delta = _END_DISTANCE
    for _ in range(8):
        defect = np.asarray(system.f(x_eq + delta * v, pvec), dtype=float) - f0 - delta * (A @ v)
        try:
            shift = np.linalg.solve(A, defect)
        except np.linalg.LinAlgError:  # (a hyperbolic saddle has an invertible A)
            break
        if not float(np.linalg.norm(shift)) > _LINEAR_DEFECT * delta:
            break
        delta *= 0.1
    return delta


def find_connection(
    system: Any,
    params: Any,
    free: str | tuple[str, ...],
    *,
    source: Any,
    target: Any = None,
    shift: Any = None,
    branch: int = 1,
    T: float | None = None,
    end_distance: float | None = None,
    t_max: float | None = None,
    n_intervals: int = DEFAULT_N_INTERVALS,
    degree: int = 4,
    phase: str | PinPhase = "integral",
    accuracy: ConnectionAccuracy | None = None,
    newton: NewtonSettings | None = None,
    method: str = "newton",
    throw: bool = False,
    adapt: int | None = None,
) -> ConnectionResult:
    r"""A connecting orbit from the saddle ``source`` alone (steps: module docstring).

    Parameters
    ----------
    system : System
        With a CasADi trace (``rhs(x, p, ops)``).
    params : Params, mapping or array_like
        All parameters; the ``free`` entries are the starting guesses.
    free : str or tuple of str
        The solved parameter(s) (as in :func:`~continuation.equilibria.continue_equilibria`).
    source : array_like, shape (n,)
        The start saddle (or a guess of it); its unstable manifold must be 1-D.
    target : array_like, shape (n,), optional
        The end saddle (or a guess). Give exactly one of ``target`` and ``shift``.
    shift : 0, mapping of str to float, or array_like (n,), optional
        ``x_+ = x_- + shift``: ``0`` for a homoclinic orbit, ``{"theta": 2 * pi}`` for
        a saddle-to-shifted-saddle orbit on a cylinder.
    branch : {+1, -1}
        Which branch of the unstable manifold (``+1``: along the oriented eigenvector
        of :func:`continuation.dynamics.saddles.oriented_unstable_direction`).
    T : float, optional
        Truncation interval; default from the eigenvalues (step 4). A given ``T``
        centres the guess (held at its ends when ``T`` is longer).
    end_distance : float, optional
        Distance (state 2-norm) of both ends of the guess from the saddles. Default
        ``1e-4``, or less where the flow departs from its linearisation by more than 1 %
        at that distance along the unstable direction of ``source`` or the weakest stable
        one of the target (:func:`_linear_distance`), and ``1e-4`` of the manifold's
        excursion when that is less than ``0.1`` (states in small units: the manifold
        is integrated again from closer).
    t_max : float, optional
        Longest integration time of the manifold; default ``200 + 40 / lambda_u``. The
        integration stops earlier, once the distance to the target has risen out of
        the cut's window again (:func:`cut_at_closest_approach`: the rest of the orbit
        cannot change the cut).
    n_intervals, degree : int
        Starting mesh (adapted by the solve).
    phase : "integral" or PinPhase
        Phase condition.
    accuracy, newton, method, throw, adapt
        As for :func:`~continuation.bvp.solve.solve_connection` (``adapt`` with
        ``accuracy=ConnectionAccuracy(estimate=False)``: adaptation rounds of a plain
        solve on ``n_intervals`` intervals).

    Returns
    -------
    ConnectionResult
        With error estimates of ``free``; its ``message`` also reports the closest
        approach of the manifold to the target and the chosen ``T``.

    Raises
    ------
    ValueError
        For bad input, a ``source`` whose unstable manifold is not one-dimensional, or
        a dimension count that does not close (from :class:`HeteroclinicProblem`).
    """
    if (target is None) == (shift is None):
        raise ValueError("give exactly one of `target` and `shift`")
    if branch not in (1, -1):
        raise ValueError(f"`branch` must be +1 or -1, got {branch!r}")
    if end_distance is not None and not (
        isinstance(end_distance, (int, float)) and 0 < end_distance < 1
    ):
        raise ValueError(f"`end_distance` must be in (0, 1), got {end_distance!r}")
    if T is not None and not (math.isfinite(T) and T > 0):
        raise ValueError(f"`T` must be a positive time, got {T!r}")
    params = as_params(system, params)
    pvec = np.array(params.values, dtype=float)
    x_m = _refine_equilibrium(system, system.check_state(source, "source"), pvec, "source")
    if shift is not None:
        x_p = x_m + _shift_vector(system, shift)
    else:
        x_p = _refine_equilibrium(system, system.check_state(target, "target"), pvec, "target")
    lam_m = np.linalg.eigvals(system.jacobian(x_m, pvec))
    n_u = int(np.sum(lam_m.real > 0))
    if n_u != 1:
        lam_p = np.linalg.eigvals(system.jacobian(x_p, pvec))
        hint = "give a guess to solve_connection instead"
        if int(np.sum(lam_p.real < 0)) == 1:
            # the time-reversed flow has the same orbit, from the target's 1-D manifold
            hint = (
                "the target's stable manifold is one-dimensional: reverse time (a System "
                "with rhs -f) and swap `source` and `target`, or " + hint
            )
        raise ValueError(
            f"`source` has a {n_u}-dimensional unstable manifold (eigenvalues "
            f"{np.array2string(lam_m, precision=4)}); find_connection integrates a "
            f"one-dimensional one: {hint}"
        )
    lam_u = float(np.max(lam_m.real))
    if t_max is None:
        t_max = 200.0 + 40.0 / lam_u
    A_p = np.asarray(system.jacobian(x_p, pvec), dtype=float)
    auto_distance = end_distance is None
    if end_distance is None:
        A_m = np.asarray(system.jacobian(x_m, pvec), dtype=float)
        lam, V = np.linalg.eig(A_m)
        lam_p, V_p = np.linalg.eig(A_p)
        stable = np.flatnonzero(lam_p.real < 0)
        weak = stable[int(np.argmax(lam_p.real[stable]))] if stable.size else None
        end_distance = _linear_distance(system, pvec, x_m, A_m, V[:, int(np.argmax(lam.real))])
        if weak is not None:
            d_p = _linear_distance(system, pvec, x_p, A_p, V_p[:, weak])
            end_distance = min(end_distance, d_p)
    integrator = _manifold_method(system, lam_m, np.linalg.eigvals(A_p))

    def manifold(delta: float) -> tuple[FloatArray, FloatArray]:
        t, x, complete = _manifold_to_return(system, pvec, x_m, x_p, branch, delta, t_max,
                                             integrator)  # fmt: skip
        if not complete and integrator is not None:  # Adams failed before the return: BDF
            log.info("the Adams integration of the manifold failed early; again with BDF")
            t, x, _ = _manifold_to_return(system, pvec, x_m, x_p, branch, delta, t_max)
        return t, x

    t, x = manifold(end_distance)
    if auto_distance:
        # the orbit is small in the states' units: the ends within 1e-4 of its size
        size = float(np.max(np.linalg.norm(x - x_m, axis=1)))
        if size < _SMALL_ORBIT * end_distance and _END_DISTANCE * size < end_distance:
            end_distance = _END_DISTANCE * size
            log.info("the orbit is %.3g across: end distance %.3g", size, end_distance)
            t, x = manifold(end_distance)
    k, d_min = cut_at_closest_approach(t, x, x_m, x_p)
    t, x = t[: k + 1] - t[0], x[: k + 1]
    if k < 2:
        raise ValueError(
            f"branch {branch:+d} of the unstable manifold of `source` never leaves it "
            f"towards the target within t_max = {t_max:g}; try the other `branch`"
        )
    s, xs = _end_pad(A_p, x_p, x[-1], end_distance)
    if s.size:
        t = np.concatenate((t, t[-1] + s))
        x = np.vstack((x, xs))
    T_guess = float(t[-1] - t[0])
    T_used = T_guess if T is None else float(T)
    fine = CollocationMesh(2 * n_intervals, degree, T_guess)
    X = np.column_stack([np.interp(fine.t, t, x[:, i]) for i in range(x.shape[1])])
    mesh = fine.equidistributed(X, n_intervals=n_intervals)
    if T is not None:
        mesh = CollocationMesh(n_intervals, degree, T_used)
    kw: dict[str, Any] = {"saddle_to": x_p} if shift is None else {"shift": shift}
    names = (free,) if isinstance(free, str) else tuple(free)
    prob = HeteroclinicProblem(system, params, names, saddle_from=x_m, mesh=mesh, phase=phase, **kw)
    t_cut = float(t[k])
    reach = float(np.max(np.linalg.norm(x[: k + 1] - x_m, axis=1)))
    note = (
        f"guess: branch {branch:+d} of W^u(source), closest approach {d_min:.2e} to the "
        f"target at t = {t_cut:.4g}; T = {T_used:.6g}"
    )
    if d_min > 0.5 * max(reach, float(np.linalg.norm(x_p - x_m))):
        note += (
            "; the manifold does not come near the target: try the other `branch` or a "
            "better guess of the free parameter(s)"
        )
    log.info(note)
    res = solve_connection(
        prob, (t, x), accuracy=accuracy, newton=newton, method=method, throw=False, adapt=adapt
    )
    res = dataclasses.replace(res, message=f"{res.message} ({note})")
    if throw and not res.success:
        from ..errors import ConvergenceError

        raise ConvergenceError(res.message)
    return res


__all__ = ["cut_at_closest_approach", "find_connection"]
