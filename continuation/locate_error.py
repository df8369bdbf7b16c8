r"""The error of a located zero of a test function along a branch.

:func:`~continuation.locate.locate_zero` proves a zero by a sign change within ``tol``;
what it cannot see from the bracket alone is estimated here, in the same
``theta``-arclength units as ``tol``:

- :func:`noise_slope` and :func:`noise_error`: ``g`` itself may be noisy near its zero
  (round-off, finite-difference derivatives inside it), so that the sign changes seen
  inside a narrow bracket are those of the noise; the zero is then only known to
  ``(|g_best| + A) / |g'|``, ``A`` the noise amplitude sampled around the point;
- :func:`point_error`: the corrected point itself is ill-determined next to a branch
  point of the branch (a nearly singular bordered matrix).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .algorithms.base import theta_norm
from .algorithms.point import PointInfo
from .problem import linearize

#: a sample's ``|g|`` must exceed the located point's by this factor to enter the slope
#: of :func:`noise_error` (its value is then signal, not noise)
NOISE_MARGIN = 100.0


def noise_slope(
    samples: list[tuple[float, PointInfo, float]], lo: float, hi: float, g_best: float
) -> float:
    r"""Slope ``|g'|`` at a zero bracketed by ``[lo, hi]``, from samples above the noise.

    The secant slope between the nearest samples on either side of the bracket whose
    ``|g|`` exceeds ``NOISE_MARGIN |g_best|`` (their difference is then signal, not
    noise); NaN when there is no such pair on both sides (the samples cannot tell).
    """
    g0 = abs(g_best)
    left = [q for q in samples if q[0] <= lo and abs(q[2]) > NOISE_MARGIN * g0]
    right = [q for q in samples if q[0] >= hi and abs(q[2]) > NOISE_MARGIN * g0]
    if not left or not right:
        return math.nan
    ql = max(left, key=lambda q: q[0])
    qr = min(right, key=lambda q: q[0])
    if ql[2] * qr[2] >= 0 or qr[0] <= ql[0]:
        return math.nan
    return abs(qr[2] - ql[2]) / (qr[0] - ql[0])


#: extra trial points at ``s_best + k delta`` that sample the noise of ``g`` at a zero
NOISE_PROBES = (-3.0, -1.0, 1.0, 3.0)


def noise_error(
    samples: list[tuple[float, PointInfo, float]],
    lo: float,
    hi: float,
    best: tuple[float, PointInfo, float],
    evaluate: Callable[[float], tuple[float, PointInfo, float] | None],
) -> float:
    r"""Uncertainty in ``sigma`` of a zero bracketed by ``[lo, hi]`` from the noise in ``g``.

    Once the bracket is narrow, ``|g|`` at its better end is bounded by ``|g'| (hi - lo)``
    for a smooth ``g``; a larger value is noise (round-off, or the error of
    finite-difference derivatives inside ``g``), and the sign changes seen inside the
    bracket are those of the noise. With ``g_i = m (s_i - s*) + n_i``, ``|n_i| <= A``
    (``m`` from :func:`noise_slope`), the zero ``s*`` is then only known to
    ``(|g_best| + A) / m``. The amplitude ``A`` is sampled: ``g`` is evaluated
    (``evaluate(sigma)``, a corrected point of the branch) at ``s_best + k delta``,
    ``k`` in ``NOISE_PROBES``, ``delta = |g_best| / m``, and ``A`` is estimated by the
    largest ``|r_i - r_best|`` of the residuals ``r_i = g_i - m (s_i - s_best)`` of these
    and the samples within ``3 delta``. Returns 0 when ``g`` is not noisy
    (``|g_best| <= m (hi - lo)``) or the samples cannot tell (no slope).
    """
    s_b, _, g_b = best
    m = noise_slope(samples, lo, hi, g_b)
    if not (math.isfinite(m) and m > 0.0) or abs(g_b) <= m * max(hi - lo, 0.0):
        return 0.0
    delta = abs(g_b) / m
    near = [q for q in samples if abs(q[0] - s_b) <= 3.0 * delta]
    for k in NOISE_PROBES:
        q = evaluate(s_b + k * delta)
        if q is not None:
            near.append(q)
    amp = max((abs((q[2] - m * (q[0] - s_b)) - g_b) for q in near), default=0.0)
    return (abs(g_b) + amp) / m


def point_error(problem: Any, pt: PointInfo, w: Any) -> float:
    r"""Estimated ``theta``-distance from a corrected point to the branch it approximates.

    The corrector stops at a residual ``r = (G, 0)`` of the bordered system
    ``A = [[G_z, G_p], [c^T]]``; the next Newton correction ``d = A^{-1} r`` estimates
    the error where ``A`` is well conditioned. Next to a branch point of the branch
    (``A`` nearly singular, smallest singular value ``s = |r| / |d|_theta`` along ``d``)
    the residual grows quadratically along the near-null direction
    ``v = d / |d|_theta``: ``|G(u + e v)| ~ s e + M e^2 / 2`` with
    ``M = |A'(u)[v] v|``, so a residual ``|r|`` leaves the point uncertain by the
    smaller root ``e = 2 |r| / (s + sqrt(s^2 + 2 M |r|))``, of order
    ``sqrt(2 |r| / M)`` where ``s -> 0``; where ``M`` vanishes too (a pitchfork, the
    residual cubic along ``v``) by ``(6 |r| / M_3)^(1/3)``, ``M_3 = |A''(u)[v, v] v|``;
    the smaller of the two is returned (Keller 1977, "Numerical solution of
    bifurcation and nonlinear eigenvalue problems", in *Applications of Bifurcation
    Theory*, Sec. 5: a corrected point is within ``tol_G / sigma_min`` only to first
    order). ``M`` and ``M_3`` are central differences of ``A(u + t v) v`` with
    ``t = +-h``, ``h = 1e-4 (1 + |u|_inf)``, evaluated only when ``|d|_theta`` itself
    exceeds ``1e-12``.

    Returns
    -------
    float
        ``e``; NaN when the point has no factorisation (an exactly singular point).
    """
    r = np.append(np.asarray(pt.G, dtype=float), 0.0)
    rn = float(np.linalg.norm(r))
    if rn == 0.0:
        return 0.0
    if pt.lu is None:
        return math.nan
    try:
        d = pt.lu.solve(r)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return math.nan
    lin_err = float(theta_norm(d, w))
    if not math.isfinite(lin_err) or lin_err == 0.0:
        return lin_err if math.isfinite(lin_err) else math.nan
    if lin_err <= 1e-12:
        return lin_err
    v = d / lin_err
    s_min = rn / lin_err
    u = pt.u
    h = 1e-4 * (1.0 + float(np.max(np.abs(u))))
    n = u.size - 1

    def a_v(sign: float) -> np.ndarray:
        """``A(u + sign h v) v`` (the Jacobian rows of the bordered matrix)."""
        _, gz, gp = linearize(problem, u[:n] + sign * h * v[:n], float(u[n] + sign * h * v[n]))
        return np.asarray(gz @ v[:n] + gp * v[n], dtype=float).ravel()

    try:
        av_p, av_m = a_v(1.0), a_v(-1.0)
    except (ValueError, ArithmeticError):
        return lin_err
    av_0 = np.asarray(pt.Gz @ v[:n] + pt.Gp * v[n], dtype=float).ravel()
    m2 = float(np.linalg.norm(av_p - av_m)) / (2.0 * h)
    m3 = float(np.linalg.norm(av_p - 2.0 * av_0 + av_m)) / (h * h)
    if not (math.isfinite(m2) and math.isfinite(m3)):
        return lin_err
    e_quad = 2.0 * rn / (s_min + math.sqrt(s_min * s_min + 2.0 * m2 * rn))
    e_cub = min(lin_err, (6.0 * rn / m3) ** (1.0 / 3.0)) if m3 > 0.0 else lin_err
    return min(e_quad, e_cub)


__all__ = ["NOISE_MARGIN", "NOISE_PROBES", "noise_error", "noise_slope", "point_error"]
