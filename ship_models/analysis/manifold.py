r"""Unstable manifolds of a ship saddle and the automatic classification of their fates.

Umeda (1999), section "Unstable manifolds and numerical experiments": a fixed point
of saddle index 1 has a one-dimensional unstable manifold :math:`W^u`, tangent at the
saddle to the eigenvector of its positive eigenvalue (stable manifold theorem,
Guckenheimer & Holmes 1983, *Nonlinear Oscillations, Dynamical Systems, and
Bifurcations of Vector Fields*, Sec. 1.3). Its two branches are computed "by
numerically integrating the state equation from the fixed point with a small
perturbation for the positive or negative direction of the eigenvector":

.. math::

    x(0) = \bar x \pm \varepsilon\, S\, y'_u, \qquad \dot x = F(x; b),

with :math:`y'_u` the unstable eigenvector in the paper's nondimensional states
(max-norm 1, ``xi_G`` component positive; :mod:`ship_models.analysis.eigen`) and
``S = diag(scales)``, so ``eps`` is a nondimensional distance. The ``+`` branch moves
the ship forward relative to the wave: from the crest saddle it runs down the front
face, the paper's *downslope* branch (:math:`0.5 < \xi_G/\lambda < 1`); the ``-``
branch is the *upslope* branch (the wave overtakes the ship).

Fates (:func:`classify_ship_fate`), decided while integrating in segments:

``capsize``
    :math:`|\phi|` passed the capsize angle (default: vanishing stability of GZ;
    :func:`~ship_models.analysis.events.capsize_event`), a terminal event.
``periodic``
    a periodic attractor: crossings ``k`` and ``k - m`` of the Poincare section
    :math:`\xi_G/\lambda = c \pmod 1` (``c`` half a wave from the saddle, where no
    fixed point lies) agree to ``return_tol`` in the nondimensional states, closer
    than crossings ``k - m`` and ``k - 2m`` (the ``m``-th return map contracts onto
    a fixed point; ``m = 1..max_lag``).
``recurrent``
    ``n_recurrent`` section crossings without capsize, equilibrium or a converged
    periodic orbit: bounded recurrent motion of the same (surging) kind, e.g. the
    irregular attractor next to the heteroclinic connection, where the orbit passes
    the saddles so closely that no short period settles. ``period`` is the return
    time and ``drift`` the wavelengths travelled per period (``-1``: overtaken by
    every wave, the ship's ordinary surging motion).
``equilibrium``
    within ``eq_radius`` of a *stable* fixed point (modulo whole wavelengths):
    stable surf-riding.
``saddle``
    within ``eq_radius`` of the same saddle at two consecutive segment ends: the
    branch converges onto a saddle (on an invariant subspace, e.g. the surge plane
    at ``chi_c = 0``, or exactly on a connection).
``undecided``
    none of these by ``t_max`` (or the integrator failed / was interrupted; see
    ``status``).

Every fate also lists the saddles the branch passed close to (``visits``: label,
shift in wavelengths, time and distance of closest approach, and the side of the
saddle's stable manifold on which it left, :attr:`SaddleVisit.side`), e.g. the paper's
"approaches a saddle next to the original saddle and then ..." (upslope or back down
the slope: the first-passage criterion of :mod:`ship_models.analysis.critical`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from continuation.dynamics import (
    EventHits,
    Fate,
    FateClassifier,
    FateKind,
    PoincareSection,
    SimEvent,
    Trajectory,
)
from continuation.dynamics import unstable_manifold as engine_unstable_manifold
from continuation.errors import ContinuationError
from continuation.params import Params
from continuation.status import Status
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .eigen import paper_scales
from .events import capsize_angle as capsize_angle_of
from .fixed_points import FixedPoint, find_fixed_point, fixed_points
from .outcomes import ShipOutcome
from .params import check_positive_fields, replace_settings, ship_params

log = logging.getLogger(__name__)

#: Branch names: sign of the displacement along the unstable eigenvector.
BRANCH_SIGNS = {"downslope": 1.0, "upslope": -1.0}


@dataclass(frozen=True)
class SaddleVisit:
    """A close approach of a trajectory to a saddle (possibly shifted by whole waves).

    Attributes
    ----------
    label : str
        Label of the fixed point (:class:`~ship_models.analysis.fixed_points.FixedPoint`).
    shift : int
        Wavelengths: the point visited is ``xi_G = xi_fp + shift``.
    t : float
        Time of closest approach (s).
    distance : float
        Nondimensional max-norm distance there.
    side : int
        Side of that saddle's stable manifold on which the trajectory left it: the
        sign of its coordinate along the saddle's unstable eigenvector (oriented with
        ``xi_G`` increasing) on leaving, so ``-1`` continues upslope (the wave
        overtakes the ship) and ``+1`` turns back down the slope; ``0`` if unknown
        (:class:`continuation.dynamics.fates.SaddleVisit`).
    """

    label: str
    shift: int
    t: float
    distance: float
    side: int = 0


@dataclass(frozen=True)
class ShipFate:
    """Where a trajectory goes.

    Attributes
    ----------
    kind : ShipOutcome
        One of :data:`~ship_models.analysis.outcomes.FATE_KINDS`.
    t : float
        Time at which the fate was decided (s).
    visits : tuple of SaddleVisit
        Saddles passed close to, in time order.
    period : float or None
        Return time of the periodic attractor (s).
    drift : int or None
        Wavelengths travelled per period relative to the wave.
    returns : int or None
        Section crossings per period of a periodic orbit.
    equilibrium : str or None
        Label of the fixed point reached (``equilibrium`` and ``saddle`` fates).
    shift : int or None
        Its shift in wavelengths.
    status : Status
        ``SUCCESS`` when decided, else why not (``MAX_STEPS`` for the time limit,
        ``INTEGRATION_FAILED``, ``INTERRUPTED``).
    message : str
    """

    kind: ShipOutcome
    t: float
    visits: tuple[SaddleVisit, ...] = ()
    period: float | None = None
    drift: int | None = None
    returns: int | None = None
    equilibrium: str | None = None
    shift: int | None = None
    status: Status = Status.SUCCESS
    message: str = ""

    @property
    def label(self) -> str:
        """Short name: ``"capsize"``, ``"periodic"``, ``"equilibrium:<label>"``, ..."""
        if self.kind in (ShipOutcome.EQUILIBRIUM, ShipOutcome.SADDLE):
            return f"{self.kind}:{self.equilibrium}"
        return self.kind

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            "kind": self.kind,
            "label": self.label,
            "t": self.t,
            "period": self.period,
            "drift": self.drift,
            "returns": self.returns,
            "equilibrium": self.equilibrium,
            "shift": self.shift,
            "visits": [
                {
                    "label": v.label,
                    "shift": v.shift,
                    "t": v.t,
                    "distance": v.distance,
                    "side": v.side,
                }
                for v in self.visits
            ],
            "status": self.status.name,
            "message": self.message,
        }


def _ship_fate(
    fate: Fate,
    hits: Any,
    n_recurrent: int,
    max_lag: int,
    points: Sequence[FixedPoint],
    scales: FloatArray,
    match_tol: float,
) -> ShipFate:
    """Translate a generic :class:`~continuation.dynamics.fates.Fate` into a :class:`ShipFate`."""
    visits = tuple(
        SaddleVisit(
            v.name, int(v.shift[0]) if v.shift else 0, float(v.t), float(v.distance), int(v.side)
        )
        for v in fate.visits
    )
    shift = int(fate.shift[0]) if fate.shift else 0
    common = {"t": float(fate.t), "visits": visits, "message": fate.message}
    kind = fate.kind
    if kind is FateKind.EVENT and fate.name == ShipOutcome.CAPSIZE:
        return ShipFate(ShipOutcome.CAPSIZE, **common)
    if kind is FateKind.PERIODIC:
        return ShipFate(
            ShipOutcome.PERIODIC,
            period=fate.period,
            drift=shift,
            returns=fate.multiplicity,
            **common,
        )
    if kind in (FateKind.EQUILIBRIUM, FateKind.SADDLE):
        k = ShipOutcome.EQUILIBRIUM if kind is FateKind.EQUILIBRIUM else ShipOutcome.SADDLE
        name = fate.name
        if fate.index is None and fate.x_equilibrium is not None:
            # an equilibrium the classifier found by itself: match it to a known point
            for fp in points:
                d = np.asarray(fate.x_equilibrium, dtype=float) - fp.x
                kk = round(d[0])
                d[0] -= kk
                if np.max(np.abs(d) / scales) < match_tol:
                    name, shift = fp.label, int(kk)
                    break
        return ShipFate(k, equilibrium=name, shift=shift, **common)
    if kind is FateKind.UNDECIDED and fate.status is Status.SUCCESS and len(hits) >= n_recurrent:
        m = len(hits) - 1
        return ShipFate(
            ShipOutcome.RECURRENT,
            period=float((hits.t[-1] - hits.t[0]) / m),
            drift=int(round((hits.x[-1, 0] - hits.x[0, 0]) / m)),
            t=float(fate.t),
            visits=visits,
            message=(
                f"{len(hits)} section crossings without capsize, equilibrium or a converged "
                f"periodic orbit (up to {max_lag} returns): bounded recurrent motion"
            ),
        )
    status = fate.status
    if kind is FateKind.UNDECIDED and status is Status.SUCCESS:
        status = Status.MAX_STEPS
    return ShipFate(ShipOutcome.UNDECIDED, status=status, **common)


@dataclass(frozen=True)
class ShipFateSettings:
    """Settings of the ship's fate classification (:func:`classify_ship_fate`).

    Attributes
    ----------
    capsize_angle : float, optional
        Roll angle (rad) of the capsize event; default: vanishing stability of GZ.
    t_max : float
        Time limit (s); the fate is ``undecided`` (or ``recurrent``) if reached.
    segment : float
        Length of one integration segment (s): the fate is checked, and ``progress``
        called with the time reached, after each.
    dt : float
        Output sample spacing (s), also the event-detection resolution.
    section : float, optional
        Poincare section level of ``xi_G/lambda`` (mod 1); default half a wave from
        the first saddle in ``points`` (0 if there is none).
    return_tol : float
        Section crossings ``k`` and ``k - m`` closer than this (nondimensional
        max-norm) make the fate ``periodic`` (an orbit of ``m`` returns); also the
        distance to a fixed point that counts as having reached it.
    max_lag : int
        Largest number of returns ``m`` of a periodic orbit looked for.
    n_recurrent : int
        With at least this many section crossings by ``t_max`` and no other fate, the
        fate is ``recurrent``.
    visit_radius : float
        Distance to a saddle that counts as a visit.
    rtol, atol : float
        Integrator tolerances (CVODES BDF, :mod:`continuation.dynamics.simulate`).

    Raises
    ------
    ValueError
        On construction, naming a non-positive field.
    """

    capsize_angle: float | None = None
    t_max: float = 600.0
    segment: float = 50.0
    dt: float = 0.05
    section: float | None = None
    return_tol: float = 1e-4
    max_lag: int = 4
    n_recurrent: int = 30
    visit_radius: float = 0.1
    rtol: float = 1e-9
    atol: float = 1e-11

    def __post_init__(self) -> None:
        check_positive_fields(
            self,
            ("t_max", "segment", "dt", "return_tol", "max_lag", "n_recurrent", "visit_radius",
             "rtol", "atol"),
        )  # fmt: skip

    def replace(self, **changes: Any) -> ShipFateSettings:
        """A copy with ``changes``; unknown names raise a ValueError naming them."""
        return replace_settings(self, "fate", **changes)


def classify_ship_fate(
    model: VesselModel,
    params: Params,
    x0: FloatArray,
    *,
    points: Sequence[FixedPoint],
    settings: ShipFateSettings | None = None,
    progress: Callable[[float], None] | None = None,
    **options: Any,
) -> tuple[Trajectory, ShipFate]:
    """Integrate from ``x0`` in segments until the fate is known (see module notes).

    The generic :class:`continuation.dynamics.fates.FateClassifier` does the work; this function
    supplies the ship's capsize event, Poincare section, nondimensional distance and
    fixed points, and adds the ``recurrent`` fate.

    Parameters
    ----------
    model : VesselModel
    params : Params
    x0 : ndarray, shape (8,)
    points : sequence of FixedPoint
        The fixed points at ``params`` (saddles for ``visits`` and the ``saddle``
        fate, stable points for the ``equilibrium`` fate), e.g. from
        :func:`~ship_models.analysis.fixed_points`.
    settings : ShipFateSettings, optional
        Time limit, segments, tolerances (default ``ShipFateSettings()``).
    progress : callable, optional
        ``progress(t)`` after each segment.
    **options
        Fields of :class:`ShipFateSettings` replaced in ``settings`` (``t_max=...``).

    Returns
    -------
    trajectory : Trajectory
        The whole run (``xi_G`` unwrapped).
    fate : ShipFate

    Raises
    ------
    ValueError
        For non-positive settings or unknown option names.
    """
    cfg = (settings or ShipFateSettings()).replace(**options)
    capsize_angle, t_max, segment, dt = cfg.capsize_angle, cfg.t_max, cfg.segment, cfg.dt
    section, return_tol, max_lag = cfg.section, cfg.return_tol, cfg.max_lag
    n_recurrent, visit_radius, rtol, atol = cfg.n_recurrent, cfg.visit_radius, cfg.rtol, cfg.atol
    x0 = model.check_state(x0, "x0")
    pts = list(points)
    saddles = [fp for fp in pts if fp.saddle_index >= 1]
    scales, _ = paper_scales(model, params, saddles[0].x if saddles else x0)
    if section is None:
        section = float(np.mod(saddles[0].x[0] + 0.5, 1.0)) if saddles else 0.0
    phi_cap = capsize_angle_of(model, capsize_angle)
    i_phi = model.state_index("phi")
    capsize = SimEvent(
        ShipOutcome.CAPSIZE,
        lambda t, x: np.abs(np.asarray(x)[..., i_phi]) - phi_cap,
        terminal=True,
        direction=1,
        vectorized=True,
    )
    sec = PoincareSection("xi_G", float(section), name="section")
    clf = FateClassifier(
        model,
        params,
        equilibria={fp.label: fp.x for fp in pts},
        events=(capsize,),
        poincare=sec,
        tol=return_tol,
        saddle_radius=visit_radius,
        scale=scales,
        t_max=t_max,
        segment=segment,
        dt=dt,
        max_multiplicity=int(max_lag),
        rtol=rtol,
        atol=atol,
    )
    cb = None if progress is None else (lambda t, x: progress(t))
    fate = clf.classify(x0, progress=cb)
    traj = fate.trajectory
    if traj is None:  # pragma: no cover - the classifier always attaches it
        raise ContinuationError("fate classification returned no trajectory")
    hits = traj.events.get("section")
    if hits is None:
        hits = EventHits(np.zeros(0), np.zeros((0, x0.size)))
    return traj, _ship_fate(
        fate, hits, int(n_recurrent), int(max_lag), pts, scales, 1e3 * return_tol
    )


@dataclass(frozen=True, eq=False)
class ManifoldBranch:
    """One branch of the unstable manifold.

    Attributes
    ----------
    name : str
        ``"downslope"`` (``+`` eigenvector, ``xi_G`` increasing) or ``"upslope"``.
    sign : float
        ``+1`` or ``-1``.
    x0 : ndarray, shape (8,)
        Start ``x_s + sign * eps * S y'_u``.
    trajectory : Trajectory
    fate : ShipFate
    """

    name: str
    sign: float
    x0: FloatArray
    trajectory: Trajectory
    fate: ShipFate


@dataclass(frozen=True, eq=False)
class ShipManifold:
    """Both branches of the unstable manifold of a saddle of index 1.

    Attributes
    ----------
    saddle : FixedPoint
    params : Params
    eps : float
    branches : dict of str to ManifoldBranch
        ``"downslope"`` and ``"upslope"``.
    points : tuple of FixedPoint
        All fixed points used for the classification.
    """

    saddle: FixedPoint
    params: Params
    eps: float
    branches: dict[str, ManifoldBranch] = field(default_factory=dict)
    points: tuple[FixedPoint, ...] = ()

    @property
    def fates(self) -> dict[str, str]:
        """``{branch name: fate label}``."""
        return {k: b.fate.label for k, b in self.branches.items()}

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (no trajectories)."""
        return {
            "saddle": self.saddle.to_json(),
            "eps": self.eps,
            "branches": {
                k: {
                    "sign": b.sign,
                    "x0": [float(v) for v in b.x0],
                    "t_end": b.trajectory.t_final,
                    "x_end": [float(v) for v in b.trajectory.x_final],
                    "max_abs_phi_deg": float(np.degrees(np.max(np.abs(b.trajectory.x[:, 5])))),
                    "fate": b.fate.to_json(),
                }
                for k, b in self.branches.items()
            },
        }


def _engine_eps(saddle: FixedPoint, eps: float) -> float:
    """``eps |y'_u|_2``: the engine's start distance for the ship's nondimensional ``eps``.

    :func:`continuation.dynamics.manifolds.unstable_manifold` starts at ``x_s + sign eps_2 v``
    with ``v`` the unstable eigenvector of unit ``||v / S||_2`` (``S = scales``), i.e.
    ``v = S y'_u / |y'_u|_2`` with ``y'_u`` the nondimensional eigenvector of max-norm 1.
    """
    y = saddle.eigen.unstable_vector(0, nondim=True)
    return float(eps) * float(np.linalg.norm(y))


def manifold_start(saddle: FixedPoint, eps: float, sign: float) -> FloatArray:
    """``x_s + sign * eps * S y'_u``: the start of one unstable-manifold branch, shape (8,).

    Computed as the engine's :func:`continuation.dynamics.manifolds.unstable_manifold` does
    (``x_s + sign eps_2 v``, ``v`` the real eigenvector of the largest eigenvalue of unit
    scale-weighted 2-norm, ``xi_G`` component positive, ``eps_2`` from
    :func:`_engine_eps`), so it is the start point of :func:`unstable_manifold` to the bit.
    """
    s = np.asarray(saddle.eigen.scales, dtype=float)
    v = np.real(saddle.eigen.vectors[:, 0])
    v = v / np.linalg.norm(v / s)
    if v[list(saddle.eigen.state_names).index("xi_G")] < 0:
        v = -v
    return np.asarray(saddle.x + sign * _engine_eps(saddle, eps) * v, dtype=float)


def unstable_manifold(
    model: VesselModel,
    params: Params | None = None,
    saddle: FixedPoint | str = "crest",
    *,
    eps: float = 1e-6,
    branches: Sequence[str] = ("downslope", "upslope"),
    points: Sequence[FixedPoint] | None = None,
    settings: ShipFateSettings | None = None,
    progress: Callable[[str, float], None] | None = None,
    **options: Any,
) -> ShipManifold:
    """Both branches of the unstable manifold of a ship saddle, with their fates.

    Parameters
    ----------
    model : VesselModel
    params : Params, optional
        Default: the model's defaults (``ship_models.paper``: Fn = 0.3248, chi_c = 10 deg).
    saddle : FixedPoint or str
        The saddle, or its label among :func:`~ship_models.analysis.fixed_points`
        (default ``"crest"``: the point near the wave crest, as in the paper).
    eps : float
        Nondimensional initial displacement along the unstable eigenvector.
    branches : sequence of str
        Which of ``"downslope"``, ``"upslope"`` to compute.
    points : sequence of FixedPoint, optional
        Fixed points for the classification (default: all at ``params``).
    settings : ShipFateSettings, optional
        The classification of each branch (time limit ``t_max``, ``capsize_angle``,
        ``segment``, ``dt``, ``return_tol``, ``visit_radius``, ``section``, ...).
    progress : callable, optional
        ``progress(branch_name, t)`` after each integration segment.
    **options
        Fields of :class:`ShipFateSettings` replaced in ``settings``.

    Returns
    -------
    ShipManifold

    Raises
    ------
    ValueError
        If the saddle does not have exactly one unstable eigenvalue, which must be
        real; for ``eps`` outside (0, 0.1); for an unknown branch name.
    """
    par = ship_params(model, params)
    cfg = (settings or ShipFateSettings()).replace(**options)
    if not (isinstance(eps, (int, float)) and 0 < eps < 0.1):
        raise ValueError(f"`eps` must be in (0, 0.1), got {eps!r}")
    bad = [b for b in branches if b not in BRANCH_SIGNS]
    if bad or not branches:
        raise ValueError(f"`branches` must name some of {tuple(BRANCH_SIGNS)}, got {branches!r}")
    pts = tuple(points) if points is not None else tuple(fixed_points(model, par))
    if isinstance(saddle, str):
        match = [fp for fp in pts if fp.label == saddle]
        sp = match[0] if match else find_fixed_point(model, par, saddle)
    else:
        sp = saddle
    if sp.saddle_index != 1:
        raise ValueError(
            f"`saddle` {sp.label!r} has saddle index {sp.saddle_index}; a one-dimensional "
            "unstable manifold needs exactly one unstable eigenvalue"
        )
    lam = sp.eigen.values[0]
    if lam.imag != 0.0:
        raise ValueError(f"`saddle` {sp.label!r}: unstable eigenvalue {lam} is not real")
    eps_2 = _engine_eps(sp, eps)  # the engine's distance for x_s + sign eps S y'_u
    out: dict[str, ManifoldBranch] = {}
    for name in branches:
        sign = BRANCH_SIGNS[name]
        cb = None if progress is None else (lambda t, _n=name: progress(_n, t))
        found: dict[str, Any] = {}

        def classify_branch(x0: FloatArray, _cb: Any = cb, _found: dict = found) -> ShipFate:
            _found["trajectory"], fate = classify_ship_fate(
                model, par, x0, points=pts, settings=cfg, progress=_cb
            )
            return fate

        man = engine_unstable_manifold(
            model,
            np.asarray(par.values, dtype=float),
            sp.x,
            eps=eps_2,
            classify=classify_branch,
            branches=(int(sign),),
            orient="xi_G",
            scale=sp.eigen.scales,
            refine=False,
        )
        br = man.branch(int(sign)) if man.branches else None
        if br is None:  # interrupted before the branch was classified
            break
        fate = br.fate
        out[name] = ManifoldBranch(name, sign, br.x0, found["trajectory"], fate)
        log.debug("%s branch of %s: %s (%s)", name, sp.label, fate.label, fate.message)
        if fate.status is Status.INTERRUPTED:
            break
    return ShipManifold(sp, par, float(eps), out, pts)


__all__ = [
    "BRANCH_SIGNS",
    "ManifoldBranch",
    "SaddleVisit",
    "ShipFate",
    "ShipManifold",
    "classify_ship_fate",
    "manifold_start",
    "unstable_manifold",
]
