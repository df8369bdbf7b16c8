r"""The heteroclinic bifurcation: critical Fn where the upslope branch switches fate.

Umeda (1999), Figs. 10-15: for ``chi_c = 10 deg`` the upslope branch of the unstable
manifold of the crest saddle "approaches the saddle next to the original one and then
tends to a periodic attractor" at Fn = 0.3247 but capsizes at Fn = 0.3248, so between
them "is a nominal Froude number whose unstable manifold of a saddle tends to a
different saddle": a heteroclinic connection, the paper's critical condition for
capsizing due to broaching.

:func:`critical_fn` locates it by bisection on the fate of that branch
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
``criterion="final"`` bisects the final fate (:func:`outcome`) as before.

At every new ``Fn`` the crest saddle is re-solved by Newton's method from the saddle
at the nearest ``Fn`` already evaluated. Next to the connection the periodic
attractor passes close to the saddles and the Poincare return map contracts slowly,
so a fate still undecided at ``t_max`` is retried with twice (then four times) the
time limit (not needed when the first passage already decides the outcome).

``method="bisection"`` is the only method here; a boundary-value (collocation)
method for the same connection lives in :mod:`ship_models.analysis.connection`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from continuation.dynamics import Fate, FateKind, bisect_fate, fate_label
from continuation.errors import ContinuationError, ConvergenceError
from continuation.params import Params
from continuation.status import Status

from .fixed_points import FixedPoint, find_fixed_point, fixed_points, polish
from .manifold import (
    BRANCH_SIGNS,
    PERIODIC,
    RECURRENT,
    UNDECIDED,
    ShipFate,
    unstable_manifold,
)

log = logging.getLogger(__name__)

#: Default search interval of Fn.
FN_BRACKET = (0.25, 0.40)
#: Default time limit of one branch simulation (s); doubled on an undecided fate.
T_MAX = 1500.0
#: How often an undecided fate is retried with twice the time limit.
UNDECIDED_RETRIES = 2


@dataclass(frozen=True)
class FateEvaluation:
    """One simulation of the bisection.

    ``Fn``, the fate of the branch, the saddle, and the outcome the bisection compared
    (:func:`first_passage` or :func:`outcome`, by the ``criterion`` of
    :func:`critical_fn`; ``""`` if undecided).
    """

    Fn: float
    fate: ShipFate
    saddle_x: tuple[float, ...]
    outcome: str = ""


@dataclass(frozen=True)
class CriticalResult:
    """The critical Froude number of one autopilot course.

    Attributes
    ----------
    chi_c : float
        Autopilot course (rad).
    fn_critical : float
        Midpoint of the final bracket (NaN when no switch was bracketed).
    bracket : tuple of float
        ``(Fn_lo, Fn_hi)`` with different fates; width ``<= tol`` on success.
    fate_lo, fate_hi : str
        Outcomes at the bracket ends (:func:`outcome`: ``"periodic"``, ``"capsize"``).
    branch : str
        The manifold branch used (``"upslope"``).
    tol : float
    n_evaluations : int
        Branch simulations done.
    evaluations : tuple of FateEvaluation
        All of them, in order.
    status : Status
        ``SUCCESS``; ``NO_BRACKET`` (same fate at both ends of the search interval);
        ``UNDECIDED`` (a third fate appeared, or a fate was undecided by ``t_max``);
        ``NEWTON_FAILED`` (the saddle was lost); ``INTERRUPTED``; ``MAX_ITER``.
    message : str
    method : str
        ``"bisection"``.
    criterion : str
        ``"first_passage"`` or ``"final"`` (see the module notes).
    """

    chi_c: float
    fn_critical: float
    bracket: tuple[float, float]
    fate_lo: str
    fate_hi: str
    branch: str
    tol: float
    n_evaluations: int
    evaluations: tuple[FateEvaluation, ...]
    status: Status
    message: str
    method: str = "bisection"
    criterion: str = "first_passage"

    @property
    def width(self) -> float:
        """``Fn_hi - Fn_lo``."""
        return self.bracket[1] - self.bracket[0]

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "method": self.method,
            "criterion": self.criterion,
            "chi_c": self.chi_c,
            "chi_c_deg": math.degrees(self.chi_c),
            "fn_critical": self.fn_critical,
            "bracket": list(self.bracket),
            "width": self.width,
            "fate_lo": self.fate_lo,
            "fate_hi": self.fate_hi,
            "branch": self.branch,
            "tol": self.tol,
            "n_evaluations": self.n_evaluations,
            "evaluations": [
                {
                    "Fn": e.Fn,
                    "fate": e.fate.label,
                    "outcome": e.outcome,
                    "via": [f"{v.label}@{v.shift:+d}:{v.side:+d}" for v in e.fate.visits],
                }
                for e in self.evaluations
            ],
            "status": self.status.name,
            "message": self.message,
        }


def outcome(fate: ShipFate) -> str:
    """The outcome the bisection compares: the fate label, with ``recurrent`` as ``periodic``.

    Bounded recurrent surging without a settled period (next to the connection the
    attractor is irregular) is the paper's "periodic motion" as opposed to capsize.
    """
    return PERIODIC if fate.kind == RECURRENT else fate.label


#: Outcome of a branch that turned back at the neighbouring saddle yet ended periodic.
RETURNED = "returned"
#: Bisection criteria of :func:`critical_fn`.
CRITERIA = ("first_passage", "final")


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
    final = None if fate.kind == UNDECIDED else outcome(fate)
    for v in fate.visits:
        if v.label != saddle or v.shift == 0:
            continue
        if v.shift * sign >= 2:  # the first copy was passed outside the visit radius
            return PERIODIC
        if v.shift * sign < 0:  # a copy in the other direction: not the connection sought
            continue
        if v.side == 0:  # still near it, or no side known
            return None
        if v.side == sign:
            return PERIODIC
        if final is None:  # turned back, but where to is not known yet: look longer
            return None
        return RETURNED if final == PERIODIC else final
    return final


class _FateAt:
    """Fate of one manifold branch as a function of Fn, tracking the saddle by Newton."""

    def __init__(
        self,
        model: Any,
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
            return None if fate.kind == UNDECIDED else outcome(fate)
        return first_passage(fate, self.label, self.branch)

    def __call__(self, fn: float) -> ShipFate | None:
        sp = self.saddle(fn)
        if sp is None:
            return None
        par = self.params.replace(Fn=fn)
        others = [fp for fp in fixed_points(self.model, par) if fp.label != self.label]
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


def critical_fn(
    model: Any = None,
    chi_c: float = math.radians(10.0),
    *,
    params: Params | None = None,
    fn_bracket: tuple[float, float] = FN_BRACKET,
    tol: float = 1e-5,
    branch: str = "upslope",
    saddle: str = "crest",
    method: str = "bisection",
    criterion: str = "first_passage",
    max_evaluations: int = 60,
    progress: Callable[[FateEvaluation], None] | None = None,
    throw: bool = False,
    **manifold_options: Any,
) -> CriticalResult:
    """Critical ``Fn`` of the heteroclinic bifurcation at autopilot course ``chi_c``.

    Parameters
    ----------
    model : Umeda4DOF, optional
        Default: :func:`ship_models.purse_seiner`.
    chi_c : float
        Autopilot course (rad).
    params : Params, optional
        Other parameters (wave, autopilot); default the model's defaults.
    fn_bracket : (float, float)
        Search interval; its ends must give different fates.
    tol : float
        Required bracket width in ``Fn`` (default 1e-5).
    branch : str
        Manifold branch whose fate is bisected (``"upslope"``, as in the paper).
    saddle : str
        Label of the saddle (``"crest"``).
    method : {"bisection"}
        Only bisection is implemented here (see module notes).
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
    CriticalResult

    Raises
    ------
    ValueError
        Bad ``fn_bracket``, ``tol``, ``method``, ``criterion``, ``branch``,
        ``max_evaluations``, or
        no saddle ``saddle`` at the lower end of the bracket.
    """
    if method != "bisection":
        raise ValueError(f"`method` must be 'bisection', got {method!r}")
    if criterion not in CRITERIA:
        raise ValueError(f"`criterion` must be one of {CRITERIA}, got {criterion!r}")
    if branch not in ("upslope", "downslope"):
        raise ValueError(f"`branch` must be 'upslope' or 'downslope', got {branch!r}")
    try:
        lo, hi = (float(v) for v in fn_bracket)
    except (TypeError, ValueError):
        raise ValueError(f"`fn_bracket` must be two numbers, got {fn_bracket!r}") from None
    if not (0 < lo < hi and math.isfinite(hi)):
        raise ValueError(f"`fn_bracket` must satisfy 0 < lo < hi, got {fn_bracket!r}")
    if not (isinstance(tol, (int, float)) and 0 < tol < hi - lo):
        raise ValueError(f"`tol` must be in (0, {hi - lo:g}), got {tol!r}")
    if not (isinstance(max_evaluations, int) and max_evaluations >= 2):
        raise ValueError(f"`max_evaluations` must be an integer >= 2, got {max_evaluations!r}")
    if model is None:
        from ship_models import purse_seiner

        model = purse_seiner()
    base = model.default_params() if params is None else params
    base = Params(model.param_names, model.check_params(base, "params")).replace(chi_c=chi_c, Fn=lo)
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
    out = CriticalResult(
        float(chi_c),
        float(res.p_critical),
        (float(res.bracket[0]), float(res.bracket[1])),
        "" if f_lo is None else str(f_lo),
        "" if f_hi is None else str(f_hi),
        branch,
        float(tol),
        len(fate_at.evaluations),
        tuple(fate_at.evaluations),
        res.status,
        res.message,
        criterion=criterion,
    )
    log.debug(
        "critical Fn (chi_c=%.4g deg): %s, %s", math.degrees(chi_c), out.fn_critical, res.message
    )
    if throw and res.status is not Status.SUCCESS:
        raise ContinuationError(res.message)
    return out


__all__ = [
    "CRITERIA",
    "FN_BRACKET",
    "RETURNED",
    "CriticalResult",
    "FateEvaluation",
    "critical_fn",
    "first_passage",
    "outcome",
]
