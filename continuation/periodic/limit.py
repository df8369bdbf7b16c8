r"""The end of a cycle branch whose period grows without bound.

Near a homoclinic or heteroclinic orbit of saddles the period of the cycles follows
:math:`T \approx a - b \ln|p^* - p|` (the law of a cycle approaching a connection of
saddles; ``1/b`` is the saddle's unstable eigenvalue for a homoclinic orbit with
:math:`\lambda_u < |\lambda_s|`). :func:`period_limit` fits it to the last rows and
returns :class:`PeriodLimit`: the limit ``p*`` and a guess of the connecting orbit for a
connection solver. :func:`limit_end` is where :func:`~continuation.periodic.continue_periodic`
(with ``error_tol``) ends such a branch: where the parameter is within
:data:`LIMIT_MARGIN` times its discretisation error of ``p*``, that error estimated by
the connections' halving step (:func:`~continuation.bvp.accuracy.discretisation_changes`
with the cycle's re-solve at fixed period).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize as so

from ..branch import Branch
from ..bvp.accuracy import discretisation_changes
from ..bvp.collocation import CollocationMesh
from ..errors import ConvergenceError
from ..status import Status
from ..typing import FloatArray
from .orbit import PeriodicOrbit
from .rows import orbit_at, problem_at, truncated
from .solve import CycleSolve, cycle_resolves

log = logging.getLogger(__name__)

#: A branch ends with ``Status.PERIOD_UNBOUNDED`` where the period grows without bound and
#: the parameter is within this many times its discretisation error (``|p_{2N} - p_N|``
#: at fixed period) of the limit ``p*`` fitted to ``T = a - b ln|p* - p|`` (beyond that
#: the rows cannot tell on which side of ``p*`` they are).
LIMIT_MARGIN = 10.0


@dataclass(frozen=True)
class PeriodLimit:
    r"""The end of a cycle branch whose period grows without bound.

    Attributes
    ----------
    p_star : float
        Fitted limit of the parameter, from :math:`T = a - b \ln|p^* - p|` over the
        last rows (NaN if the fit failed).
    rate : float
        ``b``; ``1/b`` estimates the unstable eigenvalue of the saddle that the cycle
        approaches (for a homoclinic orbit of a saddle with ``lambda_u < |lambda_s|``).
        NaN where the last rows do not determine it (the parameter has converged to
        round-off): the fit then uses ``b = 1 / lambda_u``.
    p_last, T_last : float
        Parameter and period of the last row.
    saddle : ndarray, shape (n,)
        The point of the last cycle where ``|f|`` is smallest: a guess of the saddle.
    t, x : ndarray
        The last cycle as one period starting and ending at that point, ``(K,)`` and
        ``(K, n)``: a guess of the connecting orbit for a connection solver.
    fit_residual : float
        RMS residual of the fit in ``p``.
    orbit : PeriodicOrbit
        The last cycle.
    free : str
        The continuation parameter.
    lambda_u : float
        Largest real part of the eigenvalues at :attr:`saddle` (its unstable rate).
    """

    p_star: float
    rate: float
    p_last: float
    T_last: float
    saddle: FloatArray
    t: FloatArray
    x: FloatArray
    fit_residual: float
    orbit: PeriodicOrbit
    free: str
    lambda_u: float = math.nan

    def connection_problem(self, mesh: CollocationMesh | None = None) -> Any:
        """A :class:`~continuation.bvp.HeteroclinicProblem` for the limiting connection.

        The saddle is :attr:`saddle` corrected by Newton's method on ``f = 0``; the
        connection returns to it shifted by the cycle's winding (``x_+ = x_- + k o
        period``, a homoclinic orbit when ``k = 0``); the free parameter is solved for,
        at :attr:`p_last` to start. Solve it with
        ``solve_connection(problem, (limit.t, limit.x))``. ``mesh``: default 80
        intervals of degree 4 over ``T_last``. Only a connection of *one* saddle to
        itself is set up (a cycle approaching a heteroclinic cycle of several saddles
        needs its own problem).

        Raises
        ------
        ConvergenceError
            If Newton's method on the saddle fails.
        """
        from ..bvp import HeteroclinicProblem

        orb = self.orbit
        P = np.array(orb.params.values, dtype=float)
        x = np.array(self.saddle, dtype=float)
        for _ in range(30):
            dx = np.linalg.solve(orb.system.jacobian(x, P), orb.system.f(x, P))
            x = x - dx
            if np.max(np.abs(dx)) <= 1e-13 * (1.0 + np.max(np.abs(x))):
                break
        else:
            raise ConvergenceError("the saddle of the period limit did not converge")
        mesh = mesh if mesh is not None else CollocationMesh(80, 4, self.T_last)
        return HeteroclinicProblem(orb.system, orb.params, free=(self.free,),
                                   saddle_from=x, shift=orb.shift, mesh=mesh)  # fmt: skip


def _log_fit(
    p: FloatArray, T: FloatArray, b_fixed: float | None = None
) -> tuple[float, float, float]:
    """Fit ``p = p* + c exp(-T / b)`` (i.e. ``T = a - b ln|p - p*|``).

    Returns ``(p*, b, rms of the fit in p)``. For fixed ``b`` the fit is linear in ``(p*,
    c)``; ``b`` is found by a bounded scalar search on ``ln b``. Where that search ends on a
    bound or the rows agree to ``1e-10`` relative (``b`` is not determined by the rows), the
    fit with ``b = b_fixed`` is returned, with ``b`` as NaN.
    """
    Tn = T - float(np.min(T))  # exponentials in (0, 1]: no overflow

    def lsq(lb: float) -> tuple[float, float, float]:
        A = np.column_stack([np.ones_like(Tn), np.exp(-Tn / math.exp(lb))])
        coef, *_ = np.linalg.lstsq(A, p, rcond=None)
        r = A @ coef - p
        return float(coef[0]), float(coef[1]), float(np.sqrt(np.mean(r**2)))

    span = float(np.ptp(T)) + 1e-300
    lo, hi = math.log(span) - 8, math.log(span) + 4
    res = so.minimize_scalar(lambda q: lsq(q)[2], bounds=(lo, hi), method="bounded",
                             options={"xatol": 1e-10})  # fmt: skip
    q = float(res.x)
    p_star, _, rms = lsq(q)
    if b_fixed is not None and math.isfinite(b_fixed) and b_fixed > 0:
        # the rate is not determined by these rows where the search ends on a bound or
        # the parameter has converged to round-off: then the fit with the saddle's own
        # rate, and no rate
        p_fix, _, rms_fix = lsq(math.log(b_fixed))
        at_bound = q - lo < 0.05 or hi - q < 0.05
        flat = float(np.ptp(p)) <= 1e-10 * max(1.0, float(np.max(np.abs(p))))
        if at_bound or flat:
            return p_fix, math.nan, rms_fix
    return p_star, math.exp(q), rms


def period_limit(branch: Branch, n_fit: int = 8, *, warn: bool = True) -> PeriodLimit:
    """The limit of a cycle branch whose period grows (see :class:`PeriodLimit`).

    Parameters
    ----------
    branch : Branch
        A branch of :func:`continue_periodic` (typically ended with
        ``Status.PERIOD_UNBOUNDED``).
    n_fit : int
        Number of last rows in the fit (at least 4).
    warn : bool
        Log a warning where the fit is poor (below).

    Notes
    -----
    The law holds for a monotone approach. Where the branch snakes towards a
    saddle-focus loop (Shilnikov: folds of cycles on both sides of ``p*``) its rows
    swing about the limit and the fit is poor (``fit_residual`` larger than the last
    row's distance from ``p_star``; a warning is logged); the branch's message then
    holds the limit ``continue_periodic`` fitted on the converged rows beyond its end.
    """
    problem_at(branch, 0)  # (checks the branch)
    if not (isinstance(n_fit, int) and n_fit >= 4):
        raise ValueError(f"`n_fit` must be an integer >= 4, got {n_fit!r}")
    if len(branch) < 4:
        raise ValueError("`branch` needs at least 4 rows for the period fit")
    k = min(n_fit, len(branch))
    p = np.asarray(branch.p[-k:], dtype=float)
    T = np.asarray(branch.records["T"][-k:], dtype=float)
    orb = orbit_at(branch, len(branch) - 1)
    F = np.array([orb.system.f(x, orb.params.values) for x in orb.X])
    q = int(np.argmin(np.linalg.norm(F, axis=1)))
    lam_u = _unstable_rate(orb, orb.X[q])
    try:
        p_star, b, rms = _log_fit(p, T, 1.0 / lam_u if lam_u > 0 else None)
    except (ValueError, np.linalg.LinAlgError, FloatingPointError):
        p_star, b, rms = math.nan, math.nan, math.nan
    if warn and math.isfinite(rms) and rms > abs(float(p[-1]) - p_star) > 0.0:
        # the rows swing about the limit by more than they are from it: a branch that
        # snakes towards a saddle-focus loop (folds of cycles on both sides of p*), whose
        # end continue_periodic cuts before such rows (the limit it fitted on the rows
        # past the cut is in the branch's message)
        log.warning("period limit %s*=%.10g: the last %d rows do not follow T = a - b ln|%s* - "
                    "%s| (fit residual %.2g, last row %.2g from the limit): p* is unreliable",
                    branch.free, p_star, k, branch.free, branch.free, rms,
                    abs(float(p[-1]) - p_star))  # fmt: skip
    t0 = float(orb.t[q])
    t = np.linspace(t0, t0 + orb.T, 4 * orb.mesh.n_points)
    x = orb(t)
    return PeriodLimit(p_star, b, float(branch.p[-1]), float(T[-1]), orb.X[q].copy(),
                       t - t0, x, rms, orb, branch.free, lam_u)  # fmt: skip


def _unstable_rate(orb: PeriodicOrbit, x: FloatArray) -> float:
    """Largest real part of the eigenvalues of ``f_x`` at ``x`` (the saddle guess)."""
    try:
        ev = np.linalg.eigvals(orb.system.jacobian(x, np.asarray(orb.params.values, float)))
    except (np.linalg.LinAlgError, ValueError):
        return math.nan
    return float(np.max(ev.real))


def limit_end(br: Branch, free: str, n_tail: int = 8) -> Branch | None:
    r"""The end of a branch whose period grows without bound, or None.

    The branch ended where its period grows without bound and its parameter has come within
    its own error of the limit; None while it has not.

    Near a homoclinic or heteroclinic orbit of saddles ``p = p^* + c e^{-T/b}``. Where
    the period grew over the last ``n_tail`` rows and the parameter moved one way (or
    has stalled at round-off), ``p*`` is fitted
    (:func:`period_limit`), and where the parameter has nearly converged to it the
    parameter's discretisation error is estimated by re-solving the last cycle at its
    period on the mesh with every interval halved, ``delta = |p_{2N} - p_N|``. Rows
    within ``LIMIT_MARGIN delta + 1e-12 (1 + |p*|)`` of ``p*`` (the last term the
    round-off of ``p``) cannot tell on which side of the limit they are: the branch is
    cut before the first of the last ``n_tail`` rows (those of the monotone approach)
    that is within that distance or past ``p*``, with ``Status.PERIOD_UNBOUNDED``. Rows
    before them are kept wherever they lie: a branch that snakes towards a saddle-focus
    loop (Shilnikov) passes ``p*`` and turns back at folds of cycles far from it on
    either side, and keeps those rows with their folds. A discretised
    cycle does not see the end (on a finite mesh the period stays finite and the rows
    may pass ``p*``, where no cycle exists), so this is where the branch must stop.
    Only where the fit of the last rows is as good as that bound: a snake whose last
    rows still swing about ``p*`` by more than it is not ended here.
    """
    n = len(br)
    if n < n_tail + 2:
        return None
    T = np.asarray(br.records["T"][-n_tail:], dtype=float)
    p_tail = np.asarray(br.p[-n_tail:], dtype=float)
    if not np.all(np.diff(T) > 0):
        return None
    dp = np.diff(p_tail)
    stalled = float(np.ptp(p_tail)) <= 1e-8 * (1.0 + float(np.max(np.abs(p_tail))))
    if not (np.all(dp > 0) or np.all(dp < 0) or stalled):
        return None  # (the parameter turns: not the monotone approach, e.g. snaking)
    try:
        lim = period_limit(br, n_fit=n_tail, warn=False)
    except (ValueError, np.linalg.LinAlgError):
        return None
    if not math.isfinite(lim.p_star):
        return None
    # (cheap pre-check before the discretisation estimate: the parameter has nearly
    # converged, its remaining distance small against its last moves or tiny)
    span = float(np.ptp(p_tail))
    if abs(float(p_tail[-1]) - lim.p_star) > max(0.1 * span, 1e-8 * (1.0 + abs(lim.p_star))):
        return None
    last = orbit_at(br, n - 1)
    # the connections' discretisation estimate (safety 1: LIMIT_MARGIN is the margin)
    fine, change = discretisation_changes(
        CycleSolve(last, (free,)), cycle_resolves(free, fix_period=True), 1.0
    )
    if change is None:
        log.debug("no discretisation estimate of %s at T=%.6g: %s", free, last.T, fine.message)
        return None
    delta = change[free]
    thr = LIMIT_MARGIN * delta + 1e-12 * (1.0 + abs(lim.p_star))
    if not lim.fit_residual <= thr:
        # the rows do not follow the monotone law to their accuracy (e.g. the snaking
        # of a cycle near a saddle-focus loop, with cycles on both sides of p*): no end
        return None
    log.debug("period limit %s*=%.15g: delta %.2g, fit rms %.2g, last row %.3g from it",
              free, lim.p_star, delta, lim.fit_residual, float(br.p[-1]) - lim.p_star)  # fmt: skip
    # The side of the rows is that of the tail's approach (the tail moves one way, its
    # first row farthest from p*). The branch is cut before the first tail row that is
    # not farther than thr on that side (within thr, or past p*: on a finite mesh the
    # rows may pass the limit, where no cycle exists), and before any rows within thr
    # just ahead of it. Rows before the tail are kept wherever they lie: where the
    # branch snakes towards a saddle-focus loop (Shilnikov) it passes p* and turns back
    # at folds of cycles far from it on both sides, and those rows are cycles like any
    # other, kept with their folds (cutting at the first pass of p* dropped the snake).
    p_all = np.asarray(br.p, dtype=float)
    tail0 = n - n_tail
    side = 1.0 if p_all[tail0] >= lim.p_star else -1.0
    signed = side * (p_all - lim.p_star)
    close = np.flatnonzero(signed[tail0:] <= thr)
    if close.size == 0:
        return None
    k = tail0 + int(close[0]) - 1
    while k > 1 and abs(signed[k]) <= thr:
        k -= 1
    k = max(k, 1)
    dist = np.abs(p_all - lim.p_star)
    msg = (
        f"{Status.PERIOD_UNBOUNDED.value} The period grows without bound towards "
        f"{free}*={lim.p_star:.12g} (fit of T = a - b ln|{free}* - {free}|); the rows "
        f"stop {dist[k]:.2g} from it, where the parameter's discretisation error "
        f"({delta:.1g}) no longer tells the side. Last period T={br.records['T'][k]:.10g} "
        f"at {free}={br.p[k]:.12g}."
    )
    log.info(msg)
    return truncated(br, k, Status.PERIOD_UNBOUNDED, msg)


__all__ = ["LIMIT_MARGIN", "PeriodLimit", "limit_end", "period_limit"]
