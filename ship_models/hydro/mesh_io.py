r"""A closed hull mesh from a file: reading, cleaning and the checks a hull must pass.

Axes and placement
------------------
The mesh is the hull's watertight envelope (bottom, sides, ends and deck: a *closed*
surface) in the axes of Capytaine and of most design tools' hydrodynamic exports:
x forward from midship, y to **port**, z up, metres, placed at the loading condition so
that the calm waterline is the plane ``z = 0`` (trim, if any, is in the mesh).

Formats
-------
Wavefront ``.obj`` (``v``/``f`` lines) and STL (ASCII or binary) are read by this
module's own readers; every other format through ``meshio`` (``.vtk``, ``.vtu``,
``.msh``, ``.ply``, ``.off``...; optional extra ``pip install -e ".[hull]"``), then
Capytaine's loader (``.gdf``, Nemoh ``.dat``, ``.pnl``, ``.hst``, ``.mar``).
Polygons are split into triangles (fans from their first corner).

Checks (:func:`clean_closed_mesh`), each refused in one line naming the problem
-------------------------------------------------------------------------------
* non-finite coordinates, face indices out of range, no volume (degenerate);
* coincident vertices are merged (STL stores each triangle's corners apart) and
  faces of zero area dropped (they carry no area and no normal);
* closed: every edge is shared by exactly two faces (a free edge is a hole, an edge
  of three or more faces is not a surface);
* orientable and consistently wound: the two faces of an edge run it in opposite
  directions;
* outward: the enclosed volume :math:`\oint z\,n_z\,dS` is positive (negative: the
  normals point into the hull, "inverted").
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import numpy as np

from continuation.typing import FloatArray, IntArray

from .offsets import OffsetsError

#: Extensions read without meshio.
OWN_FORMATS = (".obj", ".stl")


class MeshError(OffsetsError):
    """A bad hull mesh; the one-line message names the file and the problem."""


def _fan(polys: list[list[int]]) -> IntArray:
    tris = [(p[0], p[i], p[i + 1]) for p in polys for i in range(1, len(p) - 1)]
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def _read_obj(p: Path) -> tuple[FloatArray, IntArray]:
    verts: list[list[float]] = []
    polys: list[list[int]] = []
    for n, raw in enumerate(p.read_text(errors="replace").splitlines(), start=1):
        parts = raw.split("#", 1)[0].split()
        if not parts:
            continue
        try:
            if parts[0] == "v":
                verts.append([float(c) for c in parts[1:4]])
                if len(verts[-1]) != 3:
                    raise ValueError
            elif parts[0] == "f":
                ids = [int(c.split("/")[0]) for c in parts[1:]]
                nv = len(verts)
                polys.append([i - 1 if i > 0 else nv + i for i in ids])
                if len(ids) < 3:
                    raise ValueError
        except ValueError:
            raise MeshError(
                f"mesh {p}: line {n} is not a valid `v x y z` or `f i j k` line"
            ) from None
    if not verts or not polys:
        raise MeshError(f"mesh {p}: no vertices or no faces (`v` and `f` lines)")
    return np.array(verts, dtype=float), _fan(polys)


def _read_stl(p: Path) -> tuple[FloatArray, IntArray]:
    data = p.read_bytes()
    if len(data) >= 84:
        (n,) = struct.unpack("<I", data[80:84])
        if len(data) == 84 + 50 * n:  # binary STL
            rec = np.frombuffer(data[84:], dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                                            ("a", "<u2")]))  # fmt: skip
            V = rec["v"].reshape(-1, 3).astype(float)
            return V, np.arange(V.shape[0], dtype=np.int64).reshape(-1, 3)
    text = data.decode("ascii", errors="replace")
    pts = [line.split()[1:4] for line in text.splitlines() if line.strip().startswith("vertex")]
    try:
        V = np.array(pts, dtype=float).reshape(-1, 3)
    except ValueError:
        raise MeshError(
            f"mesh {p}: not a readable STL file (a `vertex` line is not 3 numbers)"
        ) from None
    if V.shape[0] == 0 or V.shape[0] % 3:
        raise MeshError(f"mesh {p}: not a readable STL file (no facets of 3 vertices)")
    return V, np.arange(V.shape[0], dtype=np.int64).reshape(-1, 3)


def _read_meshio(p: Path) -> tuple[FloatArray, IntArray] | None:
    try:
        import meshio  # optional: the [hull] extra
    except ImportError:
        return None
    try:
        m = meshio.read(str(p))
    except Exception as exc:  # the reader's own error, reduced to one line below
        if "Unknown file format" in str(exc) or "Could not deduce" in str(exc):
            return None
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else "unreadable"
        raise MeshError(f"mesh {p}: cannot be read: {first}") from None
    polys: list[list[int]] = []
    for block in m.cells:
        if block.type in ("triangle", "quad") or block.type.startswith("polygon"):
            polys.extend(block.data.tolist())
    if not polys:
        raise MeshError(f"mesh {p}: no surface cells (triangles, quadrilaterals or polygons)")
    return np.asarray(m.points, dtype=float)[:, :3], _fan(polys)


def _read_capytaine(p: Path) -> tuple[FloatArray, IntArray]:
    try:
        import capytaine as cpt  # optional: the [hull] extra
    except ImportError:
        raise MeshError(
            f'mesh {p}: format not read without the hull extra (pip install -e ".[hull]"); '
            f"{' and '.join(OWN_FORMATS)} are read without it"
        ) from None
    try:
        mesh = cpt.load_mesh(str(p))
    except Exception as exc:  # the reader's own error, reduced to one line
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else "unreadable"
        raise MeshError(f"mesh {p}: cannot be read: {first}") from None
    F = np.asarray(mesh.faces, dtype=np.int64)
    polys = [[int(i) for j, i in enumerate(f) if j == 0 or i != f[j - 1]] for f in F]
    polys = [q[:-1] if q[-1] == q[0] else q for q in polys]
    return np.asarray(mesh.vertices, dtype=float), _fan(polys)


def read_mesh_file(path: str | Path) -> tuple[FloatArray, IntArray]:
    """Vertices and triangles of a mesh file, as stored (not yet checked).

    Returns
    -------
    vertices : ndarray, shape (n_v, 3)
    triangles : ndarray of int, shape (n_t, 3)

    Raises
    ------
    MeshError
        Missing or unreadable file.
    """
    p = Path(path)
    if not p.is_file():
        raise MeshError(f"no mesh file {str(p)!r}")
    ext = p.suffix.lower()
    if ext == ".obj":
        return _read_obj(p)
    if ext == ".stl":
        return _read_stl(p)
    got = _read_meshio(p)
    return got if got is not None else _read_capytaine(p)


def triangle_areas(V: FloatArray, T: IntArray) -> FloatArray:
    """Area vectors ``(b - a) x (c - a) / 2`` of triangles, shape (n_t, 3)."""
    p = V[T]
    return 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def enclosed_volume(V: FloatArray, T: IntArray) -> float:
    r"""Volume enclosed by a closed triangle mesh, :math:`\oint z\,n_z\,dS` (exact)."""
    zc = V[T][:, :, 2].mean(axis=1)
    return float(np.sum(zc * triangle_areas(V, T)[:, 2]))


def clean_closed_mesh(
    V: FloatArray, T: IntArray, *, source: str = "", merge_tol: float = 1e-9
) -> tuple[FloatArray, IntArray]:
    """Merge coincident vertices, drop zero-area faces, refuse an unusable hull surface.

    Parameters
    ----------
    V : ndarray, shape (n_v, 3)
    T : ndarray of int, shape (n_t, 3)
    source : str
        Named in the messages (the file).
    merge_tol : float
        Vertices closer than ``merge_tol`` times the mesh size are one vertex.

    Returns
    -------
    vertices, triangles
        A closed, consistently and outward-wound triangle mesh.

    Raises
    ------
    MeshError
        Non-finite or out-of-range data, no volume, an open or non-manifold surface,
        inconsistent winding, inverted normals (module docstring).
    """
    name = f"mesh {source}" if source else "mesh"
    V = np.asarray(V, dtype=float)
    T = np.asarray(T, dtype=np.int64)
    if V.ndim != 2 or V.shape[1] != 3 or T.ndim != 2 or T.shape[1] != 3 or T.shape[0] < 4:
        raise MeshError(f"{name} is degenerate: it needs at least 4 faces in 3-D")
    if not np.all(np.isfinite(V)):
        raise MeshError(f"{name}: a vertex coordinate is not a finite number")
    if T.min() < 0 or T.max() >= V.shape[0]:
        raise MeshError(f"{name}: a face refers to vertex {int(T.max()) + 1} of {V.shape[0]}")
    size = float(np.ptp(V, axis=0).max())
    if not size > 0:
        raise MeshError(f"{name} is degenerate: all its vertices coincide")
    key = np.round(V / (merge_tol * size)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    V, T = V[first], inverse.reshape(-1)[T]
    area = np.linalg.norm(triangle_areas(V, T), axis=1)
    T = T[(area > 1e-14 * size * size) & (T[:, 0] != T[:, 1]) & (T[:, 1] != T[:, 2])
          & (T[:, 2] != T[:, 0])]  # fmt: skip
    if T.shape[0] < 4:
        raise MeshError(f"{name} is degenerate: fewer than 4 faces of non-zero area")
    # directed edges: a closed, consistently wound surface uses each one exactly once,
    # and its reverse exactly once
    e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    und = np.sort(e, axis=1)
    uniq, counts = np.unique(und, axis=0, return_counts=True)
    if np.any(counts == 1):
        a, b = uniq[np.argmax(counts == 1)]
        mid = 0.5 * (V[a] + V[b]) + 0.0  # no -0
        raise MeshError(
            f"{name} is open: a free edge (a hole) at x = {mid[0]:.4g}, y = {mid[1]:.4g}, "
            f"z = {mid[2]:.4g} m; the hull must be a closed surface (bottom, sides, ends, deck)"
        )
    if np.any(counts > 2):
        a, b = uniq[np.argmax(counts > 2)]
        mid = 0.5 * (V[a] + V[b]) + 0.0  # no -0
        raise MeshError(
            f"{name} is not a surface: an edge of {int(counts.max())} faces at x = "
            f"{mid[0]:.4g}, y = {mid[1]:.4g}, z = {mid[2]:.4g} m"
        )
    _, dcount = np.unique(e, axis=0, return_counts=True)
    if np.any(dcount > 1):
        d = np.unique(e, axis=0)[np.argmax(dcount > 1)]
        mid = 0.5 * (V[d[0]] + V[d[1]]) + 0.0
        raise MeshError(
            f"{name} has inconsistent normals: neighbouring faces are wound in opposite "
            f"senses (e.g. at x = {mid[0]:.4g}, y = {mid[1]:.4g}, z = {mid[2]:.4g} m)"
        )
    vol = enclosed_volume(V, T)
    if vol < 0:
        raise MeshError(
            f"{name} is inverted: its normals point into the hull (volume {vol:.5g} m^3)"
        )
    if vol <= 1e-12 * size**3:
        raise MeshError(f"{name} is degenerate: it encloses no volume")
    used = np.unique(T)
    remap = np.full(V.shape[0], -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return V[used], remap[T]


def is_wetted_surface(V: FloatArray, T: IntArray, *, tol: float = 1e-6) -> bool:
    """Whether a mesh is a wetted surface only: open, with every free edge on ``z = 0``.

    Such a mesh (what panel codes use) serves the panel method but is no hull: it has
    no topsides for the GZ curve.
    """
    V = np.asarray(V, dtype=float)
    size = float(np.ptp(V, axis=0).max()) or 1.0
    key = np.round(V / (1e-9 * size)).astype(np.int64)
    _, inverse = np.unique(key, axis=0, return_inverse=True)
    T = inverse.reshape(-1)[np.asarray(T)]
    e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    e = e[e[:, 0] != e[:, 1]]
    uniq, counts = np.unique(e, axis=0, return_counts=True)
    free = uniq[counts == 1]
    if free.size == 0:
        return False
    Vm = np.zeros((int(inverse.max()) + 1, 3))
    Vm[inverse.reshape(-1)] = V
    return bool(np.all(np.abs(Vm[free][:, :, 2]) <= tol * size))


def write_obj(V: FloatArray, faces: Any, path: str | Path, comment: str = "") -> Path:
    """Write a mesh as Wavefront OBJ (metres, 1-based indices), atomically.

    ``comment`` lines are written as ``#`` lines first (the mesh's source).
    """
    p = Path(path)
    lines = [f"# {c}" for c in comment.splitlines() if c.strip()]
    V = np.asarray(V, dtype=float)
    V = np.where(V == 0.0, 0.0, V)  # no "-0.000000"
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in V]
    lines += ["f " + " ".join(str(int(i) + 1) for i in f) for f in faces]
    tmp = p.with_name(p.name + ".tmp")
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(p)
    return p


def write_stl(V: FloatArray, T: IntArray, path: str | Path) -> Path:
    """Write a triangle mesh as binary STL, atomically."""
    p = Path(path)
    tri = np.asarray(V, dtype=float)[np.asarray(T)]
    n = triangle_areas(V, T)
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rec = np.zeros(tri.shape[0], dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                                 ("a", "<u2")]))  # fmt: skip
    rec["n"] = n
    rec["v"] = tri
    tmp = p.with_name(p.name + ".tmp")
    tmp.write_bytes(b"broachkit hull mesh".ljust(80, b" ") + struct.pack("<I", tri.shape[0])
                    + rec.tobytes())  # fmt: skip
    tmp.replace(p)
    return p


__all__ = [
    "MeshError",
    "OWN_FORMATS",
    "clean_closed_mesh",
    "enclosed_volume",
    "is_wetted_surface",
    "read_mesh_file",
    "triangle_areas",
    "write_obj",
    "write_stl",
]
