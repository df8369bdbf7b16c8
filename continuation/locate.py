r"""Locating a zero of a test function between two consecutive branch rows.

Points between rows ``a`` and ``b`` are parameterised by the pseudo-arclength
``sigma = <tau_a, u - u_a>_theta`` in ``[0, sigma_b]``, the same constraint that
produced row ``b`` from row ``a``. A trial point at ``sigma`` is predicted on the chord
``u_a + (sigma / sigma_b)(u_b - u_a)`` and corrected by Newton's method on
``G(z, p) = 0, <tau_a, u - u_a>_theta = sigma``, so every trial point lies on the
branch and strictly inside the step. The zero of the test function ``g(sigma)`` is
found by the Illinois variant of regula falsi (Dowell & Jarratt 1971, BIT 11:168-174),
which keeps a sign-changing bracket and converges superlinearly; it stops when the
bracket has collapsed to width ``tol`` (in ``sigma``), or when the secant correction
falls below ``tol`` and a probe ``tol`` beyond the trial point towards the secant's
zero changes sign (the "tolerance step" of Brent 1973, *Algorithms for Minimization
without Derivatives*, Ch. 4), which proves the zero within ``tol``. A tiny ``|g|``
alone is never taken as a zero (``g = x^3`` is ``1e-15`` already ``1e-5`` from its
zero). If the probe does not change sign but ``|g|`` still falls, the secant was misled
by a flat ``g`` (a zero of higher odd order) and the search goes on by bisection, as it
does once ``STALL`` trial points have not halved the bracket (unless the midpoint's
corrected point leaves the branch, :func:`tangent_agrees`; next to a branch point the
secant creeping from the branch's side is kept and the limit of its last points is
probed, :func:`_probe_limit`); if ``|g|`` does not fall, ``g`` is noise there and the
error is ``|g| / |g'|``. A point counts as located only if ``|g|`` there is below
``1e-3 max(|g_a|, |g_b|)``, so a sign change across a jump of ``g`` is reported as
bracketed, never as a zero, while round-off noise in ``g`` near a genuine zero is
tolerated.

Every result carries ``error``, the estimated distance in ``sigma`` to the zero
(:func:`_located`): the width of the bracket that proves it, or more where ``g`` is
noisy there (round-off, finite-difference derivatives; :func:`noise_error` samples the
noise) or the corrected point itself is ill-determined (next to a branch point of the
branch a residual ``|G|`` leaves it uncertain by about ``sqrt(|G|)``,
:func:`point_error`; both in :mod:`continuation.locate_error`). A located point with
``error > tol`` says so in its message.

Next to a branch point of the branch the bordered matrix is singular: Newton's method
determines a trial point only to ``tol / sigma_min`` and may converge onto the crossing
branch, where ``g`` has other values. For test functions smooth along the branch
(``same_branch``) a trial point is kept only if its tangent is the branch's
(:func:`tangent_agrees`); where none can be corrected, the zero and the point there are
interpolated through the points already on the branch (:func:`_interpolated_zero`),
located only if the interpolation's error estimate is within ``tol``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .algorithms.base import theta_norm
from .algorithms.corrector import CorrectorResult
from .algorithms.point import PointInfo, make_point
from .algorithms.step import palc_point
from .linalg import inf_norm as _inf_norm
from .locate_error import noise_error, noise_slope, point_error
from .problem import linearize
from .settings import NewtonSettings
from .typing import FloatArray

log = logging.getLogger(__name__)


@dataclass(eq=False)
class LocateResult:
    """Outcome of :func:`locate_zero`.

    Attributes
    ----------
    sigma : float
        Pseudo-arclength from row ``a`` of the returned point, in ``[0, sigma_b]``.
    point : PointInfo
        The point (the best trial point if not located).
    g : float
        Test-function value at ``point``.
    located : bool
        Converged to tolerance.
    iterations : int
        Number of trial points corrected.
    message : str
    error : float
        Estimated error of ``sigma`` (distance to the zero of ``g`` along the branch):
        at most ``tol`` when located; the bracket's width, an interpolation's error
        estimate, or NaN (unknown) otherwise.
    """

    sigma: float
    point: PointInfo
    g: float
    located: bool
    iterations: int
    message: str = ""
    error: float = math.nan


def _chord_point(
    z: FloatArray,
    p: float,
    lin: tuple[FloatArray, Any, FloatArray],
    ua: FloatArray,
    ub: FloatArray,
    c: FloatArray,
    w: Any,
    iters: int = 0,
    residual_norm: float | None = None,
) -> PointInfo:
    """The point ``(z, p)`` where the bordered matrix is exactly singular.

    An exact branch point: the tangent is not unique there, so it is the chord
    direction from ``ua`` to ``ub`` (``theta``-normalised), and the BP test is zero.
    ``lin = (G, Gz, Gp)`` at the point; ``residual_norm`` default ``max |G|``.
    """
    G, Gz, Gp = lin
    tau = (ub - ua) / max(theta_norm(ub - ua, w), 1e-300)
    return PointInfo(
        z=z,
        p=p,
        tau=tau,
        G=G,
        Gz=Gz,
        Gp=Gp,
        lu=None,
        border=c,
        t_raw=tau,
        _bp_sign=0.0,
        _bp_logdet=-math.inf,
        iters=iters,
        residual_norm=_inf_norm(G) if residual_norm is None else residual_norm,
    )


def point_at(
    problem: Any,
    a: PointInfo,
    b: PointInfo,
    sigma: float,
    sigma_b: float,
    w: Any,
    newton: NewtonSettings,
    near: tuple[float, PointInfo] | None = None,
    same_branch: bool = False,
) -> PointInfo | None:
    """The branch point at pseudo-arclength ``sigma`` from ``a`` towards ``b``.

    The predictor is the chord from ``a`` to ``b``, or, when ``near = (sigma_q, q)``
    gives a converged point closer to ``sigma``, the tangent of ``q`` scaled to meet the
    constraint; near a branch point (where the bordered matrix is almost singular and
    Newton converges slowly) this keeps the initial residual tiny. Returns None if the
    corrector fails, or, with ``same_branch``, if the corrected point's tangent is not
    that of the branch through ``a`` and ``b`` (:func:`tangent_agrees`).
    """
    if sigma <= 0.0:
        return a
    if sigma >= sigma_b:
        return b
    ua, ub = a.u, b.u
    c = w * a.tau
    u_pred = ua + (sigma / sigma_b) * (ub - ua)
    u_base = ua
    if near is not None:
        s_q, q = near
        ct = float(c.dot(q.tau))
        if 0.0 < s_q < sigma_b and abs(sigma - s_q) < min(sigma, sigma_b - sigma) and ct > 0.1:
            u_pred = q.u + ((sigma - s_q) / ct) * q.tau
            u_base = q.u

    def on_branch(res: CorrectorResult) -> str:
        # the corrector must stay on the branch it started from: its correction may not
        # exceed the predictor step (as in PALC), up to the corrector's own tolerance.
        # Next to a branch point Newton otherwise drifts, along the near-null vector of
        # the bordered matrix, onto the crossing branch.
        noise = 2.0 * newton.step_tol * (1.0 + _inf_norm(res.u))
        if _inf_norm(res.u - u_pred) > max(_inf_norm(u_pred - u_base), noise):
            return "left the branch"
        return ""

    got = palc_point(problem, u_pred, ua, c, sigma, w, newton, accept=on_branch)
    res, pt = got.res, got.point
    if got.singular and res.lin is not None:
        if same_branch:
            return None  # (no tangent to check: the caller interpolates instead)
        return _chord_point(res.z, res.p, res.lin, ua, ub, c, w, res.iters, res.residual_norm)
    if pt is None:
        return None
    if same_branch and not tangent_agrees(pt, a, b, w):
        return None
    return pt


#: Slack of :func:`tangent_agrees`: a trial point's tangent may turn this much
#: (``1 - cos`` of the angle, about 18 degrees) beyond the turn between the two rows.
TANGENT_SLACK = 0.05


def tangent_agrees(pt: PointInfo, a: PointInfo, b: PointInfo, w: Any) -> bool:
    r"""Whether the tangent at a trial point inside the step ``a -> b`` is the branch's.

    Along a smooth arc the unit tangent turns continuously: at a point between the
    rows it makes with ``tau_a`` and with ``tau_b`` angles no larger than the turn
    ``phi_ab`` between them (for an arc turning one way). The point passes if
    ``min(|<tau, tau_a>_theta|, |<tau, tau_b>_theta|) >= cos(phi_ab) - slack`` with
    ``slack = max(TANGENT_SLACK, (1 - cos(phi_ab)) / 2)``. Next to a branch point of
    the branch Newton's method may converge onto the crossing branch (a genuine
    solution on the same constraint hyperplane, at a finite angle); its tangent is
    the crossing branch's and fails this test, as does the ill-determined tangent of
    a point within ``tol / sigma_min`` of the branch point itself (Allgower & Georg
    1990, *Numerical Continuation Methods*, Sec. 8.1). Crossings at angles below
    ~18 degrees are not told apart.
    """
    cab = abs(float((w * a.tau).dot(b.tau)))
    floor = min(cab, 1.0) - max(TANGENT_SLACK, 0.5 * (1.0 - cab))
    ca = abs(float((w * a.tau).dot(pt.tau)))
    cb = abs(float((w * b.tau).dot(pt.tau)))
    return min(ca, cb) >= floor


def fold_guess(a: PointInfo, b: PointInfo, sigma_b: float) -> float | None:
    """First trial ``sigma`` for a fold between ``a`` and ``b``.

    The stationary point of the cubic Hermite interpolant of ``p(sigma)``.

    Along the step ``sigma = c . (u - u_a)`` with ``c = w o tau_a`` (the border of
    ``b``), so ``dp/dsigma = tau_p / (c . tau)``: ``tau_a[-1]`` at ``a`` and
    ``tau_b[-1] / b.ctau`` at ``b``, of opposite signs at a fold. The zero of the
    derivative of the cubic through ``(0, p_a)``, ``(sigma_b, p_b)`` with these slopes
    is ``O(sigma_b^3)`` from the fold on a smooth branch, against ``O(sigma_b^2)`` for the
    secant of ``tau_p``. Returns None when it is not strictly inside the step.
    """
    if not (sigma_b > 0 and b.ctau > 0):
        return None
    h = sigma_b
    m0 = float(a.tau[-1])
    m1 = float(b.tau[-1]) / b.ctau
    dp = (b.p - a.p) / h
    # derivative of the Hermite cubic, P'(t h) for t in [0, 1], as A t^2 + B t + C
    A = 3.0 * (m0 + m1 - 2.0 * dp)
    B = 2.0 * (3.0 * dp - 2.0 * m0 - m1)
    C = m0
    roots: list[float] = []
    if abs(A) <= 1e-14 * (abs(B) + abs(C)):
        if B != 0.0:
            roots.append(-C / B)
    else:
        disc = B * B - 4.0 * A * C
        if disc >= 0.0:
            q = -0.5 * (B + math.copysign(math.sqrt(disc), B))
            roots.append(q / A)  # (A != 0 here)
            if q != 0.0:
                roots.append(C / q)
    inside = [t for t in roots if 0.0 < t < 1.0]
    if len(inside) != 1:
        return None
    return inside[0] * h


#: Most branch points :func:`_interpolated_zero` interpolates through (a cubic).
INTERP_POINTS = 4


def _poly_zero(x: np.ndarray, g: np.ndarray, lo: float, hi: float) -> float | None:
    """The zero in ``[lo, hi]`` of the polynomial through ``(x_i, g_i)`` nearest its secant zero.

    ``g`` changes sign between the samples at ``lo`` and ``hi``.
    """
    scale = float(np.max(np.abs(g)))
    if not (scale > 0 and math.isfinite(scale)):
        return None
    coef = np.polyfit(x, g / scale, x.size - 1)
    roots = np.roots(coef) if x.size > 2 else np.array([-coef[1] / coef[0]])
    tiny = 1e-9 * (hi - lo)
    real = [float(r.real) for r in np.atleast_1d(roots)
            if abs(r.imag) <= tiny and lo - tiny <= r.real <= hi + tiny]  # fmt: skip
    if not real:
        return None
    return min(max(min(real, key=lambda r: abs(r - 0.5 * (lo + hi))), lo), hi)


def _lagrange(x: np.ndarray, at: float) -> np.ndarray:
    """Lagrange basis weights ``l_i(at)`` of the nodes ``x``, shape ``(len(x),)``."""
    out = np.ones(x.size)
    for i in range(x.size):
        for j in range(x.size):
            if j != i:
                out[i] *= (at - x[j]) / (x[i] - x[j])
    return out


def _interpolated_zero(
    problem: Any,
    a: PointInfo,
    samples: list[tuple[float, PointInfo, float]],
    end_lo: tuple[float, PointInfo, float],
    end_hi: tuple[float, PointInfo, float],
    w: Any,
    newton: NewtonSettings,
    test: Callable[[PointInfo, float], float],
    sigma_b: float,
    tol: float,
) -> LocateResult | None:
    r"""The zero of ``g`` and the branch point there, interpolated from points on the branch.

    Used where Newton's method cannot produce a trial point next to the zero (at a
    branch point of the branch the bordered matrix is singular and a corrected point
    is only determined to ``tol / sigma_min``, or lands on the crossing branch). ``g``
    and ``u`` are smooth functions of the pseudo-arclength ``sigma`` along the branch,
    so both are interpolated by polynomials through the ``k <= INTERP_POINTS`` corrected
    points of ``samples`` (``(sigma, point, g)`` on the branch, the bracket ends
    ``end_lo``, ``end_hi`` with ``g`` of opposite signs among them) nearest the
    bracket: ``sigma*`` is the zero of the ``g`` interpolant inside the bracket and
    ``u* = sum_i l_i(sigma*) u_i`` (Lagrange weights ``l_i``). The error estimate is
    the difference between the degree ``k - 1`` and ``k - 2`` results (the farthest
    sample dropped), ``max(|sigma*_k - sigma*_{k-1}|, ||u*_k - u*_{k-1}||_theta)``;
    with only the two bracket ends it is the bracket's width. The point is
    ``located`` only if that estimate is at most ``tol`` and ``max |G(u*)|`` at most
    ``newton.tol``; it is returned (not located) if only the residual test passes, and
    None is returned otherwise. The result's ``error`` is the larger of that estimate
    and the point's own distance to the branch (:func:`point_error`), which next to
    the branch point can exceed ``tol`` although the residual is tiny.
    """
    lo, hi = end_lo[0], end_hi[0]
    if not (hi > lo and end_lo[2] * end_hi[2] < 0):
        return None
    mid = 0.5 * (lo + hi)
    others = sorted(
        (q for q in samples if q[0] not in (lo, hi) and math.isfinite(q[2])),
        key=lambda q: abs(q[0] - mid),
    )
    chosen = [end_lo, end_hi, *others[: INTERP_POINTS - 2]]
    width = hi - lo

    def estimate(pts: list[tuple[float, PointInfo, float]]) -> tuple[float, np.ndarray] | None:
        x = np.array([(q[0] - lo) / width for q in pts])
        gz = _poly_zero(x, np.array([q[2] for q in pts]), 0.0, 1.0)
        if gz is None:
            return None
        lw = _lagrange(x, gz)
        u = sum(li * q[1].u for li, q in zip(lw, pts, strict=True))
        return lo + gz * width, np.asarray(u, dtype=float)

    best = estimate(chosen)
    if best is None:
        return None
    s, u = best
    err = width
    if len(chosen) > 2:
        lower = estimate(chosen[:-1])
        if lower is None:
            return None
        err = max(abs(s - lower[0]), theta_norm(u - lower[1], w))
    n = u.size - 1
    z, p = u[:n].copy(), float(u[n])
    try:
        lin = linearize(problem, z, p)
    except (ValueError, ArithmeticError):
        return None
    if not _inf_norm(lin[0]) <= newton.tol:
        return None
    c = w * a.tau
    try:
        pt = make_point(z, p, lin, c, w, u=u)
    except np.linalg.LinAlgError:
        pt = _chord_point(z, p, lin, end_lo[1].u, end_hi[1].u, c, w)
    g = float(test(pt, s / sigma_b))
    if not math.isfinite(g):
        return None
    msg = (
        f"interpolated through {len(chosen)} points on the branch next to a point where "
        f"the corrector fails (error estimate {err:.1e})"
    )
    located = err <= tol
    # the interpolated point is not a Newton solution: its own distance to the branch
    # (next to a branch point, of order sqrt(|G|)) enters its error, not its acceptance
    e_pt = point_error(problem, pt, w)
    if math.isfinite(e_pt) and e_pt > max(err, tol):
        err = e_pt
        msg = (
            f"{msg}; located only to {err:.1e}, not to tol {tol:.1e}: the point is "
            "ill-determined (bordered matrix near singular)"
        )
    return LocateResult(s, pt, g, located, 0, msg, error=err)


def _located(
    problem: Any,
    best: tuple[float, PointInfo, float],
    width: float,
    samples: list[tuple[float, PointInfo, float]],
    lo: float,
    hi: float,
    w: Any,
    tol: float,
    it: int,
    evaluate: Callable[[float], tuple[float, PointInfo, float] | None],
) -> LocateResult:
    """A located zero at ``best`` with its error estimate.

    The error is the largest of the bracket width, the uncertainty from the noise of
    ``g`` (:func:`noise_error`) and that of the corrected point itself
    (:func:`point_error`); the point stays located when it exceeds ``tol`` (the
    bracket closed on a zero, not a jump) but says so in its message and ``error``.
    """
    err = width
    why = [] if width <= tol else [f"the sign change is bracketed to {width:.1e}"]
    e_noise = noise_error(samples, lo, hi, best, evaluate)
    if e_noise > max(err, tol):
        why.append(f"|g| = {abs(best[2]):.1e} at the zero is noise of the test function")
    err = max(err, e_noise)
    e_pt = point_error(problem, best[1], w)
    if math.isfinite(e_pt) and e_pt > max(err, tol):
        why.append("the corrected point is ill-determined (bordered matrix near singular)")
        err = e_pt
    msg = ""
    if err > tol:
        msg = f"located only to {err:.1e}, not to tol {tol:.1e}: " + "; ".join(why)
    return LocateResult(best[0], best[1], best[2], True, it, msg, error=err)


def locate_beyond(
    problem: Any,
    a: PointInfo,
    end: tuple[float, PointInfo, float],
    sigma_b: float,
    w: Any,
    test: Callable[[PointInfo, float], float],
    slope: float,
    *,
    newton: NewtonSettings,
    tol: float = 1e-10,
    max_iter: int = 8,
) -> LocateResult:
    """The zero of ``g`` just outside the step, beyond the bracket end ``end``.

    For a test function whose sign change is decided with a tolerance band (the Hopf
    test: ``Re`` of the critical pair, counted as stable up to ``eig_tol``), ``g`` can
    have the same sign at both rows although the band says it crossed: its value at
    ``end = (sigma_e, point, g_e)`` (``sigma_e`` 0 or ``sigma_b``) is tiny, and the zero
    lies about ``g_e / slope`` beyond it, outside ``[0, sigma_b]``. It is found by the
    secant method from that estimate (``slope`` is ``dg/dsigma``, e.g. the mean slope over
    the step), each trial point corrected on the branch with the step's constraint
    ``<tau_a, u - u_a>_theta = sigma`` (``sigma`` slightly outside ``[0, sigma_b]``).
    When the first estimate is within ``tol`` of the row, the row itself is returned.

    Returns
    -------
    LocateResult
        ``sigma`` may lie slightly outside ``[0, sigma_b]``; not located if the
        corrector fails, ``g`` is not finite, or the secant iteration does not settle
        within ``max_iter`` trial points.
    """
    s_e, q, g_e = end
    if not (math.isfinite(g_e) and math.isfinite(slope) and slope != 0.0 and sigma_b > 0):
        return LocateResult(s_e, q, g_e, False, 0, "no slope to extrapolate the zero")
    s = s_e - g_e / slope
    if abs(s - s_e) <= tol:
        return LocateResult(s_e, q, g_e, True, 0, "zero within tol of the row")
    c = w * a.tau
    ct = float(c.dot(q.tau))
    if not ct > 0.1:
        return LocateResult(s_e, q, g_e, False, 0, "tangent unsuited to extrapolate")
    s_prev, g_prev = s_e, g_e
    for it in range(1, max_iter + 1):
        u_pred = q.u + ((s - s_e) / ct) * q.tau
        got = palc_point(problem, u_pred, a.u, c, s, w, newton)
        pt = got.point
        if pt is None:
            why = "singular point" if got.singular else "corrector failed"
            return LocateResult(s_e, q, g_e, False, it, f"{why} beyond the row")
        g = float(test(pt, s / sigma_b))
        if not math.isfinite(g):
            return LocateResult(s_e, q, g_e, False, it, "test not finite")
        if g == 0.0:
            return LocateResult(s, pt, g, True, it)
        if g == g_prev:
            break
        s_next = s - g * (s - s_prev) / (g - g_prev)
        if abs(s_next - s) <= tol:
            ok = abs(g) <= max(abs(g_e), 10.0 * abs(slope) * tol)
            msg = "" if ok else "test function jumps, no zero"
            return LocateResult(s, pt, g, ok, it, msg)
        s_prev, g_prev, s = s, g, s_next
    return LocateResult(s_e, q, g_e, False, max_iter, "zero beyond the row not found")


#: a bisection step is taken when ``STALL`` trial points have not halved the bracket
#: (Illinois creeps towards a zero of higher odd order, or when one bracket end is far)
STALL = 4
#: the probe's distance in units of ``tol`` (below 1 by more than the rounding of
#: ``sigma + tol - sigma``)
PROBE = 1.0 - 1e-6


def _probe_limit(
    trail: list[float],
    q: tuple[float, PointInfo, float],
    toward: float,
    evaluate: Callable[[float], tuple[float, PointInfo, float] | None],
    tol: float,
) -> tuple[float, PointInfo, float] | None:
    """A point just beyond the limit of a linearly converging secant, if ``g`` changes sign.

    Returns ``(sigma, point, g)`` with ``g`` of the other sign than at ``q``, else None.

    The last three trial points ``s0, s1, s2`` (``trail``) approach the zero
    monotonically with ratio ``r = (s2 - s1) / (s1 - s0)``, ``0 < r < 1``; their limit is
    ``s2 + (s2 - s1) r / (1 - r)`` (Aitken's delta-squared). The probe is ``tol / 2``
    beyond it, in the direction ``toward``, and past ``q`` (the failed tolerance probe).
    """
    if len(trail) < 3:
        return None
    s0, s1, s2 = trail[-3:]
    d1, d2 = s1 - s0, s2 - s1
    if not (d1 * d2 > 0 and abs(d2) < abs(d1)):
        return None
    r = d2 / d1
    s_lim = s2 + d2 * r / (1.0 - r) + toward * 0.5 * tol
    if not (s_lim - q[0]) * toward > 0:
        return None
    got = evaluate(s_lim)
    if got is None or (got[2] > 0) == (q[2] > 0):
        return None
    return got


def locate_zero(
    problem: Any,
    a: PointInfo,
    b: PointInfo,
    sigma_b: float,
    w: Any,
    test: Callable[[PointInfo, float], float],
    g_a: float,
    g_b: float,
    *,
    newton: NewtonSettings,
    tol: float = 1e-10,
    max_iter: int = 50,
    first: float | None = None,
    continuity: float | None = None,
    bracket: tuple[tuple[float, PointInfo, float], tuple[float, PointInfo, float]] | None = None,
    same_branch: bool = False,
) -> LocateResult:
    """Find ``sigma`` in ``[0, sigma_b]`` where ``test(point(sigma), t) = 0``.

    Parameters
    ----------
    problem : ContinuationProblem
    a, b : PointInfo
        The two branch rows around the zero.
    sigma_b : float
        Pseudo-arclength of ``b`` from ``a`` (``> 0``).
    w : ndarray, shape (N + 1,)
        ``theta`` weights.
    test : callable
        ``test(point, t) -> float`` with ``t = sigma / sigma_b`` in ``[0, 1]``.
    g_a, g_b : float
        Test values at ``a`` and ``b``; must have opposite signs (or one is zero).
    newton : NewtonSettings
        Corrector settings for the trial points.
    tol : float
        Tolerance on ``sigma``.
    max_iter : int
        Maximum number of trial points.
    first : float, optional
        A better first trial ``sigma`` than the secant of ``g`` (e.g.
        :func:`fold_guess`); ignored unless strictly inside ``(0, sigma_b)``.
    continuity : float, optional
        For a test function known to be smooth along the branch (the branch-point
        determinant): a point counts as located only if ``|g|`` there is at most
        ``continuity`` times the mean slope ``|g_b - g_a| / sigma_b`` times the final
        bracket or correction, plus ``1e-6 max(|g_a|, |g_b|)`` for round-off;
        otherwise the bracket closed on a jump (reported, not located).
    bracket : ((sigma_lo, point_lo, g_lo), (sigma_hi, point_hi, g_hi)), optional
        A sub-bracket ``0 <= sigma_lo < sigma_hi <= sigma_b`` of the step, its ends on
        the branch (e.g. from :func:`point_at`) with their test values of opposite
        signs; the search is confined to it and ``g_lo, g_hi`` replace ``g_a, g_b``
        (including in the ``1e-3`` and ``continuity`` rules, whose mean slope is then
        taken over the sub-bracket). Default: the whole step, ``(0, a, g_a)`` and
        ``(sigma_b, b, g_b)``.
    same_branch : bool
        Accept a trial point only if its tangent is the branch's
        (:func:`tangent_agrees`), so that next to a branch point ``g`` is never
        evaluated on the crossing branch. Where no trial point of the branch can be
        corrected, the zero is interpolated through the points already found on it
        (:func:`_interpolated_zero`, located only within ``tol`` by its error
        estimate).

    Returns
    -------
    LocateResult
    """
    end_lo, end_hi = (0.0, a, g_a), (sigma_b, b, g_b)  # true values at the bracket ends
    if bracket is not None:
        end_lo, end_hi = bracket
        g_a, g_b = end_lo[2], end_hi[2]
    lo, hi = end_lo[0], end_hi[0]
    if g_a == 0.0:
        return LocateResult(lo, end_lo[1], 0.0, True, 0, error=0.0)
    if g_b == 0.0:
        return LocateResult(hi, end_hi[1], 0.0, True, 0, error=0.0)
    if not (
        sigma_b > 0
        and 0.0 <= lo < hi <= sigma_b
        and g_a * g_b < 0
        and math.isfinite(g_a)
        and math.isfinite(g_b)
    ):
        return LocateResult(lo, end_lo[1], g_a, False, 0, "test function does not change sign")
    width = hi - lo  # (sigma_b unless a sub-bracket is given)
    # a located zero must have |g| <= g_jump * max(|g_a|, |g_b|) once the bracket has
    # collapsed: a continuous g is far smaller there (it is bounded by its slope times the
    # tolerance, plus round-off noise), a jump of g is not
    g_jump = 1e-3
    g_max = max(abs(g_a), abs(g_b))

    def g_ok(d: float) -> float:
        """Largest ``|g|`` at a zero known to within ``d``.

        With `continuity`, a zero within ``d`` of the point leaves ``|g|`` there of about
        slope * d; allow `continuity` times the mean slope over the bracket plus round-off
        noise.
        """
        bound = g_jump * g_max
        if continuity is not None:
            bound = min(bound, continuity * abs(g_b - g_a) / width * d + 1e-6 * g_max)
        return bound

    def bracket_result(it: int, message: str = "") -> LocateResult:
        """The better bracket end, not located, its error the bracket's width."""
        best = min(end_lo, end_hi, key=lambda e: abs(e[2]))
        return LocateResult(best[0], best[1], best[2], False, it, message, error=hi - lo)

    def evaluate(s: float) -> tuple[float, PointInfo, float] | None:
        """``(s, point, g)`` at a corrected point of this branch inside the step, or None.

        Only points whose tangent is the branch's (:func:`tangent_agrees`): a probe
        corrected onto a crossing branch would read a jump of ``g`` as its noise.
        """
        if not 0.0 < s < sigma_b:
            return None
        q = point_at(problem, a, b, s, sigma_b, w, newton, None, True)
        if q is None:
            return None
        gq = float(test(q, s / sigma_b))
        return (s, q, gq) if math.isfinite(gq) else None

    samples = [end_lo, end_hi]  # points on the branch with their test values
    glo, ghi = g_a, g_b  # glo/ghi are Illinois-scaled values
    side = 0
    s_prev = math.nan
    widths = [width]  # bracket width after each trial point
    trail: list[float] = []  # the trial points' sigma, in order
    bisect = False  # the secant stalls: bisect from now on
    safeguard = True  # bisection steps allowed (off once one left the branch)
    for it in range(1, max_iter + 1):
        s = hi - ghi * (hi - lo) / (ghi - glo)
        if it == 1 and first is not None and 0.0 < first < sigma_b:
            s = first
        bisect = bisect or (
            safeguard and len(widths) > STALL and widths[-1] > 0.5 * widths[-1 - STALL]
        )
        if bisect:
            s = 0.5 * (lo + hi)
        if not (lo < s < hi):
            s = 0.5 * (lo + hi)
        near = min(end_lo, end_hi, key=lambda e: abs(e[0] - s))
        pt = point_at(
            problem, a, b, s, sigma_b, w, newton, (near[0], near[1]), same_branch or bisect
        )
        if pt is None and bisect and not same_branch:
            # a bisection point off this branch (next to a branch point): back to the
            # secant, which approaches from the branch's side
            safeguard = bisect = False
            s = hi - ghi * (hi - lo) / (ghi - glo)
            if not (lo < s < hi):
                s = 0.5 * (lo + hi)
            near = min(end_lo, end_hi, key=lambda e: abs(e[0] - s))
            pt = point_at(problem, a, b, s, sigma_b, w, newton, (near[0], near[1]), False)
        if pt is None:
            # Newton cannot produce a point of this branch here (e.g. next to a branch
            # point, where the bordered matrix is singular and the corrected point is
            # only determined to tol / sigma_min, or lies on the crossing branch):
            # interpolate g and the branch through the points already on it
            r_int = _interpolated_zero(
                problem, a, samples, end_lo, end_hi, w, newton, test, sigma_b, tol
            )
            if r_int is not None and r_int.located:
                r_int.iterations = it
                return r_int
            s = 0.5 * (lo + hi)
            near = min(end_lo, end_hi, key=lambda e: abs(e[0] - s))
            pt = point_at(problem, a, b, s, sigma_b, w, newton, (near[0], near[1]), same_branch)
            if pt is None:
                msg = f"corrector failed in a bracket of width {hi - lo:.1e}"
                if r_int is not None:
                    msg = f"{msg}; {r_int.message}"
                    # (not located: the zero is surely only in the bracket)
                    return LocateResult(
                        r_int.sigma, r_int.point, r_int.g, r_int.located, it, msg,
                        error=max(r_int.error, hi - lo),
                    )  # fmt: skip
                # otherwise accept the bracket if it is already narrow and g small at its
                # better end (its error, the bracket's width, is reported)
                best = min(end_lo, end_hi, key=lambda e: abs(e[2]))
                narrow = hi - lo <= 1e-6 * width
                ok = narrow and abs(best[2]) <= g_jump * max(abs(g_a), abs(g_b))
                return LocateResult(best[0], best[1], best[2], ok, it, msg, error=hi - lo)
        g = float(test(pt, s / sigma_b))
        if not math.isfinite(g):
            return bracket_result(it, "test not finite")
        if g == 0.0:
            return _located(problem, (s, pt, g), 0.0, samples, s, s, w, tol, it, evaluate)
        samples.append((s, pt, g))
        trail.append(s)
        if (g > 0) == (ghi > 0):
            hi, ghi, end_hi = s, g, (s, pt, g)
            if side == 1:
                glo *= 0.5
            side = 1
        else:
            lo, glo, end_lo = s, g, (s, pt, g)
            if side == -1:
                ghi *= 0.5
            side = -1
        widths.append(hi - lo)
        # the next (Illinois-scaled) secant correction, without evaluating it: when it
        # (or the last step) is below tol the zero is probably within tol of this trial
        # point, but only a sign change proves it (a flat g, at a zero of higher order,
        # has tiny secant corrections far from its zero)
        s_next = hi - ghi * (hi - lo) / (ghi - glo)
        collapsed = hi - lo <= tol
        if collapsed or (not bisect and (abs(s - s_prev) <= tol or abs(s_next - s) <= tol)):
            best = min(end_lo, end_hi, key=lambda e: abs(e[2]))
            # a larger |g| than g_ok means the bracket closed on a jump of g (e.g. trial
            # points corrected onto a crossing branch next to a branch point, or a Hopf
            # test that switched between eigenvalue pairs), not on a zero
            d = min(hi - lo, max(abs(s_next - s), tol))
            if abs(best[2]) > g_ok(d):
                return bracket_result(it, "test function jumps, no zero")
            if collapsed:
                return _located(problem, best, hi - lo, samples, lo, hi, w, tol, it, evaluate)
            # probe tol beyond this trial point towards the secant's zero: a sign change
            # there proves the zero within tol; otherwise the bracket (narrowed by the
            # probe) is the honest error, and the search goes on only if g is smooth
            # there (a flat zero), not noise
            toward = 1.0 if s == lo else -1.0
            q = evaluate(s + toward * min(PROBE * tol, 0.5 * (hi - lo)))
            if q is not None:
                samples.append(q)
                if (q[2] > 0) != (g > 0):
                    lo_v, hi_v = sorted((s, q[0]))
                    err = max(abs(best[0] - lo_v), abs(best[0] - hi_v))
                    return _located(problem, best, err, samples, lo_v, hi_v, w, tol, it, evaluate)
                # (the same end moved again: Illinois halves the other end's value)
                if toward > 0:
                    lo, glo, end_lo, side = q[0], q[2], q, -1
                    ghi *= 0.5
                else:
                    hi, ghi, end_hi, side = q[0], q[2], q, 1
                    glo *= 0.5
                widths.append(hi - lo)
                if abs(q[2]) < abs(g):
                    # |g| still falls towards the zero: smooth and flat, keep searching
                    # (bisecting: the secant creeps); where bisection would leave the
                    # branch, the secant creeps linearly from the branch's side and the
                    # limit of its last three points (Aitken's delta-squared) is probed
                    bisect = safeguard
                    r_lim = None if bisect else _probe_limit(trail, q, toward, evaluate, tol)
                    if r_lim is not None:
                        samples.append(r_lim)
                        lo_v, hi_v = sorted((q[0], r_lim[0]))
                        best = min(q, r_lim, key=lambda e: abs(e[2]))
                        err = hi_v - lo_v
                        return _located(
                            problem, best, err, samples, lo_v, hi_v, w, tol, it, evaluate
                        )
                    s_prev = s
                    continue
            # no sign change within tol, and |g| does not fall towards the zero: the
            # zero is |g| / |g'| away for a smooth g (|g'| from samples above the noise,
            # see noise_slope), plus the noise of g (_located); the bracket otherwise
            best = min(end_lo, end_hi, key=lambda e: abs(e[2]))
            m = noise_slope(samples, lo, hi, best[2])
            err = hi - lo
            if math.isfinite(m) and m > 0.0:
                step = abs(q[0] - s) if q is not None else tol
                err = min(err, max(step, abs(best[2]) / m))
            return _located(problem, best, err, samples, lo, hi, w, tol, it, evaluate)
        s_prev = s
    return bracket_result(max_iter, "max_iter reached")


__all__ = [
    "LocateResult",
    "point_error",
    "fold_guess",
    "locate_beyond",
    "locate_zero",
    "point_at",
    "tangent_agrees",
]
