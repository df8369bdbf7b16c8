r"""A closed hull mesh as the vessel's hull: strips by slicing, panels by clipping, and back.

:func:`hull_from_mesh` takes a closed hull mesh (:mod:`~ship_models.hydro.mesh_io`:
x forward from midship, y to port, z up from the calm waterline) and gives a
:class:`MeshHull`, a :class:`~ship_models.hydro.offsets.OffsetsHull` whose table of
offsets is *sliced from the mesh*: at ``n_stations`` equally spaced stations over the
mesh's length, the half-breadth at each waterline is half the chord of the section
polygon at that height (the crossings of the mesh's edges with the plane ``x =
const``, paired), so the Froude-Krylov strips, the Lewis sections and the wetted
surface use the mesh's sections. The waterlines are the mesh's own vertex heights
when there are at most ``max_waterlines`` of them (then the section between them is
exactly linear in z, as the bilinear table assumes), else equally spaced; the calm
waterline is always one. The baseline is the keel's lowest point.

The hydrostatics and the GZ curve of a :class:`MeshHull` are those of the mesh itself
(:mod:`~ship_models.hydro.mesh_hydrostatics`: exact integration over the clipped
polyhedron; :func:`ship_models.hydro.upright.hydrostatics` and
:func:`ship_models.hydro.hydrostatics.gz_curve` dispatch to them), and its panel mesh
for the panel method is the mesh clipped at the calm waterline (:func:`wetted_panels`).
The strips (sampled sections) and the mesh (exact) agree to the slicing's resolution;
``tests/test_hull_mesh.py`` states by how much.

:func:`offsets_closed_mesh` goes the other way: the closed mesh of a table of offsets'
bilinear surface up to the deck (the form-parameter hull or the Wigley example written
as a mesh), and :func:`box_mesh`, :func:`horizontal_cylinder_mesh` are closed-form
bodies for the checks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from continuation.typing import FloatArray, IntArray

from .mesh_hydrostatics import clip_below, mesh_hydrostatics
from .mesh_io import MeshError, clean_closed_mesh, read_mesh_file
from .offsets import OffsetsHull, OffsetsTable, hull_from_offsets
from .upright import Hydrostatics, check_particulars


@dataclass(frozen=True)
class MeshHull(OffsetsHull):
    """An :class:`~ship_models.hydro.offsets.OffsetsHull` sliced from a closed mesh.

    Attributes
    ----------
    vertices : ndarray, shape (n_v, 3)
        The closed mesh (x forward from midship, y to port, z up from the calm
        waterline), m.
    triangles : ndarray of int, shape (n_t, 3)
        Outward-wound triangles.
    mesh_source : str
        The file (or text) the mesh comes from.
    d_mean : float
        Mean draft (the particulars' ``(d_f + d_a)/2``, else the keel's depth): ``KB``
        is above the baseline at midship, ``C_b`` on ``L B d_mean``.
    """

    vertices: FloatArray = field(default=None, repr=False)  # type: ignore[arg-type]
    triangles: IntArray = field(default=None, repr=False)  # type: ignore[arg-type]
    mesh_source: str = ""
    d_mean: float = 0.0

    def mesh_hydrostatics(self) -> Hydrostatics:
        """Upright hydrostatics of the mesh (exact), ``C_b`` on ``L B d_mean``."""
        return mesh_hydrostatics(self.vertices, self.triangles, L=self.L, B=self.B,
                                 d_m=self.d_mean or None)  # fmt: skip


def section_chords(
    V: FloatArray, T: IntArray, x: float, z: FloatArray, *, source: str = "", sym_tol: float = 1e-3
) -> FloatArray:
    """Half-breadths (half the chord) of the mesh's section at station ``x``, heights ``z``.

    The section is cut by the plane ``x``; at each height the crossings of its edges
    (half-open in z, so a vertex counts once) are sorted and paired, and the chord is
    the length inside. A hull not symmetric about ``y = 0`` (centre of the chord more
    than ``sym_tol`` of the mesh's breadth off) is refused.

    Returns
    -------
    ndarray, shape (K,)
    """
    P = V[T]
    s = P[:, :, 0] - x
    below = s <= 0.0
    nb = below.sum(axis=1)
    m = (nb == 1) | (nb == 2)
    Pm, sm, bm = P[m], s[m], below[m]
    segs = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        cross = bm[:, i] != bm[:, j]
        t = (sm[cross, i] / (sm[cross, i] - sm[cross, j]))[:, None]
        segs.append((np.flatnonzero(cross), Pm[cross, i] + t * (Pm[cross, j] - Pm[cross, i])))
    # each crossing triangle has exactly two crossing edges: pair them by triangle
    ids = np.concatenate([a for a, _ in segs])
    pts = np.concatenate([b for _, b in segs])
    order = np.argsort(ids, kind="stable")
    pts = pts[order].reshape(-1, 2, 3)[:, :, 1:]  # (S, 2, (y, z))
    z = np.asarray(z, dtype=float)
    za, zb = pts[:, 0, 1], pts[:, 1, 1]
    lo, hi = np.minimum(za, zb), np.maximum(za, zb)
    inside = (z[:, None] >= lo[None, :]) & (z[:, None] < hi[None, :])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (z[:, None] - za[None, :]) / (zb - za)[None, :]
        y = pts[None, :, 0, 0] + t * (pts[None, :, 1, 0] - pts[None, :, 0, 0])
    y = np.sort(np.where(inside, y, np.nan), axis=1)  # crossings first, NaN after
    if y.shape[1] % 2:
        y = np.concatenate([y, np.full((z.size, 1), np.nan)], axis=1)
    n = inside.sum(axis=1)
    name = f"mesh {source}" if source else "mesh"
    if np.any(n % 2):
        k = int(np.argmax(n % 2))
        raise MeshError(f"{name}: the section at x = {x:.4g} m is not closed at z = {z[k]:.4g} m")
    width = np.nan_to_num(y[:, 1::2] - y[:, 0::2]).sum(axis=1) if y.shape[1] else np.zeros(z.size)
    if y.shape[1]:
        y_lo = np.where(n > 0, y[:, 0], 0.0)
        y_hi = np.where(n > 0, y[np.arange(z.size), np.maximum(n - 1, 0)], 0.0)
        off = np.abs(y_lo + y_hi)
        breadth = float(np.ptp(V[:, 1]))
        if np.any(off > sym_tol * breadth):
            k = int(np.argmax(off))
            raise MeshError(
                f"{name} is not symmetric about the centre plane y = 0 (at x = {x:.4g} m, "
                f"z = {z[k]:.4g} m the section spans y = {y_lo[k]:.4g} to {y_hi[k]:.4g} m); "
                "the strips of the 4-DOF model need a port-starboard symmetric hull"
            )
    return 0.5 * width


def mesh_offsets(
    V: FloatArray,
    T: IntArray,
    *,
    L: float,
    n_stations: int = 81,
    max_waterlines: int = 121,
    source: str = "",
) -> OffsetsTable:
    """A table of offsets sliced from a closed mesh (lines-plan frame of the module doc).

    Stations from the AP (``x_ap = x + L/2``), waterlines above the keel's lowest point.
    """
    x0, x1 = float(V[:, 0].min()), float(V[:, 0].max())
    z0, z1 = float(V[:, 2].min()), float(V[:, 2].max())
    eps = 1e-7 * max(x1 - x0, z1 - z0)
    xs = np.linspace(x0 + eps, x1 - eps, n_stations)
    zv = np.unique(np.round(V[:, 2], 9))
    zs = zv if zv.size <= max_waterlines else np.linspace(z0, z1, max_waterlines)
    zs = np.unique(np.concatenate([zs, [0.0]]))
    zs = zs[(zs >= z0) & (zs <= z1)]
    zs[-1] = min(zs[-1], z1 - eps)  # the deck's own edges are not crossed at z1
    Y = np.stack([section_chords(V, T, float(x), zs, source=source) for x in xs])
    return OffsetsTable(xs + 0.5 * L, zs - z0, Y, f"sliced from the mesh {source}".strip())


def hull_from_mesh(
    mesh: str | Path | tuple[FloatArray, IntArray],
    *,
    L: float,
    D: float,
    d_f: float | None = None,
    d_a: float | None = None,
    B: float | None = None,
    C_b: float | None = None,
    lcb_aft: float | None = None,
    n_stations: int = 81,
    n_per_interval: int = 2,
    max_waterlines: int = 121,
) -> MeshHull:
    """The vessel's hull from a closed mesh file (or ``(vertices, triangles)``), checked.

    Parameters
    ----------
    mesh : path or (vertices, triangles)
        Closed hull at its loading condition, calm waterline ``z = 0``.
    L, D : float
        ``L_pp`` and depth (m); the FP at ``x = L/2``.
    d_f, d_a, B, C_b, lcb_aft : float, optional
        The vessel file's particulars, checked against the mesh when given: the keel's
        depth below the waterline against ``max(d_f, d_a)`` within 2 %, and
        :func:`~ship_models.hydro.upright.check_particulars` (displacement ``C_b L B
        d_m`` within 2 %, l.c.b. within 1 % of L, breadth within 2 %).
    n_stations, n_per_interval, max_waterlines : int
        Slicing: stations, strip stations per station interval, most waterlines.

    Raises
    ------
    MeshError
        Unreadable, open, inverted or degenerate mesh; a mesh not crossing the
        waterline; units inconsistent with ``L``; an asymmetric hull; particulars that
        contradict the mesh (one line naming the problem).
    """
    if isinstance(mesh, (str, Path)):
        src = str(mesh)
        V, T = read_mesh_file(mesh)
    else:
        src = "given"
        V, T = mesh
    V, T = clean_closed_mesh(V, T, source=src)
    name = f"mesh {src}"
    z0, z1 = float(V[:, 2].min()), float(V[:, 2].max())
    if not z0 < 0.0 < z1:
        raise MeshError(
            f"{name} does not cross the calm waterline z = 0 (z from {z0:.4g} to {z1:.4g} m): "
            "place it at the loading condition, z up from the waterline"
        )
    length = float(np.ptp(V[:, 0]))
    if not 0.5 * L <= length <= 2.0 * L:
        raise MeshError(
            f"{name} is {length:.5g} long but L_pp = {L:g} m (units inconsistent? the mesh "
            "must be in metres)"
        )
    T0 = -z0
    if d_f is not None and d_a is not None:
        d_max = max(d_f, d_a)
        if abs(T0 - d_max) > 0.02 * d_max:
            which = "d_a" if d_a >= d_f else "d_f"
            raise MeshError(
                f"`particulars.{which}` = {d_max:g} m contradicts the hull {name}: its keel "
                f"is {T0:.4g} m below the calm waterline z = 0"
            )
    table = mesh_offsets(V, T, L=L, n_stations=n_stations, max_waterlines=max_waterlines,
                         source=src)  # fmt: skip
    depth = max(D, float(table.z[-1]) + 1e-6)
    strips = hull_from_offsets(table, L=L, D=depth, d_f=T0, d_a=T0,
                               n_per_interval=n_per_interval)  # fmt: skip
    hull = MeshHull(
        strips.L, strips.B, strips.D, strips.x, strips.w, strips.d, strips.b_wl, strips.n_exp,
        dict(strips.info), table, T0, T0, strips.n_gauss, V, T, src,
        0.5 * (d_f + d_a) if d_f is not None and d_a is not None else T0,
    )  # fmt: skip
    if C_b is not None and B is not None and lcb_aft is not None and d_f is not None:
        assert d_a is not None
        check_particulars(
            mesh_hydrostatics(V, T, L=L, B=B, d_m=0.5 * (d_f + d_a)),
            L=L, B=B, d_m=0.5 * (d_f + d_a), C_b=C_b, lcb_aft=lcb_aft,
            B_hull=_waterline_breadth(V, T), source=name,
        )  # fmt: skip
    return hull


def _waterline_breadth(V: FloatArray, T: IntArray) -> float:
    from .mesh_hydrostatics import _waterline_points

    p = _waterline_points(V, T)
    return float(np.ptp(p[:, 1])) if p.size else 0.0


def wetted_panels(hull: MeshHull) -> tuple[FloatArray, IntArray]:
    """The mesh clipped at the calm waterline: the panel method's wetted hull.

    Returns
    -------
    vertices : ndarray, shape (n_v, 3)
    faces : ndarray of int, shape (n_f, 3)
        Triangles, outward, open at ``z = 0``.
    """
    P = clip_below(hull.vertices, hull.triangles, np.array([0.0, 0.0, 1.0]), 0.0)
    V = P.reshape(-1, 3)
    size = float(np.ptp(hull.vertices, axis=0).max())
    key = np.round(V / (1e-9 * size)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    F = inverse.reshape(-1, 3)
    area = np.linalg.norm(np.cross(V[first][F[:, 1]] - V[first][F[:, 0]],
                                   V[first][F[:, 2]] - V[first][F[:, 0]]), axis=1)  # fmt: skip
    return V[first], F[area > 1e-12 * size * size]


# ------------------------------------------------------------------ meshes of hulls
def _grid_mesh(X: FloatArray, Y: FloatArray, Z: FloatArray) -> tuple[FloatArray, IntArray]:
    """Triangles of a structured grid of points ``(I, K, 3)`` (two per cell)."""
    I, K = X.shape
    P = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    i, k = np.meshgrid(np.arange(I - 1), np.arange(K - 1), indexing="ij")
    a = (i * K + k).ravel()
    b = ((i + 1) * K + k).ravel()
    c, d = b + 1, a + 1
    T = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return P, T


def _orient(V: FloatArray, T: IntArray) -> tuple[FloatArray, IntArray]:
    """Reverse every triangle if the (consistently wound) mesh encloses negative volume."""
    from .mesh_io import enclosed_volume

    return V, T if enclosed_volume(V, T) > 0 else T[:, ::-1]


def offsets_closed_mesh(
    table: OffsetsTable,
    *,
    L: float,
    D: float,
    d_f: float,
    d_a: float,
    refine: int = 1,
) -> tuple[FloatArray, IntArray]:
    """The closed mesh of a table of offsets' bilinear surface, keel to deck.

    Vertices at the table's stations and waterlines (and the deck ``D`` above the
    baseline, wall-sided above the top waterline), each interval split into
    ``refine`` parts (the bilinear surface is linear along each grid line, so only
    the split of each curved cell into two flat triangles differs from it:
    second order in the cell size). Bottom and deck close the sections at the centre
    plane, the end stations are closed by flat ends. Placed in the mesh axes of
    :mod:`~ship_models.hydro.mesh_io`: midship at ``x = 0``, the waterline through the
    drafts ``d_a`` (AP) and ``d_f`` (FP) rotated to ``z = 0``.

    Returns
    -------
    vertices, triangles
        Checked closed and outward (:func:`~ship_models.hydro.mesh_io.clean_closed_mesh`).
    """
    r = max(1, int(refine))

    def split(a: FloatArray) -> FloatArray:
        t = np.linspace(0.0, 1.0, r + 1)[:-1]
        return np.concatenate([(a[:-1, None] + t[None, :] * np.diff(a)[:, None]).ravel(), a[-1:]])

    xs = split(np.asarray(table.x, dtype=float))
    zt = np.asarray(table.z, dtype=float)
    zs = split(zt[zt < D]) if np.any(zt < D) else np.array([0.0])
    zs = np.unique(np.concatenate([[0.0], zs, [D]]))
    Xg, Zg = np.meshgrid(xs, zs, indexing="ij")
    Yg = table.half_breadth(Xg, np.minimum(Zg, zt[-1]))
    # section curve: keel centre, starboard offsets keel -> deck, deck centre
    X = np.concatenate([Xg[:, :1], Xg, Xg[:, -1:]], axis=1)
    Ys = np.concatenate([np.zeros((xs.size, 1)), Yg, np.zeros((xs.size, 1))], axis=1)
    Z = np.concatenate([Zg[:, :1], Zg, Zg[:, -1:]], axis=1)
    Vs, Ts = _grid_mesh(X, -Ys, Z)  # starboard: y < 0 in the mesh axes
    Vp, Tp = _grid_mesh(X, Ys, Z)
    parts_V, parts_T = [Vs, Vp], [Ts, Tp[:, ::-1] + Vs.shape[0]]
    n = Vs.shape[0] + Vp.shape[0]
    for i in (0, xs.size - 1):  # flat ends: starboard curve, centre line, port curve
        curve = np.stack([X[i], -Ys[i], Z[i]], axis=-1)
        mid = curve * [1.0, 0.0, 1.0]
        port = curve * [1.0, -1.0, 1.0]
        Ve, Te = _grid_mesh(*np.stack([curve, mid, port]).transpose(2, 0, 1))
        parts_V.append(Ve)
        parts_T.append((Te[:, ::-1] if i == 0 else Te) + n)
        n += Ve.shape[0]
    V = np.concatenate(parts_V)
    T = np.concatenate(parts_T)
    # drop the centre-plane faces both sides share (zero thickness), then orient
    inplane = np.all(np.abs(V[T][:, :, 1]) < 1e-12 * L, axis=1)
    side = np.zeros(T.shape[0], dtype=bool)
    side[: Ts.shape[0] + Tp.shape[0]] = True
    T = T[~(inplane & side)]
    # the waterline through the drafts: rotate it to z = 0, midship to x = 0
    ux = np.array([L, d_f - d_a]) / math.hypot(L, d_f - d_a)
    nz = np.array([-ux[1], ux[0]])
    rel = np.stack([V[:, 0] - 0.5 * L, V[:, 2] - 0.5 * (d_f + d_a)], axis=1)
    V = np.stack([rel @ ux, V[:, 1], rel @ nz], axis=1)
    V, T = _orient(V, T)
    return clean_closed_mesh(V, T, source="of the offsets")


def box_mesh(L: float, B: float, D: float, T: float, n: int = 1) -> tuple[FloatArray, IntArray]:
    """Closed mesh of a box barge ``L x B x D`` at draft ``T``, edges in ``max(n, 2)`` parts."""
    n = max(2, int(n))
    table = OffsetsTable(np.linspace(0.0, L, n + 1), np.linspace(0.0, D, n + 1),
                         np.full((n + 1, n + 1), 0.5 * B), "box")  # fmt: skip
    return offsets_closed_mesh(table, L=L, D=D, d_f=T, d_a=T)


def horizontal_cylinder_mesh(
    L: float, R: float, z_axis: float, n_around: int, n_along: int = 1
) -> tuple[FloatArray, IntArray]:
    """Closed mesh of a circular cylinder, axis along x at height ``z_axis``.

    ``n_around`` facets around (vertices on the circle, one at the bottom), flat ends.
    """
    a = -0.5 * math.pi + 2.0 * math.pi * np.arange(n_around) / n_around
    xs = np.linspace(-0.5 * L, 0.5 * L, n_along + 1)
    ring_y, ring_z = R * np.cos(a), z_axis + R * np.sin(a)
    Xg = np.repeat(xs[:, None], n_around + 1, axis=1)
    Yg = np.broadcast_to(np.append(ring_y, ring_y[0]), Xg.shape)
    Zg = np.broadcast_to(np.append(ring_z, ring_z[0]), Xg.shape)
    V, T = _grid_mesh(Xg, Yg, Zg)
    parts_V, parts_T, nv = [V], [T], V.shape[0]
    for x, flip in ((xs[0], True), (xs[-1], False)):
        c = np.array([[x, 0.0, z_axis]])
        ring = np.stack([np.full(n_around, x), ring_y, ring_z], axis=1)
        parts_V.append(np.concatenate([c, ring]))
        k = np.arange(n_around)
        tri = np.stack([np.zeros(n_around, int), 1 + (k + 1) % n_around, 1 + k], axis=1)
        parts_T.append((tri[:, ::-1] if flip else tri) + nv)
        nv += n_around + 1
    V, T = np.concatenate(parts_V), np.concatenate(parts_T)
    V, T = _orient(V, T)
    return clean_closed_mesh(V, T, source="cylinder")


__all__ = [
    "MeshHull",
    "box_mesh",
    "horizontal_cylinder_mesh",
    "hull_from_mesh",
    "mesh_offsets",
    "offsets_closed_mesh",
    "section_chords",
    "wetted_panels",
]
