"""Manoeuvring: the hull derivatives Y_v, Y_r, N_v, N_r (Inoue, Hirano & Kijima 1981)
moved to G, the heel derivatives (Son & Nomoto 1981 ratios, an analogy), the rudder
lift slope (Fujii & Tsuda 1961) and the roll damping (zeta_0, assumed, plus Ikeda,
Himeno & Tanaka 1978 lift damping)."""

from __future__ import annotations

import numpy as np

from ..hydro.heel import (
    SON_NOMOTO_BAND,
    SON_NOMOTO_SOURCE,
    HeelDerivatives,
    son_nomoto_heel_derivatives,
    son_nomoto_validity,
)
from ..hydro.manoeuvring import fujii_lift_slope, inoue_hull_derivatives
from ..hydro.roll import ikeda_lift_damping_per_speed
from ..validity import ValidityRange
from ..validity import report as report_validity
from .common import Build, estimated
from .inertia import Inertia


def derivatives_about_g(prime: dict[str, float], a_over_L: float) -> dict[str, float]:
    r"""Move the linear hull derivatives from an origin O to the centre of gravity G.

    With G a distance :math:`a = x_G - x_O` ahead of O, the lateral velocity at O is
    :math:`v_O = v_G - a r` and the yaw moment about G is :math:`N_G = N_O - a Y`, so

    .. math::

        Y'_v{}^G &= Y'_v, \qquad Y'_r{}^G = Y'_r - a' Y'_v, \qquad
        N'_v{}^G = N'_v - a' Y'_v, \\
        N'_r{}^G &= N'_r - a'(Y'_r + N'_v) + a'^2 Y'_v, \qquad a' = a / L,

    (non-dimensionalised as in :mod:`ship_models.hydro.manoeuvring`). The added-mass
    cross-coupling that the same shift creates (:math:`-a\,m_y\dot r` in the sway
    equation) is not part of Umeda's (1999) equations and is neglected.

    Parameters
    ----------
    prime : dict
        ``Y_v_prime, Y_r_prime, N_v_prime, N_r_prime`` about O.
    a_over_L : float
        :math:`(x_G - x_O)/L`.

    Returns
    -------
    dict
        The same keys, about G (other keys are copied unchanged).
    """
    a = float(a_over_L)
    Yv, Yr, Nv, Nr = (prime[k] for k in ("Y_v_prime", "Y_r_prime", "N_v_prime", "N_r_prime"))
    out = dict(prime)
    out["Y_r_prime"] = Yr - a * Yv
    out["N_v_prime"] = Nv - a * Yv
    out["N_r_prime"] = Nr - a * (Yr + Nv) + a * a * Yv
    return out


def estimate_derivatives(
    b: Build, x_G: float, zeta_G: float, inertia: Inertia
) -> tuple[dict[str, float], Inertia, float]:
    """The non-dimensional hull and heel derivatives about G and the rudder lift slope.

    Parameters
    ----------
    b : Build
        The build; the stage records the hull and heel derivatives and f_alpha it
        estimates (or assumes).
    x_G, zeta_G : float
        Position of G: from midship, forward +; height above the waterline (KG - d_m).
    inertia : Inertia
        A J_zz the file gives is moved to G with the derivatives
        (``hydrodynamics.x_ref``).

    Returns
    -------
    prime : dict
        ``Y_v_prime, Y_r_prime, N_v_prime, N_r_prime, Y_phi_prime, N_phi_prime,
        K_phi_prime`` about G.
    inertia : Inertia
        With J_zz about G.
    f_alpha : float
        Rudder lift slope.
    """
    v, p, est = b.vessel, b.p, b.estimates
    L, B, d_f, d_a, d_m, C_b = p.L, p.B, p.d_f, p.d_a, p.d_m, p.C_b
    m_y, J_zz, J_zz_given = inertia.m_y, inertia.J_zz, inertia.J_zz_given
    ino = inoue_hull_derivatives(L, B, d_m, d_a - d_f, C_b)
    prime: dict[str, float] = {}
    for name, val in ino.items():
        key = f"hydrodynamics.{name}"
        if v.has(key):
            prime[name] = v.get(key)
        else:
            prime[name] = val
            est[key] = estimated(
                val,
                "-",
                "Inoue, Hirano & Kijima (1981), Hydrodynamic derivatives on ship "
                "manoeuvring, ISP 28(321)",
            )
    if v.has("hydrodynamics.x_ref"):
        # derivatives (and a given J_zz) measured about x_ref: move them to G
        a_ref = x_G - v.get("hydrodynamics.x_ref")
        prime = derivatives_about_g(prime, a_ref / L)
        if J_zz_given:
            J_zz = J_zz + a_ref**2 * m_y  # parallel axes, no added-mass cross term
    heel_est: HeelDerivatives | None = None
    if v.heel_derivatives_method == "son_nomoto_ratio":
        z_H_over_d = v.get("roll.z_H_over_d") + zeta_G / d_m  # lateral force below G
        form = {"L/B": L / B, "B/d": B / d_m, "C_b": C_b}
        heel_est = son_nomoto_heel_derivatives(
            prime["Y_v_prime"],
            prime["N_v_prime"],
            z_H_over_d,
            L_over_B=form["L/B"],
            B_over_d=form["B/d"],
            C_b=form["C_b"],
        )
        for key, (lo, hi) in son_nomoto_validity().items():
            report_validity(
                v.name,
                ValidityRange(
                    "heel derivatives (Son & Nomoto 1981 ratios, an analogy)",
                    key,
                    lo,
                    hi,
                    f"+-{SON_NOMOTO_BAND:.0%} of the container ship SR 108's {key}",
                ),
                form[key],
                "this hull",
            )
    for name in ("Y_phi_prime", "N_phi_prime", "K_phi_prime"):
        key = f"hydrodynamics.{name}"
        if v.has(key):
            prime[name] = v.get(key)
        elif heel_est is not None:
            prime[name] = float(getattr(heel_est, name))
            out = (
                "; outside its hull form: " + ", ".join(heel_est.outside)
                if heel_est.outside
                else ""
            )
            est[key] = estimated(
                prime[name],
                "-",
                "analogy: the ratio to the drift derivative (about G) of the same equation of "
                f"{SON_NOMOTO_SOURCE} (ship_models.hydro.heel){out}",
            )
        else:
            prime[name] = 0.0
            est[key] = estimated(
                0.0,
                "-",
                "heel-induced hydrodynamic force neglected (no regression for this hull form; "
                "vessel.heel_derivatives_method = 'son_nomoto_ratio' gives an analogy estimate)",
                "assumed",
            )
    if v.has("rudder.f_alpha"):
        f_alpha = v.get("rudder.f_alpha")
    else:
        f_alpha = fujii_lift_slope(v.get("rudder.aspect_ratio"))
        est["rudder.f_alpha"] = estimated(
            f_alpha, "-", "6.13 Lambda/(Lambda + 2.25): Fujii & Tsuda (1961)"
        )
    return prime, inertia._replace(J_zz=J_zz), f_alpha


def estimate_roll_damping(b: Build, zeta_G: float) -> tuple[float, float]:
    """The roll damping coefficients: zero-speed ``K_p0`` (from the assumed damping
    ratio ``roll.zeta_0``) and the hull-lift part ``K_p_lift_prime`` per speed.

    Parameters
    ----------
    b : Build
        The build; the stage records K_p0 and K_p_lift_prime where estimated.
    zeta_G : float
        Depth of G below the waterline is ``-zeta_G``.

    Returns
    -------
    Kp0, Kp_lift : float
    """
    v, p, est = b.vessel, b.p, b.estimates
    rho, L, B, d_m, T_phi = p.rho, p.L, p.B, p.d_m, p.T_phi
    omega_phi = 2.0 * np.pi / T_phi
    if v.has("hydrodynamics.K_p0"):
        Kp0 = v.get("hydrodynamics.K_p0")
    else:
        Kp0 = 2.0 * v.get("roll.zeta_0") * omega_phi
        est["hydrodynamics.K_p0"] = estimated(
            Kp0, "-", "2 zeta_0 omega_phi from the assumed zero-speed damping ratio roll.zeta_0"
        )
    OG = -zeta_G  # depth of G below the waterline
    if v.has("hydrodynamics.K_p_lift_prime"):
        Kp_lift = v.get("hydrodynamics.K_p_lift_prime")
    else:
        Kp_lift = ikeda_lift_damping_per_speed(rho, L, B, d_m, v.get("hull.C_M"), OG) / (
            0.5 * rho * L * d_m**3
        )
        est["hydrodynamics.K_p_lift_prime"] = estimated(
            Kp_lift,
            "-",
            "hull lift roll damping: Ikeda, Himeno & Tanaka (1978), substitute for Takahashi",
        )
    return Kp0, Kp_lift
