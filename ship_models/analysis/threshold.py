r"""The capsizing threshold: the lowest Fn at which the ship capsizes, and why there.

Umeda (1999) judges capsizing by the upslope branch of the crest saddle's unstable
manifold: below the critical nominal Froude number it "tends to a periodic attractor",
above it the ship capsizes due to broaching. The paper finds the switch at the
heteroclinic connection (chi_c = 10 deg) and confirms it by sudden-change experiments.
For a given vessel that coincidence is a finding, not a definition: the periodic
attractor can lose stability and die *before* the connection (period doublings, a
chaotic attractor, a crisis; Spyrou 1996, 1997 for this model class), and the ship then
capsizes at a lower ``Fn`` by another route.

:func:`capsizing_threshold` therefore computes the paper's criterion directly:

.. math::

    Fn_c = \min \{ Fn \in W : \text{the upslope branch of } W^u(\text{crest})
    \text{ capsizes within } t_{max} \},

with the fate of the branch decided by simulation
(:func:`~ship_models.analysis.manifold.unstable_manifold`; capsize = the roll angle
passes the angle of vanishing stability). The search:

1. by the engine's :func:`continuation.dynamics.lowest_fate.lowest_fate`: a grid of
   spacing ``coarse_step`` from ``Fn_h - depth`` (``Fn_h`` the heteroclinic Fn; without
   a connection, about ``Fn_anchor`` or over the surf-riding window
   :mod:`~ship_models.analysis.fn_window`) upwards; every interval whose two ends are
   not both the plain overtaken cycle (a periodic fate of one return, one wave per
   period) is scanned again at ``step``; the first capsizing grid point ends the scan;
2. bisection of the fates between the last surviving and the first capsizing grid
   point to ``tol`` (the error estimate is half the final bracket);
3. evidence: the fates at ``Fn_c - check_distance`` and ``Fn_c + check_distance``;
4. the mechanism: ``"heteroclinic"`` when ``|Fn_c - Fn_h|`` is within the sum of the
   two error estimates; otherwise the loss of the periodic attractor, supported by the
   overtaken cycle's own bifurcations (:func:`cycle_bifurcations`: its first period
   doubling ``PD``, fold ``LPC`` or Neimark-Sacker point ``NS``, located by
   :mod:`continuation.periodic`) and the attractor seen just below ``Fn_c``
   (``period-m`` or ``recurrent`` for a bounded irregular motion, i.e. a chaotic
   attractor): ``"period-doubling cascade and crisis"``, ``"fold of cycles"``,
   ``"torus breakdown"`` or ``"crisis"`` (the attractor meets the basin boundary with
   no bifurcation of the cycle found below ``Fn_c``).

What is and is not claimed (the result's ``resolution``): a capsizing window narrower
than ``step`` below ``Fn_c`` (or than ``coarse_step`` between two plain-cycle fates) is
not resolved; "survives" means no capsize within ``t_max`` (retried at 2x and 4x when
the fate is still undecided); a branch undecided after that is reported, and the result
is then not ``SUCCESS``. Above ``Fn_c`` the fates need not be monotone (survival windows
above a capsizing window are reported when the ``+check_distance`` check finds one).
The fixed points a fate can reach are traced in full at the scan's points and tracked by
Newton between two of them at most 0.01 apart
(:class:`~ship_models.analysis.fixed_points.FixedPointsInFn`): a pair of fixed points
born and gone again inside such an interval is not seen, the same resolution as the
scan's ``coarse_step``.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from continuation.dynamics.lowest_fate import lowest_fate
from continuation.status import Status

from ..contracts import VesselModel
from .critical_bisection import _FateAt
from .critical_result import CriticalFn
from .fixed_points import find_fixed_point
from .fn_window import fn_limit, surf_riding_window
from .manifold import ShipFate
from .outcomes import ShipOutcome
from .params import check_positive_fields, course, replace_settings, ship_model, ship_params

log = logging.getLogger(__name__)

#: The mechanisms a threshold can have.
MECHANISMS = (
    "heteroclinic",
    "period-doubling cascade and crisis",
    "subcritical period doubling",
    "fold of cycles",
    "torus breakdown",
    "crisis",
    "none",
)

CAPSIZE, SURVIVE, UNDECIDED, NO_SADDLE = "capsize", "survive", "undecided", "no saddle"


@dataclass(frozen=True)
class ThresholdSettings:
    """Settings of :func:`capsizing_threshold` (all in nominal Froude number, except times).

    Attributes
    ----------
    step : float
        Resolution of the scan where the dynamics is not the plain overtaken cycle.
    coarse_step : float
        Grid spacing elsewhere.
    depth : float
        The scan starts this far below the heteroclinic Fn (or at the surf-riding
        window's lower end, whichever is higher).
    tol : float
        Width of the final bracket (the error estimate is half of it).
    check_distance : float
        The fates at ``Fn_c -+ check_distance`` are reported as evidence.
    t_max : float
        Survival time (s) of one fate; an undecided fate is retried at 2x and 4x.
    coincide : float
        The threshold is called heteroclinic when ``|Fn_c - Fn_h|`` is at most the sum
        of the two error estimates plus this: the secondary connections that accumulate
        on the primary one from below, and the folds of the cycle's snaking approach to
        it, lie within it (for the default vessel 1.6e-5 at 10 deg and 8e-5 at 20 deg).
    locate_bifurcations : bool
        Continue the overtaken cycle in ``Fn`` to locate its PD/LPC/NS points when the
        threshold is not heteroclinic (a few seconds).
    """

    step: float = 0.002
    coarse_step: float = 0.01
    depth: float = 0.1
    tol: float = 2e-4
    check_distance: float = 0.002
    t_max: float = 1200.0
    coincide: float = 1e-3
    locate_bifurcations: bool = True

    def __post_init__(self) -> None:
        check_positive_fields(
            self, ("step", "coarse_step", "depth", "tol", "check_distance", "t_max", "coincide")
        )
        if not self.tol < self.step <= self.coarse_step:
            raise ValueError(
                f"need tol < step <= coarse_step, got {self.tol}, {self.step}, {self.coarse_step}"
            )


@dataclass(frozen=True)
class FateSample:
    """The upslope branch's fate at one ``Fn``.

    Attributes
    ----------
    Fn : float
    outcome : {"capsize", "survive", "undecided", "no saddle"}
    label : str
        The fate's own label (``periodic``, ``recurrent``, ``capsize``, ...).
    t : float
        Time the fate was decided (s).
    returns : int or None
        Section crossings per period of a periodic attractor (``period-m``).
    drift : int or None
        Wavelengths per period.
    """

    Fn: float
    outcome: str
    label: str
    t: float
    returns: int | None = None
    drift: int | None = None

    @property
    def attractor(self) -> str:
        """``"period-1"``, ``"period-m"``, ``"recurrent"``, or the label."""
        if self.label == ShipOutcome.PERIODIC and self.returns:
            return f"period-{self.returns}"
        return self.label

    @property
    def plain_cycle(self) -> bool:
        """The ordinary overtaken-by-waves cycle: periodic, one return, one wave."""
        return self.label == ShipOutcome.PERIODIC and self.returns == 1 and self.drift == -1

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            "Fn": self.Fn,
            "outcome": self.outcome,
            "fate": self.label,
            "attractor": self.attractor,
            "t": self.t,
            "returns": self.returns,
            "drift": self.drift,
        }


@dataclass(frozen=True)
class CycleBifurcations:
    """Bifurcations of the overtaken-by-waves cycle continued in ``Fn``.

    Attributes
    ----------
    PD, LPC, NS : tuple of float
        Located period doublings, folds and Neimark-Sacker points (ascending ``Fn``).
    lost_stability_at : float
        First ``Fn`` with a Floquet multiplier outside the unit circle (NaN: none).
    end_Fn : float
        Where the branch ended (the period blow-up at the connection, or a bound).
    status : str
    message : str
    """

    PD: tuple[float, ...]
    LPC: tuple[float, ...]
    NS: tuple[float, ...]
    lost_stability_at: float
    end_Fn: float
    status: str
    message: str

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            "PD": list(self.PD),
            "LPC": list(self.LPC),
            "NS": list(self.NS),
            "lost_stability_at": _finite_or_none(self.lost_stability_at),
            "end_Fn": _finite_or_none(self.end_Fn),
            "status": self.status,
            "message": self.message,
        }


@dataclass(frozen=True, eq=False)
class CapsizingThreshold:
    """The capsizing threshold of one course and its mechanism.

    Attributes
    ----------
    chi_c : float
        Course (rad).
    Fn : float
        The threshold ``Fn_c`` (midpoint of the final bracket; NaN if none found).
    error : float
        Half the final bracket (NaN if none found).
    bracket : (float, float) or None
        Last surviving and first capsizing ``Fn``.
    mechanism : str
        One of :data:`MECHANISMS`.
    Fn_heteroclinic : float
        The heteroclinic connection's ``Fn`` (NaN if it was not found at this course).
    Fn_heteroclinic_error : float
        Its error estimate (NaN if not estimated).
    is_heteroclinic : bool
        ``|Fn - Fn_heteroclinic| <= error + Fn_heteroclinic_error``.
    below, above : FateSample or None
        The evidence: fates at ``Fn -+ check_distance``.
    samples : tuple of FateSample
        Every fate evaluated, in ``Fn`` order.
    bifurcations : CycleBifurcations or None
        The overtaken cycle's bifurcations (when located).
    attractor_below : str
        The attractor reached at the upper end of the surviving side of the bracket.
    scanned : (float, float)
        The ``Fn`` range searched.
    resolution : str
        What the scan resolves (module notes).
    status : Status
        ``SUCCESS`` when a threshold was bracketed to ``tol`` with every fate below it
        decided; ``UNDECIDED`` if a fate below it stayed undecided; ``NO_BRACKET`` if no
        capsize was found in the scanned range; ``NO_SOLUTION`` if there is none: above
        the connection the branch surf-rides instead (``chi_c = 0``: no lateral motion,
        no capsize), or there is no crest saddle; ``REJECTED`` when the ship cannot hold
        the course (rudder at its limit at the crest saddle).
    message : str
    elapsed : float
        Wall time (s).
    heteroclinic : CriticalFn or None
        The connection's result.
    """

    chi_c: float
    Fn: float
    error: float
    bracket: tuple[float, float] | None
    mechanism: str
    Fn_heteroclinic: float
    Fn_heteroclinic_error: float
    is_heteroclinic: bool
    below: FateSample | None
    above: FateSample | None
    samples: tuple[FateSample, ...]
    bifurcations: CycleBifurcations | None
    attractor_below: str
    scanned: tuple[float, float]
    resolution: str
    status: Status
    message: str
    elapsed: float = 0.0
    heteroclinic: CriticalFn | None = field(default=None, repr=False)

    @property
    def success(self) -> bool:
        """True when ``status`` is ``SUCCESS``."""
        return self.status is Status.SUCCESS

    @property
    def chi_c_deg(self) -> float:
        """Course in degrees."""
        return math.degrees(self.chi_c)

    @property
    def confirmed(self) -> bool:
        """The evidence holds: no capsize at ``Fn - d``, capsize at ``Fn + d``."""
        return (
            self.below is not None
            and self.above is not None
            and self.below.outcome == SURVIVE
            and self.above.outcome == CAPSIZE
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary (angles in degrees)."""
        return {
            "chi_c_deg": self.chi_c_deg,
            "Fn": _finite_or_none(self.Fn),
            "error": _finite_or_none(self.error),
            "bracket": list(self.bracket) if self.bracket else None,
            "mechanism": self.mechanism,
            "Fn_heteroclinic": _finite_or_none(self.Fn_heteroclinic),
            "Fn_heteroclinic_error": _finite_or_none(self.Fn_heteroclinic_error),
            "is_heteroclinic": self.is_heteroclinic,
            "attractor_below": self.attractor_below,
            "evidence": {
                "below": self.below.to_json() if self.below else None,
                "above": self.above.to_json() if self.above else None,
                "confirmed": self.confirmed,
            },
            "bifurcations": self.bifurcations.to_json() if self.bifurcations else None,
            "scanned": list(self.scanned),
            "resolution": self.resolution,
            "n_fates": len(self.samples),
            "fates": [s.to_json() for s in self.samples],
            "status": self.status.name,
            "message": self.message,
            "elapsed_s": self.elapsed,
        }


def _finite_or_none(x: float | None) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


def sample_of(Fn: float, fate: ShipFate | None) -> FateSample:
    """A :class:`FateSample` from a fate (``None``: the crest saddle was lost)."""
    if fate is None:
        return FateSample(float(Fn), NO_SADDLE, NO_SADDLE, math.nan)
    if fate.kind == ShipOutcome.CAPSIZE:
        out = CAPSIZE
    elif fate.kind == ShipOutcome.UNDECIDED:
        out = UNDECIDED
    else:
        out = SURVIVE
    return FateSample(float(Fn), out, str(fate.label), float(fate.t), fate.returns, fate.drift)


def fates_at(
    model: VesselModel, params: Any, Fn: list[float], *, t_max: float = 1200.0
) -> list[FateSample]:
    """The upslope branch's fate at each ``Fn`` (the crest saddle tracked by Newton from
    the first), e.g. the evidence of a heteroclinic Fn at ``Fn -+ 0.002``."""
    par = ship_params(model, params)
    start = find_fixed_point(model, par.replace(Fn=Fn[0]), "crest")
    fate_at = _FateAt(model, par.replace(Fn=Fn[0]), start, "upslope", {"t_max": t_max}, "final")
    return [sample_of(f, fate_at(f)) for f in Fn]


class _Fates:
    """Memoised upslope fates as a function of ``Fn`` (the saddle tracked by Newton)."""

    def __init__(self, fate_at: _FateAt, progress: Callable[[FateSample], None] | None) -> None:
        self.fate_at = fate_at
        self.samples: dict[float, FateSample] = {}
        self.progress = progress

    def __call__(self, Fn: float) -> FateSample:
        key = round(float(Fn), 12)
        if key not in self.samples:
            s = sample_of(key, self.fate_at(key))
            self.samples[key] = s
            if self.progress is not None:
                self.progress(s)
        return self.samples[key]

    def sorted(self) -> tuple[FateSample, ...]:
        return tuple(self.samples[k] for k in sorted(self.samples))


def cycle_bifurcations(
    model: VesselModel, params: Any, *, Fn_min: float = 0.0, Fn_max: float
) -> CycleBifurcations:
    """Bifurcations of the overtaken cycle continued in ``Fn``, those in ``[Fn_min, Fn_max]``.

    The cycle is simulated at ``Fn_min`` (or 0.1, the paper's initial state of Fig. 16,
    where it does not settle there), corrected by collocation
    and continued with period-doubling / Neimark-Sacker detection
    (:func:`~ship_models.analysis.cycles.cycle_branch`, ``detect_pd=True``).

    Returns
    -------
    CycleBifurcations
    """
    from continuation.branch import SpecialKind

    from .cycles import cycle_branch, simulated_cycle

    par = ship_params(model, params)
    orbit = None
    for fn0 in (Fn_min, 0.1):
        if not 0 < fn0 < Fn_max:
            continue
        try:
            orbit = simulated_cycle(model, par.replace(Fn=fn0))
            break
        except ValueError:
            continue
    if orbit is None:
        why = f"no settled overtaken cycle at Fn {Fn_min:.4f} or 0.1"
        return CycleBifurcations((), (), (), math.nan, math.nan, "NO_SOLUTION", why)
    # the bifurcations name the mechanism; 1e-5 in the states locates them to ~1e-8 in Fn
    cb = cycle_branch(orbit, "Fn", p_max=Fn_max, detect_pd=True, error_tol=1e-5)
    pd, lpc, ns = [], [], []
    for sp in cb.branch.special_points:
        if not Fn_min <= float(sp.p) <= Fn_max:
            continue
        if sp.kind == SpecialKind.FOLD:
            lpc.append(float(sp.p))
        elif sp.kind == SpecialKind.PERIOD_DOUBLING:
            pd.append(float(sp.p))
        elif sp.kind == SpecialKind.NEIMARK_SACKER:
            ns.append(float(sp.p))
    return CycleBifurcations(
        tuple(sorted(pd)), tuple(sorted(lpc)), tuple(sorted(ns)), float(cb.lost_stability_at),
        float(cb.p[-1]), cb.status.name, cb.message,
    )  # fmt: skip


def _mechanism(
    Fn: float, Fn_h: float, attractor: str, bif: CycleBifurcations | None, tol: float
) -> tuple[str, str]:
    """Name the non-heteroclinic mechanism from the overtaken cycle's first bifurcation.

    The first loss of stability of the cycle (PD, LPC or NS) is taken to set the
    threshold when it lies below ``Fn_c`` (the attractor is lost beyond it: a cascade
    and crisis after a supercritical period doubling) or within a quarter of the way
    from ``Fn_c`` to the connection above it (the branch leaves the cycle's basin as it
    shrinks onto the bifurcation: a subcritical one).
    """
    if bif is None or not (bif.PD or bif.LPC or bif.NS):
        doubled = attractor.startswith("period-") and attractor != "period-1"
        if attractor == "recurrent" or doubled:
            return "period-doubling cascade and crisis", (
                f"the attractor just below Fn_c is {attractor}; no bifurcation of the "
                "overtaken cycle was located"
            )
        return "crisis", (
            f"no bifurcation of the overtaken cycle was located below its end; the attractor "
            f"just below Fn_c is {attractor}: it meets the capsize basin's boundary"
        )
    first = min([*bif.PD, *bif.LPC, *bif.NS])
    reach = Fn + tol + (0.25 * (Fn_h - Fn) if math.isfinite(Fn_h) and Fn_h > Fn else 0.0)
    if first > reach:
        return "crisis", (
            f"the overtaken cycle's first bifurcation, Fn = {first:.5f}, lies above Fn_c; the "
            f"attractor just below Fn_c is {attractor}: it meets the capsize basin's boundary"
        )
    if first in bif.PD:
        name = "period-doubling cascade and crisis"
        if first <= Fn + tol:
            how = (f"the overtaken cycle period-doubles at Fn = {first:.5f}; the attractor "
                   f"just below Fn_c is {attractor}, destroyed at Fn_c")  # fmt: skip
        else:
            name = "subcritical period doubling"
            how = (f"the overtaken cycle period-doubles at Fn = {first:.5f}, {first - Fn:.4f} "
                   "above Fn_c: its basin shrinks onto the cycle and the branch leaves it "
                   "before the doubling")  # fmt: skip
        return name, how
    if first in bif.LPC:
        return "fold of cycles", f"the overtaken cycle folds at Fn = {first:.5f}"
    return "torus breakdown", f"the overtaken cycle has a Neimark-Sacker point at {first:.5f}"


#: Lateral states that vanish on the surge plane of a symmetric ship.
LATERAL = ("v", "r", "phi", "p_roll", "delta")


def _lateral_at_rest(model: VesselModel, saddle: Any) -> bool:
    """The saddle on the surge plane (all lateral states zero, heading on the course)."""
    names = [n for n in LATERAL if n in model.state_names]
    return bool(names) and all(abs(float(saddle.x[model.state_index(n)])) < 1e-12 for n in names)


#: Fraction of the rudder limit at which the crest saddle counts as saturated.
RUDDER_SATURATED = 0.95


def _rudder_saturated(model: VesselModel, saddle: Any) -> bool:
    """The crest saddle's rudder angle within 5 % of its limit: the course is not held."""
    limit = getattr(getattr(model, "forces", None), "delta_max", None)
    if limit is None or "delta" not in model.state_names:
        return False
    delta = float(saddle.x[model.state_index("delta")])
    return abs(delta) >= RUDDER_SATURATED * float(limit)


def capsizing_threshold(
    model: VesselModel | None = None,
    params: Any = None,
    *,
    chi_c: float | None = None,
    heteroclinic: CriticalFn | None = None,
    Fn_heteroclinic: tuple[float, float] | None = None,
    Fn_anchor: float | None = None,
    Fn_range: tuple[float, float] | None = None,
    settings: ThresholdSettings | None = None,
    progress: Callable[[FateSample], None] | None = None,
    **options: Any,
) -> CapsizingThreshold:
    """The capsizing threshold of one course, its evidence and mechanism (module notes).

    Parameters
    ----------
    model : Umeda4DOF, optional
        Default a new :func:`ship_models.purse_seiner`.
    params : Params or mapping, optional
        Wave and autopilot parameters (default the model's).
    chi_c : float, optional
        Course (rad); default that of ``params``.
    heteroclinic : CriticalFn, optional
        The connection at this course if already solved (e.g. from the critical curve);
        otherwise solved here (:func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`
        with its convergence check).
    Fn_heteroclinic : (float, float), optional
        Instead of ``heteroclinic``: its ``Fn`` and error estimate (NaN: no connection on
        this course, e.g. beyond the critical curve's fold); nothing is solved.
    Fn_anchor : float, optional
        Where there is no connection: the scan covers ``Fn_anchor -+ depth`` (default
        the surf-riding window).
    Fn_range : (float, float), optional
        The range scanned, instead of the one derived from the connection (the first
        capsize in it is the answer; ``NO_BRACKET`` if the branch already capsizes at
        its lower end).
    settings : ThresholdSettings, optional
    progress : callable, optional
        Called with each new :class:`FateSample`.
    **options
        Fields of :class:`ThresholdSettings` replaced in ``settings``.

    Returns
    -------
    CapsizingThreshold
    """
    t0 = time.perf_counter()
    cfg = replace_settings(settings or ThresholdSettings(), "threshold", **options)
    m = ship_model(model)
    base = ship_params(m, params)
    chi = course(base["chi_c"] if chi_c is None else chi_c)
    base = base.replace(chi_c=chi)
    window = surf_riding_window(m, base)
    if heteroclinic is None and Fn_heteroclinic is None:
        from .critical_bvp import critical_fn_bvp

        lo_g = max(window.Fn_lo, 0.1) if window.exists else 0.2
        hi_g = min(window.Fn_hi, 0.65) if window.exists else 0.45
        try:
            bracket = (lo_g, max(hi_g, lo_g + 0.05))
            heteroclinic = critical_fn_bvp(
                chi, model=m, params=base, check=True, guess_bracket=bracket
            )
        except (ValueError, ArithmeticError) as exc:  # no usable guess on this course
            log.debug("no heteroclinic connection at chi_c=%g deg: %s", math.degrees(chi), exc)
            heteroclinic = None
    Fn_h = math.nan
    err_h = math.nan
    if heteroclinic is not None and heteroclinic.success and math.isfinite(heteroclinic.Fn):
        Fn_h = float(heteroclinic.Fn)
        err_h = float(heteroclinic.error) if heteroclinic.error is not None else math.nan
    elif Fn_heteroclinic is not None:
        Fn_h, err_h = (float(v) for v in Fn_heteroclinic)
    top_fit = fn_limit(m)
    lo_w = window.Fn_lo if window.exists else 0.05
    hi_w = window.Fn_hi if window.exists else 0.6
    if math.isfinite(Fn_h):
        lo = max(lo_w, Fn_h - cfg.depth)
        hi = min(hi_w, Fn_h + 2 * cfg.check_distance)
    elif Fn_anchor is not None and math.isfinite(Fn_anchor):
        lo, hi = max(lo_w, Fn_anchor - cfg.depth), min(hi_w, Fn_anchor + cfg.depth)
    else:
        lo, hi = lo_w, hi_w
    lo = max(lo, 0.05)
    if Fn_range is not None:
        lo, hi = (float(v) for v in Fn_range)
        if not (0 < lo < hi and math.isfinite(hi)):
            raise ValueError(f"`Fn_range` must satisfy 0 < lo < hi, got {Fn_range!r}")
    resolution = (
        f"grid {cfg.coarse_step:g} where the branch reaches the plain overtaken cycle at both "
        f"ends, {cfg.step:g} elsewhere, from Fn = {lo:.4f}; bisection to {cfg.tol:g}; "
        f"survival = no capsize within {cfg.t_max:g} s (undecided fates retried at 2x, 4x)"
    )

    def result(**kw: Any) -> CapsizingThreshold:
        base_kw: dict[str, Any] = {
            "chi_c": float(chi), "Fn": math.nan, "error": math.nan, "bracket": None,
            "mechanism": "none", "Fn_heteroclinic": Fn_h, "Fn_heteroclinic_error": err_h,
            "is_heteroclinic": False, "below": None, "above": None, "samples": (),
            "bifurcations": None, "attractor_below": "", "scanned": (lo, hi),
            "resolution": resolution, "elapsed": 0.0, "heteroclinic": heteroclinic,
        }  # fmt: skip
        base_kw.update(kw)
        base_kw["elapsed"] = time.perf_counter() - t0
        return CapsizingThreshold(**base_kw)

    start, first_error = None, ""
    while lo < hi:  # the crest saddle may exist only higher up in the window
        try:
            start = find_fixed_point(m, base.replace(Fn=lo), "crest")
            break
        except (ValueError, ArithmeticError) as exc:
            first_error = first_error or str(exc)
            lo = min(hi, lo + cfg.coarse_step)
    if start is None:
        return result(status=Status.NO_SOLUTION,
                      message=f"no crest saddle in Fn [{lo:.4f}, {hi:.4f}] at chi_c = "
                              f"{math.degrees(chi):.4g} deg: {first_error}")  # fmt: skip
    if chi == 0.0 and _lateral_at_rest(m, start):
        # head-on following waves: the lateral motions are not excited (the surge plane is
        # invariant), so nothing capsizes; the connection is the surf-riding threshold
        return result(status=Status.NO_SOLUTION,
                      message="chi_c = 0: the lateral motions are not excited (the crest "
                              "saddle lies on the invariant surge plane), so the ship cannot "
                              "capsize; the heteroclinic Fn is the surf-riding threshold "
                              "there")  # fmt: skip
    if _rudder_saturated(m, start):
        return result(status=Status.REJECTED,
                      message=f"the rudder is at its limit at the crest saddle (chi_c = "
                              f"{math.degrees(chi):.4g} deg): the ship cannot hold this course, "
                              "so it has no course-dependent threshold")  # fmt: skip
    fate_at = _FateAt(m, base.replace(Fn=lo), start, "upslope", {"t_max": cfg.t_max}, "final")
    fates = _Fates(fate_at, progress)

    def decided(Fn: float) -> FateSample | None:
        smp = fates(Fn)
        return smp if smp.outcome in (CAPSIZE, SURVIVE) else None

    try:

        def search(a: float, b: float) -> Any:
            return lowest_fate(
                decided, a, b, is_target=lambda smp: smp.outcome == CAPSIZE,
                is_plain=lambda smp: smp.plain_cycle, step=cfg.step,
                coarse_step=cfg.coarse_step, tol=cfg.tol,
            )  # fmt: skip

        found = search(lo, hi)
        while (found.bracket is None and Fn_range is None and lo > max(lo_w, 0.05) + 1e-9
               and fates(lo).outcome == CAPSIZE):  # fmt: skip
            # the branch already capsizes where the scan began: the threshold lies lower
            new_lo = max(lo_w, 0.05, lo - cfg.depth)
            try:
                find_fixed_point(m, base.replace(Fn=new_lo), "crest")
            except (ValueError, ArithmeticError):
                break  # no crest saddle lower down: the branch capsizes from its start
            found = search(new_lo, lo + cfg.coarse_step)
            lo = new_lo
        top = min(hi_w, top_fit)
        if found.bracket is None and Fn_range is None and hi < top - cfg.coarse_step:
            # nothing capsizes up to just above the connection (gentle waves): the
            # threshold, if any, lies higher in the window where the crest saddle exists
            found = search(lo, top)
            hi = top
        if found.bracket is None:
            above_h = [smp for smp in fates.sorted() if smp.outcome == SURVIVE]
            why, st = "", Status.NO_BRACKET
            if fates(lo).outcome == CAPSIZE:
                return result(samples=fates.sorted(), status=st, scanned=(lo, hi),
                              message=f"the upslope branch already capsizes at the lowest Fn "
                                      f"with a crest saddle searched, {lo:.4f} (chi_c = "
                                      f"{math.degrees(chi):.4g} deg): no threshold inside "
                                      "the window")  # fmt: skip
            riding = ("equilibrium", "saddle")  # on the surge plane at chi_c = 0: a saddle
            if above_h and all(smp.label.startswith(riding) for smp in above_h[-2:]):
                why = (" (above the connection the branch reaches a stable equilibrium: "
                       "surf-riding, the threshold of the surge model, not capsizing; "
                       "there is no capsizing threshold on this course)")  # fmt: skip
                st = Status.NO_SOLUTION
            return result(samples=fates.sorted(), status=st,
                          scanned=(lo, hi),
                          message=f"the upslope branch does not capsize anywhere in Fn "
                                  f"[{lo:.4f}, {hi:.4f}] at chi_c = {math.degrees(chi):.4g} "
                                  f"deg (grid {cfg.step:g}-{cfg.coarse_step:g}){why}")  # fmt: skip
        a, b = found.bracket
        Fn_c, err_c = found.p, found.error
        d = cfg.check_distance
        below = fates(Fn_c - d)
        above = fates(Fn_c + d)
    except KeyboardInterrupt:
        return result(samples=fates.sorted(), status=Status.INTERRUPTED,
                      message="interrupted; the fates computed so far are kept")  # fmt: skip
    samples = fates.sorted()
    undecided = [s.Fn for s in samples if s.outcome == UNDECIDED and s.Fn < Fn_c]
    attractor = fates(a).attractor
    is_het = math.isfinite(Fn_h) and abs(Fn_c - Fn_h) <= err_c + cfg.coincide + (
        err_h if math.isfinite(err_h) else 0.0
    )
    bif = None
    if is_het:
        mech = "heteroclinic"
        why = (
            f"it coincides with the heteroclinic connection Fn = {Fn_h:.6f} "
            f"({Fn_h - Fn_c:+.1e}) within their error estimates and the band of secondary "
            f"connections ({err_c:.1e} + {err_h:.1e} + {cfg.coincide:g})"
        )
    else:
        if cfg.locate_bifurcations:
            try:
                t_b = time.perf_counter()
                bif = cycle_bifurcations(m, base, Fn_min=max(lo, Fn_c - 0.03),
                                         Fn_max=min(hi, Fn_c + 2 * d))  # fmt: skip
                log.debug("cycle bifurcations in %.1f s", time.perf_counter() - t_b)
            except (ValueError, ArithmeticError) as exc:
                log.debug("cycle bifurcations not located: %s", exc)
        mech, why = _mechanism(Fn_c, Fn_h, attractor, bif, cfg.tol)
        if math.isfinite(Fn_h):
            why += f"; the heteroclinic connection is at Fn = {Fn_h:.6f}, {Fn_h - Fn_c:+.4f} away"
        else:
            why += "; no heteroclinic connection was found on this course"
    notes = []
    if b - a > cfg.tol:
        notes.append(f"bisection stopped at an undecided fate inside [{a:.6f}, {b:.6f}]")
    if above.outcome != CAPSIZE:
        up = [s for s in samples if s.Fn > Fn_c and s.outcome == SURVIVE]
        notes.append(
            f"the branch survives again at Fn = {up[0].Fn:.5f}: the capsizing window above "
            f"Fn_c is narrower than {d:g}"
            if up
            else "the fate above Fn_c is not a capsize"
        )
    if below.outcome != SURVIVE:
        notes.append(f"the fate at Fn_c - {d:g} is {below.label}")
    chaotic = [smp.Fn for smp in samples if smp.label == ShipOutcome.RECURRENT and smp.Fn < Fn_c]
    if chaotic:
        notes.append(
            "bounded irregular motion without a settled period (a chaotic attractor, or a "
            f"transient longer than {cfg.t_max:g} s) below Fn_c at Fn = "
            + ", ".join(f"{f:.5f}" for f in chaotic)
        )  # fmt: skip
    if undecided:
        status = Status.UNDECIDED
        notes.append(
            "undecided fates below Fn_c at Fn = " + ", ".join(f"{f:.5f}" for f in undecided)
            + ": a lower capsize cannot be excluded"
        )  # fmt: skip
    elif b - a > cfg.tol:
        status = Status.UNDECIDED
    else:
        status = Status.SUCCESS
    msg = (
        f"capsizing threshold Fn_c = {Fn_c:.5f} +- {err_c:.1e} at chi_c = "
        f"{math.degrees(chi):.4g} deg, mechanism: {mech} ({why})"
    )
    if notes:
        msg += "; " + "; ".join(notes)
    return result(
        Fn=Fn_c, error=err_c, bracket=(a, b), mechanism=mech, is_heteroclinic=is_het,
        below=below, above=above, samples=samples, bifurcations=bif,
        attractor_below=attractor, status=status, message=msg,
    )  # fmt: skip


__all__ = [
    "MECHANISMS",
    "CapsizingThreshold",
    "CycleBifurcations",
    "FateSample",
    "ThresholdSettings",
    "capsizing_threshold",
    "cycle_bifurcations",
    "fates_at",
    "sample_of",
]
