r"""The righting-arm curve GZ(phi), whatever describes the hull.

:class:`HeeledState` is the free-floating equilibrium at one heel, :func:`heeled_gz`
turns a sequence of them into

.. math::

    GZ(\phi) = y_B \cos\phi + (\zeta_B - \zeta_G)\sin\phi ,

and :class:`GZCurve` holds that curve with its odd sine-series fit
:math:`GZ(\phi) \approx \sum_{i=1}^{n} g_i \sin(i\phi)` (least squares with the
constraint :math:`\sum_i i g_i = GM`, :func:`fit_sine_series`). The strip hull's
equilibria are :func:`ship_models.hydro.hydrostatics.heeled_equilibrium`, a mesh
hull's :func:`ship_models.hydro.mesh_hydrostatics.mesh_heeled_equilibrium`; both
modules build on this one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from continuation.typing import FloatArray


@dataclass(frozen=True)
class HeeledState:
    """Hydrostatic equilibrium at one heel angle.

    Attributes
    ----------
    phi, h0, theta : float
        Heel (rad), sinkage of the water level at midship (m), trim slope (-).
    volume, y_B, zeta_B, x_B : float
        Displaced volume and centre of buoyancy (body axes).
    converged : bool
        Newton converged.
    """

    phi: float
    h0: float
    theta: float
    volume: float
    y_B: float
    zeta_B: float
    x_B: float
    converged: bool


@dataclass(frozen=True)
class GZCurve:
    """Righting-arm curve from hydrostatics and its smooth sine-series fit.

    Attributes
    ----------
    phi : ndarray, shape (K,)
        Heel angles of the hydrostatic computation, 0..pi (rad).
    gz : ndarray, shape (K,)
        Hydrostatic GZ (m).
    coeffs : ndarray, shape (n,)
        Sine-series coefficients ``g_i`` (m), ``GZ = sum g_i sin(i phi)``.
    GM : float
        Metacentric height imposed on the fit (m).
    zeta_G : float
        Height of G above the calm waterline (m).
    volume : float
        Displaced volume of the polygon hull (m^3).
    topside_height : float
        Watertight extension above the deck used (m).
    """

    phi: FloatArray
    gz: FloatArray
    coeffs: FloatArray
    GM: float
    zeta_G: float
    volume: float
    topside_height: float = 0.0

    def __call__(self, phi: FloatArray | float) -> FloatArray:
        """Fitted GZ at ``phi`` (rad), NumPy."""
        p = np.asarray(phi, dtype=float)
        i = np.arange(1, self.coeffs.size + 1)
        return np.sin(np.multiply.outer(p, i)) @ self.coeffs

    def slope0(self) -> float:
        """``dGZ/dphi`` at 0 of the fit (equals GM by construction)."""
        return float(np.arange(1, self.coeffs.size + 1) @ self.coeffs)

    @property
    def fit_error(self) -> float:
        """Max |fit - hydrostatic| over the computed angles (m)."""
        return float(np.max(np.abs(self(self.phi) - self.gz)))

    @property
    def max_gz(self) -> tuple[float, float]:
        """``(phi_max, GZ_max)`` of the hydrostatic curve (rad, m)."""
        k = int(np.argmax(self.gz))
        return float(self.phi[k]), float(self.gz[k])

    @property
    def vanishing_angle(self) -> float:
        """Angle of vanishing stability (rad): first zero of the hydrostatic GZ after 0."""
        g = self.gz
        idx = np.nonzero((g[1:-1] > 0) & (g[2:] <= 0))[0]
        if idx.size == 0:
            return float(self.phi[-1])
        k = idx[0] + 1
        return float(self.phi[k] - g[k] * (self.phi[k + 1] - self.phi[k]) / (g[k + 1] - g[k]))

    def area(self, phi_to: float, phi_from: float = 0.0) -> float:
        """Area under the hydrostatic GZ curve between two angles (m rad), trapezoidal."""
        m = (self.phi >= phi_from - 1e-12) & (self.phi <= phi_to + 1e-12)
        return float(np.trapezoid(self.gz[m], self.phi[m]))


def fit_sine_series(phi: FloatArray, gz: FloatArray, n_terms: int, slope0: float) -> FloatArray:
    r"""Least-squares sine series with an exact initial slope.

    Minimises :math:`\sum_k (\sum_i g_i \sin(i\phi_k) - GZ_k)^2` subject to
    :math:`\sum_i i g_i = GM` (Lagrange multiplier / KKT system).
    """
    i = np.arange(1, n_terms + 1)
    A = np.sin(np.multiply.outer(phi, i))
    c = i.astype(float)
    K = np.zeros((n_terms + 1, n_terms + 1))
    K[:n_terms, :n_terms] = A.T @ A
    K[:n_terms, n_terms] = c
    K[n_terms, :n_terms] = c
    rhs = np.concatenate([A.T @ gz, [slope0]])
    sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
    return sol[:n_terms]


def heeled_gz(
    equilibrium: Callable[[float, tuple[float, float]], HeeledState],
    what: str,
    zeta_G: float,
    phi_max: float,
    heel_step: float,
) -> tuple[FloatArray, FloatArray]:
    r"""GZ at the heels ``0, heel_step, ..., phi_max`` from the free-floating equilibria:
    :math:`GZ = y_B \cos\phi + (\zeta_B - \zeta_G) \sin\phi`.

    Parameters
    ----------
    equilibrium : callable
        ``equilibrium(phi, guess) -> HeeledState`` at heel ``phi`` (rad), ``guess`` the
        ``(h0, theta)`` of the previous heel.
    what : str
        The equilibrium's name in the error message.
    zeta_G : float
        Height of G (m), as the equilibria measure ``zeta_B``.
    phi_max, heel_step : float
        Largest heel and heel step (rad).

    Returns
    -------
    phis, gz : ndarray, shape (n + 1,)
        Heels (rad) and GZ (m); exactly 0 upright and at 180 deg.

    Raises
    ------
    ValueError
        The equilibrium fails at some heel (names the heel in degrees).
    """
    n = int(round(phi_max / heel_step))
    phis = np.linspace(0.0, phi_max, n + 1)
    gz = np.zeros_like(phis)
    guess = (0.0, 0.0)
    for k, ph in enumerate(phis):
        st = equilibrium(ph, guess)
        if not st.converged:
            raise ValueError(f"{what} failed at heel {np.rad2deg(ph):.1f} deg")
        guess = (st.h0, st.theta)
        gz[k] = st.y_B * np.cos(ph) + (st.zeta_B - zeta_G) * np.sin(ph)
    gz[0] = 0.0
    if abs(phi_max - np.pi) < 1e-12:
        gz[-1] = 0.0
    return phis, gz


__all__ = ["GZCurve", "HeeledState", "fit_sine_series", "heeled_gz"]
