r"""Hydrostatic righting arm GZ(phi) of a strip hull, free to sink and trim.

Each station is a closed convex polygon (bottom from the section shape, vertical
topsides up to the deck, the deck). At heel :math:`\phi` (starboard down) the
submerged part of station j is the polygon clipped by the half-plane

.. math::

    \zeta\cos\phi - y\sin\phi \le h_0 + \theta x_j ,

(body axes: y to starboard, zeta up from the calm waterline). Sinkage ``h_0`` and
trim ``theta`` are solved by Newton's method so that the displaced volume and its
longitudinal centre equal those of the upright ship (``dV/dh_0`` is the waterline
chord, which gives the exact Newton matrix). Areas and first moments of the clipped
polygons come from Green's theorem, :math:`A = \tfrac12\oint (y\,d\zeta - \zeta\,dy)`,
vectorised over stations. The righting arm is the horizontal distance from G to B,

.. math::

    GZ(\phi) = y_B \cos\phi + (\zeta_B - \zeta_G)\sin\phi ,

with the height of G, :math:`\zeta_G = \zeta_{B0} + I_T/\nabla - GM`, set by the given
GM; so :math:`GZ'(0) = GM` is a check of the integration (tested), not an input.
Deck immersion (the purse seiner's freeboard is only 0.27-0.57 m) is included;
bulwarks, superstructures and water on deck are not.

For the equations of motion, :class:`GZCurve` fits an odd sine series
:math:`GZ(\phi) \approx \sum_{i=1}^{n} g_i \sin(i\phi)` to the computed curve by
least squares with the constraint :math:`\sum_i i g_i = GM` (exact initial slope),
which is smooth, :math:`2\pi`-periodic and odd, and evaluates with CasADi.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize as so

from continuation.typing import FloatArray

from .gz import GZCurve, HeeledState, fit_sine_series, heeled_gz
from .hull import HullForm
from .mesh_hydrostatics import mesh_gz_curve


def section_polygons(hull: HullForm, n_side: int = 40, topside_height: float = 0.0) -> FloatArray:
    """Closed counter-clockwise polygons of all stations, shape ``(J, V, 2)`` as ``(y, zeta)``.

    Vertices: keel centre, starboard bottom curve (clustered near the keel), starboard
    deck edge, port deck edge, port bottom curve. ``topside_height`` raises the
    watertight deck above ``D`` (wall-sided), a stand-in for enclosed superstructures.
    """
    if topside_height < 0:
        raise ValueError(f"`topside_height` must be >= 0, got {topside_height}")
    own = getattr(hull, "section_polygons", None)
    if callable(own):  # a hull given by its offsets has its own sections
        return np.asarray(own(topside_height), dtype=float)
    s = 1.0 - (1.0 - np.linspace(0.0, 1.0, n_side + 1)) ** 3  # 0 (WL) .. 1 (keel)
    s = s[::-1]  # keel -> WL
    d = hull.d[:, None]
    with np.errstate(over="ignore"):
        yb = hull.b_wl[:, None] * (1.0 - s[None, :] ** hull.n_exp[:, None])
    zb = -s[None, :] * d
    deck = (hull.D + topside_height - hull.d)[:, None]
    bw = hull.b_wl[:, None]
    # starboard: keel (y=0) -> WL, then deck edge; port mirrored back down
    ys = np.concatenate([yb, bw], axis=1)
    zs = np.concatenate([zb, deck], axis=1)
    yp = -ys[:, ::-1]
    zp = zs[:, ::-1]
    y = np.concatenate([ys, yp[:, :-1]], axis=1)  # drop duplicated keel point at the end
    z = np.concatenate([zs, zp[:, :-1]], axis=1)
    poly = np.stack([y, z], axis=-1)
    return poly


def clipped_moments(
    poly: FloatArray, cphi: float, sphi: float, h: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    r"""Area, first moments and waterline chord of the submerged part of each polygon.

    Parameters
    ----------
    poly : ndarray, shape (J, V, 2)
        Convex counter-clockwise polygons ``(y, zeta)``.
    cphi, sphi : float
        ``cos(phi)``, ``sin(phi)``.
    h : ndarray, shape (J,)
        Water level: submerged where :math:`\zeta\cos\phi - y\sin\phi \le h`.

    Returns
    -------
    A, My, Mz, chord : ndarray, shape (J,)
        Area, :math:`\int y\,dA`, :math:`\int \zeta\,dA` and the length of the waterline
        chord (``dA/dh``).
    """
    P = poly
    Q = np.roll(poly, -1, axis=1)
    g0 = P[..., 1] * cphi - P[..., 0] * sphi - h[:, None]
    g1 = Q[..., 1] * cphi - Q[..., 0] * sphi - h[:, None]
    in0 = g0 <= 0
    in1 = g1 <= 0
    denom = np.where(g0 == g1, 1.0, g0 - g1)
    tx = np.clip(g0 / denom, 0.0, 1.0)[..., None]
    X = P + tx * (Q - P)
    a = np.where((in0)[..., None], P, X)
    b = np.where((in1)[..., None], Q, X)
    keep = (in0 | in1)[..., None]
    a = np.where(keep, a, 0.0)
    b = np.where(keep, b, 0.0)
    exit_ = (in0 & ~in1)[..., None]
    entry = (~in0 & in1)[..., None]
    E = np.sum(np.where(exit_, X, 0.0), axis=1)
    N = np.sum(np.where(entry, X, 0.0), axis=1)

    def seg(a_: FloatArray, b_: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        cr = a_[..., 0] * b_[..., 1] - a_[..., 1] * b_[..., 0]
        return cr, (a_[..., 0] + b_[..., 0]) * cr, (a_[..., 1] + b_[..., 1]) * cr

    c1, y1, z1 = seg(a, b)
    c2, y2, z2 = seg(E, N)
    A = 0.5 * (np.sum(c1, axis=1) + c2)
    My = (np.sum(y1, axis=1) + y2) / 6.0
    Mz = (np.sum(z1, axis=1) + z2) / 6.0
    chord = np.hypot(E[:, 0] - N[:, 0], E[:, 1] - N[:, 1])
    return A, My, Mz, chord


def heeled_equilibrium(
    hull: HullForm,
    poly: FloatArray,
    phi: float,
    volume: float,
    x_B: float,
    guess: tuple[float, float] = (0.0, 0.0),
    *,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> HeeledState:
    """Solve sinkage and trim at heel ``phi`` for given volume and l.c.b. (Newton)."""
    c, s = float(np.cos(phi)), float(np.sin(phi))
    h0, th = guess
    x, w = hull.x, hull.w
    ok = False
    for _ in range(max_iter):
        A, My, Mz, ch = clipped_moments(poly, c, s, h0 + th * x)
        V = float(w @ A)
        Mx = float(w @ (x * A))
        F = np.array([V - volume, Mx - x_B * volume])
        J = np.array([[w @ ch, w @ (x * ch)], [w @ (x * ch), w @ (x * x * ch)]], dtype=float)
        if np.max(np.abs(F)) <= tol * volume * max(1.0, hull.L):
            ok = True
            break
        try:
            dz = np.linalg.solve(J, F)
        except np.linalg.LinAlgError:
            break
        lam = 1.0
        # keep the water level inside the hull's height range
        step = np.max(np.abs(dz[0]) + np.abs(dz[1]) * hull.L / 2)
        if step > 0.5:
            lam = 0.5 / step
        h0 -= lam * dz[0]
        th -= lam * dz[1]
    A, My, Mz, _ = clipped_moments(poly, c, s, h0 + th * x)
    V = float(w @ A)
    return HeeledState(
        float(phi),
        float(h0),
        float(th),
        V,
        float(w @ My) / V,
        float(w @ Mz) / V,
        float(w @ (x * A)) / V,
        ok,
    )


def gz_curve(
    hull: HullForm,
    GM: float,
    *,
    heel_step: float = np.deg2rad(1.0),
    n_terms: int = 40,
    n_side: int = 40,
    topside_height: float = 0.0,
    phi_max: float = np.pi,
) -> GZCurve:
    """Hydrostatic GZ over 0..180 deg and its sine-series fit.

    Parameters
    ----------
    hull : HullForm
    GM : float
        Metacentric height (m); fixes the height of G.
    heel_step : float
        Heel increment (rad).
    n_terms : int
        Number of sine terms of the fit.
    n_side : int
        Polygon vertices per side of each section.
    topside_height : float
        Watertight extension of the sides above the deck (m), see
        :func:`section_polygons`.
    phi_max : float
        Largest heel computed (rad); the sine fit needs the full range ``pi``.

    A hull sliced from a closed mesh (:class:`~ship_models.hydro.mesh_hull.MeshHull`)
    is integrated over the mesh itself, clipped at the inclined waterplane
    (:func:`~ship_models.hydro.mesh_hydrostatics.mesh_gz_curve`), with no topside
    extension (the mesh is the watertight envelope).

    Raises
    ------
    ValueError
        If ``GM <= 0`` or the hydrostatic equilibrium fails at some angle.
    """
    if not GM > 0:
        raise ValueError(f"`GM` must be positive, got {GM}")
    if getattr(hull, "triangles", None) is not None:  # a hull given by a closed mesh
        if topside_height != 0.0:
            raise ValueError(
                "a hull given by a mesh is its own watertight envelope: the topside "
                f"extension must be 0 (got {topside_height:g} m; model the superstructure "
                "in the mesh instead)"
            )
        return mesh_gz_curve(hull.vertices, hull.triangles, GM, heel_step=heel_step,  # type: ignore[attr-defined]
                             n_terms=n_terms, phi_max=phi_max)  # fmt: skip
    poly = section_polygons(hull, n_side, topside_height)
    A, My, Mz, ch = clipped_moments(poly, 1.0, 0.0, np.zeros(hull.n_stations))
    V0 = float(hull.w @ A)
    xB0 = float(hull.w @ (hull.x * A)) / V0
    zB0 = float(hull.w @ Mz) / V0
    I_T = float(hull.w @ (ch**3 / 12.0))
    zeta_G = zB0 + I_T / V0 - GM
    phis, gz = heeled_gz(
        lambda ph, guess: heeled_equilibrium(hull, poly, ph, V0, xB0, guess),
        "hydrostatic equilibrium",
        zeta_G,
        phi_max,
        heel_step,
    )
    coeffs = fit_sine_series(phis, gz, n_terms, GM)
    return GZCurve(phis, gz, coeffs, float(GM), float(zeta_G), V0, float(topside_height))


#: IMO 2008 Intact Stability Code, Part A, 2.2 (general criteria; formerly Res.
#: A.749(18) 3.1.2): (name, required value). Areas in m rad, GZ in m, angle in rad.
IS_CODE_GENERAL = (
    ("area_0_30", 0.055),
    ("area_0_40", 0.090),
    ("area_30_40", 0.030),
    ("gz_at_30_or_more", 0.20),
    ("angle_of_max_gz", float(np.deg2rad(25.0))),
    ("GM0", 0.15),
)


def is_code_criteria(gz: GZCurve) -> dict[str, tuple[float, float]]:
    """IMO IS Code general intact-stability criteria ``{name: (value, required)}``.

    Uses the hydrostatic curve (flooding angle taken above 40 deg; weather
    criterion not evaluated). The angle of maximum GZ is refined by a parabola
    through the largest sample and its neighbours.
    """
    d30, d40 = np.deg2rad(30.0), np.deg2rad(40.0)
    if gz.phi[-1] < d40:
        raise ValueError("the GZ curve must extend to at least 40 deg")
    k = int(np.argmax(gz.gz))
    phi_m = float(gz.phi[k])
    if 0 < k < gz.phi.size - 1:
        y0, y1, y2 = gz.gz[k - 1], gz.gz[k], gz.gz[k + 1]
        den = y0 - 2 * y1 + y2
        if den < 0:
            phi_m += 0.5 * (y0 - y2) / den * (gz.phi[k + 1] - gz.phi[k])
    beyond = gz.phi >= d30 - 1e-12
    values = {
        "area_0_30": gz.area(d30),
        "area_0_40": gz.area(d40),
        "area_30_40": gz.area(d40, d30),
        "gz_at_30_or_more": float(np.max(gz.gz[beyond])),
        "angle_of_max_gz": phi_m,
        "GM0": gz.GM,
    }
    return {name: (values[name], req) for name, req in IS_CODE_GENERAL}


def is_code_margin(gz: GZCurve) -> float:
    """Smallest relative margin ``value/required - 1`` over the IS Code general criteria."""
    return min(v / r - 1.0 for v, r in is_code_criteria(gz).values())


def marginal_topside_height(
    hull: HullForm,
    GM: float,
    *,
    h_max: float = 2.0,
    tol: float = 1e-3,
    heel_step: float = np.deg2rad(2.0),
) -> float:
    """Smallest watertight topside extension for which the IS Code criteria are met.

    Brent's method on :func:`is_code_margin` (continuous, increasing in the
    height) of the GZ curve over 0-60 deg. Returns 0 if
    the bare hull already complies.

    Raises
    ------
    ValueError
        If even ``h_max`` does not make the condition comply.
    """

    def margin(h: float) -> float:
        g = gz_curve(
            hull, GM, heel_step=heel_step, n_terms=4, topside_height=h, phi_max=np.deg2rad(60.0)
        )
        return is_code_margin(g)

    if margin(0.0) >= 0:
        return 0.0
    if margin(h_max) < 0:
        raise ValueError(
            f"the loading condition does not meet the IS Code criteria even with a topside "
            f"extension of {h_max} m; give `stability.topside_height` explicitly"
        )
    return float(so.brentq(margin, 0.0, h_max, xtol=tol))


__all__ = [
    "GZCurve",
    "HeeledState",
    "clipped_moments",
    "fit_sine_series",
    "gz_curve",
    "heeled_equilibrium",
    "heeled_gz",
    "IS_CODE_GENERAL",
    "is_code_criteria",
    "is_code_margin",
    "marginal_topside_height",
    "section_polygons",
]
