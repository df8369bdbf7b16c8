r"""The ship "overtaken by waves" as a periodic orbit: collocation, continuation, its end.

Umeda (1999) starts every sudden-change experiment from "a harmonic periodic motion":
the ship overtaken by waves. On the wave-relative coordinate :math:`\xi_G/\lambda`
(periodic, period 1) it is a *rotation orbit*: :math:`\xi_G/\lambda` falls by one
wavelength per period,

.. math:: x(t + T) = x(t) - e_{\xi_G}, \qquad \text{winding } \{\xi_G: -1\}.

This module computes it by orthogonal collocation (:mod:`continuation.periodic`) and
continues it in ``Fn`` or ``chi_c``:

* :func:`simulated_cycle` -- the attracting cycle from a settled simulation, corrected
  on the collocation mesh;
* :func:`cycle_branch` -- the branch of cycles in ``Fn`` (or ``chi_c``); it ends where
  the period grows without bound, i.e. where the cycle becomes the heteroclinic orbit
  from the crest saddle to the next crest saddle (the paper's heteroclinic bifurcation,
  :func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`);
* :func:`cycle_at` -- the cycle at other controls by continuation (where simulation
  from the calm-water guess capsizes, e.g. ``Fn = 0.3``, ``chi_c = 45 deg``);
* :func:`section_state`, :func:`compare_with_shooting` -- the cross-check against the
  return-map shooting solver :func:`~ship_models.analysis.sudden_change.periodic_orbit`.

*The end of the branch.* Near the connection the period grows like
:math:`T \approx a - b \ln|Fn^* - Fn|`; :attr:`CycleBranch.limit` is :math:`Fn^*`
fitted so (:func:`continuation.periodic.period_limit`) to the rows with
``T >= fit_from * T_last``. The crest saddle is a saddle-focus (purse seiner,
``chi_c = 10 deg``: :math:`\lambda_u = 0.31`, leading stable pair
:math:`-0.073 \pm 0.85 i` 1/s), for which Shilnikov's theory predicts a snaking
approach :math:`Fn(T) \approx Fn^* + e^{-\rho T}(a\cos\omega T + b\sin\omega T)`;
:func:`fit_saddle_focus_limit` fits that law too (:attr:`CycleBranch.limit_saddle_focus`),
as a second estimate. Measured on the purse seiner (``T`` 30-60 s): the approach is
monotone up to a fold of cycles at ``T`` about 50 s, the log law fits to 4e-6 of the
connection solver and the saddle-focus law to 2e-5.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize as so

from continuation.branch import Branch
from continuation.bvp import CollocationMesh
from continuation.dynamics import simulate
from continuation.dynamics.shooting import ShootingOrbit
from continuation.errors import ContinuationError
from continuation.periodic import (
    PeriodicOrbit,
    continue_periodic,
    multipliers,
    orbit_at,
    orbit_from_trajectory,
    period_limit,
)
from continuation.settings import ContinuationSettings
from continuation.status import Status
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .crest_saddle import crest_saddle
from .eigen import paper_scales
from .events import capsize_angle as capsize_angle_of
from .sudden_change import default_guess

log = logging.getLogger(__name__)

#: The overtaken-by-waves cycle: xi_G / lambda falls by one wavelength per period.
WINDING = {"xi_G": -1}
#: Default collocation mesh: intervals and degree.
N_INTERVALS, DEGREE = 60, 4


def simulated_cycle(
    model: VesselModel,
    params: Any,
    *,
    x_guess: Any = None,
    t_settle: float = 300.0,
    mesh: CollocationMesh | None = None,
) -> PeriodicOrbit:
    """The attracting overtaken-by-waves cycle from a settled simulation.

    Simulates ``t_settle`` seconds from ``x_guess`` (default: calm-water start,
    :func:`~ship_models.analysis.sudden_change.default_guess`), cuts the last period
    and corrects it by Newton's method on the collocation system
    (:func:`continuation.periodic.orbit_from_trajectory`, winding :data:`WINDING`).

    Parameters
    ----------
    model : VesselModel
    params : Params, mapping or array
    x_guess : array_like, shape (8,), optional
    t_settle : float
        Simulated time (s).
    mesh : CollocationMesh, optional
        Default :data:`N_INTERVALS` intervals of degree :data:`DEGREE`.

    Returns
    -------
    PeriodicOrbit
        ``X (M, 8)``, period ``T`` (s).

    Raises
    ------
    ValueError
        On bad input, or if the simulation capsizes or does not settle on a cycle
        drifting back one wave per period.
    """
    par = model.as_params(params)
    if not (math.isfinite(t_settle) and t_settle > 0):
        raise ValueError(f"`t_settle` must be a positive time, got {t_settle!r}")
    x0 = default_guess(model, par) if x_guess is None else model.check_state(x_guess, "x_guess")
    tr = simulate(model, x0, par, (0.0, float(t_settle)), dt=0.05)
    i_phi = model.state_index("phi")
    if not tr.status.ok or np.max(np.abs(tr.x[:, i_phi])) >= capsize_angle_of(model):
        raise ValueError(
            "`params`: the simulation from the guess does not settle on a cycle "
            f"({tr.message or 'capsized'}); "
            "reach these controls by cycle_at from another cycle"
        )
    mesh = mesh if mesh is not None else CollocationMesh(N_INTERVALS, DEGREE, 1.0)
    return orbit_from_trajectory(model, par, tr, mesh=mesh, winding=WINDING)


def section_state(orbit: PeriodicOrbit, xi_0: float = 0.0) -> tuple[FloatArray, float]:
    r"""The state on the cycle where :math:`\xi_G/\lambda \equiv \xi_0 \pmod 1`.

    The crossing time is found by Brent's method on the collocation polynomial.

    Returns
    -------
    x : ndarray, shape (8,)
        With ``xi_G`` set to ``xi_0`` exactly.
    t : float
        Time of the crossing after the start of ``orbit.X`` (s).
    """
    model = orbit.system
    i = model.state_index("xi_G")
    a = float(orbit.X[0, i])
    level = xi_0 + math.floor(a - xi_0)  # the first level at or below the start
    if math.isclose(level, a, abs_tol=1e-14):
        t = 0.0
    else:
        t = so.brentq(lambda s: float(orbit(s)[0, i]) - level, 0.0, orbit.T, xtol=1e-14)
    x = orbit(t)[0].copy()
    x[i] = xi_0
    return x, float(t)


@dataclass(frozen=True)
class CycleComparison:
    """Collocation cycle against the shooting solver's.

    Attributes
    ----------
    dT : float
        ``T_collocation - T_shooting`` (s).
    d_state : float
        Largest difference of the section states (``xi_G = section``), each state
        divided by its scale of the paper's nondimensionalisation.
    d_multiplier : float
        Largest difference of the sorted moduli of the nontrivial multipliers.
    """

    dT: float
    d_state: float
    d_multiplier: float


def compare_with_shooting(orbit: PeriodicOrbit, shooting: ShootingOrbit) -> CycleComparison:
    """:class:`CycleComparison` of a collocation cycle with a shooting one."""
    model = orbit.system
    x, _ = section_state(orbit, shooting.section)
    scales, _ = paper_scales(model, shooting.params, default_guess(model, shooting.params))
    d = (x - shooting.x_section) / np.asarray(scales, dtype=float)
    d[model.state_index("xi_G")] = 0.0
    from continuation.periodic import PeriodicOrbitProblem

    prob = PeriodicOrbitProblem.from_orbit(orbit, "Fn")
    mu = np.sort(np.abs(prob.floquet(prob.reference, orbit.param("Fn")).multipliers))
    ref = np.sort(np.abs(shooting.multipliers))
    return CycleComparison(
        float(orbit.T - shooting.period), float(np.max(np.abs(d))), float(np.max(np.abs(mu - ref)))
    )


def cycle_at(
    orbit: PeriodicOrbit,
    settings: ContinuationSettings | None = None,
    **targets: float,
) -> PeriodicOrbit:
    """The cycle at new controls, continued from ``orbit`` one parameter at a time.

    Parameters
    ----------
    orbit : PeriodicOrbit
        A ship cycle.
    settings : ContinuationSettings, optional
        Step sizes (the bounds are set from the targets).
    **targets : float
        New values in the order given, e.g. ``cycle_at(o, chi_c=0.785, Fn=0.3)``.

    Raises
    ------
    ValueError
        Unknown parameter name.
    ContinuationError
        If a branch ends before its target (fold, period blow-up, failure).
    """
    st0 = settings if settings is not None else ContinuationSettings(ds=0.01, ds_max=0.03,
                                                                     max_steps=300)  # fmt: skip
    for name, value in targets.items():
        if name not in orbit.system.param_names:
            raise ValueError(f"`{name}`: not a parameter of the model {orbit.system.param_names}")
        p0 = orbit.param(name)
        value = float(value)
        if math.isclose(p0, value, rel_tol=0, abs_tol=1e-14):
            continue
        up = value > p0
        st = dataclasses.replace(
            st0, ds=abs(st0.ds) if up else -abs(st0.ds),
            p_max=value if up else max(st0.p_max, value + 10.0),
            p_min=value if not up else min(st0.p_min, value - 10.0),
        )  # fmt: skip
        br = continue_periodic(orbit.system, orbit, orbit.params, name, st, detect_pd=False,
                               detect_ns=False)  # fmt: skip
        if br.status != Status.PARAM_BOUND or not math.isclose(br.p[-1], value, abs_tol=1e-10):
            raise ContinuationError(
                f"cycle_at: the cycle branch in {name} ended at {br.p[-1]:.8g} before "
                f"{value:.8g}: {br.message}"
            )
        orbit = orbit_at(br, len(br) - 1)
    return orbit


@dataclass(frozen=True)
class SaddleFocusFit:
    r"""Fit of :math:`p = p^* + e^{-\rho T}(a\cos\omega T + b\sin\omega T)`.

    Attributes
    ----------
    p_star : float
    rho, omega : float
        Leading stable eigenvalue ``-rho +- i omega`` of the saddle (1/s), fixed.
    residual : float
        RMS residual in ``p``.
    n_rows : int
    """

    p_star: float
    rho: float
    omega: float
    residual: float
    n_rows: int


def fit_saddle_focus_limit(p: Any, T: Any, rho: float, omega: float) -> SaddleFocusFit:
    """Least-squares :class:`SaddleFocusFit` of rows ``(p, T)`` (linear in ``p*, a, b``)."""
    p = np.asarray(p, dtype=float)
    T = np.asarray(T, dtype=float)
    if p.shape != T.shape or p.size < 4:
        raise ValueError("`p` and `T` must have the same shape with at least 4 rows")
    Tn = T - T[-1]
    e = np.exp(-rho * Tn)
    A = np.column_stack([np.ones_like(T), e * np.cos(omega * T), e * np.sin(omega * T)])
    coef, *_ = np.linalg.lstsq(A, p, rcond=None)
    r = A @ coef - p
    rms = float(np.sqrt(np.mean(r**2)))
    return SaddleFocusFit(float(coef[0]), float(rho), float(omega), rms, p.size)


@dataclass(frozen=True, eq=False)
class CycleBranch:
    """A branch of overtaken-by-waves cycles and where it ends.

    Attributes
    ----------
    branch : Branch
        From :func:`continuation.periodic.continue_periodic`.
    free : str
        ``"Fn"`` or ``"chi_c"``.
    p, T : ndarray, shape (K,)
        Parameter and period (s).
    max_roll, max_heading : ndarray, shape (K,)
        ``max |phi|`` and ``max |chi - chi_c|`` over each cycle (rad).
    mu_max : ndarray, shape (K,)
        Largest modulus of the nontrivial Floquet multipliers.
    mu_lead : ndarray, shape (K,), complex
        That multiplier (its sign tells a fold, +1, from a period doubling, -1).
    n_unstable : ndarray, shape (K,)
        Multipliers outside the unit circle.
    limit : float
        The parameter where the period grows without bound, from the law
        ``T = a - b ln|p* - p|`` (NaN if the branch did not end so).
    limit_saddle_focus : float
        The same from :func:`fit_saddle_focus_limit` (NaN if not ended so).
    fit : SaddleFocusFit or None
    lost_stability_at : float
        First parameter with an unstable multiplier (NaN: stable throughout).
    status : Status
    message : str
    """

    branch: Branch
    free: str
    p: FloatArray
    T: FloatArray
    max_roll: FloatArray
    max_heading: FloatArray
    mu_max: FloatArray
    n_unstable: np.ndarray
    mu_lead: np.ndarray
    limit: float
    limit_saddle_focus: float
    fit: SaddleFocusFit | None
    lost_stability_at: float
    status: Status
    message: str

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (arrays as lists)."""
        return {
            "free": self.free,
            "status": self.status.name,
            "message": self.message,
            "limit": self.limit,
            "limit_saddle_focus": self.limit_saddle_focus,
            "fit": dataclasses.asdict(self.fit) if self.fit is not None else None,
            "lost_stability_at": self.lost_stability_at,
            "rows": {
                self.free: self.p.tolist(),
                "T": self.T.tolist(),
                "max_roll": self.max_roll.tolist(),
                "max_heading": self.max_heading.tolist(),
                "mu_max": self.mu_max.tolist(),
                "mu_lead_real": self.mu_lead.real.tolist(),
                "mu_lead_imag": self.mu_lead.imag.tolist(),
                "n_unstable": self.n_unstable.tolist(),
            },
        }


def cycle_branch(
    orbit: PeriodicOrbit,
    free: str = "Fn",
    *,
    p_min: float = 0.0,
    p_max: float = 0.45,
    ds: float = 0.02,
    ds_max: float = 0.1,
    max_steps: int = 400,
    period_max: float = 60.0,
    adapt_every: int = 10,
    direction: str = "forward",
    n_fit: int = 40,
    fit_from: float = 0.5,
    detect_pd: bool = False,
    error_tol: float | None = 1e-6,
) -> CycleBranch:
    r"""Continue the ship's cycle in ``free`` until its period exceeds ``period_max``.

    Parameters
    ----------
    orbit : PeriodicOrbit
        The start cycle (e.g. :func:`simulated_cycle`).
    free : {"Fn", "chi_c"}
    p_min, p_max : float
        Bounds of ``free``.
    ds, ds_max : float
        Steps (sign of ``ds``: direction of the first step).
    max_steps : int
    period_max : float
        The branch ends where ``T`` reaches it (``Status.PERIOD_UNBOUNDED``): well past
        the first folds of the snaking near the connection (``T`` about 40 s for the
        purse seiner), before the mesh of ``N`` intervals stops resolving the long stay
        at the saddle.
    adapt_every : int
        Equidistribute the mesh every so many steps (0: never).
    direction : {"forward", "backward", "both"}
    n_fit : int
        Most rows in the limit fits.
    fit_from : float
        Fit the rows with ``T >= fit_from * T_last`` (at least 6).
    detect_pd : bool
        Also locate period doublings / Neimark-Sacker points (costs about twice the
        Floquet work; stability changes are in ``n_unstable`` either way).
    error_tol : float or None
        Collocation error tolerance of every row (the mesh grows to meet it;
        :func:`continuation.periodic.continue_periodic`); None: one fixed mesh.

    Returns
    -------
    CycleBranch
    """
    model = orbit.system
    if free not in ("Fn", "chi_c"):
        raise ValueError(f"`free` must be 'Fn' or 'chi_c', got {free!r}")
    st = ContinuationSettings(ds=ds, ds_max=ds_max, max_steps=max_steps, p_min=p_min, p_max=p_max)
    br = continue_periodic(model, orbit, orbit.params, free, st, period_max=period_max,
                           adapt_every=adapt_every, direction=direction, detect_pd=detect_pd,
                           detect_ns=detect_pd, error_tol=error_tol)  # fmt: skip
    rec = br.records
    i_chi = model.param_names.index("chi_c")
    if free == "chi_c":
        chi_c = br.p
    else:
        chi_c = np.full(len(br), float(orbit.params.values[i_chi]))
    max_roll = np.maximum(rec["max_phi"], -rec["min_phi"])
    max_heading = np.maximum(rec["max_chi"] - chi_c, chi_c - rec["min_chi"])
    mu_all = multipliers(br)
    lead = np.argmax(np.abs(mu_all), axis=1)
    mu_lead = mu_all[np.arange(len(br)), lead]
    mu_max = np.abs(mu_lead)
    nun = np.asarray(br.n_unstable)
    bad = np.flatnonzero(nun > 0)
    lost = float(br.p[bad[0]]) if bad.size else math.nan
    limit = limit_sf = math.nan
    fit = None
    if br.status == Status.PERIOD_UNBOUNDED and len(br) >= 8:
        T = np.asarray(rec["T"], float)
        # the asymptotic law holds where the cycle stays long at the saddle: rows with
        # T at least fit_from * T_last, at least 6 of them, at most n_fit
        k = int(np.sum(T >= fit_from * T[-1]))
        k = min(max(k, 6), n_fit, len(br))
        limit = float(period_limit(br, n_fit=max(k, 4)).p_star)
        last = orbit_at(br, len(br) - 1)
        sad = crest_saddle(model, last.params)
        lam = np.asarray(sad.eigen.values)
        stable = lam[lam.real < 0]
        lam_s = stable[np.argmax(stable.real)]
        fit = fit_saddle_focus_limit(br.p[-k:], T[-k:], float(-lam_s.real), float(abs(lam_s.imag)))
        limit_sf = fit.p_star
    return CycleBranch(br, free, np.asarray(br.p, float), np.asarray(rec["T"], float), max_roll,
                       max_heading, mu_max, nun, mu_lead, limit, limit_sf, fit, lost, br.status,
                       br.message)  # fmt: skip


__all__ = [
    "DEGREE",
    "N_INTERVALS",
    "WINDING",
    "CycleBranch",
    "CycleComparison",
    "SaddleFocusFit",
    "compare_with_shooting",
    "cycle_at",
    "cycle_branch",
    "fit_saddle_focus_limit",
    "section_state",
    "simulated_cycle",
]
