r"""Weights ``w_ij`` of the regular wave cases in one sea state (Longuet-Higgins 1983).

The Level 2 surf-riding criterion (MSC.1/Circ.1627) replaces an irregular sea
state ``(Hs, Tz)`` by regular waves of local height ``H`` and length ``lambda`` with
the probability of the joint distribution of local wave height and period of
M.S. Longuet-Higgins (1983), "On the joint distribution of wave periods and amplitudes
in a random wave field", Proc. R. Soc. Lond. A 389:241-258:

.. math::

    p(R, \tau) = \frac{2}{\sqrt\pi}\,\frac{R^2}{\nu\,\tau^2}\,
    \exp\Bigl\{-R^2\Bigl[1 + \frac{(1 - 1/\tau)^2}{\nu^2}\Bigr]\Bigr\}\,L(\nu),
    \qquad L(\nu) = \frac{2}{1 + (1 + \nu^2)^{-1/2}},

with the amplitude ``R = a / sqrt(2 m0) = sqrt(2) H / Hs`` (``Hs = 4 sqrt(m0)``), the
period ``tau = T / T01`` (``T01 = 2 pi m0 / m1``) and the spectral width
``nu = sqrt(m0 m2 / m1^2 - 1)``. For the two-parameter (Bretschneider / ITTC)
spectrum :math:`S(\omega) \propto \omega^{-5} e^{-B\omega^{-4}}` the moments give
``T01 / Tz = sqrt(Gamma(1/2)) / Gamma(3/4) = 1.0864`` and ``nu = 0.4247``
(:func:`bretschneider_period_ratio`, :func:`spectral_width`; derived here from the
spectrum, not taken from the circular, whose constants could not be checked against
its text: see :mod:`ship_models.assessment.standard`). The local wavelength follows
from the deep-water dispersion relation ``lambda = g T^2 / (2 pi)``.

The cell weight of the wave case ``(lambda_i/L, s_j = H/lambda)`` is the density in
``(lambda/L, s)`` times the cell area (midpoint rule), :func:`wave_case_weights`. The
grid of the criterion covers only ``lambda/L`` in about [1, 3] and ``s`` in about
[0.03, 0.15]: its weights sum to the probability of such waves, far below one (gentle
and short waves are not counted). :func:`band_probability` is the closed form of the
mass in a band of wavelengths (all heights), used to check the discretisation.
"""

from __future__ import annotations

import math

import numpy as np

from continuation.typing import FloatArray

G_STANDARD = 9.80665


def bretschneider_period_ratio() -> float:
    r"""``T01 / T02`` of the spectrum :math:`\omega^{-5}e^{-B\omega^{-4}}` (= 1.08644).

    The moments are :math:`m_n \propto B^{n/4}\Gamma(1 - n/4)`, so
    :math:`T_{01}/T_{02} = \sqrt{m_0 m_2}/m_1 = \sqrt{\Gamma(1/2)}/\Gamma(3/4)`.
    ``Tz`` of a scatter table is :math:`T_{02}`.
    """
    return math.sqrt(math.gamma(0.5)) / math.gamma(0.75)


def spectral_width() -> float:
    r"""Longuet-Higgins' ``nu = sqrt(m0 m2 / m1^2 - 1)`` of the same spectrum (= 0.42468)."""
    r = bretschneider_period_ratio()
    return math.sqrt(r * r - 1.0)


def lh83_normalisation(nu: float) -> float:
    r"""``L(nu) = 2 / (1 + (1 + nu^2)^{-1/2})`` (Longuet-Higgins 1983), which makes
    :func:`lh83_density` integrate to one over ``R > 0, tau > 0``."""
    return 2.0 / (1.0 + 1.0 / math.sqrt(1.0 + nu * nu))


def lh83_density(R: FloatArray, tau: FloatArray, nu: float) -> FloatArray:
    r"""Joint density ``p(R, tau)`` of normalised amplitude and period (Longuet-Higgins 1983).

    Parameters
    ----------
    R, tau : array_like
        ``R = a / sqrt(2 m0)`` and ``tau = T / T01`` (broadcast together; ``tau > 0``).
    nu : float
        Spectral width.

    Returns
    -------
    ndarray
        The density (module doc), shape of the broadcast inputs.
    """
    R = np.asarray(R, dtype=float)
    tau = np.asarray(tau, dtype=float)
    x = (1.0 - 1.0 / tau) / nu
    return (
        2.0
        / math.sqrt(math.pi)
        * R**2
        / (nu * tau**2)
        * np.exp(-(R**2) * (1.0 + x * x))
        * lh83_normalisation(nu)
    )


def wave_case_density(
    lambda_over_L: FloatArray,
    steepness: FloatArray,
    L: float,
    Hs: float,
    Tz: float,
    *,
    g: float = G_STANDARD,
    nu: float | None = None,
    period_ratio: float | None = None,
) -> FloatArray:
    r"""Density of local waves in ``(lambda/L, s = H/lambda)`` for the sea state ``(Hs, Tz)``.

    With ``H = s lambda``, ``lambda = (lambda/L) L``, ``T = sqrt(2 pi lambda / g)``:

    .. math::

        p_{\lambda/L,\,s} = p(R, \tau)\,\frac{\sqrt2}{H_s}\,\frac{1}{T_{01}}\,
        \frac{T\,L}{2}\cdot\frac{\lambda}{L}\,L

    (the Jacobians of ``(R, tau) -> (H, T) -> (H, lambda) -> (s, lambda/L)``).

    Parameters
    ----------
    lambda_over_L, steepness : array_like
        Broadcast together.
    L, Hs, Tz : float
        Ship length (m), significant wave height (m), zero-crossing period (s).
    g : float
        Gravity (m/s^2).
    nu, period_ratio : float, optional
        Spectral width and ``T01 / Tz``; default those of the Bretschneider spectrum.

    Returns
    -------
    ndarray
        Shape of the broadcast inputs.
    """
    nu = spectral_width() if nu is None else float(nu)
    ratio = bretschneider_period_ratio() if period_ratio is None else float(period_ratio)
    lam = np.asarray(lambda_over_L, dtype=float) * L
    s = np.asarray(steepness, dtype=float)
    H = s * lam
    T = np.sqrt(2.0 * math.pi * lam / g)
    T01 = ratio * Tz
    R = math.sqrt(2.0) * H / Hs
    p_HT = lh83_density(R, T / T01, nu) * math.sqrt(2.0) / Hs / T01
    p_Hlam = p_HT * T / (2.0 * lam)
    return p_Hlam * lam * L


def wave_case_weights(
    lambda_over_L: FloatArray,
    steepness: FloatArray,
    d_lambda_over_L: float,
    d_steepness: float,
    L: float,
    Hs: float,
    Tz: float,
    *,
    g: float = G_STANDARD,
) -> FloatArray:
    r"""Weights ``w_ij`` of the wave cases (Level 2; midpoint rule of the
    Longuet-Higgins density over the cell of each grid point).

    Parameters
    ----------
    lambda_over_L : ndarray, shape (n_lambda,)
    steepness : ndarray, shape (n_s,)
    d_lambda_over_L, d_steepness : float
        Cell sizes.
    L, Hs, Tz, g : float
        As for :func:`wave_case_density`.

    Returns
    -------
    ndarray, shape (n_lambda, n_s)
        ``w_ij``; their sum is the probability of the grid's band of waves (< 1).
    """
    lam = np.asarray(lambda_over_L, dtype=float)[:, None]
    s = np.asarray(steepness, dtype=float)[None, :]
    return wave_case_density(lam, s, L, Hs, Tz, g=g) * d_lambda_over_L * d_steepness


def band_probability(
    lambda_min: float, lambda_max: float, Tz: float, *, g: float = G_STANDARD
) -> float:
    r"""Closed form: probability of a local wavelength in ``[lambda_min, lambda_max]`` (m),
    any height.

    Integrating :func:`lh83_density` over ``R`` gives
    ``p(tau) = L(nu) / (2 nu tau^2 (1 + x^2)^{3/2})`` with ``x = (1 - 1/tau)/nu``, whose
    integral is ``L(nu)/2 [x / sqrt(1 + x^2)]`` between the limits.
    """
    nu = spectral_width()
    T01 = bretschneider_period_ratio() * Tz

    def q(lam: float) -> float:
        if lam <= 0.0:
            return -1.0
        if math.isinf(lam):
            return 1.0 / math.sqrt(1.0 + nu * nu)
        tau = math.sqrt(2.0 * math.pi * lam / g) / T01
        x = (1.0 - 1.0 / tau) / nu
        return x / math.sqrt(1.0 + x * x)

    return 0.5 * lh83_normalisation(nu) * (q(lambda_max) - q(lambda_min))


__all__ = [
    "G_STANDARD",
    "band_probability",
    "bretschneider_period_ratio",
    "lh83_density",
    "lh83_normalisation",
    "spectral_width",
    "wave_case_density",
    "wave_case_weights",
]
