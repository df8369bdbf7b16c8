r"""Calm-water resistance R(u): ITTC-1957 friction with Holtrop's form factor and wave resistance.

.. math::

    R(u) = \tfrac12 \rho S_f u^2 \,[(1 + k_1) C_F(Re) + C_A] + R_W(Fn), \qquad
    C_F = \frac{0.075}{(\log_{10} Re - 2)^2}, \quad Re = \frac{u L}{\nu},

- :math:`C_F`: ITTC-1957 model-ship correlation line (Proc. 8th ITTC, Madrid 1957).
- :math:`1 + k_1` and :math:`C_A`: Holtrop, J. (1984), "A statistical re-analysis of
  resistance and propulsion data", Int. Shipbuilding Progress 31(363):272-276 (form
  factor of Holtrop & Mennen 1982 with the stern term :math:`c_{14}`).
- :math:`R_W`: Holtrop & Mennen (1982), "An approximate power prediction method",
  Int. Shipbuilding Progress 29(335):166-170, in Holtrop's (1984) revision:
  :math:`R_{Wa}` for Fn <= 0.4, :math:`R_{Wb}` for Fn >= 0.55 and linear
  interpolation between :math:`R_{Wa}(0.4)` and :math:`R_{Wb}(0.55)` in between
  (no bulb, no immersed transom for the purse seiner).

For the equations of motion :func:`fit_resistance` fits a C2 cubic regression
spline over ``0 <= u <= Fn_max sqrt(g L)`` (knots every 0.025 in Fn): smooth,
differentiable with CasADi, exact zero at ``u = 0``; its error against the formula
is reported (and tested). Holtrop's (1984) linear interpolation between Fn = 0.4 and
0.55 has kinks, which the spline rounds off (error ~ 0.5 % at Fn = 0.4).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.ops import NUMPY_OPS, Ops
from continuation.typing import FloatArray

from .curves import CubicSpline1D, interpolating_spline


def ittc57_cf(Re: FloatArray | float) -> FloatArray:
    """ITTC-1957 friction coefficient ``0.075 / (log10(Re) - 2)^2`` (Re > 100)."""
    Re = np.asarray(Re, dtype=float)
    return 0.075 / (np.log10(Re) - 2.0) ** 2


@dataclass(frozen=True)
class HoltropHull:
    """Hull data used by Holtrop & Mennen's regression (SI units).

    Attributes
    ----------
    L, B, T, T_F : float
        Waterline length (taken as L_pp), breadth, mean and forward draft (m).
    volume : float
        Displacement volume (m^3).
    C_M, C_wp : float
        Midship and waterplane coefficients.
    lcb_percent : float
        l.c.b. in percent of L forward of midship (negative aft).
    S : float
        Wetted surface (m^2).
    C_stern : float
        Stern-shape parameter (-25 pram ... 0 normal ... 10 U-shaped).
    """

    L: float
    B: float
    T: float
    T_F: float
    volume: float
    C_M: float
    C_wp: float
    lcb_percent: float
    S: float
    C_stern: float = 0.0

    @property
    def C_B(self) -> float:
        """Block coefficient."""
        return self.volume / (self.L * self.B * self.T)

    @property
    def C_P(self) -> float:
        """Prismatic coefficient."""
        return self.C_B / self.C_M

    @property
    def L_R(self) -> float:
        """Length of run (Holtrop & Mennen 1982)."""
        cp = self.C_P
        return self.L * (1.0 - cp + 0.06 * cp * self.lcb_percent / (4.0 * cp - 1.0))

    def form_factor(self) -> float:
        """Viscous form factor ``1 + k_1`` (Holtrop 1984)."""
        c14 = 1.0 + 0.011 * self.C_stern
        L, B, T, V, cp = self.L, self.B, self.T, self.volume, self.C_P
        return (
            0.93
            + 0.487118
            * c14
            * (B / L) ** 1.06806
            * (T / L) ** 0.46106
            * (L / self.L_R) ** 0.121563
            * (L**3 / V) ** 0.36486
            * (1.0 - cp) ** -0.604247
        )

    def correlation_allowance(self) -> float:
        """Model-ship correlation allowance ``C_A`` (Holtrop 1984, no bulb)."""
        c4 = min(self.T_F / self.L, 0.04)
        return (
            0.006 * (self.L + 100.0) ** -0.16
            - 0.00205
            + 0.003 * np.sqrt(self.L / 7.5) * self.C_B**4 * (0.04 - c4)
        )

    def _wave_terms(self) -> dict[str, float]:
        L, B, T, V, cp = self.L, self.B, self.T, self.volume, self.C_P
        bl = B / L
        c7 = 0.229577 * bl ** (1 / 3) if bl < 0.11 else (bl if bl < 0.25 else 0.5 - 0.0625 / bl)
        iE = 1.0 + 89.0 * np.exp(
            -((L / B) ** 0.80856)
            * (1.0 - self.C_wp) ** 0.30484
            * (1.0 - cp - 0.0225 * self.lcb_percent) ** 0.6367
            * (self.L_R / B) ** 0.34574
            * (100.0 * V / L**3) ** 0.16302
        )
        c1 = 2223105.0 * c7**3.78613 * (T / B) ** 1.07961 * (90.0 - iE) ** -1.37565
        slender = L**3 / V
        if slender < 512.0:
            c15 = -1.69385
        elif slender < 1727.0:
            c15 = -1.69385 + (L / V ** (1 / 3) - 8.0) / 2.36
        else:
            c15 = 0.0
        c16 = (
            8.07981 * cp - 13.8673 * cp**2 + 6.984388 * cp**3 if cp < 0.8 else 1.73014 - 0.7067 * cp
        )
        m1 = 0.0140407 * L / T - 1.75254 * V ** (1 / 3) / L - 4.79323 * B / L - c16
        lam = 1.446 * cp - 0.03 * L / B if L / B < 12.0 else 1.446 * cp - 0.36
        c17 = 6919.3 * self.C_M**-1.3346 * (V / L**3) ** 2.00977 * (L / B - 2.0) ** 1.40692
        m3 = -7.2035 * (B / L) ** 0.326869 * (T / B) ** 0.605375
        return {"c1": c1, "c15": c15, "m1": m1, "lam": lam, "c17": c17, "m3": m3, "iE": iE}

    def wave_resistance(self, Fn: FloatArray | float, rho: float, g: float) -> FloatArray:
        """Wave resistance ``R_W`` (N) at Froude numbers ``Fn`` (Holtrop 1984)."""
        t = self._wave_terms()
        W = rho * g * self.volume
        Fn = np.atleast_1d(np.asarray(Fn, dtype=float))
        out = np.zeros_like(Fn)

        def m4(f: FloatArray) -> FloatArray:
            return t["c15"] * 0.4 * np.exp(-0.034 * f**-3.29)

        def rwa(f: FloatArray) -> FloatArray:
            return t["c1"] * W * np.exp(t["m1"] * f**-0.9 + m4(f) * np.cos(t["lam"] * f**-2))

        def rwb(f: FloatArray) -> FloatArray:
            return t["c17"] * W * np.exp(t["m3"] * f**-0.9 + m4(f) * np.cos(t["lam"] * f**-2))

        pos = Fn > 1e-3
        lo = pos & (Fn <= 0.4)
        hi = Fn >= 0.55
        mid = pos & ~lo & ~hi
        out[lo] = rwa(Fn[lo])
        out[hi] = rwb(Fn[hi])
        if np.any(mid):
            a, b = rwa(np.array([0.4]))[0], rwb(np.array([0.55]))[0]
            out[mid] = a + (20.0 * Fn[mid] - 8.0) / 3.0 * (b - a)
        return out

    def total_resistance(
        self,
        u: FloatArray | float,
        *,
        rho: float,
        g: float,
        nu: float,
        form_factor: float | None = None,
        C_A: float | None = None,
    ) -> FloatArray:
        """Calm-water resistance (N) at speeds ``u`` (m/s, >= 0)."""
        u = np.atleast_1d(np.asarray(u, dtype=float))
        k = self.form_factor() if form_factor is None else form_factor
        ca = self.correlation_allowance() if C_A is None else C_A
        Re = np.maximum(u, 1e-6) * self.L / nu
        cf = np.where(Re > 1e3, ittc57_cf(np.maximum(Re, 1e3)), 0.0)
        visc = 0.5 * rho * self.S * u**2 * (k * cf + ca)
        return visc + self.wave_resistance(u / np.sqrt(g * self.L), rho, g)


@dataclass(frozen=True)
class ResistanceFit:
    r"""Cubic regression spline of the resistance curve.

    .. math::

        R(u) = r_2 s^2 + r_3 s^3 + \sum_k c_k \max(s - \kappa_k, 0)^3,
        \qquad s = u / u_{max},

    a C2 cubic spline in the truncated-power basis (de Boor 1978, "A Practical Guide
    to Splines", Springer, ch. VIII) with ``R(0) = R'(0) = 0``; it evaluates with
    ``ops.fmax`` so CasADi differentiates it exactly.

    Attributes
    ----------
    poly : ndarray, shape (2,)
        ``r_2, r_3`` (N).
    knots : ndarray, shape (K,)
        Scaled knots ``kappa_k`` in (0, 1).
    coeffs : ndarray, shape (K,)
        ``c_k`` (N).
    u_max : float
        Upper end of the fitted speed range (m/s).
    max_rel_error : float
        Max relative error against the formula for ``Fn >= 0.1`` within the range.
    """

    poly: FloatArray
    knots: FloatArray
    coeffs: FloatArray
    u_max: float
    max_rel_error: float

    def evaluate(self, u: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Fitted resistance (N) at scalar ``u`` with the given ops (NumPy or CasADi)."""
        s = u / self.u_max
        out = self.poly[0] * s**2 + self.poly[1] * s**3
        for k, c in zip(self.knots, self.coeffs, strict=True):
            out = out + c * ops.fmax(s - k, 0.0) ** 3
        return out

    def __call__(self, u: FloatArray | float) -> FloatArray:
        """Fitted resistance (N) at ``u`` (NumPy, any shape)."""
        return np.asarray(self.evaluate(np.asarray(u, dtype=float)), dtype=float)


def fit_resistance(
    fun: Callable[[FloatArray], FloatArray],
    u_max: float,
    knot_spacing: float,
    *,
    u_ref: float | None = None,
    n_samples: int = 800,
) -> ResistanceFit:
    """Least-squares cubic spline (relative error weighting) to ``fun(u)`` on ``[0, u_max]``.

    Parameters
    ----------
    fun : callable
        ``fun(u: ndarray) -> ndarray`` resistance in N.
    u_max : float
        Upper end of the speed range (m/s).
    knot_spacing : float
        Knot spacing in m/s.
    u_ref : float, optional
        Speed below which errors are not reported (default ``0.15 u_max``).
    """
    if not (0 < knot_spacing < u_max):
        raise ValueError(f"`knot_spacing` must be in (0, u_max), got {knot_spacing}")
    u = np.linspace(0.0, u_max, n_samples)
    R = np.asarray(fun(u), dtype=float)
    s = u / u_max
    knots = np.arange(knot_spacing, u_max - 0.5 * knot_spacing, knot_spacing) / u_max
    A = np.column_stack([s**2, s**3] + [np.maximum(s - k, 0.0) ** 3 for k in knots])
    wt = 1.0 / np.maximum(np.abs(R), 0.01 * np.max(np.abs(R)))
    c = np.linalg.lstsq(A * wt[:, None], R * wt, rcond=None)[0]
    fit = ResistanceFit(c[:2], knots, c[2:], float(u_max), 0.0)
    m = u >= (0.15 * u_max if u_ref is None else u_ref)
    err = float(np.max(np.abs(fit(u[m]) - R[m]) / np.abs(R[m])))
    return ResistanceFit(c[:2], knots, c[2:], float(u_max), err)


#: Upper Froude number of Holtrop & Mennen's (1982) regression by hull type: the
#: range of the models behind it ("trawlers, coasters, tugs": Fn <= 0.38).
HOLTROP_FN_MAX: dict[str, float] = {"fishing_vessel": 0.38}

HOLTROP_RANGE_SOURCE = (
    "Holtrop & Mennen (1982), An approximate power prediction method, ISP 29(335), "
    "range of the regression for trawlers, coasters and tugs: Fn <= 0.38"
)


@dataclass(frozen=True)
class ResistanceTable:
    """Measured resistance R(u) interpolated by a C2 cubic spline.

    The table is extended by ``R(0) = 0`` (if absent) and the spline is clamped to
    ``R'(0) = 0`` (resistance is quadratic at low speed) with a natural end at the
    highest measured speed (:func:`ship_models.hydro.curves.interpolating_spline`).

    Attributes
    ----------
    spline : CubicSpline1D
    u_max : float
        Highest measured speed (m/s): the validity range is ``[0, u_max]``.
    max_rel_error : float
        0 (an interpolant).
    """

    spline: CubicSpline1D
    u_max: float
    max_rel_error: float = 0.0

    def evaluate(self, u: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Resistance (N) at scalar ``u`` (NumPy or CasADi)."""
        return self.spline.evaluate(u, ops)

    def __call__(self, u: FloatArray | float) -> FloatArray:
        """Resistance (N) at ``u`` (NumPy, any shape)."""
        return self.spline(u)


def resistance_table(u: Any, R: Any) -> ResistanceTable:
    """:class:`ResistanceTable` through measured ``(u_i, R_i)`` (SI, u strictly increasing)."""
    u = np.asarray(u, dtype=float)
    R = np.asarray(R, dtype=float)
    if u[0] > 0:
        u, R = np.concatenate([[0.0], u]), np.concatenate([[0.0], R])
    return ResistanceTable(interpolating_spline(u, R, slope_start=0.0), float(u[-1]))


__all__ = [
    "HOLTROP_FN_MAX",
    "HOLTROP_RANGE_SOURCE",
    "HoltropHull",
    "ResistanceFit",
    "ResistanceTable",
    "fit_resistance",
    "ittc57_cf",
    "resistance_table",
]
