"""Wave forces: the builder a vessel file names (``[vessel] wave_forces``) and the
inputs it gets, with the surge-force correction of ``[vessel] wave_surge_model``
(G.I. Taylor's 1928 long-wave diffraction ratio, :mod:`ship_models.hydro.diffraction`)."""

from __future__ import annotations

from typing import Any

from ..contracts import WaveForceBuilder, WaveInputs
from ..hydro.diffraction import taylor_diffraction_ratio
from ..hydro.waves import strip_waves
from ..vessel import VesselData, VesselFileError
from .common import Build, estimated
from .hull import HullEstimate, mesh_is_hull
from .inertia import Inertia

#: ``[vessel] wave_forces`` of a vessel file: the wave-force model it asks for.
WAVE_FORCE_MODELS = ("froude_krylov_strips", "panel_fk_diffraction", "panel_fk")


def file_wave_builder(vessel: VesselData) -> WaveForceBuilder:
    """The builder named by ``[vessel] wave_forces`` (default: Froude-Krylov strips)."""
    name = str(vessel.meta.get("wave_forces", WAVE_FORCE_MODELS[0]))
    if name == "froude_krylov_strips":
        if vessel.meta.get("hull_mesh") and not mesh_is_hull(vessel):
            raise VesselFileError(
                "`vessel.hull_mesh` is used by the panel method only (a wetted-surface mesh, "
                "or a mesh beside `vessel.hull_offsets`): set `vessel.wave_forces` to "
                "'panel_fk_diffraction' or 'panel_fk' (the strips use the offsets or the "
                "particulars), or give a closed mesh of the whole hull"
            )
        return strip_waves
    if name in ("panel_fk_diffraction", "panel_fk"):
        from ..hydro.panel import PanelWaveBuilder  # Capytaine only when asked for

        return PanelWaveBuilder(diffraction=name == "panel_fk_diffraction")
    raise VesselFileError(f"`vessel.wave_forces` must be one of {WAVE_FORCE_MODELS}, got {name!r}")


def wave_force_model(
    b: Build,
    builder: WaveForceBuilder,
    h: HullEstimate,
    zeta_G: float,
    z_H: float,
    inertia: Inertia,
) -> Any:
    """The wave-force model ``builder`` makes for the vessel (checked to have ``forces``).

    Parameters
    ----------
    b : Build
        The build; the stage records the surge-force scale and diffraction ratio it
        assumes or estimates.
    builder : WaveForceBuilder
    h : HullEstimate
        The hull, its volume and x_G.
    zeta_G, z_H : float
        Height of G above the waterline (KG - d_m) and body z (down) of the lateral
        force.
    inertia : Inertia
        ``m22`` and ``m_x`` (the long-wave diffraction ratio).

    Returns
    -------
    WaveForceModel
    """
    v, p, est = b.vessel, b.p, b.estimates
    vessel, hull, x_G, volume = v, h.hull, h.x_G, h.volume
    rho, g, m22, m_x = p.rho, p.g, inertia.m22, inertia.m_x
    if v.has("hydrodynamics.wave_surge_scale"):
        surge_scale = v.get("hydrodynamics.wave_surge_scale")
    else:
        surge_scale = 1.0
        est["hydrodynamics.wave_surge_scale"] = estimated(
            1.0,
            "-",
            "no correction of the wave surge force of the selected wave_surge_model "
            "(Froude-Krylov, as in Umeda 1999)",
            "assumed",
        )
    diffraction_factor = 1.0
    if v.wave_surge_model == "froude_krylov_taylor":
        if v.has("hydrodynamics.wave_surge_diffraction"):
            r_D = v.get("hydrodynamics.wave_surge_diffraction")
        else:
            r_D = taylor_diffraction_ratio(m_x, rho, volume)
            est["hydrodynamics.wave_surge_diffraction"] = estimated(
                r_D,
                "-",
                "m_x/(rho V): long-wave diffraction part of the surge force, G.I. Taylor "
                "(1928) Proc. R. Soc. Lond. A 120:260-283 (ship_models.hydro.diffraction)",
            )
        diffraction_factor = 1.0 + r_D
    wave_model = builder(
        WaveInputs(
            vessel=vessel,
            hull=hull,
            x_G=x_G,
            zeta_G=zeta_G,
            m22=m22,
            z_H=z_H,
            rho=rho,
            g=g,
            n_depth=int(v.get("hull.n_depth")),
            surge_scale=surge_scale * diffraction_factor,
        )
    )
    if not callable(getattr(wave_model, "forces", None)):
        raise ValueError(
            f"`waves`: the builder gave a {type(wave_model).__name__}, which has no "
            "forces(xi_over_lambda, u, chi, H_over_lambda, lambda_over_L, ops, *, lift) method"
        )
    return wave_model
