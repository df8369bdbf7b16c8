"""Resistance R(u): the measured table, the MMG straight-running coefficient R0', or
ITTC-1957 + Holtrop & Mennen (1982) / Holtrop (1984) fitted by a spline."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..hydro.hull import HullForm
from ..hydro.resistance import (
    HOLTROP_FN_MAX,
    HOLTROP_RANGE_SOURCE,
    HoltropHull,
    ResistanceFit,
    resistance_table,
)
from ..validity import ValidityRange
from ..vessel import VesselData
from .common import Build, estimated
from .memo import memo_fit


def holtrop_hull(v: VesselData, hull: HullForm, C_wp: float, S: float) -> HoltropHull:
    """The inputs of Holtrop's (1984) regression for the vessel's hull (waterplane
    coefficient ``C_wp``, wetted surface ``S``)."""
    L = v.get("particulars.L_pp")
    return HoltropHull(
        L=L,
        B=v.get("particulars.B"),
        T=0.5 * (v.get("particulars.d_f") + v.get("particulars.d_a")),
        T_F=v.get("particulars.d_f"),
        volume=hull.volume,
        C_M=v.get("hull.C_M"),
        C_wp=C_wp,
        lcb_percent=-100.0 * v.get("particulars.lcb_aft") / L,
        S=S,
        C_stern=v.get("resistance.C_stern"),
    )


def estimate_resistance(
    b: Build, hull: HullForm, C_wp: float, S_f: float
) -> tuple[HoltropHull, Any]:
    """The resistance of ``[vessel] resistance_method`` and its validity ranges.

    Parameters
    ----------
    b : Build
        The build; the stage records the Holtrop form factor and correlation allowance
        it estimates, and the validity ranges of the resistance.
    hull : HullForm
    C_wp, S_f : float
        Waterplane coefficient and wetted surface (m^2) used.

    Returns
    -------
    hh : HoltropHull
        The Holtrop regression inputs (for reports and the thrust deduction).
    rfit : ResistanceFit or table
        R(u) with ``evaluate``, ``u_max`` and ``max_rel_error``.
    """
    v, p, est, validity = b.vessel, b.p, b.estimates, b.validity
    rho, g, nu, L, d_m = p.rho, p.g, p.nu, p.L, p.d_m
    hh = holtrop_hull(v, hull, C_wp, S_f)
    hull_type = v.meta.get("hull_type", "")
    rfit: Any
    if v.resistance_method == "table":
        curve = v.curves["resistance"]
        rfit = resistance_table(curve.x, curve.y)
        validity.append(
            ValidityRange(
                f"resistance table ({curve.status}: {curve.source})",
                "u",
                0.0,
                curve.x_range[1],
                "speed range of the measured table",
            )
        )
    elif v.has("resistance.R0_prime"):
        # MMG standard method: R(u) = R0' rho/2 L d u^2 (exact, no fit)
        u_max = (
            v.get("resistance.Fn_max_fit") * np.sqrt(g * L)
            if v.has("resistance.Fn_max_fit")
            else np.sqrt(g * L)
        )
        r2 = v.get("resistance.R0_prime") * 0.5 * rho * L * d_m * u_max**2
        rfit = ResistanceFit(np.array([r2, 0.0]), np.zeros(0), np.zeros(0), float(u_max), 0.0)
    else:
        if v.has("resistance.form_factor"):
            k1 = v.get("resistance.form_factor")
        else:
            k1 = hh.form_factor()
            est["resistance.form_factor"] = estimated(
                k1, "-", "1 + k1: Holtrop (1984), A statistical re-analysis of resistance data"
            )
        if v.has("resistance.C_A"):
            C_A = v.get("resistance.C_A")
        else:
            C_A = hh.correlation_allowance()
            est["resistance.C_A"] = estimated(C_A, "-", "Holtrop (1984) correlation allowance")
        u_max = v.get("resistance.Fn_max_fit") * np.sqrt(g * L)
        knot = v.get("resistance.knot_spacing_Fn") * np.sqrt(g * L)

        def R_formula(u: Any) -> Any:
            return hh.total_resistance(u, rho=rho, g=g, nu=nu, form_factor=k1, C_A=C_A)

        rfit = memo_fit(R_formula, u_max, knot)
        fn_hi = HOLTROP_FN_MAX.get(hull_type)
        if fn_hi is not None:
            validity.append(
                ValidityRange(
                    "resistance (Holtrop & Mennen 1982 / Holtrop 1984 regression)",
                    "Fn",
                    0.0,
                    fn_hi,
                    HOLTROP_RANGE_SOURCE,
                )
            )
        validity.append(
            ValidityRange("resistance spline fit", "u", 0.0, rfit.u_max, "resistance.Fn_max_fit")
        )
    return hh, rfit
