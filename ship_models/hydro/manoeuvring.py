r"""Linear manoeuvring derivatives of the hull and the rudder.

Hull (Inoue, S., Hirano, M. & Kijima, K. 1981, "Hydrodynamic derivatives on ship
manoeuvring", Int. Shipbuilding Progress 28(321):112-125), with
:math:`k = 2 d_m / L` and the trim ratio :math:`\tau' = (d_a - d_f)/d_m`:

.. math::

    Y'_v &= -(\tfrac{\pi}{2}k + 1.4\,C_b B/L)\,(1 + \tfrac23\tau'), \qquad
    Y'_r = \tfrac{\pi}{4}k\,(1 + 0.8\,\tau'), \\
    N'_v &= -k\,(1 - 0.27\,\tau'/l'_v), \quad l'_v = N'_{v0}/Y'_{v0}, \qquad
    N'_r = -(0.54 k - k^2)(1 + 0.3\,\tau'),

non-dimensionalised with :math:`\tfrac12\rho L d U` (``Y_v``),
:math:`\tfrac12\rho L^2 d U` (``Y_r``, ``N_v``) and :math:`\tfrac12\rho L^3 d U`
(``N_r``); they are the hull forces of the MMG form
:math:`(m + m_y)\dot v = -(m + m_x) u r + Y_v v + Y_r r + \dots` of Umeda (1999) Eq. (6).

Rudder lift slope (Fujii, H. & Tsuda, T. 1961, "Experimental researches on rudder
performance (2)", J. Zosen Kiokai 110:31-42):
:math:`f_\alpha = 6.13\,\Lambda / (\Lambda + 2.25)` per rad.
"""

from __future__ import annotations

import numpy as np


def inoue_hull_derivatives(
    L: float, B: float, d_m: float, trim: float, C_b: float
) -> dict[str, float]:
    """Hull derivatives ``Y_v', Y_r', N_v', N_r'`` of Inoue et al. (1981).

    Parameters
    ----------
    L, B, d_m : float
        Length, breadth, mean draft (m).
    trim : float
        ``d_a - d_f`` (m), positive by the stern.
    C_b : float
        Block coefficient.
    """
    k = 2.0 * d_m / L
    tau = trim / d_m
    Yv0 = -(0.5 * np.pi * k + 1.4 * C_b * B / L)
    Nv0 = -k
    lv = Nv0 / Yv0
    return {
        "Y_v_prime": float(Yv0 * (1.0 + 2.0 * tau / 3.0)),
        "Y_r_prime": float(0.25 * np.pi * k * (1.0 + 0.8 * tau)),
        "N_v_prime": float(Nv0 * (1.0 - 0.27 * tau / lv)),
        "N_r_prime": float(-(0.54 * k - k * k) * (1.0 + 0.3 * tau)),
    }


def fujii_lift_slope(aspect_ratio: float) -> float:
    """Rudder normal-force slope ``6.13 Lambda / (Lambda + 2.25)`` per rad (Fujii 1961)."""
    return 6.13 * aspect_ratio / (aspect_ratio + 2.25)


__all__ = ["fujii_lift_slope", "inoue_hull_derivatives"]
