r"""Fixed points (surf-riding equilibria) of the ship model, found and traced as the paper does.

Umeda (1999), section "Fixed points": solve :math:`F(\bar x; b) = 0` (Eq. 13). For
:math:`\chi_c = 0` the lateral states vanish and Eq. (13) reduces to the uncoupled
surge model, solved "by a regula falsi method" (a bracketing root finder; we use
Brent's method, Brent 1973, *Algorithms for Minimization without Derivatives*, Ch. 4,
which keeps the bracket of regula falsi and converges superlinearly). There are
usually two fixed points per wave: a saddle near the crest and a stable point near
the trough. Each is lifted to the 8-state vector
``(xi_G, u = c, v = 0, chi = 0, r = 0, phi = 0, p_roll = 0, delta = 0)`` and traced
by pseudo-arclength continuation in ``chi_c`` (the paper's Figs. 2-5) or in ``Fn``.

:func:`fixed_points` returns every fixed point at one ``(Fn, chi_c)`` that is
connected to the ``chi_c = 0`` surge roots by a path of fixed points in ``chi_c``
(the crossings of the target course by the traced branches, including those past
folds), each polished by Newton's method and given its eigen-structure.
"""

from __future__ import annotations

import logging
import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.api import continue_equilibria
from continuation.branch import Branch, BranchPoint
from continuation.equilibria import solve_equilibrium, unique_equilibria
from continuation.params import Params
from continuation.settings import NewtonSettings
from continuation.status import Status
from continuation.typing import FloatArray

from ..contracts import VesselModel
from ..surge import SurgeModel
from ..umeda_4dof import follow_in_chi_c
from .eigen import EigenStructure, eigen_structure
from .params import describe_params, ship_params

log = logging.getLogger(__name__)

#: Default upper end of the course traced from chi_c = 0 (rad): the paper's Figs. 2-5.
CHI_C_MAX = math.radians(50.0)

_SURGE_CACHE: weakref.WeakKeyDictionary[Any, SurgeModel] = weakref.WeakKeyDictionary()


def surge_model_of(model: VesselModel) -> SurgeModel:
    """The uncoupled surge model sharing ``model``'s resolved vessel (cached per model)."""
    sm = _SURGE_CACHE.get(model)
    if sm is None:
        sm = SurgeModel(model.data)
        _SURGE_CACHE[model] = sm
    return sm


def position_label(xi: float) -> str:
    """``"crest"`` if ``xi_G/lambda`` (mod 1) is nearer the crest (0.5) than the trough (0)."""
    d = float(np.mod(xi, 1.0))
    return "crest" if abs(d - 0.5) < 0.25 else "trough"


@dataclass(frozen=True, eq=False)
class FixedPoint:
    """A fixed point of the ship model with its eigen-structure.

    Attributes
    ----------
    label : str
        ``"crest"`` or ``"trough"`` (:func:`position_label` of ``xi_G``), with a suffix
        ``"-2"``, ``"-3"``... when several points share a label.
    x : ndarray, shape (8,)
        The state, ``xi_G`` wrapped into [0, 1).
    params : Params
    eigen : EigenStructure
    residual_norm : float
        ``max |F(x; b)|`` after the Newton polish.
    """

    label: str
    x: FloatArray
    params: Params
    eigen: EigenStructure
    residual_norm: float

    @property
    def saddle_index(self) -> int:
        """Number of eigenvalues with positive real part."""
        return self.eigen.saddle_index

    @property
    def unstable_rate(self) -> float:
        """The largest real part of the eigenvalues, ``lambda_u`` of a saddle (1/s)."""
        return float(self.eigen.values[0].real)

    @property
    def stable(self) -> bool:
        """No eigenvalue with positive real part."""
        return self.eigen.saddle_index == 0

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready summary (angles also in degrees, nondimensional eigen-data)."""
        names = self.eigen.state_names
        d: dict[str, Any] = {
            "label": self.label,
            "state": {n: float(v) for n, v in zip(names, self.x, strict=True)},
            "state_deg": {
                n: float(np.degrees(self.x[names.index(n)]))
                for n in ("chi", "phi", "delta")
                if n in names
            },
            "params": self.params.as_dict(),
            "eigenvalues": [[float(z.real), float(z.imag)] for z in self.eigen.values],
            "eigenvalues_nondim": [
                [float(z.real), float(z.imag)] for z in self.eigen.values_nondim
            ],
            "saddle_index": self.saddle_index,
            "residual_norm": self.residual_norm,
        }
        if self.saddle_index >= 1 and abs(self.eigen.values[0].imag) == 0.0:
            v = self.eigen.unstable_vector(0)
            d["unstable_eigenvector_nondim"] = {n: float(c) for n, c in zip(names, v, strict=True)}
            d["dominant_components"] = list(self.eigen.dominant_components(0))
            d["dominant_motions"] = list(self.eigen.dominant_motions(0))
        return d


def lift_surge_point(model: VesselModel, xi: float, u: float) -> FloatArray:
    """The 8-state point ``(xi, u, 0, 0, 0, 0, 0, 0)`` of a chi_c = 0 surge fixed point."""
    x = np.zeros(model.n_states)
    x[model.index("xi_G")] = xi
    x[model.index("u")] = u
    return x


def surge_roots(
    model: VesselModel, params: Params | None = None, *, n_grid: int = 400
) -> list[FloatArray]:
    """Fixed points at ``chi_c = 0`` from the uncoupled surge model, lifted to 8 states.

    The surge force ``T(c; n) - R(c) + X_w(xi)`` is bracketed on ``n_grid`` intervals of
    one wavelength and each sign change is solved by Brent's method
    (:meth:`~ship_models.surge.SurgeModel.fixed_points`), then polished by Newton on the
    surge model.

    Parameters
    ----------
    model : VesselModel
    params : Params, optional
        Only ``Fn``, ``H_over_lambda`` and ``lambda_over_L`` are used (default: the
        model's defaults).
    n_grid : int
        Bracketing intervals per wavelength.

    Returns
    -------
    list of ndarray, shape (8,)
        Sorted by ``xi_G`` in [0, 1); empty when surf-riding is impossible at this ``Fn``.
    """
    par = ship_params(model, params)
    if not (isinstance(n_grid, int) and n_grid >= 4):
        raise ValueError(f"`n_grid` must be an integer >= 4, got {n_grid!r}")
    sm = surge_model_of(model)
    sp = sm.params(**{k: par[k] for k in sm.param_names})
    out = []
    for fp in sm.fixed_points(sp, n_grid=n_grid):
        if fp.newton.converged:
            out.append(lift_surge_point(model, float(fp.x[0]), float(fp.x[1])))
        else:  # pragma: no cover - Newton from a Brent root essentially never fails
            log.warning("surge fixed point near xi=%.4f did not converge", fp.x[0])
    return out


def trace_in_chi_c(
    model: VesselModel,
    params: Params | None = None,
    *,
    chi_c_max: float = CHI_C_MAX,
    ds: float = 0.01,
    ds_max: float = 0.02,
    max_steps: int = 2000,
    progress: Callable[[BranchPoint], None] | None = None,
) -> dict[str, Branch]:
    """Trace each ``chi_c = 0`` fixed point in the autopilot course (the paper's Figs. 2-5).

    Parameters
    ----------
    model : VesselModel
    params : Params, optional
        ``Fn`` and the wave/autopilot parameters; its ``chi_c`` is ignored.
    chi_c_max : float
        End of the course range (rad); negative values trace towards negative courses.
    ds, ds_max, max_steps
        Step control of :func:`~continuation.api.continue_equilibria`.
    progress : callable, optional
        Called with each accepted branch point.

    Returns
    -------
    dict of str to Branch
        Keyed by :func:`position_label` of the start (``"crest"``, ``"trough"``, with
        suffixes when a wave has more than two surge fixed points). Each branch runs
        from ``chi_c = 0`` to ``chi_c_max`` or, past a fold, back to ``chi_c = 0``;
        folds are located (``branch.find("fold")``). A ``KeyboardInterrupt`` inside
        a branch ends it with ``Status.INTERRUPTED`` and later branches are skipped.
    """
    par = ship_params(model, params).replace(chi_c=0.0)
    if not (math.isfinite(chi_c_max) and 0 < abs(chi_c_max) < math.pi / 2):
        raise ValueError(f"`chi_c_max` must be nonzero with |chi_c_max| < pi/2, got {chi_c_max}")
    out: dict[str, Branch] = {}
    for x0 in surge_roots(model, par):
        key = _unique_key(out, position_label(x0[0]))
        br = follow_in_chi_c(
            model, x0, par, chi_c_max, ds=ds, ds_max=ds_max, max_steps=max_steps, progress=progress
        )
        out[key] = br
        if br.status is Status.INTERRUPTED:
            break
    return out


def trace_in_fn(
    model: VesselModel,
    x0: FloatArray,
    params: Params | None = None,
    *,
    fn_min: float = 0.2,
    fn_max: float = 0.45,
    ds: float = 0.002,
    ds_max: float = 0.01,
    max_steps: int = 2000,
    progress: Callable[[BranchPoint], None] | None = None,
) -> Branch:
    """Trace a fixed point in the nominal Froude number at fixed ``chi_c``.

    Parameters
    ----------
    model : VesselModel
    x0 : ndarray, shape (8,)
        A fixed point (or a close guess) at ``params``.
    params : Params, optional
        Start ``Fn`` and fixed ``chi_c`` etc.
    fn_min, fn_max : float
        Range of ``Fn``.
    ds, ds_max, max_steps, progress
        As :func:`trace_in_chi_c`.

    Returns
    -------
    Branch
        Both directions from the start, ordered by arclength; folds located (in ``Fn``
        the crest and trough points typically merge in a fold at the lowest ``Fn``
        that allows surf-riding).
    """
    par = ship_params(model, params)
    if not (0 < fn_min < fn_max):
        raise ValueError(f"need 0 < fn_min < fn_max, got fn_min={fn_min}, fn_max={fn_max}")
    if not fn_min <= par["Fn"] <= fn_max:
        raise ValueError(f"`params['Fn']` = {par['Fn']} is outside [fn_min, fn_max]")
    return continue_equilibria(
        model,
        x0,
        par,
        "Fn",
        ds=ds,
        ds_max=ds_max,
        p_min=fn_min,
        p_max=fn_max,
        max_steps=max_steps,
        direction="both",
        progress=progress,
    )


def _unique_key(d: dict[str, Any], key: str) -> str:
    if key not in d:
        return key
    k = 2
    while f"{key}-{k}" in d:
        k += 1
    return f"{key}-{k}"


def _crossings(branch: Branch, target: float) -> list[FloatArray]:
    """Linear interpolation of the branch states where ``p`` crosses ``target``."""
    p, x = branch.p, branch.x
    out = []
    for k in range(len(p)):
        if p[k] == target:
            out.append(np.array(x[k]))
        elif k + 1 < len(p) and (p[k] - target) * (p[k + 1] - target) < 0:
            w = (target - p[k]) / (p[k + 1] - p[k])
            out.append((1 - w) * x[k] + w * x[k + 1])
    return out


def polish(
    model: VesselModel, x0: FloatArray, params: Params, settings: NewtonSettings | None = None
) -> FixedPoint | None:
    """Newton-polish a fixed point and compute its eigen-structure (None if no convergence)."""
    s = settings or NewtonSettings(tol=1e-10, step_tol=1e-10, max_iter=30)
    res = solve_equilibrium(model, x0, params, s, throw=False)
    if not res.converged:
        return None
    x = model.wrap(res.z)
    es = eigen_structure(model, x, params)
    return FixedPoint(position_label(x[0]), x, params, es, float(res.residual_norm))


def fixed_points(
    model: VesselModel,
    params: Params | None = None,
    *,
    chi_c_max: float | None = None,
    newton: NewtonSettings | None = None,
    tol: float = 1e-7,
) -> list[FixedPoint]:
    """Every fixed point at ``(Fn, chi_c)`` reachable from the ``chi_c = 0`` surge roots.

    Each surge root is traced in ``chi_c`` from 0 over ``[0, chi_c_max]`` (towards the
    sign of the target course); every crossing of the target course by a branch,
    including crossings past folds, is polished by Newton's method at the target.

    Parameters
    ----------
    model : VesselModel
    params : Params, optional
        Target parameters (default: the model's defaults, Fn = 0.3248, chi_c = 10 deg).
    chi_c_max : float, optional
        End of the traced course range (rad); default ``max(50 deg, |chi_c| + 10 deg)``
        with the sign of ``chi_c`` (capped below 85 deg).
    newton : NewtonSettings, optional
        Settings of the polish.
    tol : float
        Points closer than ``tol`` (max-norm, ``xi_G`` modulo 1) are the same.

    Returns
    -------
    list of FixedPoint
        Sorted crest first, then by ``xi_G``; labels made unique. Empty when no surge
        root exists at this ``Fn`` (surf-riding impossible).
    """
    par = ship_params(model, params)
    target = par["chi_c"]
    if not abs(target) < math.radians(85.0):
        raise ValueError(f"`params['chi_c']` must be within +-85 deg, got {target}")
    if chi_c_max is None:
        span = min(max(CHI_C_MAX, abs(target) + math.radians(10.0)), math.radians(85.0))
        chi_c_max = math.copysign(span, target if target != 0 else 1.0)
    if target != 0 and (chi_c_max * target < 0 or abs(chi_c_max) < abs(target)):
        raise ValueError(
            f"`chi_c_max` = {chi_c_max} must have the sign of chi_c and reach it ({target})"
        )
    guesses: list[FloatArray] = []
    if target == 0.0:
        guesses = surge_roots(model, par)
    else:
        # the first crossing of each branch (its primary point, no fold passed) comes
        # first, so that the plain labels "crest"/"trough" name the primary points
        branches = trace_in_chi_c(model, par, chi_c_max=chi_c_max)
        crossings = [_crossings(br, target) for br in branches.values()]
        guesses = [c[0] for c in crossings if c] + [g for c in crossings for g in c[1:]]
    pts = [fp for g in guesses if (fp := polish(model, g, par, newton)) is not None]
    keep = unique_equilibria(model, [fp.x for fp in pts], tol=tol)
    uniq = [next(fp for fp in pts if np.array_equal(fp.x, x)) for x in keep]
    uniq.sort(key=lambda fp: fp.label != "crest")  # stable: discovery order within a label
    labelled: list[FixedPoint] = []
    seen: dict[str, int] = {}
    for fp in uniq:
        seen[fp.label] = seen.get(fp.label, 0) + 1
        lab = fp.label if seen[fp.label] == 1 else f"{fp.label}-{seen[fp.label]}"
        labelled.append(FixedPoint(lab, fp.x, fp.params, fp.eigen, fp.residual_norm))
    return labelled


#: Widest Fn interval between two full traces across which :class:`FixedPointsInFn` tracks
#: the fixed points by Newton instead of tracing again.
MAX_TRACKED_GAP = 0.01


class FixedPointsInFn:
    r""":func:`fixed_points` at many ``Fn`` of one sea state and course, traced once per anchor.

    A bisection or scan in ``Fn`` needs every fixed point at each ``Fn`` it visits (the
    fate of a manifold names the points it reaches). :func:`fixed_points` traces each
    ``chi_c = 0`` surge root in the course every time (about 0.05 s). Here the full
    trace runs only at *anchors*; at an ``Fn`` strictly between two anchors ``a < b``
    with ``b - a <= max_gap`` whose point sets have the same signature (the same
    labels with the same saddle indices, in the same order), each point of the nearer
    anchor is polished by Newton's method at ``Fn`` (:func:`polish`) and accepted only
    if every one converges, keeps its label (:func:`position_label`) and saddle index,
    stays distinct from the others (``tol``) and lies near the chord between its two
    anchor points,

    .. math::  \|x(Fn) - [(1 - w)\, x_a + w\, x_b]\|_\infty \le
               \tfrac{1}{4} \|x_b - x_a\|_\infty + 10^{-7}, \quad w = \frac{Fn - a}{b - a},

    (the same branch of fixed points, not a neighbouring one); otherwise, and at every
    ``Fn`` outside such an interval, the full trace runs and its result becomes an anchor.
    Only anchors serve as starting points (no chain of tracked results).

    Claim: the result equals :func:`fixed_points` (to the Newton tolerance) unless a pair
    of fixed points is born and dies again inside one interval of at most ``max_gap``
    between two anchors (a fold in ``Fn`` on each side with the same set at both ends;
    a pair born or lost once changes the signature at one end, and a point of a tracked
    branch passing a fold changes its saddle index). This is the resolution the fate
    scans state for the fates themselves (``coarse_step`` 0.01 between plain points in
    :mod:`~ship_models.analysis.threshold`).

    Parameters
    ----------
    model : VesselModel
    params : Params
        The sea state and course; ``Fn`` is replaced per call.
    max_gap : float
        Widest anchor interval tracked across (nominal Froude number).
    tol : float
        As :func:`fixed_points`.
    """

    def __init__(
        self,
        model: VesselModel,
        params: Params,
        *,
        max_gap: float = MAX_TRACKED_GAP,
        tol: float = 1e-7,
    ) -> None:
        if not (isinstance(max_gap, (int, float)) and math.isfinite(max_gap) and max_gap >= 0):
            raise ValueError(f"`max_gap` must be a non-negative number, got {max_gap!r}")
        self.model = model
        self.params = ship_params(model, params)
        self.max_gap = float(max_gap)
        self.tol = tol
        self.anchors: dict[float, list[FixedPoint]] = {}
        #: Calls answered by tracking from an anchor / by the full trace.
        self.n_tracked = 0
        self.n_traced = 0

    @staticmethod
    def _signature(pts: list[FixedPoint]) -> tuple[tuple[str, int], ...]:
        return tuple((fp.label, fp.saddle_index) for fp in pts)

    def add(self, Fn: float, points: list[FixedPoint]) -> None:
        """Record the result of a full :func:`fixed_points` at ``Fn`` as an anchor."""
        self.anchors[float(Fn)] = list(points)

    def _tracked(self, Fn: float) -> list[FixedPoint] | None:
        below = [f for f in self.anchors if f < Fn]
        above = [f for f in self.anchors if f > Fn]
        if not below or not above:
            return None
        a, b = max(below), min(above)
        if b - a > self.max_gap + 1e-12:
            return None
        pa, pb = self.anchors[a], self.anchors[b]
        if not pa or self._signature(pa) != self._signature(pb):
            return None
        near = pa if Fn - a <= b - Fn else pb
        par = self.params.replace(Fn=Fn)
        w = (Fn - a) / (b - a)
        m = self.model
        out: list[FixedPoint] = []
        for src, xa, xb in zip(near, pa, pb, strict=True):
            fp = polish(m, src.x, par)
            if fp is None or fp.saddle_index != src.saddle_index:
                return None
            if position_label(fp.x[0]) != src.label.split("-")[0]:
                return None
            chord = xa.x + w * np.asarray(m.difference(xb.x, xa.x), dtype=float)
            off = float(np.max(np.abs(m.difference(fp.x, chord))))
            span = float(np.max(np.abs(m.difference(xb.x, xa.x))))
            if off > 0.25 * span + 1e-7:
                return None
            out.append(FixedPoint(src.label, fp.x, fp.params, fp.eigen, fp.residual_norm))
        if len(unique_equilibria(m, [fp.x for fp in out], tol=self.tol)) != len(out):
            return None
        return out

    def __call__(self, Fn: float) -> list[FixedPoint]:
        """Every fixed point at ``Fn`` (as :func:`fixed_points`; class notes)."""
        Fn = float(Fn)
        if Fn in self.anchors:
            return list(self.anchors[Fn])
        pts = self._tracked(Fn)
        if pts is not None:
            self.n_tracked += 1
            return pts
        self.n_traced += 1
        pts = fixed_points(self.model, self.params.replace(Fn=Fn), tol=self.tol)
        self.add(Fn, pts)
        return list(pts)


def find_fixed_point(
    model: VesselModel, params: Params | None = None, label: str = "crest", **kwargs: Any
) -> FixedPoint:
    """The fixed point with ``label`` (e.g. ``"crest"``) among :func:`fixed_points`.

    Raises
    ------
    ValueError
        If there is no such point at these parameters (e.g. ``Fn`` too low for
        surf-riding, or the branch folded before reaching ``chi_c``).
    """
    pts = fixed_points(model, params, **kwargs)
    for fp in pts:
        if fp.label == label:
            return fp
    raise ValueError(
        f"no {label} fixed point at {describe_params(ship_params(model, params))}; "
        f"found {', '.join(fp.label for fp in pts) or 'none'}"
    )


__all__ = [
    "CHI_C_MAX",
    "MAX_TRACKED_GAP",
    "FixedPoint",
    "FixedPointsInFn",
    "find_fixed_point",
    "fixed_points",
    "lift_surge_point",
    "polish",
    "position_label",
    "surge_model_of",
    "surge_roots",
    "trace_in_chi_c",
    "trace_in_fn",
]
