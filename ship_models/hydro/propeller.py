r"""Propeller thrust T(u; n) and the commanded revolution n(Fn).

.. math::

    T(u; n) = (1 - t_P)\,\rho\, n^2 D_p^4\, K_T(J), \qquad
    J = \frac{u (1 - w_P)}{n D_p}, \qquad K_T(J) = k_0 + k_1 J + k_2 J^2 .

- :math:`K_T(J)`: least-squares quadratic in J (over ``0 <= J <= J_max``) of the
  Wageningen B-series polynomial of Oosterveld, M.W.C. & van Oossanen, P. (1975),
  "Further computer-analyzed data of the Wageningen B-screw series", Int.
  Shipbuilding Progress 22(251):251-262 (Reynolds number 2e6, the 39-term K_T
  regression, coefficients tabulated below), for the stated blade number, pitch
  ratio and blade-area ratio.
- :math:`w_P`: Taylor's single-screw wake :math:`w_P = 0.5 C_b - 0.05` (Taylor, D.W.
  1933, "The Speed and Power of Ships", 3rd ed., Ransdell, Washington).
- :math:`t_P`: Holtrop (1984) single-screw thrust deduction
  :math:`t = 0.25014 (B/L)^{0.28956} (\sqrt{B T}/D_p)^{0.2624} /
  (1 - C_P + 0.0225\,lcb)^{0.01762} + 0.0015 C_{stern}` (Int. Shipbuilding Progress
  31(363):272-276).

With the quadratic :math:`K_T`, thrust is a quadratic form in ``(n, u_a)``,
:math:`T = (1 - t_P)\rho (k_0 D^4 n^2 + k_1 D^3 u_a n + k_2 D^2 u_a^2)`, so the
revolution that balances resistance at the nominal speed
:math:`u_0 = Fn\sqrt{g L}`, :math:`T(u_0; n) = R(u_0)`, has the closed form

.. math::

    n = \frac{-b + \sqrt{b^2 - 4 a c}}{2a},\quad a = k_0 D^4,\ b = k_1 D^3 u_{a0},\
    c = k_2 D^2 u_{a0}^2 - \frac{R(u_0)}{(1 - t_P)\rho},

which stays differentiable in ``Fn`` for CasADi (:func:`revolutions`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.ops import NUMPY_OPS, Ops
from continuation.typing import FloatArray

# Oosterveld & van Oossanen (1975), K_T = sum C J^s (P/D)^t (AE/A0)^u Z^v.
# Columns: C, s, t, u, v.
_BSERIES_KT = np.array(
    [
        [0.00880496, 0, 0, 0, 0],
        [-0.204554, 1, 0, 0, 0],
        [0.166351, 0, 1, 0, 0],
        [0.158114, 0, 2, 0, 0],
        [-0.147581, 2, 0, 1, 0],
        [-0.481497, 1, 1, 1, 0],
        [0.415437, 0, 2, 1, 0],
        [0.0144043, 0, 0, 0, 1],
        [-0.0530054, 2, 0, 0, 1],
        [0.0143481, 0, 1, 0, 1],
        [0.0606826, 1, 1, 0, 1],
        [-0.0125894, 0, 0, 1, 1],
        [0.0109689, 1, 0, 1, 1],
        [-0.133698, 0, 3, 0, 0],
        [0.00638407, 0, 6, 0, 0],
        [-0.00132718, 2, 6, 0, 0],
        [0.168496, 3, 0, 1, 0],
        [-0.0507214, 0, 0, 2, 0],
        [0.0854559, 2, 0, 2, 0],
        [-0.0504475, 3, 0, 2, 0],
        [0.0104650, 1, 6, 2, 0],
        [-0.00648272, 2, 6, 2, 0],
        [-0.00841728, 0, 3, 0, 1],
        [0.0168424, 1, 3, 0, 1],
        [-0.00102296, 3, 3, 0, 1],
        [-0.0317791, 0, 3, 1, 1],
        [0.0186040, 1, 0, 2, 1],
        [-0.00410798, 0, 2, 2, 1],
        [-0.000606848, 0, 0, 0, 2],
        [-0.00498190, 1, 0, 0, 2],
        [0.00259830, 2, 0, 0, 2],
        [-0.000560528, 3, 0, 0, 2],
        [-0.00163652, 1, 2, 0, 2],
        [-0.000328787, 1, 6, 0, 2],
        [0.000116502, 2, 6, 0, 2],
        [0.000690904, 0, 0, 1, 2],
        [0.00421749, 0, 3, 1, 2],
        [0.0000565229, 3, 6, 1, 2],
        [-0.00146564, 0, 3, 2, 2],
    ]
)


def bseries_kt(J: FloatArray | float, P_D: float, AE_A0: float, Z: int) -> FloatArray:
    """Wageningen B-series thrust coefficient K_T(J) (Oosterveld & van Oossanen 1975)."""
    J = np.asarray(J, dtype=float)
    C, s, t, u, v = _BSERIES_KT.T
    coef = C * P_D**t * AE_A0**u * float(Z) ** v
    return np.power.outer(J, s) @ coef


def fit_kt_quadratic(
    P_D: float, AE_A0: float, Z: int, J_max: float, n: int = 200
) -> tuple[float, float, float, float]:
    """Least-squares ``K_T ~ k0 + k1 J + k2 J^2`` on ``[0, J_max]``.

    Returns
    -------
    k0, k1, k2 : float
    max_abs_error : float
        Max |fit - B-series| on the interval.
    """
    J = np.linspace(0.0, J_max, n)
    kt = bseries_kt(J, P_D, AE_A0, Z)
    A = np.column_stack([np.ones_like(J), J, J**2])
    c = np.linalg.lstsq(A, kt, rcond=None)[0]
    return float(c[0]), float(c[1]), float(c[2]), float(np.max(np.abs(A @ c - kt)))


def taylor_wake(C_b: float) -> float:
    """Taylor's single-screw effective wake fraction ``0.5 C_b - 0.05``."""
    return 0.5 * C_b - 0.05


def holtrop_thrust_deduction(
    B: float, L: float, T: float, D_p: float, C_P: float, lcb_percent: float, C_stern: float
) -> float:
    """Holtrop (1984) single-screw thrust deduction fraction."""
    return (
        0.25014
        * (B / L) ** 0.28956
        * (np.sqrt(B * T) / D_p) ** 0.2624
        / (1.0 - C_P + 0.0225 * lcb_percent) ** 0.01762
        + 0.0015 * C_stern
    )


def thrust(
    u: Any,
    n: Any,
    *,
    rho: float,
    D_p: float,
    w_P: float,
    t_P: float,
    k: tuple[float, float, float],
) -> Any:
    """Effective thrust ``(1 - t_P) rho (k0 D^4 n^2 + k1 D^3 u_a n + k2 D^2 u_a^2)`` (N).

    Works for NumPy and CasADi operands (no division by ``n``).
    """
    ua = u * (1.0 - w_P)
    return (
        (1.0 - t_P) * rho * (k[0] * D_p**4 * n**2 + k[1] * D_p**3 * ua * n + k[2] * D_p**2 * ua**2)
    )


def revolutions(
    u0: Any,
    R0: Any,
    *,
    rho: float,
    D_p: float,
    w_P: float,
    t_P: float,
    k: tuple[float, float, float],
    ops: Ops = NUMPY_OPS,
) -> Any:
    """Revolutions per second ``n`` solving ``T(u0; n) = R0`` (closed form, see module doc).

    Raises
    ------
    ValueError
        If ``k0 <= 0`` (no thrust at bollard pull).
    """
    if not k[0] > 0:
        raise ValueError(f"K_T(0) = k0 must be positive, got {k[0]}")
    ua = u0 * (1.0 - w_P)
    a = k[0] * D_p**4
    b = k[1] * D_p**3 * ua
    c = k[2] * D_p**2 * ua**2 - R0 / ((1.0 - t_P) * rho)
    return (-b + ops.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)


def bseries_kt_polynomial(P_D: float, AE_A0: float, Z: int) -> tuple[float, ...]:
    """Coefficients ``c_0..c_3`` of the B-series ``K_T(J) = sum c_s J^s`` (cubic in J)."""
    C, s, t, u, v = _BSERIES_KT.T
    coef = C * P_D**t * AE_A0**u * float(Z) ** v
    return tuple(float(np.sum(coef[s == k])) for k in range(4))


def bseries_zero_thrust_J(P_D: float, AE_A0: float, Z: int) -> float:
    """Advance ratio at which the B-series ``K_T`` vanishes (smallest positive root)."""
    c = bseries_kt_polynomial(P_D, AE_A0, Z)
    roots = np.roots(c[::-1])
    real = np.sort([r.real for r in roots if abs(r.imag) < 1e-12 and r.real > 0])
    if real.size == 0:
        raise ValueError(f"B-series K_T has no zero for P/D = {P_D}, AE/A0 = {AE_A0}, Z = {Z}")
    return float(real[0])


def bseries_kt_curve(P_D: float, AE_A0: float, Z: int) -> Any:
    r"""The B-series K_T(J) with a monotone C2 continuation beyond ``K_T = 0``.

    Up to :math:`J_0` (``K_T(J_0) = 0``, :func:`bseries_zero_thrust_J`) the polynomial
    of Oosterveld & van Oossanen (1975), cubic in J, is used as published. Beyond, the
    regression has no data (a windmilling propeller) and its cubic term, extrapolated,
    turns K_T up again at large J (spurious thrust when the ship is much faster than
    the propeller's advance speed, e.g. at low commanded revolutions). There the
    curve is continued by its quadratic Taylor part at :math:`J_0` plus a cubic
    :math:`d\,s^3`, :math:`s = J - J_0`, with :math:`d = -\max(C, 0)^2 / |K_T'(J_0)|`
    (:math:`C = K_T''(J_0)/2`), which keeps it C2 and strictly decreasing for all
    :math:`J > J_0` (the stated assumption: a windmilling propeller brakes more the
    faster the inflow). Analyses that reach it are warned (:mod:`ship_models.validity`).

    Returns
    -------
    Polynomial1D
        ``valid = (0, J_0)``.
    """
    from .curves import Polynomial1D

    c = bseries_kt_polynomial(P_D, AE_A0, Z)
    J0 = bseries_zero_thrust_J(P_D, AE_A0, Z)
    slope = c[1] + 2 * c[2] * J0 + 3 * c[3] * J0**2
    curv2 = c[2] + 3 * c[3] * J0
    d = -(max(curv2, 0.0) ** 2) / abs(slope) if slope < 0 else 0.0
    return Polynomial1D(np.array(c), (0.0, J0), tail_start=J0, tail_cubic=-c[3] + d)


@dataclass(frozen=True)
class Propeller:
    r"""Open-water propeller with general K_T(J) and speed-dependent w_P, t_P.

    .. math::

        T(u; n) = (1 - t_P(u))\,\rho\, n^2 D_p^4\, K_T(J),\qquad
        J = \frac{(1 - w_P(u))\, u}{n D_p},

    with ``K_T`` a :class:`~ship_models.hydro.curves.CubicSpline1D` (measured table)
    or :class:`~ship_models.hydro.curves.Polynomial1D` (published polynomial, e.g. the
    full B-series), and ``w_P(u)``, ``t_P(u)`` constants or splines of speed.

    The revolution for the nominal speed solves :math:`K_T(J_0) = \tau J_0^2`,
    :math:`\tau = R(u_0) / ((1 - t_P)\rho D_p^2 u_{a0}^2)`, by ``n_newton`` Newton
    steps in J from the closed form of the quadratic ``kt_start`` (unrolled, so CasADi
    differentiates the converged root; the residual is checked numerically by
    :meth:`revolution_residual`), then :math:`n = u_{a0} / (J_0 D_p)`.

    Attributes
    ----------
    D_p : float
    kt : object
        ``evaluate(J, ops)`` and ``derivative(J, ops)``.
    kt_start : tuple of float
        Quadratic ``(k0, k1, k2)`` close to ``kt`` (starting guess).
    w_P, t_P : float
        Constant fractions (used when the curves are None).
    w_curve, t_curve : object or None
        Speed-dependent fractions (``evaluate(u, ops)``).
    n_newton : int
        Newton steps of the revolution solve.
    """

    D_p: float
    kt: Any
    kt_start: tuple[float, float, float]
    w_P: float
    t_P: float
    w_curve: Any = None
    t_curve: Any = None
    n_newton: int = 8

    def wake(self, u: Any, ops: Ops = NUMPY_OPS) -> Any:
        """``w_P(u)``."""
        return self.w_P if self.w_curve is None else self.w_curve.evaluate(u, ops)

    def deduction(self, u: Any, ops: Ops = NUMPY_OPS) -> Any:
        """``t_P(u)``."""
        return self.t_P if self.t_curve is None else self.t_curve.evaluate(u, ops)

    def loading(self, ua: Any, n: Any, ops: Ops = NUMPY_OPS) -> Any:
        """``K_T(J) n^2 D_p^2`` (m^2/s^2) at advance speed ``ua`` (``n > 0``)."""
        n_safe = ops.fmax(n, 1e-9)
        J = ua / (n_safe * self.D_p)
        return self.kt.evaluate(J, ops) * n * n * self.D_p**2

    def thrust(self, u: Any, n: Any, rho: float, ops: Ops = NUMPY_OPS) -> Any:
        """Effective thrust (N)."""
        ua = (1.0 - self.wake(u, ops)) * u
        return (1.0 - self.deduction(u, ops)) * rho * self.D_p**2 * self.loading(ua, n, ops)

    def advance_ratio_at(self, u0: Any, R0: Any, rho: float, ops: Ops = NUMPY_OPS) -> Any:
        """``J_0`` with ``T(u0; n) = R0`` (see class doc)."""
        ua0 = (1.0 - self.wake(u0, ops)) * u0
        t0 = self.deduction(u0, ops)
        k = self.kt_start
        tau = R0 / ((1.0 - t0) * rho * self.D_p**2 * ua0 * ua0 + 1e-300)
        # start: root of the quadratic k0 + k1 J + (k2 - tau) J^2 = 0 (positive)
        a2 = k[2] - tau
        J = (-k[1] - ops.sqrt(k[1] * k[1] - 4.0 * k[0] * a2)) / (2.0 * a2)
        for _ in range(self.n_newton):
            g = self.kt.evaluate(J, ops) - tau * J * J
            dg = self.kt.derivative(J, ops) - 2.0 * tau * J
            J = J - g / dg
        return J

    def revolutions(self, u0: Any, R0: Any, rho: float, ops: Ops = NUMPY_OPS) -> Any:
        """Revolutions per second ``n`` with ``T(u0; n) = R0`` (``u0 > 0``)."""
        ua0 = (1.0 - self.wake(u0, ops)) * u0
        return ua0 / (self.advance_ratio_at(u0, R0, rho, ops) * self.D_p)

    def revolution_residual(self, u0: float, R0: float, rho: float) -> float:
        """Relative residual ``|T(u0; n) - R0| / R0`` of :meth:`revolutions` (NumPy)."""
        n = self.revolutions(u0, R0, rho)
        return float(abs(self.thrust(u0, n, rho) - R0) / max(abs(R0), 1e-300))


__all__ = [
    "Propeller",
    "bseries_kt",
    "bseries_kt_curve",
    "bseries_kt_polynomial",
    "bseries_zero_thrust_J",
    "fit_kt_quadratic",
    "holtrop_thrust_deduction",
    "revolutions",
    "taylor_wake",
    "thrust",
]
