r"""The sudden-change capsizing boundary as a landing on a crest saddle's stable manifold.

Umeda (1999, Figs. 16 and 22) finds the capsizing boundary of the sudden-change
experiment by simulation and wishes for it as a stable manifold. Here it is solved
directly: at the initial position :math:`(\xi_G/\lambda)_0` the boundary is the ``Fn``
at which the transient, starting on the old periodic orbit at that position
(:func:`~ship_models.analysis.sudden_change.periodic_orbit`, controls ``params_from``)
and run with the new controls (``chi_c_to``, ``Fn``), lands after ``k`` waves on the
stable manifold of the crest saddle (:func:`~ship_models.analysis.crest_saddle.crest_saddle`,
index 1: its stable manifold has codimension one and separates the passages that go
on up the slope, to the periodic motion, from those that turn back down it, to
broaching and capsize)::

    x(0) = x_orbit(xi_0),   L_u^T (x(T) - x_s - k e_xi) = 0,   f(x_s; Fn) = 0,   Fn unknown

by :class:`continuation.bvp.LandingProblem` (collocation, ``T`` fixed, end distance
free, Riccati projection; error estimates by a halved mesh and a longer ``T``), and
continued in ``xi_0`` by pseudo-arclength (:func:`continuation.bvp.continue_landing`;
``dx_0/dxi_0 = f(x_0; params_from) / f_xi(x_0; params_from)``, the orbit's tangent).

:func:`capsizing_boundary_bvp` does, for each position:

1. the bisection by simulation (:func:`~ship_models.analysis.sudden_change.sudden_change_boundary`),
   the reference it is compared with;
2. the guess: the capsizing run at the bracket's upper end, cut at its closest approach
   to the last crest-saddle copy it passes (within ``passage_radius``, nondimensional)
   before it capsizes: that copy gives ``k``;
3. the solve with its error estimates, and the physical checks: the orbit stays below
   the angle of vanishing stability, and its end equilibrium is the crest saddle
   continued from ``chi_c = 0`` (:data:`~ship_models.analysis.boundary_check.SADDLE_MATCH`);
4. the comparison: the BVP's Fn inside the bisection bracket.

Between neighbouring positions with the same ``k`` the landing is continued from one to
the other (a line for the figures, checked against the next position's own solve);
where ``k`` changes or the branch folds in ``xi_0`` that is reported, not bridged.
Near the heteroclinic Fn the boundary can be a crisis of the periodic attractor
(the transient lingers for many waves before it capsizes); then ``k`` is large and
changes with the bisection's resolution: the BVP still solves the landing the
bisection found, at that ``k``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from continuation.bvp import (
    ConnectionAccuracy,
    LandingProblem,
    LandingResult,
    continue_landing,
    landing_at,
    solve_landing,
)
from continuation.dynamics import simulate
from continuation.dynamics.shooting import ShootingOrbit
from continuation.errors import ContinuationError
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status, StatusResult
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .boundary_check import SADDLE_MATCH, max_roll
from .crest_saddle import crest_saddle
from .critical_bvp import _guess_mesh
from .eigen import paper_scales
from .events import capsize_angle
from .sudden_change import (
    SuddenChangeBoundary,
    _capsize_sim_event,
    _orbit_for,
    _position,
    sudden_change_boundary,
)

#: Accuracy of the landing solves: Fn to about 3e-9 (the bisections reach 1e-7).
DEFAULT_ACCURACY = ConnectionAccuracy(rtol=1e-8, atol=1e-10, adapt_rounds=1)
_NEWTON = NewtonSettings(tol=1e-10, step_tol=1e-8, max_iter=40, damping=True)


@dataclass(frozen=True)
class BoundaryPoint(StatusResult):
    """The boundary at one initial position, by the BVP and by bisection.

    Attributes
    ----------
    xi_0 : float
    Fn : float
        The landing's Fn (nan if not solved).
    error : float
        Its discretisation + truncation estimate.
    k : int
        Waves: the orbit lands on the crest saddle shifted by ``k`` wavelengths
        (negative: the ship is overtaken).
    status : Status
        ``SUCCESS`` only for a landing within its error estimates that passes the
        physical checks (else ``REJECTED`` with the reason, or the solver's status).
    message : str
    bisection : SuddenChangeBoundary
        The reference.
    inside : bool
        ``Fn`` lies inside the bisection bracket.
    T : float
        Length of the orbit (s).
    end_distance : float
        ``|x(T) - x_saddle|`` (state 2-norm).
    max_roll_deg : float
    orbit : LandingResult or None
    """

    xi_0: float
    Fn: float
    error: float
    k: int
    status: Status
    message: str
    bisection: SuddenChangeBoundary
    inside: bool
    T: float = math.nan
    end_distance: float = math.nan
    max_roll_deg: float = math.nan
    orbit: LandingResult | None = field(default=None, repr=False)

    @property
    def difference(self) -> float:
        """``Fn - bisection midpoint``."""
        return float(self.Fn - self.bisection.Fn)

    @property
    def bracket_width(self) -> float:
        """Width of the bisection bracket."""
        return float(self.bisection.bracket[1] - self.bisection.bracket[0])

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (no orbit)."""
        return {
            "xi_0": self.xi_0,
            "Fn": self.Fn,
            "error": self.error,
            "k": self.k,
            "status": self.status.name,
            "message": self.message,
            "inside": self.inside,
            "bisection_Fn": self.bisection.Fn,
            "bracket": list(self.bisection.bracket),
            "difference": self.difference,
            "T": self.T,
            "end_distance": self.end_distance,
            "max_roll_deg": self.max_roll_deg,
        }


@dataclass(frozen=True)
class BoundarySegment:
    """A continued piece of the boundary at one ``k``: ``Fn`` against ``xi_0``.

    Attributes
    ----------
    k : int
    xi_0, Fn : ndarray, shape (K,)
    status : Status
        The branch's status (``SUCCESS``/``PARAM_BOUND``: reached the next position).
    message : str
    end_Fn, end_error : float
        The last row re-solved with error estimates (branch rows carry none: the mesh
        and ``T`` are those of the start), and that estimate; nan if not re-solved.
    """

    k: int
    xi_0: FloatArray
    Fn: FloatArray
    status: Status
    message: str = ""
    end_Fn: float = math.nan
    end_error: float = math.nan


@dataclass(frozen=True)
class CapsizeBoundary:
    """The capsizing boundary over initial positions (:func:`capsizing_boundary_bvp`).

    Attributes
    ----------
    chi_c : float
        New course (rad).
    points : tuple of BoundaryPoint
        One per position, sorted by ``xi_0``.
    segments : tuple of BoundarySegment
        Continued pieces between neighbouring positions of equal ``k``.
    notes : tuple of str
        Jumps in ``k``, folds, failed continuations: reported, not bridged.
    elapsed : float
    """

    chi_c: float
    points: tuple[BoundaryPoint, ...]
    segments: tuple[BoundarySegment, ...]
    notes: tuple[str, ...]
    elapsed: float = 0.0

    @property
    def all_inside(self) -> bool:
        """Every point solved and inside its bisection bracket."""
        return all(p.success and p.inside for p in self.points)

    def rows(self) -> list[list[Any]]:
        """One CSV row per position (see :data:`ROW_HEADER`)."""
        return [
            [
                p.xi_0,
                p.Fn,
                p.error,
                p.k,
                p.bisection.bracket[0],
                p.bisection.bracket[1],
                p.bisection.Fn,
                p.difference,
                p.bracket_width,
                int(p.inside),
                p.status.name,
                p.T,
                p.end_distance,
                p.max_roll_deg,
            ]
            for p in self.points
        ]

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "chi_c_deg": math.degrees(self.chi_c),
            "points": [p.to_json() for p in self.points],
            "segments": [
                {
                    "k": s.k,
                    "xi_0": [float(v) for v in s.xi_0],
                    "Fn": [float(v) for v in s.Fn],
                    "status": s.status.name,
                    "message": s.message,
                }
                for s in self.segments
            ],
            "notes": list(self.notes),
            "all_inside": self.all_inside,
            "elapsed_s": self.elapsed,
        }


ROW_HEADER = [
    "xi_0",
    "Fn_bvp",
    "error",
    "k_waves",
    "bisection_lower",
    "bisection_upper",
    "bisection_Fn",
    "difference",
    "bracket_width",
    "inside",
    "status",
    "T_s",
    "end_distance",
    "max_roll_deg",
]


# ------------------------------------------------------------------ pieces
def _start(
    orb: ShootingOrbit,
) -> tuple[Callable[[float], FloatArray], Callable[[float], FloatArray]]:
    """``x_0(xi_0)`` on the old orbit and its tangent ``f / f_xi`` (shape (8,) each)."""
    model = orb.system
    pvec = np.asarray(orb.params.values, dtype=float)
    i_xi = model.state_index("xi_G")

    def x0(xi: float) -> FloatArray:
        return np.asarray(orb.state_at(float(xi)), dtype=float)

    def dx0(xi: float) -> FloatArray:
        f = np.asarray(model.f(x0(xi), pvec), dtype=float)
        return f / f[i_xi]

    return x0, dx0


def _passages(
    model: VesselModel, tr: Any, saddle: FloatArray, scales: FloatArray, radius: float
) -> list[tuple[int, int, float]]:
    """Closest approaches ``(k, sample index, distance)`` to ``saddle + k e_xi`` in time order."""
    x = np.asarray(tr.x)
    i_xi = model.state_index("xi_G")
    e = np.zeros(x.shape[1])
    e[i_xi] = 1.0
    ks = np.round(x[:, i_xi] - saddle[i_xi]).astype(int)
    out = []
    for k in range(int(ks.max()), int(ks.min()) - 1, -1):
        d = np.max(np.abs((x - (saddle + k * e)) / scales), axis=1)
        i = int(np.argmin(d))
        if d[i] < radius:
            out.append((k, i, float(d[i])))
    return sorted(out, key=lambda r: r[1])


def landing_guess(
    orb: ShootingOrbit,
    params_to: Any,
    xi_0: float,
    *,
    t_max: float = 1200.0,
    passage_radius: float = 0.05,
) -> tuple[FloatArray, FloatArray, int, Any, Callable[[FloatArray], FloatArray]]:
    """The capsizing run from ``xi_0`` cut at its last crest-saddle passage before capsize.

    Returns
    -------
    t, x : ndarray, shapes (K,), (K, 8)
        The run from ``t = 0`` to the closest approach.
    k : int
        The saddle copy (waves).
    saddle : FixedPoint
        The crest saddle at ``params_to``.
    at : callable
        ``at(t) -> (len(t), 8)``: the run at any times (cubic Hermite on the samples).

    Raises
    ------
    ContinuationError
        If the run does not capsize or passes no saddle copy within ``passage_radius``.
    """
    model = orb.system
    saddle = crest_saddle(model, params_to)
    scales, _ = paper_scales(model, params_to, saddle.x)
    x0 = orb.state_at(xi_0)
    tr = simulate(
        model,
        x0,
        params_to,
        (0.0, t_max),
        events=[_capsize_sim_event(model, None)],
        dt=0.05,
        dense=True,
    )
    if tr.status is not Status.EVENT:
        raise ContinuationError(
            f"the run at Fn = {float(params_to['Fn']):.8f} from xi_0 = {xi_0:g} does not "
            f"capsize within {t_max:g} s: no landing guess"
        )
    found = _passages(model, tr, saddle.x, scales, passage_radius)
    if not found:
        raise ContinuationError(
            f"the capsizing run from xi_0 = {xi_0:g} passes no crest saddle within "
            f"{passage_radius:g} (nondimensional): no landing guess"
        )
    k, i, _ = found[-1]
    return np.asarray(tr.t[: i + 1]), np.asarray(tr.x[: i + 1]), int(k), saddle, tr.at


def _problem(
    orb: ShootingOrbit,
    params_to: Any,
    xi_0: float,
    saddle_x: FloatArray,
    k: int,
    t: FloatArray,
    x: FloatArray,
    interval_length: float,
    degree: int,
) -> LandingProblem:
    x0, dx0 = _start(orb)
    T = float(t[-1] - t[0])
    N = max(int(math.ceil(T / interval_length)), 10)
    mesh = _guess_mesh(t, x, N, degree)
    return LandingProblem(
        orb.system,
        params_to,
        "Fn",
        start=x0,
        saddle=saddle_x,
        shift={"xi_G": float(k)},
        mesh=mesh,
        s=xi_0,
        start_name="xi_0",
        start_derivative=dx0,
    )


def landing_refusal(model: VesselModel, res: LandingResult) -> str:
    """Why a converged landing is no capsizing boundary (empty when it is one).

    The orbit must stay below the angle of vanishing stability, and its end equilibrium
    (wrapped) must be the crest saddle continued from ``chi_c = 0`` at the solved Fn.
    """
    phi_v = capsize_angle(model)
    phi_max = max_roll(model, res.x)
    if phi_max >= phi_v:
        return (
            f"the orbit rolls to {math.degrees(phi_max):.1f} deg, past the angle of vanishing "
            f"stability {math.degrees(phi_v):.1f} deg: a capsize, not a boundary"
        )
    try:
        sad = crest_saddle(model, res.params)
    except ContinuationError as exc:
        return f"no crest saddle at the solved Fn: {exc}"
    i_xi = model.state_index("xi_G")
    x_end = np.array(res.x_eq, dtype=float)
    x_end[i_xi] -= math.floor(x_end[i_xi])
    d = float(np.linalg.norm(x_end - sad.x))
    if d > SADDLE_MATCH:
        return f"the orbit lands on an equilibrium {d:.2e} from the crest saddle: not the boundary"
    return ""


def _solve_point(
    orb: ShootingOrbit,
    chi: float,
    b: SuddenChangeBoundary,
    accuracy: ConnectionAccuracy,
    interval_length: float,
    degree: int,
    passage_radius: float,
) -> BoundaryPoint:
    model = orb.system
    xi = b.xi_0

    def failed(status: Status, msg: str, k: int = 0) -> BoundaryPoint:
        return BoundaryPoint(xi, math.nan, math.nan, k, status, msg, b, False)

    if not b.success:
        return failed(b.status, f"no bisection bracket: {b.message}")
    pt = orb.params.replace(chi_c=chi, Fn=float(b.bracket[1]))
    try:
        t, x, k, saddle, at = landing_guess(orb, pt, xi, passage_radius=passage_radius)
        prob = _problem(orb, pt, xi, saddle.x, k, t, x, interval_length, degree)
    except (ContinuationError, ValueError) as exc:
        return failed(Status.NO_SOLUTION, str(exc))
    tm = np.clip(prob.mesh.t, t[0], t[-1])
    res = solve_landing(prob, (tm, at(tm)), accuracy=accuracy, newton=_NEWTON)
    if res.errors is None and not res.success:
        # long orbits past many saddle passages: Newton's basin is small; once more on
        # a mesh twice as fine (the guess, an exact run, is then closer to a solution)
        prob = _problem(orb, pt, xi, saddle.x, k, t, x, 0.5 * interval_length, degree)
        tm = np.clip(prob.mesh.t, t[0], t[-1])
        res = solve_landing(prob, (tm, at(tm)), accuracy=accuracy, newton=_NEWTON)
    return _point(model, res, b, k)


def _point(
    model: VesselModel, res: LandingResult, b: SuddenChangeBoundary, k: int
) -> BoundaryPoint:
    fn = res.value("Fn")
    status, msg = res.status, res.message
    refusal = landing_refusal(model, res) if res.errors is not None or res.success else ""
    if refusal:
        status, msg = Status.REJECTED, f"not a capsizing boundary: {refusal}"
    lo, hi = b.bracket
    ok_fn = status in (Status.SUCCESS, Status.DISCRETISATION_ERROR, Status.TRUNCATION_ERROR)
    return BoundaryPoint(
        b.xi_0,
        fn if ok_fn else math.nan,
        res.error("Fn"),
        k,
        status,
        msg,
        b,
        bool(ok_fn and lo <= fn <= hi),
        res.T,
        res.end_distance,
        math.degrees(max_roll(model, res.x)),
        res,
    )


def _bridge(
    a: BoundaryPoint, b: BoundaryPoint, accuracy: ConnectionAccuracy
) -> tuple[BoundarySegment | None, str]:
    """Continue ``a``'s landing to ``b.xi_0``; a segment and a note (empty if fine)."""
    res = a.orbit
    if res is None:
        return None, ""
    lo, hi = sorted((a.xi_0, b.xi_0))
    span = hi - lo
    settings = ContinuationSettings(
        p_min=lo,
        p_max=hi,
        ds=math.copysign(0.02 * span, b.xi_0 - a.xi_0),
        ds_min=1e-6 * span,
        ds_max=0.25 * span,
        max_steps=200,
    )
    br = continue_landing(res, settings)
    xs = np.asarray(br.p, dtype=float)
    fns = np.asarray(br.records["Fn"], dtype=float)
    seg = BoundarySegment(a.k, xs, fns, br.status, br.status.value)
    folds = [sp for sp in br.special_points if "FOLD" in str(getattr(sp, "kind", "")).upper()]
    if folds or (xs.size > 2 and np.any(np.diff(xs) * np.sign(b.xi_0 - a.xi_0) < 0)):
        return seg, (
            f"the landing at k = {a.k} folds in xi_0 between {a.xi_0:g} and {b.xi_0:g}"
            " (continued branch turns back): boundary not bridged there"
        )
    if br.status is not Status.PARAM_BOUND or not math.isclose(xs[-1], b.xi_0, abs_tol=1e-9):
        return seg, (
            f"continuation at k = {a.k} from xi_0 = {a.xi_0:g} stopped at "
            f"{xs[-1]:.6g} before {b.xi_0:g}: {br.status.name}"
        )
    row = landing_at(br, -1)
    end = solve_landing(row.problem, row, accuracy=accuracy, newton=_NEWTON)
    seg = dataclasses.replace(seg, end_Fn=end.value("Fn"), end_error=end.error("Fn"))
    if not end.success:
        return seg, f"the continued landing at xi_0 = {b.xi_0:g} does not re-solve: {end.message}"
    if b.success and abs(end.value("Fn") - b.Fn) > end.error("Fn") + b.error + 1e-12:
        return seg, (
            f"continued landing at xi_0 = {b.xi_0:g} (Fn = {end.value('Fn'):.10f}) differs "
            f"from the solve there ({b.Fn:.10f}) beyond their estimates: another landing of "
            "the same k"
        )
    return seg, ""


# ------------------------------------------------------------------ entry point
def capsizing_boundary_bvp(
    model: VesselModel,
    params_from: Any,
    chi_c_to: float,
    xi_0: Sequence[float],
    fn_bracket: tuple[float, float] | None = None,
    *,
    orbit: ShootingOrbit | None = None,
    tol: float = 1e-6,
    bisections: Sequence[SuddenChangeBoundary] | None = None,
    accuracy: ConnectionAccuracy | None = None,
    interval_length: float = 0.8,
    degree: int = 4,
    passage_radius: float = 0.05,
    bridge: bool = True,
    progress: Callable[[str], None] | None = None,
) -> CapsizeBoundary:
    r"""The capsizing boundary of the sudden change as a landing BVP at each ``xi_0``.

    Parameters
    ----------
    model : VesselModel
    params_from : Params, mapping or array
        The old controls (ignored with ``orbit``).
    chi_c_to : float
        New course (rad).
    xi_0 : sequence of float
        Initial positions :math:`(\xi_G/\lambda)_0`.
    fn_bracket : (float, float), optional
        Bisection bracket (periodic below, capsize above) for every position; needed
        unless ``bisections`` are given.
    orbit : ShootingOrbit, optional
        The old periodic orbit.
    tol : float
        Bisection tolerance (final bracket width).
    bisections : sequence of SuddenChangeBoundary, optional
        Bisections already run (one per ``xi_0``, same order); then none is run.
    accuracy : ConnectionAccuracy, optional
        Of the landing solves (default :data:`DEFAULT_ACCURACY`).
    interval_length, degree : float, int
        Mesh of the guess: ``ceil(T / interval_length)`` intervals of this degree.
    passage_radius : float
        Nondimensional distance within which a run passes a crest-saddle copy.
    bridge : bool
        Continue between neighbouring positions of equal ``k``.
    progress : callable, optional
        ``progress(message)`` after each position.

    Returns
    -------
    CapsizeBoundary

    Raises
    ------
    ValueError
        For bad positions, bracket, tolerance or a ``bisections`` list of the wrong length.
    """
    t_start = time.perf_counter()
    say = progress or (lambda m: None)
    xs = sorted(_position(v) for v in np.atleast_1d(np.asarray(xi_0, dtype=object)))
    if not xs:
        raise ValueError("`xi_0` must not be empty")
    chi = float(chi_c_to)
    orb = _orbit_for(model, params_from, orbit)
    acc = DEFAULT_ACCURACY if accuracy is None else accuracy
    if bisections is not None:
        bis = sorted(bisections, key=lambda b: b.xi_0)
        if [b.xi_0 for b in bis] != xs:
            raise ValueError("`bisections` must hold one SuddenChangeBoundary per `xi_0`")
    elif fn_bracket is None:
        raise ValueError("give `fn_bracket` (or `bisections` already run)")
    else:
        bis = [sudden_change_boundary(model, None, chi, x, fn_bracket, tol, orbit=orb) for x in xs]
    points = []
    for b in bis:
        p = _solve_point(orb, chi, b, acc, interval_length, degree, passage_radius)
        say(
            f"xi_0 = {b.xi_0:g}: Fn = {p.Fn:.9f} (k = {p.k}, {p.status.name}); bisection "
            f"{b.bracket[0]:.9f}-{b.bracket[1]:.9f}: {'inside' if p.inside else 'OUTSIDE'}"
        )
        points.append(p)
    segments, notes = [], []
    for a, b in zip(points[:-1], points[1:], strict=True):
        if not (a.success and b.success):
            continue
        if a.k != b.k:
            notes.append(
                f"jump in k between xi_0 = {a.xi_0:g} (k = {a.k}) and {b.xi_0:g} "
                f"(k = {b.k}): the boundary changes landing there"
            )
            continue
        if bridge:
            seg, note = _bridge(a, b, acc)
            if seg is not None:
                segments.append(seg)
            if note:
                notes.append(note)
    return CapsizeBoundary(
        chi, tuple(points), tuple(segments), tuple(notes), time.perf_counter() - t_start
    )


__all__ = [
    "DEFAULT_ACCURACY",
    "ROW_HEADER",
    "BoundaryPoint",
    "BoundarySegment",
    "CapsizeBoundary",
    "capsizing_boundary_bvp",
    "landing_guess",
    "landing_refusal",
]
