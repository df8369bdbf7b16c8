r"""Estimation pipeline: from a vessel file to every coefficient of the model.

:func:`resolve_vessel` fills each coefficient that the file does not give with a
named method and records it with status ``estimated`` (or ``assumed`` where no
method exists) and the method in ``source``; coefficients given in the file (or by
:meth:`VesselData.with_overrides`) are never replaced. :func:`build_forces` turns
the resolved data into :class:`~ship_models.forces.ShipForces` (strip arrays, GZ
series, resistance spline), the numbers of Eqs. (4)-(11).

Methods (one module each under :mod:`ship_models.hydro`):

==========================  ==================================================
quantity                    method
==========================  ==================================================
hull sections S, B, d       parametric form-parameter hull (:mod:`.hydro.hull`)
C_wp                        Schneekluth & Bertram (1998)
R(u)                        ITTC-1957 + Holtrop & Mennen (1982) / Holtrop (1984),
                            or the MMG straight-running coefficient R0' if given
K_T(J)                      Wageningen B-series (Oosterveld & van Oossanen 1975)
w_P, t_P                    Taylor (1933); Holtrop (1984)
m_x                         Söding (1982) fit of Motora's charts
m_y, J_zz                   strip theory, Lewis sections at zero frequency
Y_v, Y_r, N_v, N_r          Inoue, Hirano & Kijima (1981)
f_alpha                     Fujii & Tsuda (1961)
I_xx + J_xx                 from T_phi and GM
K_p(u)                      zeta_0 (assumed) + Ikeda et al. (1978) lift damping
GZ(phi)                     hull hydrostatics, free sinkage and trim
X_w, Y_w, N_w, K_w          Froude-Krylov strips + slender-body lift
X_w diffraction (optional)  G.I. Taylor (1928) long-wave m_x/(rho V) ratio
==========================  ==================================================

Published coefficients can be given instead of estimated (every such key is
optional in the file): added masses dimensionally (``m_x``) or as MMG primes
(``m_x_prime = m_x / (rho/2 L^2 d)``, ``J_zz_prime = J_zz / (rho/2 L^4 d)``), the
resistance as the MMG coefficient ``resistance.R0_prime`` (then
:math:`R(u) = R'_0\,\tfrac12\rho L d\,u^2`, Yasukawa & Yoshimura 2015),
the rudder span ``rudder.H_R``. Hull derivatives measured about another origin than G
(the MMG standard method uses midship) are moved to G when ``hydrodynamics.x_ref``
names that origin (:func:`derivatives_about_g`).

Each group of coefficients is estimated by one stage of :mod:`ship_models.estimates`;
this module runs them in order and assembles the result.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .contracts import WaveForceBuilder
from .estimates.common import Build
from .estimates.hull import (
    estimate_hull,
    form_parameters,
    hull_mesh_path,
    mesh_hull,
    mesh_is_hull,
    offsets_hull,
    offsets_path,
)
from .estimates.inertia import estimate_inertia
from .estimates.manoeuvring import (
    derivatives_about_g,
    estimate_derivatives,
    estimate_roll_damping,
)
from .estimates.memo import reuse_hydrostatics
from .estimates.propulsion import estimate_propulsion
from .estimates.resistance import estimate_resistance
from .estimates.stability import estimate_stability
from .estimates.wave_forces import WAVE_FORCE_MODELS, file_wave_builder, wave_force_model
from .forces import ShipForces
from .hydro.hull import HullForm
from .hydro.hydrostatics import GZCurve, is_code_margin
from .hydro.resistance import HoltropHull
from .hydro.waves import strip_waves
from .vessel import VesselData

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class VesselModelData:
    """Everything derived from a vessel file.

    Attributes
    ----------
    vessel : VesselData
        The resolved data (file values plus estimates, with sources).
    forces : ShipForces
        Coefficients of the equations of motion.
    hull : HullForm
        Strip hull.
    gz : GZCurve
        Hydrostatic righting-arm curve and its fit.
    holtrop : HoltropHull
        Resistance regression inputs (for reports and checks).
    info : dict
        Derived numbers for reports (wetted-surface check, fit errors, ...).
    wave_builder : WaveForceBuilder
        How ``forces.waves`` was made (:func:`~ship_models.hydro.waves.strip_waves`
        by default); a rebuild with changed coefficients uses it again.
    """

    vessel: VesselData
    forces: ShipForces
    hull: HullForm
    gz: GZCurve
    holtrop: HoltropHull
    info: dict[str, float]
    wave_builder: WaveForceBuilder = field(default=strip_waves, repr=False)


_CACHE: dict[tuple[Any, ...], VesselModelData] = {}
_CACHE_SIZE = 8


def _builder_key(waves: WaveForceBuilder | None) -> Any:
    if waves is None:
        return None
    try:
        hash(waves)
    except TypeError:
        return ("id", id(waves))
    return waves


def resolve_vessel(vessel: VesselData, *, waves: WaveForceBuilder | None = None) -> VesselModelData:
    """Cached :func:`build_vessel_model` (keyed by the vessel's name and coefficients
    and the wave-force builder)."""
    meta = tuple(sorted((k, str(v)) for k, v in vessel.meta.items()))  # wave_forces, offsets
    key = (vessel.name, vessel.path, meta, tuple(sorted(vessel.coefficients.items())),
           tuple(sorted(vessel.curves.items())), _builder_key(waves))  # fmt: skip
    hit = _CACHE.get(key)
    if hit is not None:
        return hit
    out = build_vessel_model(vessel, waves=waves)
    if len(_CACHE) >= _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = out
    return out


def build_vessel_model(
    vessel: VesselData, *, waves: WaveForceBuilder | None = None
) -> VesselModelData:
    """Estimate every coefficient the file does not give and build the force model.

    Parameters
    ----------
    vessel : VesselData
        A validated vessel description.
    waves : WaveForceBuilder, optional
        Makes the wave-force model from the hull and loading
        (:class:`~ship_models.contracts.WaveInputs`); default the one the file names
        in ``[vessel] wave_forces`` (:data:`WAVE_FORCE_MODELS`), else the
        Froude-Krylov strips :func:`~ship_models.hydro.waves.strip_waves`.

    Returns
    -------
    VesselModelData
        With ``vessel`` holding file values plus estimates (status ``estimated`` or
        ``assumed``, method in ``source``) and ``wave_builder`` the builder used.
    """
    builder: WaveForceBuilder = file_wave_builder(vessel) if waves is None else waves
    if not callable(builder):
        raise ValueError(
            f"`waves` must be a wave-force builder (a callable taking WaveInputs), got "
            f"a {type(builder).__name__}"
        )
    v = vessel
    b = Build.of(v)
    p, est, validity = b.p, b.estimates, b.validity
    rho, g, L, B, d_a, d_m, GM = p.rho, p.g, p.L, p.B, p.d_a, p.d_m, p.GM
    h = estimate_hull(b)
    volume, mass, x_G = h.volume, h.mass, h.x_G
    topside, gz = estimate_stability(b, h.hull)
    zeta_G = gz.zeta_G
    hh, rfit = estimate_resistance(b, h.hull, h.C_wp, h.S_f)
    prop = estimate_propulsion(b, hh, rfit)
    D_p, w_P, t_P, kt, kt_err = prop.D_p, prop.w_P, prop.t_P, prop.kt, prop.kt_err
    inertia = estimate_inertia(b, h)
    prime, inertia, f_alpha = estimate_derivatives(b, x_G, zeta_G, inertia)
    m_x, m_y, J_zz = inertia.m_x, inertia.m_y, inertia.J_zz
    I_zz, Ixx = inertia.I_zz, inertia.I_xx_J_xx
    Kp0, Kp_lift = estimate_roll_damping(b, zeta_G)

    # ---- geometry of forces -------------------------------------------------------------
    z_H = v.get("roll.z_H_over_d") * d_m + zeta_G  # body z (down) of the lateral force below G
    A_R = v.get("rudder.A_R")
    if v.has("rudder.H_R"):
        h_R = v.get("rudder.H_R")
    else:
        h_R = float(np.sqrt(v.get("rudder.aspect_ratio") * A_R))
    z_R = (d_a - 0.5 * h_R) + zeta_G  # rudder centre: lower edge at the keel line aft
    eta = min(1.0, D_p / h_R)
    wave_model = wave_force_model(b, builder, h, zeta_G, z_H, inertia)
    q_speed = 0.5 * rho * L * d_m
    forces = ShipForces(
        rho=rho,
        g=g,
        L=L,
        B=B,
        d_m=d_m,
        mass=mass,
        m_x=m_x,
        m_y=m_y,
        I_zz=I_zz,
        J_zz=J_zz,
        I_xx_J_xx=Ixx,
        Y_v1=prime["Y_v_prime"] * q_speed,
        Y_r1=prime["Y_r_prime"] * q_speed * L,
        N_v1=prime["N_v_prime"] * q_speed * L,
        N_r1=prime["N_r_prime"] * q_speed * L * L,
        Y_phi2=prime["Y_phi_prime"] * q_speed,
        N_phi2=prime["N_phi_prime"] * q_speed * L,
        K_phi2=prime["K_phi_prime"] * q_speed * d_m,
        z_H=z_H,
        K_p0=-Kp0 * Ixx,
        K_p1=-Kp_lift * 0.5 * rho * L * d_m**3,
        A_R=A_R,
        f_alpha=f_alpha,
        a_H=v.get("rudder.a_H"),
        x_R=-0.5 * L - x_G,
        x_H=v.get("rudder.x_H_over_L") * L - x_G,
        z_R=z_R,
        gamma_R=v.get("rudder.gamma_R"),
        l_R=v.get("rudder.l_R_over_L") * L,
        epsilon=v.get("rudder.epsilon"),
        kappa=v.get("rudder.kappa"),
        eta=eta,
        D_p=D_p,
        w_P=w_P,
        t_P=t_P,
        kt=(float(kt[0]), float(kt[1]), float(kt[2])),
        resistance=rfit,
        gz_coeffs=np.array(gz.coeffs),
        waves=wave_model,
        T_E=v.get("autopilot.T_E"),
        delta_max=v.get("rudder.delta_max"),
        propeller=prop.propeller,
        validity=tuple(validity),
    )
    phi_m, gz_m = gz.max_gz
    info = {
        "volume": volume,
        "mass": mass,
        "wetted_surface_hull": h.S_hull,
        "wetted_surface_used": h.S_f,
        "zeta_G": zeta_G,
        "KG": zeta_G + d_m,
        "KM": zeta_G + d_m + GM,
        "gz_fit_error": gz.fit_error,
        "phi_gz_max": phi_m,
        "gz_max": gz_m,
        "phi_vanishing": gz.vanishing_angle,
        "topside_height": topside,
        "is_code_margin": is_code_margin(gz),
        "resistance_fit_error": rfit.max_rel_error,
        "kt_fit_error": kt_err,
        "z_H": z_H,
        "z_R": z_R,
        "eta_rudder": eta,
        "x_G": x_G,
        "I_zz": I_zz,
    }
    resolved = vessel.with_estimates(est)
    log.debug("resolved vessel %s with %d estimates", vessel.name, len(est))
    return VesselModelData(resolved, forces, h.hull, gz, hh, info, builder)


__all__ = [
    "WAVE_FORCE_MODELS",
    "VesselModelData",
    "build_vessel_model",
    "derivatives_about_g",
    "form_parameters",
    "hull_mesh_path",
    "mesh_hull",
    "mesh_is_hull",
    "offsets_hull",
    "offsets_path",
    "resolve_vessel",
    "reuse_hydrostatics",
]
