"""The hull a vessel file describes, and the estimates that come from it.

The hull is the ``[vessel] hull_offsets`` table (:func:`offsets_hull`), else the
``[vessel] hull_mesh`` when it is a closed hull (:func:`mesh_hull`), else the
parametric form-parameter hull of the particulars
(:func:`~ship_models.hydro.hull.parametric_hull`). :func:`estimate_hull` fills
C_wp (the hull's waterplane, or Schneekluth & Bertram 1998), the wetted surface
(girth integral) and the mass (:math:`\\rho` times the displaced volume).
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..hydro.hull import FormParameters, HullForm, parametric_hull, schneekluth_cwp
from ..hydro.mesh_hull import MeshHull, hull_from_mesh
from ..hydro.mesh_io import is_wetted_surface, read_mesh_file
from ..hydro.offsets import OffsetsError, OffsetsHull, hull_from_offsets, read_offsets
from ..hydro.upright import check_particulars
from ..hydro.upright import hydrostatics as offsets_hydrostatics
from ..vessel import VesselData, VesselFileError
from .common import Build, estimated
from .memo import memo_call


def _named_file(v: VesselData, key: str) -> Path | None:
    """The file named by ``[vessel] <key>``, relative to the vessel file; None if unset."""
    name = v.meta.get(key)
    if not name:
        return None
    p = Path(str(name))
    if not p.is_absolute() and v.path:
        p = Path(v.path).parent / p
    return p


def offsets_path(v: VesselData) -> Path | None:
    """The offsets file named by ``[vessel] hull_offsets`` (relative to the vessel file)."""
    return _named_file(v, "hull_offsets")


def _particulars(v: VesselData, *names: str) -> dict[str, float]:
    """The vessel's principal particulars ``names`` as keyword arguments of the hull
    builders (``L`` is ``particulars.L_pp``, the others their own names)."""
    return {n: v.get(f"particulars.{'L_pp' if n == 'L' else n}") for n in names}


def form_parameters(v: VesselData, C_wp: float | None = None) -> FormParameters:
    """The form parameters of the vessel's hull (``particulars.*``, ``hull.C_M``).

    Parameters
    ----------
    v : VesselData
    C_wp : float, optional
        Waterplane coefficient (default ``hull.C_wp`` of the file; the resolved
        vessel's estimate when the file has none).

    Returns
    -------
    FormParameters
        ``lcb`` from midship, forward + (the file's ``lcb_aft`` with its sign turned).
    """
    return FormParameters(
        **_particulars(v, "L", "B", "D", "d_f", "d_a", "C_b"),
        lcb=-v.get("particulars.lcb_aft"),
        C_M=v.get("hull.C_M"),
        C_wp=v.get("hull.C_wp") if C_wp is None else C_wp,
    )


def offsets_hull(v: VesselData) -> OffsetsHull:
    """The strip hull of the vessel's ``[vessel] hull_offsets`` table, checked against
    the particulars (C_b, l.c.b., B); VesselFileError naming the contradiction."""
    p = offsets_path(v)
    if p is None:
        raise VesselFileError("`vessel.hull_offsets`: the vessel has no offsets file")
    try:
        table = read_offsets(p)
        hull = hull_from_offsets(
            table,
            **_particulars(v, "L", "D", "d_f", "d_a"),
            n_per_interval=max(2, int(v.get("hull.n_stations")) // max(1, table.x.size - 1)),
        )
        check_particulars(
            offsets_hydrostatics(hull),
            L=v.get("particulars.L_pp"),
            B=v.get("particulars.B"),
            d_m=0.5 * (v.get("particulars.d_f") + v.get("particulars.d_a")),
            C_b=v.get("particulars.C_b"),
            lcb_aft=v.get("particulars.lcb_aft"),
            B_hull=2.0 * float(np.max(hull.b_wl)),
            source=str(p),
        )
    except OffsetsError as exc:
        raise VesselFileError(f"`vessel.hull_offsets`: {exc}") from None
    return hull


def hull_mesh_path(v: VesselData) -> Path | None:
    """The mesh file named by ``[vessel] hull_mesh`` (relative to the vessel file)."""
    return _named_file(v, "hull_mesh")


def mesh_is_hull(v: VesselData) -> bool:
    """Whether ``[vessel] hull_mesh`` is the hull (strips, hydrostatics, GZ and panels
    from the mesh) rather than the panel mesh only.

    The mesh is the hull unless the file also names ``hull_offsets`` or the mesh is a
    wetted surface only (open, its free edges on the waterline: what panel codes use),
    which serves the panel method beside the offsets or the particulars.
    """
    p = hull_mesh_path(v)
    if p is None or offsets_path(v) is not None:
        return False
    if not p.is_file():
        return True  # refused with the file's name when the hull is built
    try:
        stat = p.stat()
        return not _wetted_only(str(p), stat.st_mtime_ns, stat.st_size)
    except OffsetsError:
        return True  # unreadable: refused in one line when the hull is built


@functools.lru_cache(maxsize=32)
def _wetted_only(path: str, mtime_ns: int, size: int) -> bool:
    return is_wetted_surface(*read_mesh_file(path))


def mesh_hull(v: VesselData) -> MeshHull:
    """The hull of the vessel's ``[vessel] hull_mesh`` (a closed mesh), checked against
    the particulars (drafts, C_b, l.c.b., B); VesselFileError naming the problem."""
    p = hull_mesh_path(v)
    if p is None:
        raise VesselFileError("`vessel.hull_mesh`: the vessel has no mesh file")
    try:
        if not p.is_file():
            raise OffsetsError(f"no mesh file {str(p)!r}")
        digest = hashlib.sha256(p.read_bytes()).hexdigest()  # the key: the file's content
        return memo_call(
            "mesh_hull",
            _hull_from_mesh_file,
            str(p),
            digest,
            **_particulars(v, "L", "D", "d_f", "d_a", "B", "C_b", "lcb_aft"),
            n_per_interval=2,
            n_stations=max(41, int(v.get("hull.n_stations")) + 1),
        )
    except OffsetsError as exc:
        raise VesselFileError(f"`vessel.hull_mesh`: {exc}") from None


def _hull_from_mesh_file(path: str, digest: str, **kwargs: Any) -> MeshHull:
    """:func:`hull_from_mesh` of a file whose content hashes to ``digest`` (cache key)."""
    return hull_from_mesh(path, **kwargs)


def hull_form(v: VesselData, C_wp: float) -> HullForm:
    """The strip hull of the vessel: its offsets, its closed mesh, or the parametric hull
    of its particulars with waterplane coefficient ``C_wp``."""
    if offsets_path(v) is not None:
        return offsets_hull(v)
    if mesh_is_hull(v):
        return mesh_hull(v)
    return parametric_hull(
        form_parameters(v, C_wp),
        n_stations=int(v.get("hull.n_stations")),
        beta_min=v.get("hull.beta_min"),
        beta_max=v.get("hull.beta_max"),
    )


class HullEstimate(NamedTuple):
    """The hull of a vessel file and what the estimation takes from it.

    Attributes
    ----------
    C_wp : float
        Waterplane coefficient (given or estimated).
    hull : HullForm
        The strip hull (:func:`hull_form`).
    S_hull, S_f : float
        Wetted surface of the hull's sections (girth integral), and the one used (the
        file's ``particulars.S_f`` when given), m^2.
    volume : float
        Displaced volume, m^3 (a mesh hull's exact polyhedral volume).
    mass : float
        ``loading.mass``, or :math:`\\rho` times ``volume``, kg.
    x_G : float
        Longitudinal position of G from midship, forward + (G above B in calm water).
    """

    C_wp: float
    hull: HullForm
    S_hull: float
    S_f: float
    volume: float
    mass: float
    x_G: float


def estimate_hull(b: Build) -> HullEstimate:
    """The vessel's hull with C_wp, wetted surface and mass.

    Parameters
    ----------
    b : Build
        The build; the stage records the C_wp, S_f and mass it estimates.

    Returns
    -------
    HullEstimate
    """
    v, p, est = b.vessel, b.p, b.estimates
    L, B, C_b, rho, lcb_aft = p.L, p.B, p.C_b, p.rho, p.lcb_aft
    if v.has("hull.C_wp"):
        C_wp = v.get("hull.C_wp")
    elif offsets_path(v) is not None:
        oh = offsets_hull(v)
        C_wp = oh.waterplane_area / (L * B)
        est["hull.C_wp"] = estimated(C_wp, "-", f"waterplane area of the offsets {offsets_path(v)}")
    elif mesh_is_hull(v):
        mh = mesh_hull(v)
        C_wp = offsets_hydrostatics(mh).A_wp / (L * B)
        est["hull.C_wp"] = estimated(C_wp, "-", f"waterplane area of the mesh {hull_mesh_path(v)}")
    else:
        C_wp = schneekluth_cwp(C_b)
        est["hull.C_wp"] = estimated(
            C_wp,
            "-",
            "(1 + 2 C_b)/3: Schneekluth & Bertram (1998), Ship Design for Efficiency and Economy",
        )
    hull = hull_form(v, C_wp)
    S_hull = hull.wetted_surface()
    if v.has("particulars.S_f"):
        S_f = v.get("particulars.S_f")
    else:
        S_f = S_hull
        est["particulars.S_f"] = estimated(S_f, "m^2", "girth integral of the hull's sections")
    # a mesh hull displaces its exact (polyhedral) volume; the strips agree to the slicing
    volume = offsets_hydrostatics(hull).volume if isinstance(hull, MeshHull) else hull.volume
    if v.has("loading.mass"):
        mass = v.get("loading.mass")
    else:
        mass = rho * volume
        est["loading.mass"] = estimated(mass, "kg", "rho C_b L_pp B d_m")
    x_G = -lcb_aft  # G above B in calm water
    return HullEstimate(C_wp, hull, S_hull, S_f, volume, mass, x_G)
