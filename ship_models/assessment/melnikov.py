r"""The surf-riding threshold of the Level 2 criterion: Melnikov's closed form.

The Level 2 criterion of MSC.1/Circ.1627 takes the critical Froude number ``Fn_cr`` of each
regular wave from the uncoupled surge equation (the ``chi = 0`` reduction of Umeda
1999, :class:`ship_models.surge.SurgeModel`), written relative to a wave crest moving at
the celerity ``c``, :math:`u = c + \dot\xi`:

.. math::

    (m + m_x)\,\ddot\xi + f\sin k\xi = T(c + \dot\xi; n) - R(c + \dot\xi),

with the Froude-Krylov surge amplitude ``f`` (:func:`froude_krylov_amplitude`), the
calm-water resistance ``R(u)`` and the effective thrust
``T(u; n) = tau_0 n^2 + tau_1 n u + tau_2 u^2`` (:func:`thrust_coefficients`). Its
undamped part is a pendulum; its separatrix below the wave speed is
:math:`u(\theta) = c - v_0\cos(\theta/2)`, :math:`\theta = k\xi \in (-\pi, \pi)`,
:math:`v_0 = 2\sqrt{f / (k (m + m_x))}`. Melnikov's method (Maki, Umeda, Renilson &
Ueta 2010, "Analytical formulae for predicting the surf-riding threshold for a ship in
following seas", J. Mar. Sci. Technol. 15:218-229) puts the surf-riding threshold where
the work of the net thrust along it vanishes:

.. math::

    \int_{-\pi}^{\pi}\bigl[T(u(\theta); n) - R(u(\theta))\bigr]\,d\theta = 0
    \iff 2\pi\tau_0 n^2 + \tau_1 I_1\, n + \tau_2 I_2 - I_R = 0,

:math:`I_1 = 2\pi c - 4 v_0`, :math:`I_2 = 2\pi c^2 - 8 c v_0 + \pi v_0^2`,
:math:`I_R = \int R(u(\theta))\,d\theta` (:func:`melnikov_revolutions`; a quadratic in
``n`` with exactly one positive root when ``I_R > tau_2 I_2``, Sakai & Umeda 2024,
arXiv:2407.11601). The critical nominal speed ``u_cr`` is the calm-water speed of that
``n``: ``T(u_cr; n_cr) = R(u_cr)``, and ``Fn_cr = u_cr / sqrt(g L)``. Written with a
polynomial resistance ``sum_{k=1}^{K} r_k u^k`` (the form the criterion is described
with; its degree in the circular was not checked against the text), ``I_R`` has the
closed form of :func:`resistance_integral_polynomial`; here ``I_R`` is integrated from the
vessel's own resistance curve by Gauss-Legendre quadrature
(:func:`resistance_integral`, tested against the closed form for polynomials), so that
Melnikov's threshold and the exact one (:mod:`ship_models.assessment.exact`) belong to
the same surge equation. For the torque-driven damped pendulum
``x'' + alpha x' + sin x = beta`` the same balance is ``beta = 4 alpha / pi``
(:func:`pendulum_melnikov`).

No section, paragraph or equation number of the circular is cited: its
surf-riding/broaching text could not be reached (what was checked:
:mod:`ship_models.assessment.standard`), so the formulas here are those of the papers
cited, not a transcription of the circular.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from continuation.typing import FloatArray

from ..contracts import SeaState
from ..forces import ShipForces

N_QUADRATURE = 96


@dataclass(frozen=True)
class ThrustCoefficients:
    """``T(u; n) = tau0 n^2 + tau1 n u + tau2 u^2`` (N, with n in 1/s and u in m/s)."""

    tau0: float
    tau1: float
    tau2: float


def thrust_coefficients(F: ShipForces) -> ThrustCoefficients:
    r"""Thrust polynomial of the surge equation (the thrust term of the Level 2 criterion).

    From ``T = (1 - t_P) rho n^2 D^4 K_T(J)``, ``K_T = k0 + k1 J + k2 J^2``,
    ``J = (1 - w_P) u / (n D)``:
    ``tau0 = (1-t_P) rho D^4 k0``, ``tau1 = (1-t_P) rho D^3 (1-w_P) k1``,
    ``tau2 = (1-t_P) rho D^2 (1-w_P)^2 k2``.
    """
    k0, k1, k2 = F.kt
    a = (1.0 - F.t_P) * F.rho
    w = 1.0 - F.w_P
    return ThrustCoefficients(a * F.D_p**4 * k0, a * F.D_p**3 * w * k1, a * F.D_p**2 * w * w * k2)


def froude_krylov_amplitude(F: ShipForces, lambda_over_L: FloatArray) -> FloatArray:
    r"""Amplitude ``f`` of the wave surge force per metre of wave height (N/m).

    The linear Froude-Krylov surge force of the hull at its calm-water attitude at
    ``chi = 0`` is :math:`X_w = -\rho g a k\,[\sin k\xi_G\int\cos kx\,C\,dx +
    \cos k\xi_G\int\sin kx\,C\,dx]` (:mod:`ship_models.hydro.waves`). The strip formula
    attributed to the criterion (from the literature, not checked against the text of
    the circular), :math:`\rho g k (H/2)\sqrt{F_c^2 + F_s^2}` with
    :math:`F_{c,s} = \sum S(x) e^{-k d(x)/2} \{\sin,\cos\} kx\,\Delta x`, approximates
    the section integral ``C(x)`` by the sectional area ``S`` at half the draft ``d``.
    So ``f = sqrt(X_w(0)^2 + X_w(lambda/4)^2)``; it is evaluated by the vessel's own
    wave model (including ``wave_surge_scale`` and any diffraction factor), so that it
    is the force of the surge model, and divided by ``H``.

    Parameters
    ----------
    F : ShipForces
    lambda_over_L : array_like, shape (n,)

    Returns
    -------
    ndarray, shape (n,)
        ``f / H`` (N/m); linear theory makes ``f`` proportional to ``H``.
    """
    lam = np.atleast_1d(np.asarray(lambda_over_L, dtype=float))
    s_ref = 0.01  # any steepness: the force is linear in H
    out = np.empty_like(lam)
    for i, lL in enumerate(lam):
        sea = SeaState(s_ref, lL)
        x0 = float(F.waves.forces(0.0, 0.0, 0.0, sea, lift=False)[0])
        x1 = float(F.waves.forces(0.25, 0.0, 0.0, sea, lift=False)[0])
        out[i] = math.hypot(x0, x1) / (s_ref * lL * F.L)
    return out


def separatrix_speed(f: FloatArray, k: FloatArray, mass: float) -> FloatArray:
    r"""``v0 = 2 sqrt(f / (k (m + m_x)))`` (m/s): the largest relative speed on the
    separatrix of the undamped surge equation (``mass = m + m_x``)."""
    return 2.0 * np.sqrt(np.asarray(f, dtype=float) / (np.asarray(k, dtype=float) * mass))


def _gauss_half(n: int) -> tuple[FloatArray, FloatArray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * math.pi * (x + 1.0), 0.5 * math.pi * w  # nodes on (0, pi)


def resistance_integral(
    resistance, c: FloatArray, v0: FloatArray, n_quad: int = N_QUADRATURE
) -> FloatArray:
    r"""``I_R = int_{-pi}^{pi} R(c - v0 cos(theta/2)) dtheta`` (N) by Gauss-Legendre.

    The integrand is even in ``theta``: ``2 int_0^pi``. ``resistance`` is a vectorised
    callable ``R(u)`` (N).

    Parameters
    ----------
    resistance : callable
    c, v0 : array_like
        Broadcast together.
    n_quad : int
        Nodes on ``(0, pi)``.
    """
    th, w = _gauss_half(n_quad)
    c = np.asarray(c, dtype=float)[..., None]
    v0 = np.asarray(v0, dtype=float)[..., None]
    u = c - v0 * np.cos(0.5 * th)
    return 2.0 * np.asarray(resistance(u), dtype=float) @ w


def cos_half_moment(m: int) -> float:
    r"""``K_m = int_{-pi}^{pi} cos^m(theta/2) dtheta = 2 sqrt(pi) Gamma((m+1)/2) / Gamma(m/2+1)``
    (``2 pi, 4, pi, 8/3, 3 pi/4, 32/15`` for ``m = 0..5``)."""
    return 2.0 * math.sqrt(math.pi) * math.gamma(0.5 * (m + 1)) / math.gamma(0.5 * m + 1.0)


def resistance_integral_polynomial(r: FloatArray, c: FloatArray, v0: FloatArray) -> FloatArray:
    r"""Closed form of ``I_R`` for ``R(u) = sum_{k=1}^{K} r_k u^k`` (a polynomial
    resistance, the form the criterion is described with): binomial expansion of
    ``(c - v0 cos(theta/2))^k`` and the moments :func:`cos_half_moment`.

    Parameters
    ----------
    r : array_like, shape (K,)
        ``r_1 .. r_K`` (N s^k / m^k).
    c, v0 : array_like
        Broadcast together.
    """
    c = np.asarray(c, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    out = np.zeros(np.broadcast(c, v0).shape)
    for k, rk in enumerate(np.asarray(r, dtype=float), start=1):
        for m in range(k + 1):
            out = out + rk * math.comb(k, m) * c ** (k - m) * (-v0) ** m * cos_half_moment(m)
    return out


def melnikov_revolutions(
    tc: ThrustCoefficients, c: FloatArray, v0: FloatArray, I_R: FloatArray
) -> FloatArray:
    r"""Critical propeller revolution ``n_cr`` (1/s) of Melnikov's balance (module doc):
    the positive root of ``2 pi tau0 n^2 + tau1 I1 n + tau2 I2 - I_R = 0``.

    Returns NaN where there is no positive root (``I_R <= tau2 I2``).
    """
    c = np.asarray(c, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    I1 = 2.0 * math.pi * c - 4.0 * v0
    I2 = 2.0 * math.pi * c * c - 8.0 * c * v0 + math.pi * v0 * v0
    a = 2.0 * math.pi * tc.tau0
    b = tc.tau1 * I1
    cc = tc.tau2 * I2 - np.asarray(I_R, dtype=float)
    disc = b * b - 4.0 * a * cc
    with np.errstate(invalid="ignore"):
        n = (-b + np.sqrt(disc)) / (2.0 * a)
    return np.where((cc < 0) & (disc >= 0), n, np.nan)


def calm_water_fn(F: ShipForces, n: FloatArray, Fn_hi: float = 2.0, iters: int = 60) -> FloatArray:
    r"""``Fn`` whose calm-water revolution is ``n``: the root of ``T(u; n) = R(u)``,
    ``u = Fn sqrt(g L)`` (the inverse of :meth:`ShipForces.revolutions`, which is
    increasing in ``Fn``), by vectorised bisection on ``[0, Fn_hi]`` to
    ``Fn_hi 2^-iters``. NaN in, NaN out; ``Fn_hi`` where ``n`` is beyond it."""
    n = np.asarray(n, dtype=float)
    lo = np.zeros_like(n)
    hi = np.full_like(n, Fn_hi)
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        above = np.asarray(F.revolutions(mid), dtype=float) > n
        hi = np.where(above, mid, hi)
        lo = np.where(above, lo, mid)
    return np.where(np.isfinite(n), 0.5 * (lo + hi), np.nan)


@dataclass(frozen=True)
class MelnikovGrid:
    """Melnikov's ``Fn_cr`` over the wave cases.

    Attributes
    ----------
    lambda_over_L : ndarray, shape (n_lambda,)
    steepness : ndarray, shape (n_s,)
    Fn_cr : ndarray, shape (n_lambda, n_s)
        NaN where Melnikov's balance has no positive root.
    n_cr : ndarray, shape (n_lambda, n_s)
        Critical revolution (1/s).
    celerity_fn : ndarray, shape (n_lambda,)
        ``c / sqrt(g L)``.
    in_range : ndarray of bool, shape (n_lambda, n_s)
        The separatrix speeds ``[c - v0, c]`` lie inside the resistance curve's fitted
        range ``[0, u_max]`` (outside it ``R`` is extrapolated: a result outside the
        vessel model's validity).
    """

    lambda_over_L: FloatArray
    steepness: FloatArray
    Fn_cr: FloatArray
    n_cr: FloatArray
    celerity_fn: FloatArray
    in_range: FloatArray


def melnikov_grid(
    F: ShipForces,
    lambda_over_L: FloatArray,
    steepness: FloatArray,
    *,
    n_quad: int = N_QUADRATURE,
) -> MelnikovGrid:
    """Melnikov's critical Froude number on the grid of wave cases (vectorised, module doc).

    Parameters
    ----------
    F : ShipForces
        The vessel's forces (``model.forces``).
    lambda_over_L : array_like, shape (n_lambda,)
    steepness : array_like, shape (n_s,)
    n_quad : int
        Quadrature nodes of :func:`resistance_integral`.
    """
    lam = np.asarray(lambda_over_L, dtype=float)
    s = np.asarray(steepness, dtype=float)
    f1 = froude_krylov_amplitude(F, lam)  # N per m of wave height
    k = 2.0 * math.pi / (lam * F.L)
    c = np.sqrt(F.g / k)
    H = s[None, :] * (lam * F.L)[:, None]
    v0 = separatrix_speed(f1[:, None] * H, k[:, None], F.mass + F.m_x)
    cc = np.broadcast_to(c[:, None], v0.shape)
    I_R = resistance_integral(F.resistance, cc, v0, n_quad)
    n_cr = melnikov_revolutions(thrust_coefficients(F), cc, v0, I_R)
    Fn = calm_water_fn(F, n_cr)
    in_range = (cc - v0 >= 0.0) & (cc <= F.resistance.u_max)
    return MelnikovGrid(lam, s, Fn, n_cr, c / math.sqrt(F.g * F.L), in_range)


def pendulum_melnikov(alpha: float) -> float:
    r"""Melnikov's threshold ``beta = 4 alpha / pi`` of ``x'' + alpha x' + sin x = beta``:
    the balance above with ``T - R`` replaced by ``beta - alpha x'`` on the separatrix
    ``x' = 2 cos(x/2)`` (``2 pi beta = alpha int 2 cos(x/2) dx = 8 alpha``)."""
    return 4.0 * alpha / math.pi


__all__ = [
    "MelnikovGrid",
    "ThrustCoefficients",
    "calm_water_fn",
    "cos_half_moment",
    "froude_krylov_amplitude",
    "melnikov_grid",
    "melnikov_revolutions",
    "pendulum_melnikov",
    "resistance_integral",
    "resistance_integral_polynomial",
    "separatrix_speed",
    "thrust_coefficients",
]
