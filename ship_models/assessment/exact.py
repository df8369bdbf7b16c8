r"""The exact surf-riding threshold of the surge equation over the Level 2 wave cases.

The threshold Melnikov's formula approximates (:mod:`ship_models.assessment.melnikov`)
is a heteroclinic bifurcation of the uncoupled surge equation
(:class:`ship_models.surge.SurgeModel`): the unstable manifold of the saddle near the
wave crest, on its branch falling back relative to the wave (``u < c``), lands on the
same saddle one wavelength behind (``xi_G -> xi_G - 1``). Below that ``Fn`` the ship is
overtaken (a rotation orbit); above it the manifold turns back into surf-riding. This
is the ``chi_c = 0`` case of Umeda's (1999) critical ``Fn``
(:mod:`ship_models.analysis.critical_bvp`) and is solved the same way: the
saddle-to-shifted-saddle orbit with ``Fn`` unknown, by collocation
(:func:`continuation.bvp.find_connection` / :func:`~continuation.bvp.solve_connection`)
with error estimates.

Over the grid it is continued, not solved cold (:func:`exact_threshold_grid`):

1. one connection from the manifold's fate (:func:`surf_riding_connection`: bisection
   of ``Fn`` on the fate of the simulated branch, then :func:`find_connection`);
2. across the wavelengths at one steepness by natural-parameter steps, each column's
   start solved from its neighbour's orbit on the same (compiled) problem;
3. along each column by pseudo-arclength continuation in ``H/lambda``
   (:func:`continuation.bvp.continue_connection`), the values at the grid steepnesses
   by a cubic spline through the branch rows; its error is estimated by the spline
   through every other row (twice the spacing: about 16 times the error; the largest
   difference over the neighbouring row intervals, :func:`_spline_error`), reported
   with the solves' own error estimates: the column start's, and that of the rows on
   the start's mesh, estimated at the column's two ends (:func:`_mesh_error`).

In gentle waves the connection ends: the crest saddle meets the stable surf-riding
point in a saddle-node bifurcation *on* the overtaken orbit (a saddle-node loop, the
codimension-two point where the heteroclinic curve ends on the fold curve). Below that
steepness the overtaken motion ceases where the surf-riding equilibria are born, so the
threshold is the fold itself, ``R(c) - T(c; n) = f``
(:func:`saddle_node_fn`, closed form). The continuation is stopped by an event when
the connection's ``Fn`` comes within ``SN_MARGIN`` of the fold, and the cells below
get the fold's ``Fn`` with error estimate ``SN_MARGIN``. Melnikov's formula knows
nothing of this: it is a perturbation of the undamped separatrix.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.integrate as si
from scipy.interpolate import CubicSpline

from continuation.bvp import (
    ConnectionAccuracy,
    ConnectionResult,
    connection_at,
    continue_connection,
    find_connection,
    solve_connection,
)
from continuation.events import Event
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status
from continuation.typing import FloatArray

from ..forces import ShipForces
from ..surge import SurgeModel
from .melnikov import calm_water_fn, froude_krylov_amplitude, thrust_coefficients

log = logging.getLogger(__name__)

SHIFT = {"xi_G": -1.0}
SN_MARGIN = 2e-5


def _sn_revolutions(F: ShipForces, lam: FloatArray, s: FloatArray, f1: FloatArray) -> FloatArray:
    """``n_sn`` of :func:`saddle_node_fn` (shape (n_lambda, n_s)); ``f1`` is ``f / H``."""
    tc = thrust_coefficients(F)
    c = np.sqrt(F.g * lam * F.L / (2.0 * math.pi))[:, None]
    f = f1[:, None] * s[None, :] * (lam * F.L)[:, None]
    rhs = np.asarray(F.resistance(c), dtype=float) - f
    disc = (tc.tau1 * c) ** 2 - 4.0 * tc.tau0 * (tc.tau2 * c * c - rhs)
    with np.errstate(invalid="ignore"):
        n = (-tc.tau1 * c + np.sqrt(disc)) / (2.0 * tc.tau0)
    return np.where((disc >= 0) & (n > 0), n, np.nan)


def saddle_node_fn(F: ShipForces, lambda_over_L: FloatArray, steepness: FloatArray) -> FloatArray:
    r"""``Fn`` at which the surf-riding equilibria are born below the wave speed.

    Fixed points of the surge equation have ``u = c`` and
    ``T(c; n) - R(c) = f sin(theta)``; below the celerity they first exist when
    ``T(c; n) = R(c) - f``:
    ``n_sn = [-tau1 c + sqrt(tau1^2 c^2 - 4 tau0 (tau2 c^2 - R(c) + f))] / (2 tau0)``,
    then ``Fn_sn`` its calm-water Froude number (:func:`calm_water_fn`).

    Parameters
    ----------
    F : ShipForces
    lambda_over_L : array_like, shape (n_lambda,)
    steepness : array_like, shape (n_s,)

    Returns
    -------
    ndarray, shape (n_lambda, n_s)
        NaN where no positive ``n`` solves it (equilibria at any speed).
    """
    lam = np.atleast_1d(np.asarray(lambda_over_L, dtype=float))
    s = np.atleast_1d(np.asarray(steepness, dtype=float))
    return calm_water_fn(F, _sn_revolutions(F, lam, s, froude_krylov_amplitude(F, lam)))


def _saddle(model: SurgeModel, p: Any) -> FloatArray | None:
    sad = [fp for fp in model.fixed_points(p) if fp.kind == "saddle"]
    return None if not sad else np.asarray(sad[0].x, dtype=float)


def manifold_fate(model: SurgeModel, H_over_lambda: float, lambda_over_L: float, Fn: float) -> int:
    r"""Fate of the falling-back branch of the crest saddle's unstable manifold.

    Returns ``-1`` when the ship is overtaken (the branch reaches ``xi_s - 1``, or there
    is no saddle because the net thrust at ``u = c`` is below ``-f``: ``Fn`` below the
    threshold) and ``+1`` when it is captured (the relative speed ``u - c`` turns
    positive again, or no saddle because the net thrust exceeds ``f``).
    """
    p = model.params(Fn=Fn, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
    pv = np.asarray(p.values, dtype=float)
    c = model.celerity(pv)
    xs = _saddle(model, p)
    if xs is None:
        F = model.forces
        net = F.thrust_force(c, F.revolutions(Fn)) - F.resistance_force(c)
        return -1 if net < 0 else 1
    ev, V = np.linalg.eig(model.jacobian(xs, pv))
    v = np.real(V[:, int(np.argmax(ev.real))])
    v = -v if v[0] > 0 else v  # xi decreasing: falling back
    x0 = xs + 1e-6 * v / np.linalg.norm(v)

    def passed(t: float, x: FloatArray) -> float:
        return x[0] - (xs[0] - 1.0)

    def turned(t: float, x: FloatArray) -> float:
        return x[1] - c

    passed.terminal = True  # type: ignore[attr-defined]
    turned.terminal, turned.direction = True, 1  # type: ignore[attr-defined]
    lam_u = float(np.max(ev.real))
    sol = si.solve_ivp(
        lambda t, x: model.f(x, pv),
        (0.0, 60.0 / lam_u + 2000.0),
        x0,
        events=(passed, turned),
        rtol=1e-9,
        atol=1e-11,
    )
    if sol.t_events[0].size:
        return -1
    return 1


def surf_riding_connection(
    model: SurgeModel,
    H_over_lambda: float,
    lambda_over_L: float,
    *,
    Fn_bracket: tuple[float, float] | None = None,
    tol: float = 2e-4,
) -> ConnectionResult:
    r"""The surf-riding connection at one wave, from scratch.

    Bisection of ``Fn`` on :func:`manifold_fate` to ``tol`` (bracket default
    ``[0.05, 1.2 c / sqrt(g L)]``), then :func:`continuation.bvp.find_connection` from the
    saddle at the upper end of the final bracket (the captured side, where the branch
    comes closest to the shifted saddle).

    Raises
    ------
    ValueError
        When the bracket does not contain a change of fate.
    """
    F = model.forces
    fn_c = float(F.celerity(lambda_over_L)) / math.sqrt(F.g * F.L)
    lo, hi = Fn_bracket if Fn_bracket is not None else (0.05, 1.2 * fn_c)
    if manifold_fate(model, H_over_lambda, lambda_over_L, lo) > 0:
        raise ValueError(f"Fn = {lo:g} is already above the surf-riding threshold")
    if manifold_fate(model, H_over_lambda, lambda_over_L, hi) < 0:
        raise ValueError(f"Fn = {hi:g} is still below the surf-riding threshold")
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if manifold_fate(model, H_over_lambda, lambda_over_L, mid) < 0:
            lo = mid
        else:
            hi = mid
    p = model.params(Fn=hi, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
    xs = _saddle(model, p)
    if xs is None:
        p = model.params(Fn=lo, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
        xs = _saddle(model, p)
    if xs is None:
        raise ValueError("no crest saddle near the surf-riding threshold")
    # branch -1: the unstable eigenvector oriented with xi decreasing
    return find_connection(model, p, "Fn", source=xs, shift=SHIFT, branch=-1)


def resolve_at(result: ConnectionResult, **params: float) -> ConnectionResult:
    """The connection at other parameter values, from ``result``'s orbit on its problem."""
    prob = result.problem
    fixed = prob.replace(vary=None, reference=None, params=prob.params.replace(**params))
    return solve_connection(fixed, (np.asarray(result.t), np.asarray(result.x)))


@dataclass(frozen=True)
class ExactGrid:
    """The exact surf-riding threshold on the wave cases.

    Attributes
    ----------
    lambda_over_L : ndarray, shape (n_lambda,)
    steepness : ndarray, shape (n_s,)
    Fn_cr : ndarray, shape (n_lambda, n_s)
        NaN where the continuation did not reach the cell.
    error : ndarray, shape (n_lambda, n_s)
        Error estimate: the column start's collocation estimate, plus that of the
        rows on the start's mesh (at the column's ends), plus the spline's.
    column_status : list of str
        ``"ok"`` or why a column is (partly) missing.
    steps : int
        Continuation steps taken in all.
    seconds : float
        Wall time.
    engine : str
        Where it was computed: ``"in-process"`` (:func:`exact_threshold_grid`) or
        the sweep engine's backend and task count
        (:func:`~ship_models.assessment.exact_sweep.exact_threshold_sweep`).
    """

    lambda_over_L: FloatArray
    steepness: FloatArray
    Fn_cr: FloatArray
    error: FloatArray
    column_status: list[str] = field(default_factory=list)
    steps: int = 0
    seconds: float = 0.0
    engine: str = "in-process"

    @property
    def complete(self) -> bool:
        """Every cell has a value."""
        return bool(np.all(np.isfinite(self.Fn_cr)))


def _column(
    start: ConnectionResult,
    steepness: FloatArray,
    ds_max: float,
    F: ShipForces,
    theta: float = 0.9,
) -> tuple[FloatArray, FloatArray, int, str]:
    """Values of Fn at ``steepness`` along the continuation in H/lambda from ``start``;
    below the saddle-node loop (module doc) those of the fold."""
    lam = np.array([float(start.params["lambda_over_L"])])
    prob0 = start.problem
    f1 = froude_krylov_amplitude(F, lam)
    Fn0 = float(start.params["Fn"])
    # the margin in revolutions (n(Fn) is increasing): cheap to test at every row
    n_margin = float(F.revolutions(Fn0 + SN_MARGIN) - F.revolutions(Fn0))

    def gap(z: FloatArray, p: float) -> float:
        n = float(F.revolutions(float(prob0.unpack(z)["params"]["Fn"])))
        return n - float(_sn_revolutions(F, lam, np.array([p]), f1)[0, 0]) - n_margin

    near_fold = Event("saddle_node_loop", gap, direction="down", terminal=True)
    lo, hi = float(steepness[0]), float(steepness[-1])
    span = hi - lo
    settings = ContinuationSettings(
        ds=0.5 * ds_max,
        ds_min=1e-6,
        ds_max=ds_max,
        p_min=lo - 1e-3 * span,
        p_max=hi + 1e-3 * span,
        max_steps=400,
        theta=theta,
        newton=NewtonSettings(tol=1e-10, max_iter=12),
    )
    br = continue_connection(start, "H_over_lambda", settings, direction="both", events=[near_fold])
    if br.status is Status.INTERRUPTED:  # the engine keeps Ctrl-C as a status: stop here
        raise KeyboardInterrupt
    s = np.asarray(br.p, dtype=float)
    Fn = np.asarray(br.records["Fn"], dtype=float)
    order = np.argsort(s)
    s, Fn = s[order], Fn[order]
    keep = np.concatenate(([True], np.diff(s) > 1e-12))
    s, Fn = s[keep], Fn[keep]
    out = np.full(steepness.shape, np.nan)
    err = np.full(steepness.shape, np.nan)
    status = "ok"
    if s.size < 4:
        return out, err, len(br), f"continuation gave {s.size} rows ({br.message})"
    fold_end = any(sp.label == "saddle_node_loop" for sp in br.special_points)
    if fold_end:
        below = steepness < s[0]
        out[below] = calm_water_fn(F, _sn_revolutions(F, lam, steepness[below], f1))[0]
        err[below] = SN_MARGIN
        status = f"ok; saddle-node threshold below H/lambda = {s[0]:.5f}"
    if s[-1] < hi or (s[0] > lo and not fold_end):
        status = f"continuation stopped: {br.message}"
    inside = (steepness >= s[0]) & (steepness <= s[-1])
    spline = CubicSpline(s, Fn)
    out[inside] = spline(steepness[inside])
    err[inside] = _spline_error(s, Fn, spline, steepness[inside])
    mesh_err, checked = _mesh_error(br)
    err[inside] += mesh_err
    if not checked:  # the estimate is incomplete: not an "ok" column
        status = (
            "error estimate incomplete: the mesh error at a column end could not be "
            f"estimated (a re-solve failed); {status}"
        )
    return out, err, len(br), status


#: The estimates of a branch row on its own mesh: no adaptation, no refinement, a
#: tolerance nothing exceeds (so the estimates are reported, never acted on).
_ROW_ESTIMATE = ConnectionAccuracy(
    rtol=1.0, atol=1.0, adapt_rounds=0, max_refinements=0, max_extensions=0
)


def _spline_error(s: FloatArray, Fn: FloatArray, spline: CubicSpline, at: FloatArray) -> FloatArray:
    """Error estimate of the spline through the branch rows at the points ``at``.

    The spline through every other row (twice the spacing, about 16 times the error)
    differs from the spline through all rows by about its own error. That difference
    vanishes at the rows they share, so the estimate at a point is its largest value
    (sampled at 8 points per row interval) over the row interval holding the point
    and the two beside it. NaN with fewer than 7 rows (no coarse spline).
    """
    if s[::2].size < 4:
        return np.full(at.shape, np.nan)
    coarse = CubicSpline(s[::2], Fn[::2])
    frac = (np.arange(8) + 0.5) / 8.0
    dense = s[:-1, None] + frac[None, :] * np.diff(s)[:, None]  # (n_rows - 1, 8)
    per_interval = np.max(np.abs(coarse(dense) - spline(dense)), axis=1)
    padded = np.concatenate(([0.0], per_interval, [0.0]))
    local = np.maximum(np.maximum(padded[:-2], padded[1:-1]), padded[2:])
    k = np.clip(np.searchsorted(s, at, side="right") - 1, 0, s.size - 2)
    return local[k]


def _mesh_error(br: Any) -> tuple[float, bool]:
    """Error of the column's rows on their fixed mesh, estimated at the column's two ends.

    The rows of a continued connection are solved on the mesh of the column's start
    (adapted at the start steepness) and carry no error estimates. At the lowest and
    the highest steepness of the branch the row's own estimates are computed as
    :func:`continuation.bvp.solve_connection` does (re-solve on the halved mesh and on
    ``1.5 T``, each change times 2), on the row's mesh as it is. The larger of the two
    ends is returned for the whole column: the start mesh fits the start best, so the
    error grows with the distance from it (checked against cold adapted solves at both
    ends of a column, ``tests/test_assessment_sweep.py``, and at cells over the
    standard grid, ``benchmarks/README.md``). When a row's estimate fails, the next row
    inwards is tried (three at most per end).

    Returns
    -------
    (float, bool)
        The error, and whether both ends were estimated.
    """
    order = np.argsort(np.asarray(br.p, dtype=float))
    worst, both = 0.0, True
    for rows in (order[:3], order[::-1][:3]):
        for k in rows:
            row = connection_at(br, int(k))
            if row.problem is None or not np.isfinite(row.residual_norm):
                continue
            fixed = row.problem.replace(vary=None, reference=None)
            est = solve_connection(fixed, (np.asarray(row.t), np.asarray(row.x)),
                                   accuracy=_ROW_ESTIMATE)  # fmt: skip
            if est.status is Status.INTERRUPTED:
                raise KeyboardInterrupt
            e = est.error("Fn") if est.success else math.nan
            if np.isfinite(e):
                worst = max(worst, e)
                break
        else:
            both = False
    return worst, both


def _first_start(
    model: SurgeModel, lam: FloatArray, i0: int, s_mid: float
) -> tuple[ConnectionResult, int]:
    """A cold start at the middle wavelength, else at the nearest one that has one.

    Raises
    ------
    ValueError
        When no wavelength of ``lam`` gives a connection at ``s_mid`` (the middle one's
        reason).
    """
    first: ValueError | None = None
    for i in sorted(range(lam.size), key=lambda k: (abs(k - i0), k)):
        try:
            res = surf_riding_connection(model, s_mid, float(lam[i]))
        except ValueError as exc:
            first = first or exc
            continue
        if res.success:
            return res, i
        first = first or ValueError(f"no connection at lambda/L = {lam[i]:g}: {res.message}")
    assert first is not None
    raise first


def exact_threshold_grid(
    model: SurgeModel,
    lambda_over_L: FloatArray,
    steepness: FloatArray,
    *,
    start: ConnectionResult | None = None,
    ds_max: float | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ExactGrid:
    """The exact threshold over the grid by continuation (module doc).

    Parameters
    ----------
    model : SurgeModel
    lambda_over_L : array_like, shape (n_lambda,)
    steepness : array_like, shape (n_s,)
        Increasing.
    start : ConnectionResult, optional
        A converged connection of ``model`` to start from (default: found at the middle
        wavelength and steepness by :func:`surf_riding_connection`, or where that has
        none, at the nearest wavelength that has one).
    ds_max : float, optional
        Largest continuation step (default 1/8 of the steepness range).
    progress : callable, optional
        ``progress(done_columns, n_columns)``.

    Returns
    -------
    ExactGrid
        A ``KeyboardInterrupt`` returns the columns finished so far (the others NaN,
        status ``"interrupted"``).

    Raises
    ------
    ValueError
        For a steepness grid that is not increasing, or when no wavelength has a
        connection at the middle steepness to start from.
    """
    t0 = time.perf_counter()
    lam = np.asarray(lambda_over_L, dtype=float)
    s = np.asarray(steepness, dtype=float)
    if s.size < 2 or np.any(np.diff(s) <= 0):
        raise ValueError("`steepness` must be increasing with at least 2 values")
    ds = (s[-1] - s[0]) / 8.0 if ds_max is None else float(ds_max)
    i0 = lam.size // 2
    s_mid = float(s[s.size // 2])
    if start is None:
        start, i0 = _first_start(model, lam, i0, s_mid)
    else:
        s_mid = float(start.params["H_over_lambda"])
        i0 = int(np.argmin(np.abs(lam - float(start.params["lambda_over_L"]))))
    Fn = np.full((lam.size, s.size), np.nan)
    err = np.full_like(Fn, np.nan)
    status = ["interrupted"] * lam.size
    steps, done = 0, 0
    try:
        for order in (range(i0, lam.size), range(i0 - 1, -1, -1)):
            prev = start
            for i in order:
                res = resolve_at(prev, lambda_over_L=float(lam[i]), H_over_lambda=s_mid)
                if res.status is Status.INTERRUPTED:
                    raise KeyboardInterrupt
                if not res.success:
                    try:
                        res = surf_riding_connection(model, s_mid, float(lam[i]))
                    except ValueError as exc:
                        status[i] = f"no start: {exc}"
                        continue
                if not res.success:
                    status[i] = f"no start: {res.message}"
                    continue
                col, e, n, st = _column(res, s, ds, model.forces)
                bvp_err = res.error("Fn")
                Fn[i], err[i], status[i] = col, e + (bvp_err if np.isfinite(bvp_err) else 0), st
                steps += n
                prev = res
                done += 1
                if progress is not None:
                    progress(done, lam.size)
    except KeyboardInterrupt:
        log.warning("interrupted: %d of %d columns finished", done, lam.size)
    return ExactGrid(lam, s, Fn, err, status, steps, time.perf_counter() - t0)


__all__ = [
    "ExactGrid",
    "exact_threshold_grid",
    "manifold_fate",
    "saddle_node_fn",
    "resolve_at",
    "surf_riding_connection",
]
