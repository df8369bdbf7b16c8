r"""Hull sections S(x), B(x), d(x) along the ship, on fixed quadrature stations.

The hull is a set of strips (stations) at positions ``x_j`` (from midship, positive
forward) with quadrature weights ``w_j`` (``sum w_j = L_pp``), so that a
longitudinal integral is :math:`\int_{AP}^{FP} f(x)\,dx \approx \sum_j w_j f(x_j)`.
Each station has a draft ``d_j``, a waterline half-breadth ``b_j`` and a section
shape (symmetric about the centre plane)

.. math::

    b(x, \zeta) = b_{wl}(x)\,\bigl(1 - s^{n(x)}\bigr), \qquad s = -\zeta / d(x)
    \in [0, 1],

so that the section area is :math:`S = 2 b_{wl} d\,\beta`, with the section
coefficient :math:`\beta = n/(n+1)` (``n = inf`` is a rectangle). Above the
waterline the sides are vertical up to the deck at height ``D`` above the keel
(wall-sided topsides, no sheer, no bulwark buoyancy).

:func:`parametric_hull` generates such a hull from the principal particulars
(:class:`FormParameters`: L, B, D, drafts fore/aft, C_b, l.c.b., C_M, C_wp): waterline
:math:`b_{wl} = (B/2)(1 - |t|^q)` with :math:`q = C_{wp}/(1 - C_{wp})`, and a
sectional-area curve :math:`A(t) = C_M B d_m (1 - |t|^{p})`, :math:`t = 2x/L`, whose
exponents ``p_aft``, ``p_fore`` are solved so that the hull has exactly the
displacement :math:`C_b L B d_m` and the given l.c.b. The ends are V-sections
(``beta >= beta_min``), the midship section has ``beta = C_M``. This is a simple
form-parameter hull in the spirit of Lackenby (1950, "On the systematic geometrical
variation of ship forms", Trans. INA 92:289-316); it is an assumption, not the
paper's lines. :class:`HullForm` also accepts user-given sections (offsets reduced
to ``b_wl``, ``d``, ``beta`` per station).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.optimize as so

from continuation.typing import FloatArray


def gauss_stations(x0: float, x1: float, n: int) -> tuple[FloatArray, FloatArray]:
    """Gauss-Legendre nodes and weights on ``[x0, x1]``, each of shape ``(n,)``."""
    t, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x0 + x1) + 0.5 * (x1 - x0) * t, 0.5 * (x1 - x0) * w


@dataclass(frozen=True)
class HullForm:
    """Strip description of a hull.

    Attributes
    ----------
    L, B, D : float
        Length between perpendiculars, breadth, depth (m).
    x : ndarray, shape (J,)
        Station positions from midship, positive forward (m).
    w : ndarray, shape (J,)
        Longitudinal quadrature weights (m), ``sum(w) = L`` for a full-length hull.
    d : ndarray, shape (J,)
        Draft of each station (m).
    b_wl : ndarray, shape (J,)
        Half-breadth at the calm waterline (m).
    n_exp : ndarray, shape (J,)
        Section shape exponent ``n`` (``inf`` for a rectangular section).
    depth_ref : float
        Depth ``D`` measured from the keel; the deck of station j is at
        ``zeta = D - d_j`` above the calm waterline.
    info : dict
        Generator data (fitted exponents etc.).
    """

    L: float
    B: float
    D: float
    x: FloatArray
    w: FloatArray
    d: FloatArray
    b_wl: FloatArray
    n_exp: FloatArray
    info: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        arrs = {}
        for name in ("x", "w", "d", "b_wl", "n_exp"):
            a = np.array(getattr(self, name), dtype=float).reshape(-1)
            a.setflags(write=False)
            arrs[name] = a
            object.__setattr__(self, name, a)
        J = arrs["x"].size
        for name, a in arrs.items():
            if a.size != J:
                raise ValueError(f"`{name}` must have shape ({J},), got {a.shape}")
        if np.any(arrs["d"] <= 0) or np.any(arrs["b_wl"] < 0) or np.any(arrs["n_exp"] <= 0):
            raise ValueError("`d` must be > 0, `b_wl` >= 0 and `n_exp` > 0 at every station")
        if np.any(arrs["d"] >= self.D):
            raise ValueError("every station draft `d` must be below the depth `D`")

    @property
    def n_stations(self) -> int:
        """Number of stations ``J``."""
        return int(self.x.size)

    @property
    def beta(self) -> FloatArray:
        """Section area coefficients ``n/(n+1)``, shape (J,)."""
        n = self.n_exp
        finite = np.isfinite(n)
        return np.where(finite, np.where(finite, n, 1.0) / (np.where(finite, n, 1.0) + 1.0), 1.0)

    @property
    def area(self) -> FloatArray:
        """Section areas ``S(x_j) = 2 b_wl d beta`` (m^2), shape (J,)."""
        return 2.0 * self.b_wl * self.d * self.beta

    @property
    def volume(self) -> float:
        """Displacement volume (m^3)."""
        return float(self.w @ self.area)

    @property
    def lcb(self) -> float:
        """Longitudinal centre of buoyancy from midship, positive forward (m)."""
        return float(self.w @ (self.x * self.area)) / self.volume

    @property
    def waterplane_area(self) -> float:
        """Waterplane area (m^2)."""
        return float(self.w @ (2.0 * self.b_wl))

    @property
    def waterplane_inertia(self) -> float:
        r"""Transverse second moment of the waterplane, :math:`\int (2/3) b^3 dx` (m^4)."""
        return float(self.w @ (2.0 / 3.0 * self.b_wl**3))

    @property
    def vcb(self) -> float:
        r"""Height of the centre of buoyancy above the calm waterline (m, negative).

        For the section family, :math:`\int_{-d}^0 \zeta\, 2b\,d\zeta =
        -2 b_{wl} d^2 (1/2 - 1/(n+2))`.
        """
        n = self.n_exp
        frac = np.where(np.isinf(n), 0.5, 0.5 - 1.0 / (n + 2.0))
        mom = -2.0 * self.b_wl * self.d**2 * frac
        return float(self.w @ mom) / self.volume

    def half_breadth(self, j: int | FloatArray, zeta: FloatArray) -> FloatArray:
        """Half-breadth at height ``zeta`` (m, zeta <= 0 below the waterline) of station(s) j."""
        j = np.asarray(j)
        s = np.clip(-np.asarray(zeta, dtype=float) / self.d[j], 0.0, 1.0)
        with np.errstate(over="ignore"):
            return self.b_wl[j] * (1.0 - s ** self.n_exp[j])

    def wetted_surface(self, n_girth: int = 200) -> float:
        """Calm-water wetted surface from the section girths (m^2), by strip integration.

        Used as an independent check against the given ``S_f``.
        """
        s = 1.0 - (1.0 - np.linspace(0.0, 1.0, n_girth + 1)) ** 3
        zeta = -s[None, :] * self.d[:, None]
        with np.errstate(over="ignore"):
            y = self.b_wl[:, None] * (1.0 - s[None, :] ** self.n_exp[:, None])
        girth = 2.0 * np.sum(np.hypot(np.diff(y, axis=1), np.diff(zeta, axis=1)), axis=1)
        return float(self.w @ girth)

    def depth_quadrature(self, m: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Gauss-Legendre nodes over the draft of every station.

        Returns
        -------
        zeta : ndarray, shape (J, m)
            Node heights (m, negative).
        wz : ndarray, shape (J, m)
            Weights (m) so that ``sum_k wz[j, k] f(zeta[j, k]) ~ int_{-d_j}^0 f dzeta``.
        b : ndarray, shape (J, m)
            Half-breadths at the nodes (m).
        """
        t, wt = np.polynomial.legendre.leggauss(m)
        s = 0.5 * (t + 1.0)  # in (0, 1), s = -zeta/d
        zeta = -s[None, :] * self.d[:, None]
        wz = 0.5 * wt[None, :] * self.d[:, None]
        with np.errstate(over="ignore"):
            b = self.b_wl[:, None] * (1.0 - s[None, :] ** self.n_exp[:, None])
        return zeta, wz, b


def box_hull(L: float, B: float, d: float, D: float, n_stations: int = 20) -> HullForm:
    """A rectangular barge (for tests against closed forms)."""
    x, w = gauss_stations(-L / 2, L / 2, n_stations)
    J = x.size
    return HullForm(
        L, B, D, x, w, np.full(J, d), np.full(J, B / 2), np.full(J, np.inf), {"kind": 0.0}
    )


def _sections(
    t: FloatArray,
    d: FloatArray,
    B: float,
    d_m: float,
    C_M: float,
    q: float,
    p_a: float,
    p_f: float,
    beta_lo: float,
    beta_hi: float,
) -> tuple[FloatArray, FloatArray]:
    at = np.abs(t)
    p = np.where(t < 0, p_a, p_f)
    b_wl = 0.5 * B * (1.0 - at**q)
    area_target = C_M * B * d_m * (1.0 - at**p)
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = np.where(b_wl > 0, area_target / (2.0 * b_wl * d), beta_lo)
    beta = np.clip(beta, beta_lo, beta_hi)
    return b_wl, beta


@dataclass(frozen=True)
class FormParameters:
    """The principal particulars and form coefficients of a form-parameter hull.

    What :func:`parametric_hull` and
    :func:`~ship_models.hydro.offsets.form_parameter_offsets` build a hull from
    (:func:`ship_models.estimation.form_parameters` reads them from a vessel file).

    Attributes
    ----------
    L, B, D : float
        Length between perpendiculars, breadth, depth (m).
    d_f, d_a : float
        Drafts at the fore and aft perpendiculars (m); the keel is straight, so the
        draft varies linearly (trim by the stern if ``d_a > d_f``).
    C_b : float
        Block coefficient on ``L B d_m``, ``d_m = (d_f + d_a)/2``.
    lcb : float
        Longitudinal centre of buoyancy from midship, positive forward (m).
    C_M, C_wp : float
        Midship section and waterplane coefficients.
    """

    L: float
    B: float
    D: float
    d_f: float
    d_a: float
    C_b: float
    lcb: float
    C_M: float
    C_wp: float

    @property
    def d_m(self) -> float:
        """Mean draft ``(d_f + d_a)/2`` (m)."""
        return 0.5 * (self.d_f + self.d_a)


def parametric_hull(
    form: FormParameters,
    *,
    n_stations: int = 40,
    beta_min: float = 0.5,
    beta_max: float = 0.98,
) -> HullForm:
    """Generate a strip hull matching the principal particulars.

    Parameters
    ----------
    form : FormParameters
        Particulars and form coefficients (L, B, D, d_f, d_a, C_b, lcb, C_M, C_wp).
    n_stations : int
        Even number of strips: ``n_stations/2`` Gauss-Legendre nodes on each of the
        aft and fore bodies (the sectional-area curve has a kink at midship).
    beta_min, beta_max : float
        Bounds on the section coefficient (``beta_min >= 0.5`` keeps sections convex).

    Returns
    -------
    HullForm
        Displacement ``C_b L B d_m`` and l.c.b. reproduced to ``1e-10`` relative.

    Raises
    ------
    ValueError
        If no exponents reproduce C_b and l.c.b. (inconsistent particulars).
    """
    L, B, D, d_f, d_a = form.L, form.B, form.D, form.d_f, form.d_a
    C_b, lcb, C_M, C_wp = form.C_b, form.lcb, form.C_M, form.C_wp
    if n_stations % 2 or n_stations < 4:
        raise ValueError(f"`n_stations` must be even and >= 4, got {n_stations}")
    if not 0 < C_wp < 1 or not 0 < C_M <= 1 or not 0 < C_b < C_M:
        raise ValueError("need 0 < C_b < C_M <= 1 and 0 < C_wp < 1")
    xa, wa = gauss_stations(-L / 2, 0.0, n_stations // 2)
    xf, wf = gauss_stations(0.0, L / 2, n_stations // 2)
    x = np.concatenate([xa, xf])
    w = np.concatenate([wa, wf])
    t = 2.0 * x / L
    d_m = form.d_m
    d = d_m - (d_a - d_f) * x / L
    q = C_wp / (1.0 - C_wp)
    V_target = C_b * L * B * d_m

    def props(logp: FloatArray) -> tuple[float, float]:
        b_wl, beta = _sections(t, d, B, d_m, C_M, q, *np.exp(logp), beta_min, beta_max)
        S = 2.0 * b_wl * d * beta
        V = float(w @ S)
        return V, float(w @ (x * S)) / V

    def res(logp: FloatArray) -> FloatArray:
        V, xb = props(logp)
        return np.array([V / V_target - 1.0, (xb - lcb) / L])

    sol = so.least_squares(res, x0=np.log([2.0, 2.0]), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    if np.max(np.abs(sol.fun)) > 1e-9:
        raise ValueError(
            "parametric hull cannot match C_b and l.c.b. with these C_M, C_wp and section "
            f"bounds (residual {sol.fun}); check `particulars.C_b`, `particulars.lcb_aft`, "
            "`hull.C_M`, `hull.C_wp`"
        )
    p_a, p_f = np.exp(sol.x)
    b_wl, beta = _sections(t, d, B, d_m, C_M, q, p_a, p_f, beta_min, beta_max)
    n_exp = beta / (1.0 - beta)
    info = {"p_aft": float(p_a), "p_fore": float(p_f), "q_waterline": float(q)}
    return HullForm(L, B, D, x, w, d, b_wl, n_exp, info)


def schneekluth_cwp(C_b: float) -> float:
    """Waterplane coefficient estimate :math:`C_{wp} = (1 + 2 C_b)/3`.

    Schneekluth, H. & Bertram, V. (1998), "Ship Design for Efficiency and Economy",
    2nd ed., Butterworth-Heinemann, Sect. 2.6 (U-shaped sections with normal stern).
    """
    return (1.0 + 2.0 * C_b) / 3.0


__all__ = [
    "FormParameters",
    "HullForm",
    "box_hull",
    "gauss_stations",
    "parametric_hull",
    "schneekluth_cwp",
]
