r"""The range of nominal Froude numbers in which surf-riding equilibria exist.

Surf-riding equilibria of the uncoupled surge model (Umeda 1999, Eq. 5 with the
lateral states zero) sit at ``u = c`` where the surge force vanishes,

.. math::

    T(c; n(Fn)) - R(c) + X_w(\xi_G) = 0 ,

so they exist exactly where :math:`-\max_\xi X_w \le T(c; n) - R(c) \le -\min_\xi X_w`.
Thrust at ``u = c`` grows with the commanded revolutions ``n(Fn)`` (Fn is the calm-water
speed ``n`` gives), so the set is an interval ``[Fn_lo, Fn_hi]``: below ``Fn_lo`` the
propeller cannot hold the ship on the wave even at the wave's most favourable phase
(no fixed point, and no crest saddle whose manifolds decide capsizing), above
``Fn_hi`` the ship is pushed through every wave. The capsizing threshold
(:mod:`ship_models.analysis.threshold`) and the heteroclinic connection
(:mod:`ship_models.analysis.critical`) can only lie inside it; it is computed from the
sea state at hand, not assumed (at ``H/lambda = 0.05`` it lies well above the
``H/lambda = 1/9.2`` one).

In quartering seas (``chi_c > 0``) the surge component of the wave force shrinks
roughly with ``cos chi``, so the 4-DOF crest saddle exists in a sub-interval; the
surge window is the outer bound and callers check the saddle itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize as so

from ..contracts import SeaState, VesselModel
from .fixed_points import surge_model_of
from .params import ship_params

#: Bounds of the search for the window's ends (nominal Froude number).
FN_SEARCH = (1e-3, 1.0)


@dataclass(frozen=True)
class FnWindow:
    """Interval of ``Fn`` with surf-riding equilibria in the surge model.

    Attributes
    ----------
    Fn_lo, Fn_hi : float
        Ends (NaN if surf-riding is impossible at every ``Fn`` searched).
    X_max, X_min : float
        Largest and smallest wave surge force over one wavelength at ``u = c`` (N).
    c : float
        Wave celerity (m/s).
    """

    Fn_lo: float
    Fn_hi: float
    X_max: float
    X_min: float
    c: float

    @property
    def exists(self) -> bool:
        """True when the window is not empty."""
        return math.isfinite(self.Fn_lo) and math.isfinite(self.Fn_hi)

    def __contains__(self, Fn: object) -> bool:
        return self.exists and isinstance(Fn, (int, float)) and self.Fn_lo <= Fn <= self.Fn_hi


def fn_limit(model: VesselModel) -> float:
    """Largest Fn the model is valid for: the vessel's R(u) fit range
    (``resistance.Fn_max_fit``), or 1 without one."""
    vessel = getattr(model, "vessel", None)
    if vessel is not None and hasattr(vessel, "has") and vessel.has("resistance.Fn_max_fit"):
        return float(vessel.get("resistance.Fn_max_fit"))
    return 1.0


def surf_riding_window(model: VesselModel, params: Any = None, *, n_grid: int = 400) -> FnWindow:
    r"""The ``Fn`` interval with surf-riding equilibria, for the wave of ``params``.

    Parameters
    ----------
    model : Umeda4DOF
    params : Params, optional
        Its ``H_over_lambda`` and ``lambda_over_L`` are used (default the model's).
    n_grid : int
        Samples of the wave surge force over one wavelength.

    Returns
    -------
    FnWindow
        Ends found by Brent's method on :math:`T(c; n(Fn)) - R(c) + X = 0` for
        ``X = X_max`` (lower end) and ``X = X_min`` (upper end), to 1e-10 in ``Fn``;
        clipped to :data:`FN_SEARCH`.
    """
    par = ship_params(model, params)
    sm = surge_model_of(model)
    sp = sm.params(**{k: par[k] for k in sm.param_names})
    pv = sm.check_params(sp)
    F = sm.forces
    c = sm.celerity(sp)
    xi = np.linspace(0.0, 1.0, n_grid, endpoint=False)
    sea = SeaState(pv[1], pv[2])
    X = np.array([float(F.waves.forces(s, c, 0.0, sea, lift=False)[0]) for s in xi])
    x_max, x_min = float(X.max()), float(X.min())

    def net(Fn: float) -> float:
        return float(F.thrust_force(c, F.revolutions(Fn)) - F.resistance_force(c))

    lo_b, hi_b = FN_SEARCH

    def end(x_wave: float) -> float:
        g_lo, g_hi = net(lo_b) + x_wave, net(hi_b) + x_wave
        if g_lo > 0:  # surf-riding already possible at the smallest Fn searched
            return lo_b
        if g_hi < 0:
            return hi_b
        return float(so.brentq(lambda f: net(f) + x_wave, lo_b, hi_b, xtol=1e-10))

    if x_max <= 0 or x_min >= 0:  # no wave force of both signs: no equilibrium
        return FnWindow(math.nan, math.nan, x_max, x_min, c)
    f_lo, f_hi = end(x_max), end(x_min)
    if not f_lo < f_hi:
        return FnWindow(math.nan, math.nan, x_max, x_min, c)
    return FnWindow(f_lo, f_hi, x_max, x_min, c)


__all__ = ["FN_SEARCH", "FnWindow", "fn_limit", "surf_riding_window"]
