"""The surge-only threshold of surf-riding (``chi_c = 0``): beside the critical surface."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize as so

from continuation.dynamics import SimEvent, simulate
from continuation.errors import ContinuationError
from continuation.status import Status, StatusResult
from continuation.typing import FloatArray

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SurgeThreshold(StatusResult):
    """Critical Fn of the uncoupled surge model (``chi_c = 0``) at one wave.

    Attributes
    ----------
    Fn : float
        Where the upslope unstable manifold of the crest saddle lands on the crest
        saddle one wavelength back (nan if there is none).
    Fn_range : (float, float)
        Nominal Froude numbers with surf-riding fixed points (nan if none).
    status : Status
        ``SUCCESS`` (``success``: converged to the tolerance), or ``NO_BRACKET`` (no
        surf-riding, or the branch's fate does not change in ``Fn_range``).
    message : str
    n_runs : int
        Simulations of the manifold.
    """

    Fn: float
    Fn_range: tuple[float, float]
    status: Status
    message: str
    n_runs: int = 0


def surf_riding_range(
    surge: Any, H_over_lambda: float, lambda_over_L: float
) -> tuple[float, float]:
    r"""Nominal Froude numbers at which surf-riding fixed points exist (surge model).

    Fixed points have ``u = c`` and :math:`T(c; n(Fn)) - R(c) + X_w(\xi) = 0`; they exist
    while :math:`-\max X_w \le T - R \le -\min X_w` (:math:`T - R` increases with Fn).

    Returns
    -------
    (float, float)
        ``(Fn_a, Fn_b)``, ``(nan, nan)`` if none in ``0.01 <= Fn <= 2`` (``Fn_a = 0.01``
        when they exist already there).
    """
    F = surge.forces
    p = surge.params(Fn=0.3, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
    c = surge.celerity(p)
    grid = np.linspace(0.0, 1.0, 801)

    def net(Fn: float) -> float:
        return float(F.thrust_force(c, F.revolutions(Fn)) - F.resistance_force(c))

    xw = surge.surge_force(grid, c, p) - net(0.3)
    hi, lo = float(np.max(xw)), float(np.min(xw))
    fns = np.linspace(0.01, 2.0, 200)
    vals = np.array([net(f) for f in fns])
    out = []
    for target in (-hi, -lo):
        g = vals - target
        k = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]
        if k.size:
            i = int(k[0])
            out.append(so.brentq(lambda f, t=target: net(f) - t, fns[i], fns[i + 1], xtol=1e-12))
        elif g[0] > 0:  # already past this edge at the smallest Fn scanned
            out.append(float(fns[0]))
        else:
            out.append(math.nan)
    if not (math.isfinite(out[0]) and math.isfinite(out[1])):
        return (math.nan, math.nan)
    return (out[0], out[1])


def _surge_miss(surge: Any, pv: FloatArray, t_max: float) -> float:
    """Signed miss of the upslope branch at the next crest saddle (surge model).

    From the crest saddle ``x_s + eps v_u`` (``xi_G`` decreasing): if the branch reaches
    ``xi_s - 1`` (the shifted saddle's position) it returns ``(u - c)/c < 0`` there
    (passes the crest: periodic); if ``u`` climbs back to ``c`` first (turns back down
    the slope: surf-riding), ``xi_turn - (xi_s - 1) > 0``. Both tend to 0 at the
    connection, so the function is continuous and changes sign at the critical Fn.
    """
    fps = [fp for fp in surge.fixed_points(pv) if fp.kind == "saddle"]
    if not fps:
        raise ContinuationError("no crest saddle")
    xs = fps[0].x
    c = surge.celerity(pv)
    w, V = np.linalg.eig(surge.jacobian(xs, pv))
    k = int(np.argmax(w.real))
    v = np.real(V[:, k])
    v = v / np.linalg.norm(v / np.array([1.0, c]))
    if v[0] > 0:
        v = -v
    x0 = xs + 1e-7 * v
    xi_end = float(xs[0]) - 1.0
    passed = SimEvent("passed", lambda t, x: x[..., 0] - xi_end, True, -1, vectorized=True)
    back = SimEvent("back", lambda t, x: x[..., 1] - c, True, 1, vectorized=True)
    tr = simulate(
        surge, x0, pv, (0.0, t_max), events=[passed, back], rtol=1e-11, atol=1e-12, dt=1.0
    )
    if tr.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    xe = np.asarray(tr.x[-1], dtype=float)
    if tr.terminal_event == "passed":
        return (float(xe[1]) - c) / c
    if tr.terminal_event == "back":
        return float(xe[0]) - xi_end
    # lingering at the shifted saddle: as close to the connection as it gets
    return (float(xe[1]) - c) / c if xe[0] <= xi_end else float(xe[0]) - xi_end


def surge_threshold(
    surge: Any,
    H_over_lambda: float,
    lambda_over_L: float,
    *,
    tol: float = 1e-8,
    n_scan: int = 9,
    t_max: float = 3000.0,
) -> SurgeThreshold:
    r"""Critical Fn of the surge model: root of the signed miss of its upslope branch.

    The 2-D counterpart of the heteroclinic connection (an independent method: shooting
    + Brent instead of collocation): :func:`surf_riding_range` bounds Fn; the signed
    miss (:func:`_surge_miss`) is evaluated at ``n_scan`` interior points and the first
    sign change refined by :func:`scipy.optimize.brentq` to ``tol`` in Fn.

    Returns
    -------
    SurgeThreshold
        ``NO_BRACKET`` with the reason where there is no surf-riding at this wave or the
        branch's fate does not change.
    """
    if not (math.isfinite(H_over_lambda) and H_over_lambda > 0):
        raise ValueError(f"`H_over_lambda` must be positive, got {H_over_lambda!r}")
    if not (math.isfinite(lambda_over_L) and lambda_over_L > 0):
        raise ValueError(f"`lambda_over_L` must be positive, got {lambda_over_L!r}")
    fa, fb = surf_riding_range(surge, H_over_lambda, lambda_over_L)
    if not math.isfinite(fa):
        return SurgeThreshold(
            math.nan, (fa, fb), Status.NO_BRACKET,
            f"no surf-riding fixed points at H/lambda = {H_over_lambda:g}, "
            f"lambda/L = {lambda_over_L:g}",
        )  # fmt: skip
    n = 0

    def g(Fn: float) -> float:
        nonlocal n
        n += 1
        pv = surge.params(Fn=Fn, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
        return _surge_miss(surge, np.asarray(pv.values, dtype=float), t_max)

    w = fb - fa
    # dense near the birth of the fixed points, where the connection ends
    fns = fa + w * np.concatenate([[1e-4, 1e-3, 1e-2], np.linspace(0.02, 0.98, n_scan)])
    vals = []
    for f in fns:
        try:
            vals.append(g(float(f)))
        except ContinuationError as exc:  # e.g. fixed points too close to be resolved
            log.info("surge threshold: no miss at Fn = %.6f: %s", f, exc)
            vals.append(math.nan)
    ok = [i for i, v in enumerate(vals) if math.isfinite(v)]
    for i, k in zip(ok[:-1], ok[1:], strict=True):
        if vals[i] < 0 <= vals[k]:
            try:
                fn = so.brentq(g, fns[i], fns[k], xtol=tol, rtol=4 * np.finfo(float).eps)
            except ContinuationError as exc:
                return SurgeThreshold(
                    math.nan, (fa, fb), Status.UNDECIDED,
                    f"Brent's method failed in [{fns[i]:.6f}, {fns[k]:.6f}]: {exc}", n,
                )  # fmt: skip
            return SurgeThreshold(fn, (fa, fb), Status.SUCCESS, f"brentq, {n} simulations", n)
    if not ok:
        return SurgeThreshold(
            math.nan, (fa, fb), Status.UNDECIDED, "no crest saddle resolved at any scanned Fn", n
        )
    if all(vals[i] >= 0 for i in ok):
        msg = (
            f"no connection: the upslope branch turns back to surf-riding already at "
            f"Fn = {fns[ok[0]]:.6f}, just above the birth of the surf-riding points "
            f"(Fn = {fa:.6f}; the threshold there is that saddle-node)"
        )
    elif all(vals[i] < 0 for i in ok):
        msg = (
            f"no connection: the upslope branch passes the next crest at every Fn with "
            f"surf-riding points ({fa:.5f} < Fn < {fb:.5f})"
        )
    else:
        msg = "the miss changes sign only from captured to periodic: no threshold found"
    return SurgeThreshold(math.nan, (fa, fb), Status.NO_BRACKET, msg, n)
