"""Stability: the watertight topside height and the GZ curve of the hull.

The topside height, when the file does not give it, is the smallest watertight
extension of the sides for which the GZ curve meets the IMO 2008 IS Code general
criteria (Part A 2.2): the paper's "marginally complies" (Umeda 1999, Sec. 3).
"""

from __future__ import annotations

from ..hydro.hull import HullForm
from ..hydro.hydrostatics import GZCurve, gz_curve, marginal_topside_height
from ..hydro.mesh_hull import MeshHull
from ..vessel import VesselFileError
from .common import Build, estimated
from .hull import hull_mesh_path
from .memo import memo_call


def estimate_stability(b: Build, hull: HullForm) -> tuple[float, GZCurve]:
    """The topside height (given, assumed 0 for a mesh hull, or the IS-Code margin) and
    the GZ curve with it; VesselFileError when G would lie below the keel.

    Parameters
    ----------
    b : Build
        The build; the stage records the topside height it estimates or assumes.
    hull : HullForm

    Returns
    -------
    topside : float
        Watertight extension of the sides above D, m.
    gz : GZCurve
    """
    v, est = b.vessel, b.estimates
    GM, d_m = b.p.GM, b.p.d_m
    if isinstance(hull, MeshHull):  # the mesh is the watertight envelope
        topside = v.get("stability.topside_height") if v.has("stability.topside_height") else 0.0
        if topside != 0.0:
            raise VesselFileError(
                f"`stability.topside_height` = {topside:g} m: a hull given by a mesh is its "
                "own watertight envelope (model enclosed superstructures in the mesh); give 0 "
                "or leave it out"
            )
        if not v.has("stability.topside_height"):
            est["stability.topside_height"] = estimated(
                0.0, "m", f"the mesh {hull_mesh_path(v)} is the watertight envelope", "assumed"
            )
    elif v.has("stability.topside_height"):
        topside = v.get("stability.topside_height")
    else:
        topside = memo_call("marginal_topside_height", marginal_topside_height, hull, GM)
        est["stability.topside_height"] = estimated(
            topside,
            "m",
            "smallest watertight extension of the sides above D (stand-in for enclosed "
            "superstructures) for which the GZ curve meets the IMO 2008 IS Code general "
            "criteria (Part A 2.2) to within the 1 mm tolerance of the fit (the computed "
            "margin may miss zero by ~1e-4): the paper's condition 'marginally complies'",
        )
    gz = memo_call(
        "gz_curve",
        gz_curve,
        hull,
        GM,
        heel_step=v.get("stability.heel_step"),
        n_terms=int(v.get("stability.n_gz_terms")),
        topside_height=topside,
    )
    zeta_G = gz.zeta_G
    if zeta_G + d_m <= 0.0:  # KG = KM - GM: G at or below the keel
        raise VesselFileError(
            f"`loading.GM` = {GM} m exceeds this hull's KM = {zeta_G + d_m + GM:.4g} m "
            f"(KG = {zeta_G + d_m:.4g} m: G below the keel)"
        )
    return topside, gz
