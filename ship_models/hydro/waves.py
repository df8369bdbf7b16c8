r"""Wave-induced surge/sway forces and yaw/roll moments in a regular following/quartering sea.

Frames (Umeda 1999, Fig. 1): the wave-fixed axis :math:`\xi` points in the direction
of wave travel with its origin at a trough; the upright body axes have x forward,
y to starboard, z down, origin at G; :math:`\chi` is the heading from the
:math:`\xi` axis (positive to starboard). A hull point at ``(x, y)`` (from G) is at
:math:`\xi = \xi_G + x\cos\chi - y\sin\chi`. In the wave-fixed frame the linear deep
water wave is steady:

.. math::

    \eta = -a\cos k\xi, \qquad p_d = -\rho g a e^{k\zeta}\cos k\xi, \qquad
    a = H/2,\ k = 2\pi/\lambda,\ \omega = \sqrt{g k},

(:math:`\zeta` up from the calm waterline). The hull is held at its calm-water
attitude (heave and pitch at static equilibrium, as in the paper; linear in
:math:`a`, so every force below has zero mean over one wavelength).

Froude-Krylov part (pressure :math:`p_d` integrated over the calm-water wetted
hull; Gauss's theorem turns it into volume integrals, plus a waterplane term for the
roll moment). With symmetric sections of half-breadth :math:`b(x,\zeta)` and
:math:`s = \sin\chi`, :math:`\xi_x = \xi_G + x\cos\chi`:

.. math::

    C(x) &= \int_{-d}^{0} e^{k\zeta}\, 2b\, \mathrm{sinc}(k s b)\, d\zeta, \quad
    C_z(x) = \int_{-d}^{0} \zeta e^{k\zeta}\, 2b\, \mathrm{sinc}(k s b)\, d\zeta, \\
    S_y(x) &= \int_{-d}^{0} e^{k\zeta}\, 2 b^2 g_1(k s b)\, d\zeta, \qquad
    g_1(w) = (\sin w - w\cos w)/w^2, \\
    X_{FK} &= -\rho g a k\cos\chi \int \sin k\xi_x\, C\, dx, \qquad
    Y_{FK} = \rho g a k\sin\chi \int \sin k\xi_x\, C\, dx, \\
    N_{FK} &= \rho g a k \Bigl[\sin\chi \int x\sin k\xi_x\, C\, dx
              - \cos\chi \int \cos k\xi_x\, S_y\, dx\Bigr], \\
    K_{FK} &= -\rho g a k \int \sin k\xi_x \bigl[S_y + s(\zeta_G C - C_z)\bigr] dx
              + \rho g a \int \sin k\xi_x\, 2 b_{wl}^2 g_1(k s b_{wl})\, dx .

For a rectangular barge at :math:`\chi = 0` this gives the closed form
:math:`X_{FK} = -\rho g a B (1 - e^{-kd})\,\tfrac{2}{k}\sin\tfrac{kL}{2}\,\sin k\xi_G`
(tested). The usual approximation :math:`C \approx S e^{-kd/2}
\mathrm{sinc}(k s B/2)` of Umeda & Renilson / Hamamoto is replaced here by the
exact depth integral over the section shape (Gauss-Legendre nodes).

Hydrodynamic lift due to the wave particle velocity (slender-body theory, the
approach of Umeda, Yamakoshi & Suzuki 1995, "Experimental study for wave forces on a
ship running in quartering seas with very low encounter frequency", Proc. Int.
Symp. Ship Safety in a Seaway, Kaliningrad, 14:1-18). The lateral orbital velocity
averaged over a section is
:math:`\bar v_w(x) = a\omega\sin\chi\cos k\xi_x\, C(x)/S(x)`; a section moving
relative to the water with lateral velocity :math:`V = -\bar v_w` carries the sway
added mass :math:`m'(x)` (Lewis sections), and quasi-steady slender-body theory
(Newman, J.N. 1977, "Marine Hydrodynamics", MIT Press, Sect. 7.12) gives, with vortex
shedding only at the trailing edge :math:`x_T` (the aft perpendicular, where the
skeg makes :math:`m'_T = \rho\pi d_a^2/2`) and no force at the stem,

.. math::

    Y_L = u\, m'_T\, \bar v_w(x_T), \qquad
    N_L = u\, x_T m'_T\, \bar v_w(x_T) + u \int m'(x)\,\bar v_w(x)\,dx, \qquad
    K_L = -z_H Y_L,

where :math:`\bar v_w(x_T)` uses the depth average :math:`(1 - e^{-k d_a})/(k d_a)`
of a flat plate. (For uniform sway the same theory gives
:math:`Y'_v = -\pi d/L`, the first term of Inoue et al.'s regression.) The wave
effect on the rudder is ignored, as in the paper.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from continuation.ops import NUMPY_OPS, Ops
from continuation.typing import FloatArray

from ..contracts import SeaState
from .hull import HullForm

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..contracts import WaveInputs

_SMALL = 1e-2


def _const(a: FloatArray, ops: Ops) -> Any:
    return ca.DM(np.asarray(a, dtype=float)) if ops.name == "casadi" else np.asarray(a, float)


def _rowsum(A: Any, ops: Ops) -> Any:
    return ca.sum2(A) if ops.name == "casadi" else np.sum(A, axis=-1)


def _dot(w: FloatArray, v: Any, ops: Ops) -> Any:
    if ops.name == "casadi":
        return ca.dot(ca.DM(np.asarray(w, dtype=float)), v)
    return np.asarray(w, dtype=float) @ v


def sinc(w: Any, ops: Ops = NUMPY_OPS) -> Any:
    """``sin(w)/w``, smooth at 0 (Taylor series for ``|w| < 1e-2``), elementwise."""
    small = ops.abs(w) < _SMALL
    w_safe = ops.if_else(small, 1.0, w)
    w2 = w * w
    series = 1.0 - w2 / 6.0 + w2 * w2 / 120.0 - w2 * w2 * w2 / 5040.0
    return ops.if_else(small, series, ops.sin(w_safe) / w_safe)


def sinc_g1(w: Any, ops: Ops = NUMPY_OPS) -> tuple[Any, Any]:
    """``(sinc(w), g1(w))`` sharing one sine and cosine (smooth, elementwise)."""
    small = ops.abs(w) < _SMALL
    w_safe = ops.if_else(small, 1.0, w)
    inv = 1.0 / w_safe
    sn = ops.sin(w_safe) * inv
    g = (sn - ops.cos(w_safe)) * inv
    w2 = w * w
    s_series = 1.0 - w2 / 6.0 + w2 * w2 / 120.0 - w2 * w2 * w2 / 5040.0
    g_series = w / 3.0 - w * w2 / 30.0 + w * w2 * w2 / 840.0
    return ops.if_else(small, s_series, sn), ops.if_else(small, g_series, g)


def g1(w: Any, ops: Ops = NUMPY_OPS) -> Any:
    """``(sin w - w cos w)/w^2`` (odd, ``~ w/3`` near 0), smooth, elementwise."""
    small = ops.abs(w) < _SMALL
    w_safe = ops.if_else(small, 1.0, w)
    w2 = w * w
    series = w / 3.0 - w * w2 / 30.0 + w * w2 * w2 / 840.0
    full = (ops.sin(w_safe) - w_safe * ops.cos(w_safe)) / (w_safe * w_safe)
    return ops.if_else(small, series, full)


@dataclass(frozen=True)
class WaveStrips:
    """Precomputed strip data for the wave forces (all lengths relative to G).

    Attributes
    ----------
    x, w : ndarray, shape (J,)
        Station positions from G (forward +) and quadrature weights (m).
    b_wl, area, m22 : ndarray, shape (J,)
        Waterline half-breadth (m), section area (m^2), sway added mass per length (kg/m).
    zeta, wz, b : ndarray, shape (J, M)
        Depth nodes (m, from the calm waterline, negative), weights (m), half-breadths (m).
    zeta_G : float
        Height of G above the calm waterline (m).
    x_T, d_T, m22_T : float
        Trailing-edge position from G (m), its draft (m) and added mass per length (kg/m).
    z_H : float
        Depth of the lateral-force centre below G (body z, m).
    rho, g : float
        Water density and gravity.
    L : float
        Length between perpendiculars (m).
    surge_scale : float
        Factor on the surge force ``X_w`` (``hydrodynamics.wave_surge_scale`` of the
        vessel file; 1 = the Froude-Krylov integral as in the paper).
    """

    x: FloatArray
    w: FloatArray
    b_wl: FloatArray
    area: FloatArray
    m22: FloatArray
    zeta: FloatArray
    wz: FloatArray
    b: FloatArray
    zeta_G: float
    x_T: float
    d_T: float
    m22_T: float
    z_H: float
    rho: float
    g: float
    L: float
    surge_scale: float = 1.0

    @property
    def name(self) -> str:
        """``"froude_krylov_strips"`` (with the surge factor when it is not 1)."""
        if self.surge_scale == 1.0:
            return "froude_krylov_strips"
        return f"froude_krylov_strips (X_w x {self.surge_scale:.6g})"

    @classmethod
    def from_hull(
        cls,
        hull: HullForm,
        *,
        x_G: float,
        zeta_G: float,
        m22: FloatArray,
        z_H: float,
        rho: float,
        g: float,
        n_depth: int = 12,
        surge_scale: float = 1.0,
    ) -> WaveStrips:
        """Build from a :class:`HullForm` (``x_G`` from midship, forward +)."""
        zeta, wz, b = hull.depth_quadrature(n_depth)
        # draft at the aft perpendicular: linear extrapolation of the keel line
        d_T = float(hull.d[0])
        if hull.n_stations >= 2 and hull.x[1] != hull.x[0]:
            slope = (hull.d[1] - hull.d[0]) / (hull.x[1] - hull.x[0])
            d_T = float(hull.d[0] + slope * (-hull.L / 2 - hull.x[0]))
        return cls(
            x=hull.x - x_G,
            w=hull.w.copy(),
            b_wl=hull.b_wl.copy(),
            area=hull.area.copy(),
            m22=np.asarray(m22, dtype=float),
            zeta=zeta,
            wz=wz,
            b=b,
            zeta_G=float(zeta_G),
            x_T=float(-hull.L / 2 - x_G),
            d_T=d_T,
            m22_T=float(0.5 * rho * np.pi * d_T**2),
            z_H=float(z_H),
            rho=float(rho),
            g=float(g),
            L=float(hull.L),
            surge_scale=float(surge_scale),
        )

    # ------------------------------------------------------------------ forces
    def section_integrals(self, k: Any, s: Any, ops: Ops = NUMPY_OPS) -> tuple[Any, Any, Any]:
        """Per-station ``C(x), C_z(x), S_y(x)``, each shape (J,) (see module doc)."""
        zeta = _const(self.zeta, ops)
        wz = _const(self.wz, ops)
        b = _const(self.b, ops)
        ekz = ops.exp(k * zeta)
        base = wz * ekz * 2.0 * b
        sn, gg = sinc_g1(k * s * b, ops)
        c_int = base * sn
        C = _rowsum(c_int, ops)
        Cz = _rowsum(c_int * zeta, ops)
        Sy = _rowsum(base * b * gg, ops)
        return C, Cz, Sy

    def _phase(
        self, xi_over_lambda: Any, chi: Any, sea: SeaState, ops: Ops
    ) -> tuple[Any, Any, Any, Any, Any]:
        r"""The wave at the stations: wavenumber, amplitude, heading and phase.

        Returns
        -------
        k, a, s, c : scalar
            :math:`k = 2\pi/\lambda` (1/m), the amplitude :math:`a = H/2` (m),
            :math:`\sin\chi` and :math:`\cos\chi` (:meth:`SeaState.wave`).
        kxi : array, shape (J,)
            :math:`k\xi_x = 2\pi\,\xi_G/\lambda + k x\cos\chi` of each station
            (module doc).
        """
        _, k, a = sea.wave(self.L, ops)
        s = ops.sin(chi)
        c = ops.cos(chi)
        kxi = 2.0 * ops.pi * xi_over_lambda + k * _const(self.x, ops) * c
        return k, a, s, c, kxi

    def forces(
        self,
        xi_over_lambda: Any,
        u: Any,
        chi: Any,
        sea: SeaState,
        ops: Ops = NUMPY_OPS,
        *,
        lift: bool = True,
    ) -> tuple[Any, Any, Any, Any]:
        r"""Froude-Krylov wave forces plus the wave lift, ``(X_w, Y_w, N_w, K_w)``.

        The strip integrals :math:`X_{FK}, Y_{FK}, N_{FK}, K_{FK}` of the module doc,
        :math:`X_{FK}` times :attr:`surge_scale`, plus :meth:`lift_forces` when
        ``lift`` (the :class:`~ship_models.contracts.WaveForceModel` contract).

        Parameters
        ----------
        xi_over_lambda : scalar
            :math:`\xi_G/\lambda` (0 at a trough, 0.5 at a crest).
        u : scalar
            Surge velocity (m/s), used by the lift terms.
        chi : scalar
            Heading from the wave direction (rad).
        sea : SeaState
            Wave steepness :math:`H/\lambda` and wavelength ratio :math:`\lambda/L`.
        ops : Ops
            NumPy or CasADi namespace.
        lift : bool
            Include the hydrodynamic lift due to wave particle velocity.

        Returns
        -------
        X_w, Y_w, N_w, K_w : scalar
            Forces (N) and moments (N m) about G (CasADi expressions with CasADi
            operands).
        """
        k, a, s, c, kxi = self._phase(xi_over_lambda, chi, sea, ops)
        sk = ops.sin(kxi)
        ck = ops.cos(kxi)
        C, Cz, Sy = self.section_integrals(k, s, ops)
        rga = self.rho * self.g * a
        I_sC = _dot(self.w, sk * C, ops)
        X = -self.surge_scale * rga * k * c * I_sC
        Y = rga * k * s * I_sC
        N = rga * k * (s * _dot(self.w * self.x, sk * C, ops) - c * _dot(self.w, ck * Sy, ops))
        bwl = _const(self.b_wl, ops)
        wp = 2.0 * bwl * bwl * g1(k * s * bwl, ops)
        K = -rga * k * _dot(self.w, sk * (Sy + s * (self.zeta_G * C - Cz)), ops) + rga * _dot(
            self.w, sk * wp, ops
        )
        if lift:
            YL, NL, KL = self._lift(xi_over_lambda, u, k, a, s, c, ck, C, ops)
            Y = Y + YL
            N = N + NL
            K = K + KL
        return X, Y, N, K

    def _lift(
        self, xi: Any, u: Any, k: Any, a: Any, s: Any, c: Any, ck: Any, C: Any, ops: Ops
    ) -> tuple[Any, Any, Any]:
        omega = ops.sqrt(self.g * k)
        area = _const(self.area, ops)
        vw = a * omega * s * ck * C / area  # (J,)
        kd = k * self.d_T
        vT = (
            a
            * omega
            * s
            * ops.cos(2.0 * ops.pi * xi + k * self.x_T * c)
            * (1.0 - ops.exp(-kd))
            / kd
        )
        YL = u * self.m22_T * vT
        NL = u * self.x_T * self.m22_T * vT + u * _dot(self.w * self.m22, vw, ops)
        return YL, NL, -self.z_H * YL

    def lift_forces(
        self, xi_over_lambda: Any, u: Any, chi: Any, sea: SeaState, ops: Ops = NUMPY_OPS
    ) -> tuple[Any, Any, Any]:
        """The wave-lift part ``(Y_L, N_L, K_L)`` of :meth:`forces` alone (module doc).

        Parameters
        ----------
        xi_over_lambda, u, chi, sea, ops
            As for :meth:`forces`.

        Returns
        -------
        Y_L, N_L, K_L : scalar
            Sway force (N), yaw and roll moments (N m) of the lift due to the wave
            particle velocity.
        """
        k, a, s, c, kxi = self._phase(xi_over_lambda, chi, sea, ops)
        ck = ops.cos(kxi)
        zeta = _const(self.zeta, ops)
        b = _const(self.b, ops)
        C = _rowsum(_const(self.wz, ops) * ops.exp(k * zeta) * 2.0 * b * sinc(k * s * b, ops), ops)
        return self._lift(xi_over_lambda, u, k, a, s, c, ck, C, ops)


def strip_waves(inputs: WaveInputs) -> WaveStrips:
    """The default :class:`~ship_models.contracts.WaveForceBuilder`: Froude-Krylov strips.

    Parameters
    ----------
    inputs : WaveInputs
        Hull, G, sway added masses and environment of the vessel.

    Returns
    -------
    WaveStrips
        :meth:`WaveStrips.from_hull` of the inputs.
    """
    return WaveStrips.from_hull(
        inputs.hull,
        x_G=inputs.x_G,
        zeta_G=inputs.zeta_G,
        m22=inputs.m22,
        z_H=inputs.z_H,
        rho=inputs.rho,
        g=inputs.g,
        n_depth=inputs.n_depth,
        surge_scale=inputs.surge_scale,
    )


__all__ = ["WaveStrips", "g1", "sinc", "sinc_g1", "strip_waves"]
