r"""Panel meshes of the wetted hull: made from offsets, checked, and their volume.

Axes of the meshes (those of Capytaine): x forward from midship, y to **port**, z up
from the calm waterline. :func:`offsets_panels` makes quadrilaterals on the bilinear
surface of a table of offsets; :func:`check_wetted_mesh` refuses a mesh that is open
below the waterline or inverted; :func:`mesh_volume` is its displacement.
"""

from __future__ import annotations

import math

import numpy as np

from continuation.typing import FloatArray

from .offsets import OffsetsError, OffsetsHull, draft_at


def offsets_panels(
    hull: OffsetsHull, *, nx: int = 40, nz: int = 8
) -> tuple[FloatArray, FloatArray]:
    """Quadrilateral panels of the wetted hull (both sides, ends closed).

    Axes of the panel mesh (those of Capytaine): x forward from midship, y to
    **port**, z up from the calm waterline. The vertices lie on the bilinear surface:
    ``nx`` stations equally spaced over the table's length, ``nz`` levels from the
    keel to the local waterline (cosine-clustered at both ends), plus the flat
    bottom from the centre plane out to the bottom offsets. Panels of zero area
    (where the hull has no width) are dropped.

    Returns
    -------
    vertices : ndarray, shape (n_v, 3)
    faces : ndarray, shape (n_f, 4)
        Vertex indices, counter-clockwise seen from the water (normals outward).
    """
    t = hull.table
    L = hull.L
    xs = np.linspace(t.x[0], t.x[-1], nx + 1)
    T = draft_at(xs, L, hull.d_f, hull.d_a)
    s = 0.5 * (1.0 - np.cos(np.linspace(0.0, math.pi, nz + 1)))  # 0 keel .. 1 waterline
    h = s[None, :] * T[:, None]
    yb = t.half_breadth(np.broadcast_to(xs[:, None], h.shape), h)
    # station curve: centre-plane keel point, then the offsets up to the waterline
    Ys = np.concatenate([np.zeros((xs.size, 1)), yb], axis=1)  # (nx+1, nz+2)
    Zs = np.concatenate([h[:, :1], h], axis=1) - T[:, None]
    Xs = np.broadcast_to(xs[:, None], Ys.shape)
    n_c = Ys.shape[1]
    verts = []
    faces = []

    def side(sign: float) -> None:
        base = sum(v.shape[0] for v in verts)
        verts.append(np.stack([Xs - 0.5 * L, sign * Ys, Zs], axis=-1).reshape(-1, 3))
        for i in range(xs.size - 1):
            for k in range(n_c - 1):
                a = base + i * n_c + k
                b = base + (i + 1) * n_c + k
                quad = [a, b, b + 1, a + 1]
                faces.append(quad if sign < 0 else quad[::-1])

    side(-1.0)  # starboard (y < 0 in Capytaine's axes)
    side(+1.0)

    def end(i: int, aft: bool) -> None:
        base = sum(v.shape[0] for v in verts)
        cur = np.stack([np.full(n_c, xs[i] - 0.5 * L), Ys[i], Zs[i]], axis=-1)
        mid = cur.copy()
        mid[:, 1] = 0.0
        verts.append(np.concatenate([cur, mid, cur * [1.0, -1.0, 1.0]]))
        for k in range(n_c - 1):
            a, c, p = base + k, base + n_c + k, base + 2 * n_c + k
            q1 = [a, a + 1, c + 1, c]  # starboard half
            q2 = [c, c + 1, p + 1, p]  # port half
            if not aft:
                q1, q2 = q1[::-1], q2[::-1]
            faces.extend([q1, q2])

    end(0, aft=True)
    end(xs.size - 1, aft=False)
    V = np.concatenate(verts)
    F = np.array(faces, dtype=int)
    # merge coincident vertices (the sides meet at the keel and the ends)
    key = np.round(V / (1e-9 * L)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    V, F = V[first], inverse.reshape(-1)[F]
    area = _quad_areas(V, F)
    keep = area > 1e-10 * L * L
    return V, F[keep]


def _quad_areas(V: FloatArray, F: FloatArray) -> FloatArray:
    p = V[F]
    n = 0.5 * np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    return np.linalg.norm(n, axis=1)


def mesh_volume(V: FloatArray, F: FloatArray) -> float:
    r"""Displaced volume of a wetted-hull mesh open at ``z = 0``: :math:`\int z\,n_z\,dS`.

    With outward normals and the missing lid at ``z = 0`` (where the integrand
    vanishes), the divergence theorem gives the volume; a negative value means
    inverted normals.
    """
    p = V[F]
    n = 0.5 * np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    zc = p[:, :, 2].mean(axis=1)
    return float(np.sum(zc * n[:, 2]))


def check_wetted_mesh(V: FloatArray, F: FloatArray, *, source: str = "", tol: float = 1e-6) -> None:
    """Refuse a wetted-hull mesh that is open below the waterline or inverted.

    Every edge used by one face only must lie on the waterline ``z = 0`` (else the
    hull has a hole), and the enclosed volume :func:`mesh_volume` must be positive
    (else the normals point into the hull).

    Raises
    ------
    OffsetsError
    """
    src = f" {source}" if source else ""
    if F.ndim != 2 or F.shape[1] not in (3, 4) or V.ndim != 2 or V.shape[1] != 3:
        raise OffsetsError(f"mesh{src}: faces must be triangles or quadrilaterals in 3-D")
    edges: dict[tuple[int, int], int] = {}
    for f in F:
        ids = [int(i) for i in f]
        ring = [i for j, i in enumerate(ids) if i != ids[j - 1]]  # drop repeated corners
        for j in range(len(ring)):
            a, b = ring[j - 1], ring[j]
            key = (min(a, b), max(a, b))
            edges[key] = edges.get(key, 0) + 1
    scale = float(np.ptp(V, axis=0).max())
    for (a, b), count in edges.items():
        if count == 1 and max(abs(V[a, 2]), abs(V[b, 2])) > tol * scale:
            raise OffsetsError(
                f"mesh{src} is open below the waterline: a free edge at z = "
                f"{0.5 * (V[a, 2] + V[b, 2]):.4g} m (a hole; the hull must be closed up to "
                "the waterline)"
            )
    if mesh_volume(V, F if F.shape[1] == 4 else np.c_[F, F[:, 2]]) <= 0:
        raise OffsetsError(
            f"mesh{src} is inverted: its normals point into the hull (negative volume)"
        )


__all__ = ["check_wetted_mesh", "mesh_volume", "offsets_panels"]
