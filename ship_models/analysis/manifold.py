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
shift in wavelengths, time and distance of closest approach), e.g. the paper's
"approaches a saddle next to the original saddle and then ...".
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from continuation._types import FloatArray
from continuation.params import Params
from continuation.simulate import EventHits, PoincareSection, Simulator, Trajectory
from continuation.status import Status

from .eigen import paper_scales
from .events import capsize_event
from .fixed_points import FixedPoint, find_fixed_point, fixed_points

log = logging.getLogger(__name__)

CAPSIZE, PERIODIC, RECURRENT = "capsize", "periodic", "recurrent"
EQUILIBRIUM, SADDLE, UNDECIDED = "equilibrium", "saddle", "undecided"
#: Fate kinds, in the order of the module documentation.
FATE_KINDS = (CAPSIZE, PERIODIC, RECURRENT, EQUILIBRIUM, SADDLE, UNDECIDED)
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
    """

    label: str
    shift: int
    t: float
    distance: float


@dataclass(frozen=True)
class ShipFate:
    """Where a trajectory goes.

    Attributes
    ----------
    kind : str
        One of :data:`FATE_KINDS`.
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

    kind: str
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
        if self.kind in (EQUILIBRIUM, SADDLE):
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
                {"label": v.label, "shift": v.shift, "t": v.t, "distance": v.distance}
                for v in self.visits
            ],
            "status": self.status.name,
            "message": self.message,
        }


def _scaled_distance(
    x: FloatArray, ref: FloatArray, scales: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Max-norm nondimensional distance of samples ``x (M, n)`` to ``ref + k e_xi``.

    Returns the distances ``(M,)`` and the nearest whole-wave shifts ``k (M,)``.
    """
    k = np.round(x[:, 0] - ref[0])
    d = x - ref[None, :]
    d[:, 0] -= k
    return np.max(np.abs(d) / scales[None, :], axis=1), k


def _join(pieces: Sequence[Trajectory]) -> Trajectory:
    """One trajectory from consecutive pieces (each starts where the previous ends)."""
    first, last = pieces[0], pieces[-1]
    n = first.n_states
    names = list(dict.fromkeys(k for p in pieces for k in p.events))
    events = {
        nm: EventHits(
            np.concatenate([p.events[nm].t for p in pieces if nm in p.events]),
            np.concatenate([p.events[nm].x.reshape(-1, n) for p in pieces if nm in p.events]),
        )
        for nm in names
    }
    return Trajectory(
        np.concatenate([first.t, *(p.t[1:] for p in pieces[1:])]),
        np.concatenate([first.x, *(p.x[1:] for p in pieces[1:])]),
        events,
        last.status,
        last.message,
        first.state_names,
        first.period,
        last.terminal_event,
        None,
        first.params,
        first.method,
    )


def _return_distance(model: Any, xs: FloatArray, k: int, lag: int, scales: FloatArray) -> float:
    """Nondimensional distance between section crossings ``k`` and ``k - lag``."""
    d = model.difference(xs[k], xs[k - lag]) / scales
    d[0] = 0.0  # both on the section; xi_G differs by whole waves
    return float(np.max(np.abs(d)))


def _periodic_fate(
    model: Any, hits: Any, scales: FloatArray, tol: float, max_lag: int, t: float
) -> ShipFate | None:
    """``periodic`` if crossing ``k`` repeats crossing ``k - m`` (m <= max_lag), contracting."""
    n = len(hits)
    for lag in range(1, max_lag + 1):
        if n < 2 * lag + 1:
            break
        d1 = _return_distance(model, hits.x, n - 1, lag, scales)
        d2 = _return_distance(model, hits.x, n - 1 - lag, lag, scales)
        if d1 < tol and d1 <= d2:
            return ShipFate(
                PERIODIC,
                t,
                period=float(hits.t[-1] - hits.t[-1 - lag]),
                drift=int(round(hits.x[-1, 0] - hits.x[-1 - lag, 0])),
                returns=lag,
                message=f"Poincare return {lag} agrees to {d1:.2e} (previous {d2:.2e})",
            )
    return None


def saddle_visits(
    traj: Trajectory,
    saddles: Sequence[FixedPoint],
    scales: FloatArray,
    radius: float,
) -> tuple[SaddleVisit, ...]:
    """Close approaches (distance ``< radius``) of ``traj`` to the saddles, in time order.

    An approach is one maximal run of samples inside the radius; the run that contains
    the first sample (the start, e.g. the saddle the manifold leaves) and one still
    under way at the last sample are not counted.
    """
    visits: list[SaddleVisit] = []
    for fp in saddles:
        d, k = _scaled_distance(np.asarray(traj.x), fp.x, scales)
        inside = d < radius
        if not inside.any():
            continue
        edges = np.diff(np.concatenate([[0], inside.astype(int), [0]]))
        starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
        for a, b in zip(starts, ends, strict=True):
            if a == 0 or b == d.size:  # the start region, or an approach still under way
                continue
            j = a + int(np.argmin(d[a:b]))
            visits.append(SaddleVisit(fp.label, int(k[j]), float(traj.t[j]), float(d[j])))
    visits.sort(key=lambda v: v.t)
    return tuple(visits)


def classify_ship_fate(
    model: Any,
    params: Params,
    x0: FloatArray,
    *,
    points: Sequence[FixedPoint],
    capsize_angle: float | None = None,
    t_max: float = 600.0,
    segment: float = 50.0,
    dt: float = 0.05,
    section: float | None = None,
    return_tol: float = 1e-4,
    max_lag: int = 4,
    n_recurrent: int = 30,
    eq_radius: float = 1e-3,
    visit_radius: float = 0.1,
    progress: Callable[[float], None] | None = None,
    rtol: float = 1e-9,
    atol: float = 1e-11,
) -> tuple[Trajectory, ShipFate]:
    """Integrate from ``x0`` in segments until the fate is known (see module notes).

    Parameters
    ----------
    model : Umeda4DOF
    params : Params
    x0 : ndarray, shape (8,)
    points : sequence of FixedPoint
        The fixed points at ``params`` (saddles for ``visits``, stable points for the
        ``equilibrium`` fate), e.g. from :func:`~ship_models.analysis.fixed_points`.
    capsize_angle : float, optional
        Roll angle (rad) of the capsize event; default: vanishing stability of GZ.
    t_max : float
        Time limit (s); the fate is ``undecided`` if reached.
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
        max-norm), and closer than crossings ``k - m`` and ``k - 2m``, make the fate
        ``periodic`` (an orbit of ``m`` returns).
    max_lag : int
        Largest number of returns ``m`` of a periodic orbit looked for.
    n_recurrent : int
        After this many section crossings without another fate, the fate is
        ``recurrent``.
    eq_radius : float
        Distance to a fixed point that counts as having reached it.
    visit_radius : float
        Distance to a saddle that counts as a visit.
    progress : callable, optional
        ``progress(t)`` after each segment.
    rtol, atol : float
        Integrator tolerances (CVODES BDF, :mod:`continuation.simulate`).

    Returns
    -------
    trajectory : Trajectory
        The whole run (``xi_G`` unwrapped).
    fate : ShipFate

    Raises
    ------
    ValueError
        For non-positive ``t_max``, ``segment``, ``dt`` or tolerances.
    """
    for name, val in (
        ("t_max", t_max),
        ("segment", segment),
        ("dt", dt),
        ("return_tol", return_tol),
        ("max_lag", max_lag),
        ("n_recurrent", n_recurrent),
        ("eq_radius", eq_radius),
        ("visit_radius", visit_radius),
    ):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise ValueError(f"`{name}` must be a positive number, got {val!r}")
    x0 = model.check_state(x0, "x0")
    pts = list(points)
    saddles = [fp for fp in pts if fp.saddle_index >= 1]
    scales, _ = paper_scales(model, params, saddles[0].x if saddles else x0)
    if section is None:
        section = float(np.mod(saddles[0].x[0] + 0.5, 1.0)) if saddles else 0.0
    watch = [
        capsize_event(model, capsize_angle),
        PoincareSection("xi_G", float(section), name="section"),
    ]
    sim = Simulator(model, params, rtol=rtol, atol=atol)
    pieces: list[Trajectory] = []
    sec_t: list[float] = []
    sec_x: list[FloatArray] = []
    x, t = x0, 0.0
    fate: ShipFate | None = None
    near_before: list[tuple[str, int]] = []
    while fate is None:
        t1 = min(t + segment, t_max)
        n = max(1, round((t1 - t) / dt))
        piece = sim.run(x, (t, t1), events=watch, dt=(t1 - t) / n)
        pieces.append(piece)
        sec_t.extend(piece.events["section"].t)
        sec_x.extend(piece.events["section"].x)
        t, x = piece.t_final, piece.x_final
        if progress is not None:
            progress(t)
        if piece.status is Status.EVENT and piece.terminal_event == "capsize":
            fate = ShipFate(CAPSIZE, t, message=f"|phi| reached the capsize angle at t={t:.6g} s")
            break
        if piece.status is not Status.SUCCESS:
            fate = ShipFate(UNDECIDED, t, status=piece.status, message=piece.message)
            break
        hits = EventHits(np.array(sec_t), np.array(sec_x).reshape(len(sec_t), x0.size))
        fate = _periodic_fate(model, hits, scales, return_tol, max_lag, t)
        if fate is None and len(hits) >= n_recurrent:
            fate = ShipFate(
                RECURRENT,
                t,
                period=float((hits.t[-1] - hits.t[0]) / (len(hits) - 1)),
                drift=int(round((hits.x[-1, 0] - hits.x[0, 0]) / (len(hits) - 1))),
                message=(
                    f"{len(hits)} section crossings without capsize and without a converged "
                    f"periodic orbit (up to {max_lag} returns): bounded recurrent motion"
                ),
            )
        if fate is not None:
            break
        near_now = []
        for fp in pts:
            dist, k = _scaled_distance(x[None, :], fp.x, scales)
            if dist[0] < eq_radius:
                near_now.append((fp.label, int(k[0])))
                if fp.stable or (fp.label, int(k[0])) in near_before:
                    fate = ShipFate(
                        EQUILIBRIUM if fp.stable else SADDLE,
                        t,
                        equilibrium=fp.label,
                        shift=int(k[0]),
                        message=(
                            f"within {dist[0]:.1e} of the "
                            f"{'stable point' if fp.stable else 'saddle'} {fp.label} "
                            f"(shifted {int(k[0])} waves)"
                        ),
                    )
                    break
        near_before = near_now
        if fate is None and t >= t_max:
            fate = ShipFate(
                UNDECIDED,
                t,
                status=Status.MAX_STEPS,
                message=f"no fate decided by t_max = {t_max:g} s; increase `t_max`",
            )
    traj = _join(pieces)
    fate = dataclasses.replace(fate, visits=saddle_visits(traj, saddles, scales, visit_radius))
    return traj, fate


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


def manifold_start(saddle: FixedPoint, eps: float, sign: float) -> FloatArray:
    """``x_s + sign * eps * S y'_u``: the start of one unstable-manifold branch, shape (8,)."""
    y = saddle.eigen.unstable_vector(0, nondim=True)
    return np.asarray(saddle.x + sign * eps * saddle.eigen.scales * y, dtype=float)


def unstable_manifold(
    model: Any,
    params: Params | None = None,
    saddle: FixedPoint | str = "crest",
    *,
    eps: float = 1e-6,
    t_max: float = 600.0,
    branches: Sequence[str] = ("downslope", "upslope"),
    points: Sequence[FixedPoint] | None = None,
    capsize_angle: float | None = None,
    progress: Callable[[str, float], None] | None = None,
    **classify: Any,
) -> ShipManifold:
    """Both branches of the unstable manifold of a ship saddle, with their fates.

    Parameters
    ----------
    model : Umeda4DOF
    params : Params, optional
        Default: the model's defaults (Fn = 0.3248, chi_c = 10 deg).
    saddle : FixedPoint or str
        The saddle, or its label among :func:`~ship_models.analysis.fixed_points`
        (default ``"crest"``: the point near the wave crest, as in the paper).
    eps : float
        Nondimensional initial displacement along the unstable eigenvector.
    t_max : float
        Time limit of each branch (s).
    branches : sequence of str
        Which of ``"downslope"``, ``"upslope"`` to compute.
    points : sequence of FixedPoint, optional
        Fixed points for the classification (default: all at ``params``).
    capsize_angle : float, optional
        Roll angle of capsize (rad); default the vanishing angle of GZ.
    progress : callable, optional
        ``progress(branch_name, t)`` after each integration segment.
    **classify
        Further options of :func:`classify_ship_fate` (``segment``, ``dt``,
        ``return_tol``, ``eq_radius``, ``visit_radius``, ``section``).

    Returns
    -------
    ShipManifold

    Raises
    ------
    ValueError
        If the saddle does not have exactly one unstable eigenvalue, which must be
        real; for ``eps`` outside (0, 0.1); for an unknown branch name.
    """
    par = (
        model.default_params()
        if params is None
        else Params(model.param_names, model.check_params(params, "params"))
    )
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
    out: dict[str, ManifoldBranch] = {}
    for name in branches:
        sign = BRANCH_SIGNS[name]
        x0 = manifold_start(sp, eps, sign)
        cb = None if progress is None else (lambda t, _n=name: progress(_n, t))
        traj, fate = classify_ship_fate(
            model,
            par,
            x0,
            points=pts,
            capsize_angle=capsize_angle,
            t_max=t_max,
            progress=cb,
            **classify,
        )
        out[name] = ManifoldBranch(name, sign, x0, traj, fate)
        log.info("%s branch of %s: %s (%s)", name, sp.label, fate.label, fate.message)
        if fate.status is Status.INTERRUPTED:
            break
    return ShipManifold(sp, par, float(eps), out, pts)


__all__ = [
    "BRANCH_SIGNS",
    "CAPSIZE",
    "EQUILIBRIUM",
    "FATE_KINDS",
    "PERIODIC",
    "UNDECIDED",
    "ManifoldBranch",
    "SaddleVisit",
    "ShipFate",
    "ShipManifold",
    "classify_ship_fate",
    "manifold_start",
    "saddle_visits",
    "unstable_manifold",
]
