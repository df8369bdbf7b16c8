r"""Hydrostatics and GZ of a closed hull mesh, by the divergence theorem over the clipped mesh.

The mesh (:mod:`ship_models.hydro.mesh_io`: closed, outward, axes x forward from
midship, y to port, z up from the calm waterline) is cut by a plane, the *waterplane*

.. math::

    g(\mathbf p) = z\cos\phi + y\sin\phi - \theta x = h_0 ,

heel :math:`\phi` (starboard down), trim slope :math:`\theta` and level :math:`h_0`
(the notation of :mod:`ship_models.hydro.hydrostatics`), and the triangles are clipped
to the submerged side :math:`g \le h_0`. With the plane's unit normal
:math:`\mathbf n_c = \nabla g/\mu`, :math:`\mu = \sqrt{1 + \theta^2}`, and the signed
distance :math:`s = (g - h_0)/\mu`, every vector field used below vanishes on the
waterplane, so the cut (the "lid") never has to be built: over the clipped hull
surface :math:`S` with outward normal :math:`\mathbf n`,

.. math::

    \nabla &= \int_S s\,(\mathbf n_c\!\cdot\mathbf n)\,dS
    &&(\mathbf F = s\,\mathbf n_c),\\
    \int_V s\,dV &= \int_S \tfrac12 s^2(\mathbf n_c\!\cdot\mathbf n)\,dS
    &&(\mathbf F = \tfrac12 s^2\mathbf n_c),\\
    \int_V p_i\,dV &= \int_S p_i\,s\,(\mathbf n_c\!\cdot\mathbf n)\,dS
      - n_{c,i}\int_V s\,dV &&(\mathbf F = p_i s\,\mathbf n_c),

and the waterplane's area and moments follow from fields that are divergence-free or
nearly so (closed surface = hull + waterplane):

.. math::

    A_{wp} = -\int_S \mathbf n_c\!\cdot\mathbf n\,dS, \quad
    \int_{wp} x\,dA = n_{c,x}\nabla - \int_S x\,\mathbf n_c\!\cdot\mathbf n\,dS, \quad
    \int_{wp} x^2 dA = 2n_{c,x}\!\int_V x\,dV - \int_S x^2\,\mathbf n_c\!\cdot\mathbf n\,dS,

and upright :math:`I_T = \int_{wp} y^2 dA = -\int_S y^2 n_z\,dS`. Every integrand is a
polynomial of degree <= 2 on a flat triangle, integrated exactly by the edge-midpoint
rule: the results are exact for the polyhedral hull the mesh describes; its only error
is the mesh's own (second order in the panel size for a smooth hull, none for a box).

GZ at heel: :math:`h_0` and :math:`\theta` are solved by Newton's method so that the
volume and its longitudinal centre equal the upright ones (:math:`\partial\nabla/
\partial h_0 = A_{wp}/\mu`, :math:`\partial\nabla/\partial\theta = \int_{wp} x\,dA/\mu`,
:math:`\partial\!\int_V x\,dV/\partial\theta = \int_{wp}x^2dA/\mu`: the exact Newton
matrix); ``free_trim=False`` keeps :math:`\theta = 0`. The righting arm and the fit are
those of :func:`ship_models.hydro.hydrostatics.gz_curve`:
:math:`GZ = y_B\cos\phi + (z_B - z_G)\sin\phi` with :math:`y_B` to starboard and
:math:`z_G = z_{B0} + BM - GM`.

References: the divergence-theorem hydrostatics of panel meshes as in Lewis, E.V. (ed.)
1988, "Principles of Naval Architecture", 2nd rev., Vol. I, SNAME, Ch. II (Sect. 2-3),
and the wall-sided formula :math:`GZ = (GM + \tfrac12 BM\tan^2\phi)\sin\phi` (ibid.,
Ch. II Sect. 4), the tests' closed form for a box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from continuation.typing import FloatArray, IntArray

from .gz import GZCurve, HeeledState, fit_sine_series, heeled_gz
from .upright import Hydrostatics


def clip_below(V: FloatArray, T: IntArray, n: FloatArray, h: float) -> FloatArray:
    """The parts of the triangles where ``n . p < h``, as triangles ``(m, 3, 3)``.

    Winding (hence the outward normal) is kept: a triangle with one vertex below gives
    one triangle, with two below a quadrilateral split in two.
    """
    P = V[T]  # (n_t, 3, 3)
    s = P @ n - h  # (n_t, 3)
    below = s < 0.0  # a face lying in the plane is the waterplane itself: not hull
    nb = below.sum(axis=1)
    out = [P[nb == 3]]
    for count in (1, 2):
        m = nb == count
        if not np.any(m):
            continue
        Pm, sm, bm = P[m], s[m], below[m]
        # rotate each triangle so that its odd vertex (the lone one below for count 1,
        # the lone one above for count 2) comes first
        odd = np.argmax(bm if count == 1 else ~bm, axis=1)
        idx = (odd[:, None] + np.arange(3)[None, :]) % 3
        r = np.arange(Pm.shape[0])[:, None]
        a, b, c = (Pm[r, idx][:, k] for k in range(3))
        sa, sb, sc = (sm[r, idx][:, k][:, None] for k in range(3))
        pab = a + (sa / (sa - sb)) * (b - a)
        pca = c + (sc / (sc - sa)) * (a - c)
        if count == 1:
            out.append(np.stack([a, pab, pca], axis=1))
        else:
            out.append(np.stack([pab, b, c], axis=1))
            out.append(np.stack([pab, c, pca], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 3, 3))


@dataclass(frozen=True)
class ClippedIntegrals:
    """Integrals of the submerged part for one waterplane (see the module docstring).

    Attributes
    ----------
    volume : float
        :math:`\\nabla` (m^3).
    centre : ndarray, shape (3,)
        Centre of buoyancy in the mesh axes (x fwd, y port, z up) (m).
    A_wp, Cx, Cxx : float
        Waterplane area and its first and second moments in x (m^2, m^3, m^4).
    mu : float
        :math:`\\sqrt{1 + \\theta^2}`.
    """

    volume: float
    centre: FloatArray
    A_wp: float
    Cx: float
    Cxx: float
    mu: float


def clipped_integrals(
    V: FloatArray, T: IntArray, phi: float, h0: float, theta: float = 0.0
) -> ClippedIntegrals:
    """Volume, centre of buoyancy and waterplane moments below :math:`g = h_0`."""
    mu = float(np.hypot(1.0, theta))
    nc = np.array([-theta, np.sin(phi), np.cos(phi)]) / mu
    h = h0 / mu
    P = clip_below(V, T, nc, h)
    if P.shape[0] == 0:
        return ClippedIntegrals(0.0, np.zeros(3), 0.0, 0.0, 0.0, mu)
    An = 0.5 * np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]) @ nc  # (n_c . n) dS
    M = 0.5 * (P + np.roll(P, -1, axis=1))  # edge midpoints (exact for degree 2)
    s = M @ nc - h  # (m, 3)

    def integral(f: FloatArray) -> float:
        return float(np.sum(An * f.mean(axis=1)))

    vol = integral(s)
    m_s = integral(0.5 * s * s)
    mom = np.array([integral(M[:, :, i] * s) for i in range(3)]) - nc * m_s
    A = -float(np.sum(An))
    x = M[:, :, 0]
    Cx = nc[0] * vol - integral(x)
    Cxx = 2.0 * nc[0] * mom[0] - integral(x * x)
    centre = mom / vol if vol > 0 else np.zeros(3)
    return ClippedIntegrals(vol, centre, A, Cx, Cxx, mu)


def mesh_hydrostatics(
    V: FloatArray,
    T: IntArray,
    *,
    L: float | None = None,
    B: float | None = None,
    d_m: float | None = None,
) -> Hydrostatics:
    """Upright hydrostatics of a closed hull mesh at its calm waterline ``z = 0``.

    Parameters
    ----------
    V, T : ndarray
        Closed outward triangle mesh (:func:`~ship_models.hydro.mesh_io.clean_closed_mesh`).
    L, B, d_m : float, optional
        Length, breadth and mean draft on which ``C_b`` is taken (default: the
        waterline's length and breadth and the keel's depth below the waterline).

    Returns
    -------
    Hydrostatics
        ``KB`` above the baseline at midship, i.e. ``z_B + d_m`` (without ``d_m``:
        above the keel's lowest point), ``lcb`` and ``lcf`` from the mesh origin
        (midship), ``I_L`` about the centre of flotation; exact for the polyhedral hull.
    """
    ci = clipped_integrals(V, T, 0.0, 0.0)
    P = clip_below(V, T, np.array([0.0, 0.0, 1.0]), 0.0)
    An = 0.5 * np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])[:, 2]
    M = 0.5 * (P + np.roll(P, -1, axis=1))
    I_T = -float(np.sum(An * (M[:, :, 1] ** 2).mean(axis=1)))
    lcf = ci.Cx / ci.A_wp
    I_L = ci.Cxx - ci.A_wp * lcf * lcf
    z_keel = float(V[:, 2].min())
    KB = float(ci.centre[2]) + (d_m if d_m is not None else -z_keel)
    if L is None or B is None:
        wl = _waterline_points(V, T)
        L = float(np.ptp(wl[:, 0])) if L is None else L
        B = float(np.ptp(wl[:, 1])) if B is None else B
    d_m = -z_keel if d_m is None else d_m
    return Hydrostatics(
        volume=ci.volume,
        lcb=float(ci.centre[0]),
        KB=KB,
        BM=I_T / ci.volume,
        A_wp=ci.A_wp,
        lcf=lcf,
        I_T=I_T,
        I_L=I_L,
        C_b=ci.volume / (L * B * d_m),
    )


def _waterline_points(V: FloatArray, T: IntArray, z: float = 0.0) -> FloatArray:
    """Points where the mesh's edges cross the plane ``z`` (the waterline), ``(m, 3)``."""
    e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    za, zb = V[e[:, 0], 2] - z, V[e[:, 1], 2] - z
    m = (za < 0) != (zb < 0)
    t = (za[m] / (za[m] - zb[m]))[:, None]
    return V[e[m, 0]] + t * (V[e[m, 1]] - V[e[m, 0]])


def mesh_heeled_equilibrium(
    V: FloatArray,
    T: IntArray,
    phi: float,
    volume: float,
    x_B: float,
    guess: tuple[float, float] = (0.0, 0.0),
    *,
    free_trim: bool = True,
    tol: float = 1e-12,
    max_iter: int = 60,
) -> HeeledState:
    """Level ``h0`` and trim ``theta`` at heel ``phi`` for the given volume and LCB (Newton).

    Returns a :class:`~ship_models.hydro.gz.HeeledState` with ``y_B`` to
    **starboard** and ``zeta_B`` up (body axes of the strip GZ).
    """
    h0, th = guess
    if not free_trim:
        th = 0.0
    size = float(np.ptp(V, axis=0).max())
    ok = False
    ci = clipped_integrals(V, T, phi, h0, th)
    for _ in range(max_iter):
        F = np.array([ci.volume - volume, ci.volume * ci.centre[0] - x_B * volume])
        if abs(F[0]) <= tol * volume and (not free_trim or abs(F[1]) <= tol * volume * size):
            ok = True
            break
        J = np.array([[ci.A_wp, ci.Cx], [ci.Cx, ci.Cxx]]) / ci.mu
        if free_trim:
            try:
                dz = np.linalg.solve(J, F)
            except np.linalg.LinAlgError:
                break
        else:
            if J[0, 0] <= 0:
                break
            dz = np.array([F[0] / J[0, 0], 0.0])
        step = abs(dz[0]) + abs(dz[1]) * 0.5 * size
        lam = min(1.0, 0.1 * size / step) if step > 0 else 1.0
        h0 -= lam * dz[0]
        th -= lam * dz[1]
        ci = clipped_integrals(V, T, phi, h0, th)
    c = ci.centre
    return HeeledState(float(phi), float(h0), float(th), ci.volume, float(-c[1]), float(c[2]),
                       float(c[0]), ok)  # fmt: skip


def mesh_gz_curve(
    V: FloatArray,
    T: IntArray,
    GM: float,
    *,
    heel_step: float = float(np.deg2rad(1.0)),
    n_terms: int = 40,
    phi_max: float = float(np.pi),
    free_trim: bool = True,
) -> GZCurve:
    """Hydrostatic GZ of a closed hull mesh over ``0..phi_max`` and its sine-series fit.

    Parameters
    ----------
    V, T : ndarray
        Closed outward triangle mesh at its calm waterline ``z = 0``.
    GM : float
        Metacentric height (m); sets :math:`z_G = z_{B0} + BM - GM`.
    heel_step : float
        Heel increment (rad).
    n_terms : int
        Sine terms of the fit (:func:`~ship_models.hydro.gz.fit_sine_series`).
    phi_max : float
        Largest heel (rad); the fit needs ``pi``.
    free_trim : bool
        Solve the trim with the sinkage (default) or keep the upright trim.

    Returns
    -------
    GZCurve
        ``zeta_G`` is the height of G above the calm waterline; ``topside_height`` 0
        (the mesh is the watertight envelope).

    Raises
    ------
    ValueError
        ``GM <= 0``, or the equilibrium fails at some heel.
    """
    if not GM > 0:
        raise ValueError(f"`GM` must be positive, got {GM}")
    hs = mesh_hydrostatics(V, T, L=1.0, B=1.0, d_m=1.0)
    up = clipped_integrals(V, T, 0.0, 0.0)
    V0, xB0, zB0 = up.volume, float(up.centre[0]), float(up.centre[2])
    zeta_G = zB0 + hs.BM - GM
    phis, gz = heeled_gz(
        lambda ph, guess: mesh_heeled_equilibrium(V, T, ph, V0, xB0, guess, free_trim=free_trim),
        "hydrostatic equilibrium of the mesh",
        zeta_G,
        phi_max,
        heel_step,
    )
    coeffs = fit_sine_series(phis, gz, n_terms, GM)
    return GZCurve(phis, gz, coeffs, float(GM), float(zeta_G), V0, 0.0)


__all__ = [
    "ClippedIntegrals",
    "clip_below",
    "clipped_integrals",
    "mesh_gz_curve",
    "mesh_heeled_equilibrium",
    "mesh_hydrostatics",
]
