r"""Roll inertia from the natural period, and roll damping with forward speed.

- Inertia: the undamped linear roll equation
  :math:`(I_{xx} + J_{xx})\ddot\phi + m g GM \phi = 0` has period :math:`T_\phi`, so
  :math:`I_{xx} + J_{xx} = m g\,GM\,(T_\phi / 2\pi)^2`.
- Zero-speed damping from an equivalent linear damping ratio :math:`\zeta_0`:
  :math:`K_p(0) = -2\zeta_0\,\omega_\phi (I_{xx} + J_{xx})`,
  :math:`\omega_\phi = 2\pi/T_\phi` (roll-decay data of the paper are not available).
- Forward-speed increase: the hull lift component of Ikeda, Y., Himeno, Y. & Tanaka,
  N. (1978), "Components of roll damping of ship at forward speed", J. Soc. Naval
  Arch. Japan 143:113-125 (also ITTC 2011 Recommended Procedure 7.5-02-07-04.5,
  Sect. 2.2.2), used here as a named substitute for Takahashi's formula of the
  paper:

  .. math::

      B_L = \tfrac12\rho S_L U k_N l_0 l_R
            \Bigl(1 + 1.4\,\frac{OG}{l_R} + 0.7\,\frac{OG^2}{l_0 l_R}\Bigr),

  :math:`S_L = L d`, :math:`l_0 = 0.3 d`, :math:`l_R = 0.5 d`,
  :math:`k_N = 2\pi d/L + \kappa(4.1 B/L - 0.045)` (:math:`\kappa = 0` for
  :math:`C_M \le 0.92`, 0.1 up to 0.97, 0.3 above), OG the depth of G below the
  waterline. Then :math:`K_p(u) = K_p(0) - B_L'\,u`.
"""

from __future__ import annotations

import numpy as np


def roll_inertia(mass: float, g: float, GM: float, T_phi: float) -> float:
    """``I_xx + J_xx = m g GM (T_phi / 2 pi)^2`` (kg m^2)."""
    return mass * g * GM * (T_phi / (2.0 * np.pi)) ** 2


def ikeda_lift_damping_per_speed(
    rho: float, L: float, B: float, d: float, C_M: float, OG: float
) -> float:
    """Ikeda's hull-lift roll damping divided by the speed, ``B_L / U`` (N m s / rad / (m/s))."""
    if C_M <= 0.92:
        kap = 0.0
    elif C_M <= 0.97:
        kap = 0.1
    else:
        kap = 0.3
    kN = 2.0 * np.pi * d / L + kap * (4.1 * B / L - 0.045)
    l0, lR = 0.3 * d, 0.5 * d
    return 0.5 * rho * L * d * kN * l0 * lR * (1.0 + 1.4 * OG / lR + 0.7 * OG**2 / (l0 * lR))


__all__ = ["ikeda_lift_damping_per_speed", "roll_inertia"]
