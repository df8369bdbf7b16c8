r"""The heteroclinic bifurcation: critical Fn where the upslope branch switches fate.

Umeda (1999), Figs. 10-15: for ``chi_c = 10 deg`` the upslope branch of the unstable
manifold of the crest saddle "approaches the saddle next to the original one and then
tends to a periodic attractor" at Fn = 0.3247 but capsizes at Fn = 0.3248, so between
them "is a nominal Froude number whose unstable manifold of a saddle tends to a
different saddle": a heteroclinic connection, the paper's critical condition for
capsizing due to broaching.

:func:`first_passage_bisection` locates it by bisection on the fate of that branch
(:func:`~ship_models.analysis.manifold.unstable_manifold`, bisected by the generic
:func:`continuation.dynamics.fate_bisection.bisect_fate`): the bracket
``[Fn_lo, Fn_hi]`` always has ``fate(Fn_lo) != fate(Fn_hi)`` and is halved until its
width is at most ``tol``; its cost is one branch simulation per halving
(``log2(width / tol)`` of them).

Which fate is bisected (``criterion``). The connection is where the upslope branch
lies on the stable manifold :math:`W^s` of the crest saddle one wave back
(``crest@-1``); on either side of it the branch passes that saddle on opposite sides
of :math:`W^s`: below, it goes on upslope (the wave overtakes the ship), above, it
turns back down the slope. The *final* fate (the attractor reached) is not a step
function of ``Fn`` next to the connection: just below it the branch leaves
``crest@-1`` upslope so close to :math:`W^u(crest)` that it approaches ``crest@-2``
next, and may leave *that* one on the capsize side; these secondary switches (branch
-> ``crest@-1`` -> ``crest@-2`` connections, and so on) accumulate on the primary
one from below, at distances in ``Fn`` that shrink geometrically. Bisection on the
final fate can lock onto one of them (measured for the purse seiner with midship
derivatives, ``x_ref = 0``, chi_c = 10 deg: final-fate bracket [0.301595, 0.301596],
1.6e-5 below the collocation connection 0.3016117; at Fn = 0.3016016 the branch
passes ``crest@-1`` upslope, then capsizes after ``crest@-2``).

``criterion="first_passage"`` (default) therefore classifies the branch by the side
on which it leaves the *first* neighbouring crest saddle it visits
(:attr:`SaddleVisit.side <ship_models.analysis.manifold.SaddleVisit>`, the sign of
its coordinate along that saddle's unstable eigenvector on leaving, see
:func:`continuation.dynamics.fates.passage_side`): continuing upslope is ``"periodic"``,
turning back is named after the final fate (``"capsize"``, or stable surf-riding
``"equilibrium:..."``; ``"returned"`` should it still end periodic). This switches
exactly at the primary connection. A branch that visits no shifted crest saddle
within ``visit_radius`` (far from the connection) is classified by its final fate;
one whose first visit is ``crest@-2`` or further upslope passed ``crest@-1`` upslope.
``criterion="final"`` bisects the final fate (:func:`outcome`).

At every new ``Fn`` the crest saddle is re-solved by Newton's method from the saddle
at the nearest ``Fn`` already evaluated. Next to the connection the periodic
attractor passes close to the saddles and the Poincare return map contracts slowly,
so a fate still undecided at ``t_max`` is retried with twice (then four times) the
time limit (not needed when the first passage already decides the outcome).

:func:`upslope_bisection` is the lean variant (``criterion="events"``): the upslope
branch from :func:`~ship_models.analysis.upslope.upslope_branch`, its fate decided by
terminal events as soon as it passes the next crest or turns back; the brute-force
reference of the connecting-orbit solve (:mod:`ship_models.analysis.critical_bvp`).
Both bisect through the engine's :func:`continuation.dynamics.fate_bisection.bisect_fate`.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from typing import Any

from continuation.dynamics import Fate, FateKind, bisect_fate, fate_label
from continuation.errors import ContinuationError, ConvergenceError
from continuation.params import Params
from continuation.status import Status

from ..contracts import VesselModel
from .critical_result import CriticalFn, FateEvaluation
from .fixed_points import FixedPoint, FixedPointsInFn, find_fixed_point, polish
from .manifold import BRANCH_SIGNS, ShipFate, unstable_manifold
from .outcomes import ShipOutcome
from .params import course, ship_model, ship_params
from .upslope import upslope_branch

log = logging.getLogger(__name__)

#: Default search interval of Fn.
FN_BRACKET = (0.25, 0.40)
#: Default time limit of one branch simulation (s); doubled on an undecided fate.
T_MAX = 1500.0
#: How often an undecided fate is retried with twice the time limit.
UNDECIDED_RETRIES = 2


def outcome(fate: ShipFate) -> str:
    """The outcome the bisection compares: the fate label, with ``recurrent`` as ``periodic``.

    Bounded recurrent surging without a settled period (next to the connection the
    attractor is irregular) is the paper's "periodic motion" as opposed to capsize.
    """
    return ShipOutcome.PERIODIC if fate.kind == ShipOutcome.RECURRENT else fate.label


#: Outcome of a branch that turned back at the neighbouring saddle yet ended periodic.
RETURNED = ShipOutcome.RETURNED
#: Bisection criteria of :func:`critical_fn`.
CRITERIA = ("first_passage", "final", "events")


def first_passage(fate: ShipFate, saddle: str = "crest", branch: str = "upslope") -> str | None:
    """The outcome on the first passage of a neighbouring copy of ``saddle`` (module notes).

    Parameters
    ----------
    fate : ShipFate
        Fate of a manifold branch of ``saddle`` (with its ``visits``).
    saddle : str
        Label of the saddle the branch starts from.
    branch : {"upslope", "downslope"}
        The branch: ``upslope`` heads for the copy one wave back (``shift < 0``).

    Returns
    -------
    str or None
        ``"periodic"`` if the branch leaves the first shifted copy of ``saddle`` it
        visits in its own direction (or first visits a copy two or more waves on);
        otherwise (it turned back) :func:`outcome` of the final fate, or
        ``"returned"`` if that is periodic. Without such a visit: :func:`outcome` of
        the final fate. ``None`` if undecided (side unknown; or it turned back, or
        made no visit, and the final fate is undecided).
    """
    if branch not in BRANCH_SIGNS:
        raise ValueError(f"`branch` must be one of {tuple(BRANCH_SIGNS)}, got {branch!r}")
    sign = int(BRANCH_SIGNS[branch])
    final = None if fate.kind == ShipOutcome.UNDECIDED else outcome(fate)
    for v in fate.visits:
        if v.label != saddle or v.shift == 0:
            continue
        if v.shift * sign >= 2:  # the first copy was passed outside the visit radius
            return ShipOutcome.PERIODIC
        if v.shift * sign < 0:  # a copy in the other direction: not the connection sought
            continue
        if v.side == 0:  # still near it, or no side known
            return None
        if v.side == sign:
            return ShipOutcome.PERIODIC
        if final is None:  # turned back, but where to is not known yet: look longer
            return None
        return RETURNED if final == ShipOutcome.PERIODIC else final
    return final


class _FateAt:
    """Fate of one manifold branch as a function of Fn, tracking the saddle by Newton."""

    def __init__(
        self,
        model: VesselModel,
        params: Params,
        start: FixedPoint,
        branch: str,
        manifold_options: dict[str, Any],
        criterion: str = "first_passage",
    ) -> None:
        self.model = model
        self.criterion = criterion
        self.params = params
        self.branch = branch
        self.options = manifold_options
        self.label = start.label
        self.known: dict[float, FixedPoint] = {params["Fn"]: start}
        self.evaluations: list[FateEvaluation] = []
        # every fixed point at each Fn: traced at the first Fn's and tracked in between
        self.points = FixedPointsInFn(model, params)

    def saddle(self, fn: float) -> FixedPoint | None:
        nearest = min(self.known, key=lambda f: abs(f - fn))
        par = self.params.replace(Fn=fn)
        fp = polish(self.model, self.known[nearest].x, par)
        if fp is None or fp.saddle_index != 1:
            return None
        fp = FixedPoint(self.label, fp.x, fp.params, fp.eigen, fp.residual_norm)
        self.known[fn] = fp
        return fp

    def outcome_of(self, fate: ShipFate) -> str | None:
        """The compared outcome (``None`` if undecided)."""
        if self.criterion == "final":
            return None if fate.kind == ShipOutcome.UNDECIDED else outcome(fate)
        return first_passage(fate, self.label, self.branch)

    def __call__(self, fn: float) -> ShipFate | None:
        sp = self.saddle(fn)
        if sp is None:
            return None
        par = self.params.replace(Fn=fn)
        others = [fp for fp in self.points(fn) if fp.label != self.label]
        opts = dict(self.options)
        t_max = float(opts.pop("t_max", T_MAX))
        for _ in range(1 + UNDECIDED_RETRIES):
            man = unstable_manifold(
                self.model,
                par,
                sp,
                branches=(self.branch,),
                points=[sp, *others],
                t_max=t_max,
                **opts,
            )
            fate = man.branches[self.branch].fate
            if fate.status is not Status.MAX_STEPS or self.outcome_of(fate) is not None:
                break
            t_max *= 2.0  # slow convergence next to the connection: look longer
        out = self.outcome_of(fate)
        self.evaluations.append(FateEvaluation(fn, fate, tuple(float(v) for v in sp.x), out or ""))
        return fate


def _bracket(value: Any, name: str = "Fn_bracket") -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be two numbers, got {value!r}") from None
    if not (0 < lo < hi and math.isfinite(hi)):
        raise ValueError(f"`{name}` must satisfy 0 < lo < hi, got {value!r}")
    return lo, hi


def first_passage_bisection(
    model: VesselModel | None = None,
    params: Any = None,
    *,
    chi_c: float | None = None,
    Fn_bracket: tuple[float, float] = FN_BRACKET,
    tol: float = 1e-5,
    branch: str = "upslope",
    saddle: str = "crest",
    criterion: str = "first_passage",
    max_evaluations: int = 60,
    progress: Callable[[FateEvaluation], None] | None = None,
    throw: bool = False,
    **manifold_options: Any,
) -> CriticalFn:
    """Critical ``Fn`` of the heteroclinic bifurcation by bisection on manifold fates.

    Parameters
    ----------
    model : Umeda4DOF, optional
        Default: a new :func:`ship_models.purse_seiner`.
    params : Params, optional
        Other parameters (wave, autopilot); default the model's defaults.
    chi_c : float, optional
        Autopilot course (rad); default the course of ``params``.
    Fn_bracket : (float, float)
        Search interval; its ends must give different fates.
    tol : float
        Required bracket width in ``Fn`` (default 1e-5).
    branch : str
        Manifold branch whose fate is bisected (``"upslope"``, as in the paper).
    saddle : str
        Label of the saddle (``"crest"``).
    criterion : {"first_passage", "final"}
        Which outcome is bisected: the side on which the branch leaves the first
        neighbouring saddle (default; switches exactly at the primary connection), or
        the final fate (may lock onto a secondary switch just below it). See the
        module notes.
    max_evaluations : int
        Limit on branch simulations.
    progress : callable, optional
        Called with each :class:`FateEvaluation`.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` unless ``SUCCESS``.
    **manifold_options
        Passed to :func:`~ship_models.analysis.manifold.unstable_manifold`
        (``eps``, ``t_max``, ``capsize_angle``, ``dt``, ``return_tol``...).

    Returns
    -------
    CriticalFn
        ``method="bisection"``; ``Fn`` NaN when no switch was bracketed.

    Raises
    ------
    ValueError
        Bad ``Fn_bracket``, ``tol``, ``criterion``, ``branch``, ``max_evaluations``,
        or no saddle ``saddle`` at the lower end of the bracket.
    """
    t_start = time.perf_counter()
    if criterion not in ("first_passage", "final"):
        raise ValueError(f"`criterion` must be one of {CRITERIA}, got {criterion!r}")
    if branch not in ("upslope", "downslope"):
        raise ValueError(f"`branch` must be 'upslope' or 'downslope', got {branch!r}")
    lo, hi = _bracket(Fn_bracket)
    if not (isinstance(tol, (int, float)) and 0 < tol < hi - lo):
        raise ValueError(f"`tol` must be in (0, {hi - lo:g}), got {tol!r}")
    if not (isinstance(max_evaluations, int) and max_evaluations >= 2):
        raise ValueError(f"`max_evaluations` must be an integer >= 2, got {max_evaluations!r}")
    model = ship_model(model)
    base = ship_params(model, params)
    chi = course(base["chi_c"] if chi_c is None else chi_c)
    base = base.replace(chi_c=chi, Fn=lo)
    start = find_fixed_point(model, base, saddle)
    fate_at = _FateAt(model, base, start, branch, manifold_options, criterion)

    def fate_label_at(fn: float) -> Any:
        fate = fate_at(fn)
        if fate is None:
            raise ConvergenceError(f"lost the {saddle} saddle at Fn = {fn!r}")
        out = fate_at.outcome_of(fate)
        if out is None:  # the generic bisection stops on undecided fates
            return Fate(FateKind.UNDECIDED, "undecided", t=fate.t, message=fate.message)
        return out

    def report(lo_: float, hi_: float, n: int) -> None:
        if progress is not None and fate_at.evaluations:
            progress(fate_at.evaluations[-1])

    res = bisect_fate(
        fate_label_at, lo, hi, tol=tol, max_evaluations=max_evaluations, progress=report
    )
    f_lo = res.fate_lo if isinstance(res.fate_lo, str) else fate_label(res.fate_lo)
    f_hi = res.fate_hi if isinstance(res.fate_hi, str) else fate_label(res.fate_hi)
    bracket = (float(res.bracket[0]), float(res.bracket[1]))
    Fn = float(res.p_critical)
    out = CriticalFn(
        chi_c=float(chi),
        Fn=Fn,
        method="bisection",
        status=res.status,
        message=res.message,
        bracket=bracket,
        error=None if math.isnan(Fn) else 0.5 * (bracket[1] - bracket[0]),
        elapsed=time.perf_counter() - t_start,
        fate_lo="" if f_lo is None else str(f_lo),
        fate_hi="" if f_hi is None else str(f_hi),
        evaluations=tuple(fate_at.evaluations),
        n_evaluations=len(fate_at.evaluations),
        criterion=criterion,
        branch=branch,
        tol=float(tol),
    )
    log.debug("critical Fn (chi_c=%.4g deg): %s, %s", math.degrees(chi), out.Fn, res.message)
    if throw and res.status is not Status.SUCCESS:
        raise ContinuationError(res.message)
    return out


class _WrongEnd(Exception):
    """An end of the bracket does not have the fate the event bisection needs there."""


def upslope_bisection(
    chi_c: float,
    *,
    model: VesselModel | None = None,
    params: Any = None,
    Fn_bracket: tuple[float, float] = (0.28, 0.33),
    tol: float = 1e-6,
    eps: float = 1e-6,
    t_max: float = 600.0,
    throw: bool = False,
    progress: Callable[[float, str], None] | None = None,
) -> CriticalFn:
    r"""Critical ``Fn`` by bisection on the event-decided fate of the upslope branch.

    The brute-force reference for
    :func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`: every step simulates
    the upslope branch (:func:`~ship_models.analysis.upslope.upslope_branch`) at the
    midpoint and keeps the half whose ends have different fates
    (:func:`continuation.dynamics.fate_bisection.bisect_fate`), until the bracket is narrower
    than ``tol``. The accuracy is also limited by ``eps`` (the manifold is started on
    its tangent: an ``O(eps^2)`` error in its position) and the integrator tolerances.

    Parameters
    ----------
    chi_c : float
        Autopilot course (rad).
    model, params
        The ship (default a new :func:`ship_models.purse_seiner`) and the other
        parameters.
    Fn_bracket : (float, float)
        ``(Fn_lo, Fn_hi)``; the branch must be periodic at ``Fn_lo`` and captured at
        ``Fn_hi`` (both are simulated first).
    tol : float
        Final bracket width.
    eps, t_max : float
        Start offset and time limit of each simulation.
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` unless ``SUCCESS``.
    progress : callable, optional
        ``progress(Fn, fate)`` after every simulation.

    Returns
    -------
    CriticalFn
        ``method="bisection"``, ``criterion="events"``; ``status`` ``SUCCESS``,
        ``NO_BRACKET`` (the bracket ends do not have the fates above), ``UNDECIDED``
        (a run reached ``t_max`` undecided) or ``INTERRUPTED``.
    """
    chi = course(chi_c)
    lo, hi = (float(b) for b in Fn_bracket)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise ValueError(
            f"`Fn_bracket` must be (Fn_lo, Fn_hi) with 0 < Fn_lo < Fn_hi, got {Fn_bracket}"
        )
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"`tol` must be positive, got {tol!r}")
    m = ship_model(model)
    base = ship_params(m, params, chi_c=chi)
    t0 = time.perf_counter()
    evaluations: list[FateEvaluation] = []
    expected = {lo: ShipOutcome.PERIODIC, hi: ShipOutcome.CAPTURED}

    def fate(Fn: float) -> Any:
        try:
            f = upslope_branch(m, base.replace(Fn=Fn), eps=eps, t_max=t_max).fate
        except ContinuationError:
            f = ShipOutcome.UNDECIDED
        evaluations.append(FateEvaluation(Fn, f, (), "" if f is ShipOutcome.UNDECIDED else f))
        if progress is not None:
            progress(Fn, f)
        if len(evaluations) <= 2 and f is not expected[Fn]:
            raise _WrongEnd
        if f is ShipOutcome.UNDECIDED:
            return Fate(FateKind.UNDECIDED, "undecided", t=math.nan)
        return f

    def done(status: Status, message: str, bracket: tuple[float, float]) -> CriticalFn:
        if throw and status is not Status.SUCCESS:
            raise ConvergenceError(message)
        f_lo = evaluations[0].fate if evaluations else ShipOutcome.UNDECIDED
        f_hi = evaluations[1].fate if len(evaluations) > 1 else ShipOutcome.UNDECIDED
        return CriticalFn(
            chi_c=chi,
            Fn=0.5 * (bracket[0] + bracket[1]),
            method="bisection",
            status=status,
            message=message,
            bracket=bracket,
            error=0.5 * (bracket[1] - bracket[0]),
            elapsed=time.perf_counter() - t0,
            fate_lo=str(f_lo),
            fate_hi=str(f_hi),
            evaluations=tuple(evaluations),
            n_evaluations=len(evaluations),
            criterion="events",
            tol=float(tol),
        )

    try:
        res = bisect_fate(fate, lo, hi, tol=tol, max_evaluations=10**6)
    except _WrongEnd:
        f_lo = str(evaluations[0].fate)
        f_hi = str(evaluations[1].fate) if len(evaluations) > 1 else "(not simulated)"
        return done(
            Status.NO_BRACKET,
            f"`Fn_bracket` {Fn_bracket} does not bracket the switch: fates {f_lo!r} at "
            f"Fn={lo} and {f_hi!r} at Fn={hi} (need 'periodic' then 'captured')",
            (lo, hi),
        )
    bracket = (float(res.bracket[0]), float(res.bracket[1]))
    if res.status is Status.UNDECIDED:
        return done(Status.UNDECIDED, f"undecided fate at Fn={evaluations[-1].Fn}", bracket)
    if res.status is Status.INTERRUPTED:
        return done(Status.INTERRUPTED, Status.INTERRUPTED.value, bracket)
    if res.status is not Status.SUCCESS:
        return done(res.status, res.message, bracket)
    n = len(evaluations)
    return done(
        Status.SUCCESS, f"bracket width {bracket[1] - bracket[0]:.2e} after {n} simulations",
        bracket,
    )  # fmt: skip


__all__ = [
    "CRITERIA",
    "FN_BRACKET",
    "RETURNED",
    "first_passage",
    "first_passage_bisection",
    "outcome",
    "upslope_bisection",
]
