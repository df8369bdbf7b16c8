r"""Added masses: surge (empirical), sway and yaw (strip theory with Lewis sections).

- Surge: :math:`m_x = 2.7\,\rho\,\nabla^{5/3} / L^2`, Söding's fit of Motora's charts
  (Söding, H. 1982, "Prediction of ship steering capabilities", Schiffstechnik
  29:3-29; Motora, S. 1959/60, "On the measurement of added mass and added moment of
  inertia for ship motions", J. Zosen Kiokai 105-106).
- Sway and yaw: strip theory at zero frequency (rigid free surface, the appropriate
  limit for manoeuvring), :math:`m_y = \int m'_{22}(x)\,dx`,
  :math:`J_{zz} = \int (x - x_G)^2 m'_{22}(x)\,dx`, with the sectional added mass of a
  Lewis form (Lewis, F.M. 1929, "The inertia of the water surrounding a vibrating
  ship", Trans. SNAME 37:1-20):

  .. math::

      m'_{22} = \frac{\rho\pi}{2}\,d^2\,\frac{(1 - a_1)^2 + 3 a_3^2}{(1 - a_1 + a_3)^2},

  which is the half of the double-body added mass of the mapped contour
  :math:`z = M(\zeta + a_1/\zeta + a_3/\zeta^3)` (a flat plate of span d gives
  :math:`\rho\pi d^2/2`, a half circle of radius d the same). The Lewis coefficients
  follow from the half-breadth-to-draft ratio :math:`H = b/d` and the section
  coefficient :math:`\sigma` (e.g. Journée & Massie 2001, "Offshore
  Hydromechanics", Delft, Sect. 6.3.2).
"""

from __future__ import annotations

import numpy as np

from continuation.typing import FloatArray


def lewis_coefficients(H: FloatArray, sigma: FloatArray) -> tuple[FloatArray, FloatArray]:
    r"""Lewis-form coefficients ``(a1, a3)`` from ``H = b/d`` and ``sigma = S/(2 b d)``.

    :math:`C_1 = 3 + 4\sigma/\pi + (1 - 4\sigma/\pi)\,((H-1)/(H+1))^2`,
    :math:`a_3 = (-C_1 + 3 + \sqrt{9 - 2 C_1})/C_1`, :math:`a_1 = (1 + a_3)(H-1)/(H+1)`.
    Where the square root would be imaginary (sections outside the Lewis family) the
    root is clipped at zero.
    """
    H = np.asarray(H, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    r = (H - 1.0) / (H + 1.0)
    C1 = 3.0 + 4.0 * sigma / np.pi + (1.0 - 4.0 * sigma / np.pi) * r**2
    a3 = (-C1 + 3.0 + np.sqrt(np.maximum(9.0 - 2.0 * C1, 0.0))) / C1
    a1 = (1.0 + a3) * r
    return a1, a3


def lewis_sway_added_mass(
    rho: float, b: FloatArray, d: FloatArray, sigma: FloatArray
) -> FloatArray:
    """Zero-frequency sway added mass per unit length of Lewis sections (kg/m)."""
    b = np.asarray(b, dtype=float)
    d = np.asarray(d, dtype=float)
    a1, a3 = lewis_coefficients(b / d, sigma)
    return 0.5 * rho * np.pi * d**2 * ((1.0 - a1) ** 2 + 3.0 * a3**2) / (1.0 - a1 + a3) ** 2


def soding_surge_added_mass(rho: float, volume: float, L: float) -> float:
    """Surge added mass ``2.7 rho V^(5/3) / L^2`` (Söding 1982, fit of Motora's charts)."""
    return 2.7 * rho * volume ** (5.0 / 3.0) / L**2


__all__ = ["lewis_coefficients", "lewis_sway_added_mass", "soding_surge_added_mass"]
