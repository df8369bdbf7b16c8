r"""Intact stability criteria of the IMO 2008 IS Code by vessel class, and the weather criterion.

Source: IMO Resolution MSC.267(85) (2008), International Code on Intact Stability
(2008 IS Code).

**General criteria** (Part A, 2.2; all ships), on the righting-arm curve GZ(phi):

- area under GZ up to 30 deg >= 0.055 m rad, up to 40 deg (or the flooding angle
  if less) >= 0.090 m rad, between 30 and 40 deg >= 0.030 m rad;
- GZ >= 0.20 m at an angle of heel >= 30 deg;
- the maximum GZ at an angle >= 25 deg;
- initial metacentric height GM0 >= 0.15 m.

**Fishing vessels** (Part B, 2.1, decked fishing vessels of 24 m length and over):
the same area, GZ and angle criteria, but GM0 >= 0.35 m (single-deck vessels).

**Severe wind and rolling criterion** (weather criterion, Part A, 2.3):

.. math::

    l_{w1} = \frac{P A Z}{1000\, g\, \Delta},\qquad l_{w2} = 1.5\, l_{w1},\qquad
    \phi_1 = 109\, k X_1 X_2 \sqrt{r s}\ \text{(deg)},

with :math:`P = 504` N/m^2, :math:`A` the projected lateral area above the waterline
(m^2), :math:`Z` the height of its centre above the centre of the underwater lateral
area (approximately half the draft, m), :math:`\Delta` the displacement (t);
:math:`r = 0.73 + 0.6\,OG/d` (OG = KG - d, the height of G above the waterline),
:math:`X_1(B/d)`, :math:`X_2(C_B)`, :math:`k` (1.0 for a round bilge without keels)
and :math:`s(T)` from Tables 2.3.4-1 to 2.3.4-4, linearly interpolated, the roll
period :math:`T = 2 C B/\sqrt{GM}`, :math:`C = 0.373 + 0.023 B/d - 0.043 L_{wl}/100`.
The ship heels to :math:`\phi_0` under the steady wind (:math:`GZ(\phi_0) = l_{w1}`,
required :math:`\phi_0 \le 16` deg or 80 % of the deck-edge immersion angle, the
smaller), rolls :math:`\phi_1` to windward, and then the gust :math:`l_{w2}` acts:
area ``b`` (GZ above :math:`l_{w2}`, from the first intersection :math:`\phi_c` of
:math:`l_{w2}` with GZ to :math:`\phi_2 = \min(\phi_f, 50^\circ, \phi_{c2})`) must be
at least area ``a`` (:math:`l_{w2}` above GZ, from :math:`\phi_0 - \phi_1` to
:math:`\phi_c`).

Each formula is checked in the tests in closed form (a linear GZ curve, table end
points); no worked example with printed numbers could be read here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize as so

#: Wind pressure of the weather criterion (N/m^2), Part A 2.3.
WIND_PRESSURE = 504.0

#: Table 2.3.4-1: X_1 against B/d.
TABLE_X1 = (
    (2.4, 2.5, 2.6, 2.7, 2.8, 2.9, 3.0, 3.1, 3.2, 3.4, 3.5),
    (1.0, 0.98, 0.96, 0.95, 0.93, 0.91, 0.90, 0.88, 0.86, 0.82, 0.80),
)
#: Table 2.3.4-2: X_2 against C_B.
TABLE_X2 = ((0.45, 0.50, 0.55, 0.60, 0.65, 0.70), (0.75, 0.82, 0.89, 0.95, 0.97, 1.0))
#: Table 2.3.4-3: k against A_k 100 / (L B) (bilge keels; 1.0 without).
TABLE_K = (
    (0.0, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0),
    (1.0, 0.98, 0.95, 0.88, 0.79, 0.74, 0.72, 0.70),
)
#: Table 2.3.4-4: s against the roll period T (s).
TABLE_S = ((6.0, 7.0, 8.0, 12.0, 14.0, 16.0, 18.0, 20.0),
           (0.100, 0.098, 0.093, 0.065, 0.053, 0.044, 0.038, 0.035))  # fmt: skip

#: Part A 2.2 general criteria: (name, required). Areas m rad, GZ m, angles rad.
GENERAL = (
    ("area_0_30", 0.055),
    ("area_0_40", 0.090),
    ("area_30_40", 0.030),
    ("gz_at_30_or_more", 0.20),
    ("angle_of_max_gz", math.radians(25.0)),
    ("GM0", 0.15),
)
#: Required GM0 (m) by vessel class: Part A 2.2 (all ships), Part B 2.1 (fishing).
GM0_REQUIRED = {"general": 0.15, "fishing_vessel": 0.35}


def table(tab: tuple[tuple[float, ...], tuple[float, ...]], x: float) -> float:
    """Linear interpolation in an IS Code table, constant beyond its ends."""
    return float(np.interp(x, tab[0], tab[1]))


@dataclass(frozen=True)
class Criterion:
    """One criterion: ``value`` against ``required`` (``value >= required`` passes)."""

    name: str
    value: float
    required: float
    unit: str
    clause: str

    @property
    def passed(self) -> bool:
        """True if met."""
        return self.value >= self.required

    @property
    def margin(self) -> float:
        """``value / required - 1`` (``value - required`` for a zero requirement)."""
        if self.required == 0.0:
            return self.value
        return self.value / self.required - 1.0

    @property
    def verdict(self) -> str:
        """``"met"``, ``"at the limit"`` (missed by less than 0.1 %) or ``"NOT met"``."""
        if self.passed:
            return "met"
        return "at the limit" if self.margin > -1e-3 else "NOT met"


def general_criteria(
    phi: np.ndarray,
    gz: np.ndarray,
    GM: float,
    *,
    vessel_class: str = "general",
    phi_flood: float = math.inf,
) -> list[Criterion]:
    """Part A 2.2 criteria (GM0 by vessel class, Part B 2.1 for fishing vessels).

    Parameters
    ----------
    phi, gz : ndarray, shape (N,)
        Heel angles (rad, increasing from 0, to at least 40 deg) and GZ (m).
    GM : float
        Initial metacentric height (m).
    vessel_class : {"general", "fishing_vessel"}
    phi_flood : float
        Downflooding angle (rad); the 40 deg areas stop there if it is less.

    Raises
    ------
    ValueError
        If the class is unknown or the curve does not reach 40 deg.
    """
    if vessel_class not in GM0_REQUIRED:
        raise ValueError(
            f"`vessel_class` must be one of {list(GM0_REQUIRED)}, got {vessel_class!r}"
        )
    phi = np.asarray(phi, float)
    gz = np.asarray(gz, float)
    d30, d40 = math.radians(30.0), math.radians(40.0)
    if phi[-1] < d40 - 1e-12:
        raise ValueError("`phi` must extend to at least 40 deg")
    top = min(d40, phi_flood)

    def area(a: float, b: float) -> float:
        return _area(phi, gz, a, b)

    k = int(np.argmax(gz))
    phi_m = float(phi[k])
    if 0 < k < phi.size - 1:
        y0, y1, y2 = gz[k - 1], gz[k], gz[k + 1]
        den = y0 - 2 * y1 + y2
        if den < 0:
            phi_m += 0.5 * (y0 - y2) / den * (phi[k + 1] - phi[k])
    beyond = phi >= d30 - 1e-12
    part = "Part B 2.1" if vessel_class == "fishing_vessel" else "Part A 2.2"
    return [
        Criterion("area_0_30", area(0.0, d30), 0.055, "m rad", f"{part} (Part A 2.2.1)"),
        Criterion("area_0_40", area(0.0, top), 0.090, "m rad", f"{part} (Part A 2.2.1)"),
        Criterion("area_30_40", area(d30, top), 0.030, "m rad", f"{part} (Part A 2.2.1)"),
        Criterion(
            "gz_at_30_or_more", float(np.max(gz[beyond])), 0.20, "m", f"{part} (Part A 2.2.2)"
        ),  # fmt: skip
        Criterion("angle_of_max_gz", phi_m, math.radians(25.0), "rad", f"{part} (Part A 2.2.3)"),
        Criterion("GM0", float(GM), GM0_REQUIRED[vessel_class], "m", part),
    ]


def _interp(phi: np.ndarray, gz: np.ndarray) -> Callable[[float], float]:
    return lambda x: float(np.interp(x, phi, gz))


def _area(phi: np.ndarray, gz: np.ndarray, a: float, b: float) -> float:
    """Exact integral of the piecewise-linear GZ over ``[a, b]`` (``0 <= a <= b``)."""
    inner = phi[(phi > a) & (phi < b)]
    x = np.concatenate([[a], inner, [b]])
    y = np.interp(x, phi, gz)
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


@dataclass(frozen=True)
class WeatherCriterion:
    """Result of the severe wind and rolling criterion (Part A 2.3).

    Angles in rad, levers in m, areas in m rad.
    """

    lw1: float
    lw2: float
    phi0: float
    phi1: float
    phi_c: float
    phi2: float
    area_a: float
    area_b: float
    T_roll: float
    r: float
    s: float
    X1: float
    X2: float
    k: float
    phi0_limit: float
    checks: list[Criterion] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        """Both the steady-heel and the energy-balance requirements met."""
        return all(c.passed for c in self.checks)


def roll_period(B: float, d: float, L_wl: float, GM: float) -> float:
    """IS Code roll period ``T = 2 C B / sqrt(GM)`` (s), ``C = 0.373 + 0.023 B/d - 0.043 L/100``."""
    C = 0.373 + 0.023 * (B / d) - 0.043 * (L_wl / 100.0)
    return 2.0 * C * B / math.sqrt(GM)


def roll_to_windward(
    *, B: float, d: float, C_B: float, OG: float, T: float, k: float = 1.0
) -> tuple[float, dict[str, float]]:
    """``phi_1 = 109 k X1 X2 sqrt(r s)`` (rad) and its factors.

    ``r = 0.73 + 0.6 OG/d`` with ``OG`` the height of G above the waterline (negative
    below), as written in Part A 2.3.4.
    """
    X1 = table(TABLE_X1, B / d)
    X2 = table(TABLE_X2, C_B)
    r = 0.73 + 0.6 * OG / d
    s = table(TABLE_S, T)
    phi1_deg = 109.0 * k * X1 * X2 * math.sqrt(max(r * s, 0.0))
    return math.radians(phi1_deg), {"X1": X1, "X2": X2, "r": r, "s": s, "k": k}


def weather_criterion(
    phi: np.ndarray,
    gz: np.ndarray,
    *,
    displacement_t: float,
    A_wind: float,
    Z_wind: float,
    B: float,
    d: float,
    C_B: float,
    KG: float,
    GM: float,
    L_wl: float,
    k: float = 1.0,
    phi_flood: float = math.radians(50.0),
    phi_deck_edge: float = math.inf,
    g: float = 9.81,
) -> WeatherCriterion:
    """Evaluate the severe wind and rolling criterion (see module doc).

    Parameters
    ----------
    phi, gz : ndarray, shape (N,)
        GZ curve (rad, m), from 0 to beyond the second intersection or 50 deg.
    displacement_t : float
        Displacement (t).
    A_wind, Z_wind : float
        Projected lateral windage area (m^2) and lever (m).
    B, d, C_B, KG, GM, L_wl : float
        Breadth, mean draft, block coefficient, KG, GM (m) and waterline length.
    k : float
        Bilge-keel factor (1.0: round bilge, no keels).
    phi_flood : float
        Downflooding angle (rad); ``phi_2`` is at most this and 50 deg.
    phi_deck_edge : float
        Deck-edge immersion angle (rad): the steady heel must stay below 80 % of it.
    g : float
        Gravity of the code's formula (9.81).

    Raises
    ------
    ValueError
        If the steady wind capsizes the ship (no ``phi_0``) or an input is not positive.
    """
    for name, val in (("displacement_t", displacement_t), ("A_wind", A_wind), ("B", B),
                      ("d", d), ("GM", GM), ("L_wl", L_wl)):  # fmt: skip
        if not val > 0:
            raise ValueError(f"`{name}` must be positive, got {val}")
    phi = np.asarray(phi, float)
    gz = np.asarray(gz, float)
    f = _interp(phi, gz)
    lw1 = WIND_PRESSURE * A_wind * Z_wind / (1000.0 * g * displacement_t)
    lw2 = 1.5 * lw1

    def first_crossing(level: float, start: float) -> float:
        h = gz - level
        i0 = int(np.searchsorted(phi, start))
        for i in range(max(i0, 1), phi.size):
            if h[i - 1] <= 0.0 < h[i] or h[i - 1] < 0.0 <= h[i]:
                return float(so.brentq(lambda x: f(x) - level, phi[i - 1], phi[i]))
        return math.nan

    def down_crossing(level: float, start: float) -> float:
        h = gz - level
        i0 = int(np.searchsorted(phi, start)) + 1
        for i in range(max(i0, 1), phi.size):
            if h[i - 1] > 0.0 >= h[i]:
                return float(so.brentq(lambda x: f(x) - level, phi[i - 1], phi[i]))
        return math.inf

    phi0 = first_crossing(lw1, 0.0)
    if not math.isfinite(phi0):
        raise ValueError("the steady wind lever lw1 exceeds GZ everywhere: no angle of steady heel")
    T = roll_period(B, d, L_wl, GM)
    phi1, fac = roll_to_windward(B=B, d=d, C_B=C_B, OG=KG - d, T=T, k=k)
    phi_c = first_crossing(lw2, 0.0)
    if not math.isfinite(phi_c):
        raise ValueError("the gust lever lw2 exceeds GZ everywhere: the criterion is not met")
    phi_c2 = down_crossing(lw2, phi_c)
    phi2 = min(phi_flood, math.radians(50.0), phi_c2)
    lo = phi0 - phi1  # to windward (negative for a roll beyond upright); GZ is odd
    if lo < 0.0:
        area_a = lw2 * (phi_c - lo) + _area(phi, gz, 0.0, -lo) - _area(phi, gz, 0.0, phi_c)
    else:
        area_a = lw2 * (phi_c - lo) - _area(phi, gz, lo, phi_c)
    area_b = _area(phi, gz, phi_c, phi2) - lw2 * (phi2 - phi_c) if phi2 > phi_c else 0.0
    limit = min(math.radians(16.0), 0.8 * phi_deck_edge)
    checks = [
        Criterion("weather_area_b_over_a", area_b / area_a, 1.0, "-", "Part A 2.3.1.4"),
        Criterion("weather_steady_heel_margin", limit - phi0, 0.0, "rad", "Part A 2.3.1.2"),
    ]
    return WeatherCriterion(
        lw1, lw2, phi0, phi1, phi_c, phi2, area_a, area_b, T, fac["r"], fac["s"], fac["X1"],
        fac["X2"], k, limit, checks,
    )  # fmt: skip


def weather_limit_area(
    phi: np.ndarray, gz: np.ndarray, *, Z_wind: float, A_max: float = 2000.0, **kwargs: float
) -> float:
    """Largest windage area (m^2, at lever ``Z_wind``) for which the weather criterion holds."""

    def ok(A: float) -> float:
        try:
            w = weather_criterion(phi, gz, A_wind=A, Z_wind=Z_wind, **kwargs)
        except ValueError:
            return -1.0
        return min(w.area_b / w.area_a - 1.0, w.phi0_limit - w.phi0)

    if ok(A_max) >= 0:
        return A_max
    if ok(1e-3) < 0:
        return 0.0
    return float(so.brentq(ok, 1e-3, A_max, xtol=1e-3))


def vessel_intact_stability(data: Any) -> dict[str, Any]:
    """Both checks for a resolved vessel (:class:`ship_models.estimation.VesselModelData`).

    Vessel class from ``[vessel] hull_type`` (``fishing_vessel``: GM0 >= 0.35 m).
    The weather criterion needs the lateral windage, which the paper does not give:
    it is evaluated with the hull's own freeboard and the watertight topside only
    (``A = L_pp (D - d_m + topside)``, its centre at half that height above the
    waterline, ``Z`` to half the draft), a LOWER bound of the real windage (no
    deckhouse, bow or mast), so a pass here is necessary, not sufficient; the largest
    windage area at the same lever that still passes is reported beside it. Flooding
    angle taken as 50 deg (unknown), no bilge keels (``k = 1``).

    Returns
    -------
    dict
        ``vessel_class``, ``general`` (list of :class:`Criterion`), ``weather``
        (:class:`WeatherCriterion`), ``A_wind``, ``Z_wind``, ``A_wind_limit``,
        ``deck_edge_deg``, ``assumptions`` (str).
    """
    v = data.vessel
    vclass = "fishing_vessel" if v.meta.get("hull_type") == "fishing_vessel" else "general"
    gz = data.gz
    GM = float(gz.GM)
    gen = general_criteria(gz.phi, gz.gz, GM, vessel_class=vclass)
    L = v.get("particulars.L_pp")
    B = v.get("particulars.B")
    D = v.get("particulars.D")
    d_m = 0.5 * (v.get("particulars.d_f") + v.get("particulars.d_a"))
    top = float(data.info.get("topside_height", 0.0))
    freeboard = D - d_m + top
    A = L * freeboard
    Z = 0.5 * freeboard + 0.5 * d_m
    KG = float(data.info["KG"])
    deck_edge = math.atan2(D - d_m, 0.5 * B)
    kw = dict(
        displacement_t=float(data.info["mass"]) / 1000.0, B=B, d=d_m,
        C_B=v.get("particulars.C_b"), KG=KG, GM=GM, L_wl=L, phi_deck_edge=deck_edge,
    )  # fmt: skip
    w = weather_criterion(gz.phi, gz.gz, A_wind=A, Z_wind=Z, **kw)
    A_lim = weather_limit_area(gz.phi, gz.gz, Z_wind=Z, **kw)
    return {
        "vessel_class": vclass,
        "general": gen,
        "weather": w,
        "A_wind": A,
        "Z_wind": Z,
        "A_wind_limit": A_lim,
        "deck_edge_deg": math.degrees(deck_edge),
        "assumptions": (
            "windage of the hull's freeboard and watertight topside only (no deckhouse: "
            "a lower bound), flooding angle 50 deg, no bilge keels (k = 1), roll period "
            "by the Code's formula"
        ),
    }


__all__ = [
    "Criterion",
    "GENERAL",
    "GM0_REQUIRED",
    "TABLE_K",
    "TABLE_S",
    "TABLE_X1",
    "TABLE_X2",
    "WIND_PRESSURE",
    "WeatherCriterion",
    "general_criteria",
    "roll_period",
    "roll_to_windward",
    "table",
    "weather_criterion",
    "vessel_intact_stability",
    "weather_limit_area",
]
