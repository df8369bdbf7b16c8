"""Inertia: the added masses m_x (Söding 1982 fit of Motora's charts), m_y and J_zz
(strip theory, Lewis sections at zero frequency), the yaw inertia I_zz and the roll
inertia I_xx + J_xx (from T_phi and GM)."""

from __future__ import annotations

from typing import Any, NamedTuple

from ..hydro.added_mass import lewis_sway_added_mass, soding_surge_added_mass
from ..hydro.roll import roll_inertia
from .common import Build, estimated
from .hull import HullEstimate


class Inertia(NamedTuple):
    """Masses and inertias of the equations of motion (Umeda 1999, Eqs. 4-7).

    Attributes
    ----------
    m22 : ndarray, shape (n_stations,)
        Sway added mass per unit length of each section, kg/m.
    m_x, m_y : float
        Surge and sway added masses, kg.
    J_zz : float
        Yaw added moment of inertia, kg m^2 (about the origin of the file's
        derivatives until :func:`~.manoeuvring.estimate_derivatives` moves a given one).
    J_zz_given : bool
        Whether the file gives J_zz (dimensionally or as a prime).
    I_zz : float
        Yaw moment of inertia, kg m^2.
    I_xx_J_xx : float
        Roll moment of inertia plus added inertia, kg m^2.
    """

    m22: Any
    m_x: float
    m_y: float
    J_zz: float
    J_zz_given: bool
    I_zz: float
    I_xx_J_xx: float


def estimate_inertia(b: Build, h: HullEstimate) -> Inertia:
    """The added masses and inertias the file does not give.

    Parameters
    ----------
    b : Build
        The build; the stage records m_x, m_y, J_zz and I_xx + J_xx where estimated.
    h : HullEstimate
        The hull, its volume, the mass and x_G.

    Returns
    -------
    Inertia
    """
    v, p, est = b.vessel, b.p, b.estimates
    rho, g, L, d_m, GM, T_phi = p.rho, p.g, p.L, p.d_m, p.GM, p.T_phi
    hull, volume, mass, x_G = h.hull, h.volume, h.mass, h.x_G
    m22 = lewis_sway_added_mass(rho, hull.b_wl, hull.d, hull.beta)
    half_rho_L2d = 0.5 * rho * L**2 * d_m
    if v.has("hydrodynamics.m_x"):
        m_x = v.get("hydrodynamics.m_x")
    elif v.has("hydrodynamics.m_x_prime"):
        m_x = v.get("hydrodynamics.m_x_prime") * half_rho_L2d
    else:
        m_x = soding_surge_added_mass(rho, volume, L)
        est["hydrodynamics.m_x"] = estimated(
            m_x, "kg", "2.7 rho V^(5/3)/L^2: Soding (1982) fit of Motora's charts"
        )
    if v.has("hydrodynamics.m_y"):
        m_y = v.get("hydrodynamics.m_y")
    elif v.has("hydrodynamics.m_y_prime"):
        m_y = v.get("hydrodynamics.m_y_prime") * half_rho_L2d
    else:
        m_y = float(hull.w @ m22)
        est["hydrodynamics.m_y"] = estimated(
            m_y, "kg", "strip theory, Lewis sections at zero frequency (Lewis 1929)"
        )
    J_zz_given = v.has("hydrodynamics.J_zz") or v.has("hydrodynamics.J_zz_prime")
    if v.has("hydrodynamics.J_zz"):
        J_zz = v.get("hydrodynamics.J_zz")
    elif v.has("hydrodynamics.J_zz_prime"):
        J_zz = v.get("hydrodynamics.J_zz_prime") * half_rho_L2d * L**2
    else:
        J_zz = float(hull.w @ ((hull.x - x_G) ** 2 * m22))
        est["hydrodynamics.J_zz"] = estimated(
            J_zz, "kg m^2", "strip theory, Lewis sections at zero frequency (Lewis 1929)"
        )
    I_zz = mass * (v.get("particulars.kappa_zz_over_L") * L) ** 2
    if v.has("hydrodynamics.I_xx_plus_J_xx"):
        Ixx = v.get("hydrodynamics.I_xx_plus_J_xx")
    else:
        Ixx = roll_inertia(mass, g, GM, T_phi)
        est["hydrodynamics.I_xx_plus_J_xx"] = estimated(
            Ixx, "kg m^2", "m g GM (T_phi / 2 pi)^2 from the given T_phi and GM"
        )
    return Inertia(m22, m_x, m_y, J_zz, J_zz_given, I_zz, Ixx)
