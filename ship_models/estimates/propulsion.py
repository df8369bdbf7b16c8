"""Propulsion: the open-water thrust coefficient K_T(J) (Wageningen B-series,
Oosterveld & van Oossanen 1975, or a measured curve), the wake fraction w_P (Taylor
1933) and thrust deduction t_P (Holtrop 1984), and the propeller they make."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..hydro.curves import Polynomial1D, interpolating_spline
from ..hydro.propeller import (
    Propeller,
    bseries_kt_curve,
    bseries_zero_thrust_J,
    fit_kt_quadratic,
    holtrop_thrust_deduction,
    taylor_wake,
)
from ..hydro.resistance import HoltropHull
from ..validity import ValidityRange
from ..vessel import VesselFileError
from .common import Build, estimated


def quadratic_fit(J: Any, kt: Any) -> tuple[float, float, float]:
    """Least-squares :math:`(k_0, k_1, k_2)` of :math:`K_T \\approx k_0 + k_1 J + k_2 J^2`
    through the samples ``kt`` at ``J``."""
    A = np.column_stack([np.ones_like(J), J, J**2])
    c = np.linalg.lstsq(A, kt, rcond=None)[0]
    return float(c[0]), float(c[1]), float(c[2])


class Propulsion(NamedTuple):
    """The propulsion coefficients of a vessel.

    Attributes
    ----------
    D_p : float
        Propeller diameter, m.
    kt : tuple of 3 float
        :math:`K_T \\approx k_0 + k_1 J + k_2 J^2`.
    kt_err : float
        Error of the quadratic fit (NaN where no fit was made, 0 for the full B-series).
    w_P, t_P : float
        Wake fraction and thrust deduction.
    propeller : Propeller or None
        The propeller when a K_T curve or a w_P(u)/t_P(u) curve replaces the quadratic.
    """

    D_p: float
    kt: tuple[float, float, float]
    kt_err: float
    w_P: float
    t_P: float
    propeller: Propeller | None


def estimate_propulsion(b: Build, hh: HoltropHull, rfit: Any) -> Propulsion:
    """K_T, w_P, t_P and the propeller of ``[vessel] propeller_method``.

    Parameters
    ----------
    b : Build
        The build; the stage records the K_T quadratic, w_P and t_P it estimates, and
        the validity ranges of K_T(J) and of the w_P, t_P curves.
    hh : HoltropHull
        Holtrop inputs (prismatic coefficient, l.c.b.) for the thrust deduction.
    rfit : ResistanceFit or table
        R(u): a propeller curve is checked to balance it at Fn 0.1 ... 0.5.

    Returns
    -------
    Propulsion
    """
    v, p, est, validity = b.vessel, b.p, b.estimates, b.validity
    rho, g, L, B, d_m, C_b = p.rho, p.g, p.L, p.B, p.d_m, p.C_b
    D_p = v.get("propulsion.D_p")
    prop_method = v.propeller_method
    kt_curve: Any = None
    Z = int(v.get("propulsion.n_blades"))
    PD, AE = v.get("propulsion.P_over_D"), v.get("propulsion.AE_over_A0")
    if prop_method == "curve":
        c = v.curves["K_T"]
        if c.is_table:
            kt_curve = interpolating_spline(np.array(c.x), np.array(c.y))
        else:
            kt_curve = Polynomial1D(np.array(c.coefficients), c.x_range)
        Jg = np.linspace(c.x_range[0], min(c.x_range[1], 1.5), 200)
        kt = quadratic_fit(Jg, kt_curve(Jg))
        kt_err = float("nan")
        validity.append(
            ValidityRange(
                f"K_T curve ({c.status}: {c.source})",
                "J",
                c.x_range[0],
                c.x_range[1],
                "range of the measured K_T(J)",
            )  # fmt: skip
        )
    elif v.has("propulsion.K_T0") and prop_method == "bseries_quadratic":
        kt = (v.get("propulsion.K_T0"), v.get("propulsion.K_T1"), v.get("propulsion.K_T2"))
        kt_err = float("nan")
    else:
        J_fit = v.get("propulsion.J_max_fit")
        k0, k1_, k2, kt_err = fit_kt_quadratic(PD, AE, Z, J_fit)
        kt = (k0, k1_, k2)
        J_zero = bseries_zero_thrust_J(PD, AE, Z)
        if prop_method == "bseries":
            kt_curve = bseries_kt_curve(PD, AE, Z)
            kt_err = 0.0
            validity.append(
                ValidityRange(
                    f"K_T (Wageningen B{Z}-{AE:.2f}, P/D {PD:.3g}, full polynomial)",
                    "J",
                    0.0,
                    J_zero,
                    "K_T >= 0 (Oosterveld & van Oossanen 1975 fit open-water data; beyond, "
                    "a windmilling propeller: a monotone C2 continuation, assumed)",
                )  # fmt: skip
            )
        else:
            src = (
                f"least-squares quadratic in J on [0, {J_fit}] of the "
                f"Wageningen B{Z}-{AE:.2f} P/D={PD} polynomial (Oosterveld & van Oossanen 1975)"
            )
            for name, val in zip(("K_T0", "K_T1", "K_T2"), kt, strict=True):
                est[f"propulsion.{name}"] = estimated(val, "-", src)
            validity.append(
                ValidityRange(
                    f"K_T (quadratic fit of the B{Z}-{AE:.2f} P/D {PD:.3g} polynomial)",
                    "J",
                    0.0,
                    min(J_fit, J_zero),
                    f"fitted on J <= {J_fit}; B-series K_T = 0 at J = {J_zero:.3f}",
                )  # fmt: skip
            )
    if v.has("propulsion.w_P"):
        w_P = v.get("propulsion.w_P")
    else:
        w_P = taylor_wake(C_b)
        est["propulsion.w_P"] = estimated(w_P, "-", "0.5 C_b - 0.05: Taylor (1933) single screw")
    if v.has("propulsion.t_P"):
        t_P = v.get("propulsion.t_P")
    else:
        t_P = holtrop_thrust_deduction(
            B, L, d_m, D_p, hh.C_P, hh.lcb_percent, v.get("resistance.C_stern")
        )
        est["propulsion.t_P"] = estimated(t_P, "-", "Holtrop (1984) single-screw thrust deduction")
    w_curve = t_curve = None
    for name in ("w_P", "t_P"):
        if name in v.curves:
            cv = v.curves[name]
            spl = interpolating_spline(np.array(cv.x), np.array(cv.y), slope_start=0.0)
            if name == "w_P":
                w_curve = spl
            else:
                t_curve = spl
            validity.append(
                ValidityRange(
                    f"{name}(u) curve ({cv.source})",
                    "u",
                    0.0,
                    cv.x_range[1],
                    "speed range of the measured curve",
                )  # fmt: skip
            )
    propeller = None
    if kt_curve is not None or w_curve is not None or t_curve is not None:
        if kt_curve is None:
            kt_curve = Polynomial1D(np.array(kt, dtype=float), (0.0, np.inf))
        propeller = Propeller(D_p, kt_curve, (float(kt[0]), float(kt[1]), float(kt[2])),
                              w_P, t_P, w_curve, t_curve)  # fmt: skip
        # the revolution solve is a fixed number of Newton steps (CasADi-traceable):
        # check it converged over the Froude numbers analyses use, or refuse the curve
        for Fn_chk in (0.1, 0.2, 0.3, 0.4, 0.5):
            u_chk = Fn_chk * np.sqrt(g * L)
            res = propeller.revolution_residual(u_chk, float(rfit.evaluate(u_chk)), rho)
            if not res < 1e-9:
                raise VesselFileError(
                    f"`curves.K_T` / propeller: no thrust-resistance balance found at Fn "
                    f"{Fn_chk} (relative residual {res:.1e}); check that K_T(J) decreases "
                    "and stays positive over the advance ratios of the nominal speeds"
                )

    return Propulsion(D_p, (float(kt[0]), float(kt[1]), float(kt[2])), kt_err, w_P, t_P, propeller)
