r"""Upright hydrostatics of a strip hull, and the check of the particulars against it.

:func:`hydrostatics` integrates the hull's sections (for an
:class:`~ship_models.hydro.offsets.OffsetsHull`, exactly for the bilinear surface
between its offsets); :func:`check_particulars` refuses a vessel file whose
particulars contradict the hull (one line naming the particular).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .hull import HullForm
from .offsets import OffsetsError


@dataclass(frozen=True)
class Hydrostatics:
    """Upright hydrostatics at the given drafts (SI units).

    Attributes
    ----------
    volume : float
        Displacement volume (m^3).
    lcb : float
        Longitudinal centre of buoyancy from midship (m, forward +).
    KB : float
        Centre of buoyancy above the baseline at midship draft (m).
    BM : float
        Transverse metacentric radius ``I_T / volume`` (m).
    A_wp : float
        Waterplane area (m^2).
    lcf : float
        Centre of flotation from midship (m, forward +).
    I_T, I_L : float
        Transverse and longitudinal (about the centre of flotation) second moments of
        the waterplane (m^4).
    C_b : float
        Block coefficient on ``L B d_m``.
    """

    volume: float
    lcb: float
    KB: float
    BM: float
    A_wp: float
    lcf: float
    I_T: float
    I_L: float
    C_b: float

    def as_dict(self) -> dict[str, float]:
        """Plain dictionary (for JSON)."""
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


def hydrostatics(hull: HullForm) -> Hydrostatics:
    r"""Volume, LCB, KB, BM and waterplane moments of a strip hull.

    .. math::

        \nabla = \int S\,dx, \quad LCB = \frac{1}{\nabla}\int x S\,dx, \quad
        A_{wp} = \int 2 b_{wl}\,dx, \quad I_T = \int \tfrac23 b_{wl}^3\,dx, \quad
        I_L = \int 2 b_{wl} (x - LCF)^2 dx, \quad BM = I_T/\nabla

    (strip quadrature of the hull's stations; for an :class:`OffsetsHull` the section
    integrals are exact for the bilinear surface). A hull sliced from a closed mesh
    (:class:`~ship_models.hydro.mesh_hull.MeshHull`) gives the mesh's own hydrostatics,
    integrated exactly over the clipped polyhedron
    (:func:`~ship_models.hydro.mesh_hydrostatics.mesh_hydrostatics`).
    """
    own = getattr(hull, "mesh_hydrostatics", None)
    if callable(own):
        return own()  # type: ignore[no-any-return]
    V = hull.volume
    A_wp = hull.waterplane_area
    lcf = float(hull.w @ (hull.x * 2.0 * hull.b_wl)) / A_wp
    I_T = hull.waterplane_inertia
    I_L = float(hull.w @ (2.0 * hull.b_wl * (hull.x - lcf) ** 2))
    d_m = float(np.interp(0.0, hull.x, hull.d))
    KB = d_m + hull.vcb  # vcb at the local waterline; with trim a small approximation
    return Hydrostatics(
        volume=V,
        lcb=hull.lcb,
        KB=KB,
        BM=I_T / V,
        A_wp=A_wp,
        lcf=lcf,
        I_T=I_T,
        I_L=I_L,
        C_b=V / (hull.L * hull.B * d_m),
    )


def check_particulars(
    hs: Hydrostatics,
    *,
    L: float,
    B: float,
    d_m: float,
    C_b: float,
    lcb_aft: float,
    rel_volume: float = 0.02,
    rel_lcb: float = 0.01,
    rel_breadth: float = 0.02,
    B_hull: float | None = None,
    source: str = "",
) -> None:
    """Refuse particulars that contradict the hull (one line naming the particular).

    Parameters
    ----------
    hs : Hydrostatics
        Of the hull.
    L, B, d_m, C_b, lcb_aft : float
        The vessel file's particulars (``lcb_aft > 0`` aft of midship).
    rel_volume, rel_lcb, rel_breadth : float
        Tolerances: displacement ``C_b L B d_m`` within ``rel_volume`` of the hull's,
        LCB within ``rel_lcb L``, breadth within ``rel_breadth`` (usual precision of a
        hydrostatic table read against a lines plan).
    B_hull : float, optional
        Largest breadth of the hull below the waterline.
    source : str
        Named in the message.

    Raises
    ------
    OffsetsError
    """
    src = f" ({source})" if source else ""
    if B_hull is not None and abs(B_hull - B) > rel_breadth * B:
        raise OffsetsError(
            f"`particulars.B` = {B:g} m contradicts the hull{src}: its largest breadth at "
            f"the waterline is {B_hull:.4g} m"
        )
    V_given = C_b * L * B * d_m
    if abs(V_given - hs.volume) > rel_volume * hs.volume:
        raise OffsetsError(
            f"`particulars.C_b` = {C_b:g} contradicts the hull{src}: C_b L B d_m = "
            f"{V_given:.5g} m^3 but the hull displaces {hs.volume:.5g} m^3 (C_b = "
            f"{hs.volume / (L * B * d_m):.4f})"
        )
    if abs(-lcb_aft - hs.lcb) > rel_lcb * L:
        raise OffsetsError(
            f"`particulars.lcb_aft` = {lcb_aft:g} m contradicts the hull{src}: its "
            f"l.c.b. is {-hs.lcb:.4g} m aft of midship"
        )


__all__ = ["Hydrostatics", "check_particulars", "hydrostatics"]
