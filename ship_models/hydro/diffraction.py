r"""Long-wave (G.I. Taylor) diffraction correction of the wave surge force.

Source
------
Taylor, G.I. 1928, "The forces on a body placed in a curved or converging stream
of fluid", Proc. R. Soc. Lond. A 120(785):260-283. For a body whose dimensions are
small compared with the length scale of a non-uniform, unsteady ambient flow
:math:`U(X, t)` (in waves: the wavelength), the force along the flow is

.. math::

    F = (\rho\nabla + m_{11})\,\frac{DU}{Dt},

the first term being the Froude-Krylov force (the undisturbed pressure gradient
over the displaced volume :math:`\nabla`) and the second the diffraction
(scattering) force, the added mass :math:`m_{11}` of the body in the direction of
the flow times the fluid-particle acceleration. The same result is the
long-wavelength approximation of the wave exciting force in Newman, J.N. 1977,
"Marine Hydrodynamics", MIT Press, Ch. 4 (force on a body in a non-uniform
accelerating stream) and in Sclavounos' MIT 13.022 notes ("Long Wavelength
Approximations: G.I. Taylor's formula", wikiwaves.org).

Model
-----
For linear waves the Froude-Krylov surge force is exactly the volume integral of
the undisturbed fluid acceleration, :math:`X_{FK} = \int_V \rho\,\partial_t u\,dV`
(Gauss's theorem on :math:`-\nabla p_d = \rho\,\partial_t \mathbf u`), so in the
long-wave limit :math:`X_{FK} \to \rho\nabla\,\dot u` and Taylor's diffraction part
is :math:`X_D = (m_{11}/\rho\nabla)\,X_{FK}`. This module applies that ratio at any
wavelength:

.. math::

    X_w = (1 + r_D)\,X_{FK}, \qquad r_D = \frac{m_x}{\rho\nabla},

with :math:`m_x` the vessel's surge added mass (Söding's fit of Motora's charts
unless given). At finite wavelength this is an *assumption*: it distributes the
added mass along the hull like the displaced volume (exact only for
:math:`\lambda \gg L`). Taylor's derivation is for a body in unbounded fluid; the
free surface and the forward speed enter only through :math:`m_x`.

Limits (tested): :math:`X_w/X_{FK} = 1 + r_D` for every wavelength; as
:math:`\lambda/L \to \infty` the strip Froude-Krylov amplitude tends to
:math:`\rho\nabla\,a\omega^2` (Taylor's premise), so :math:`X_w \to
(\rho\nabla + m_x)\,a\omega^2`; for a sphere (:math:`m_{11} = \rho\nabla/2`)
:math:`r_D = 1/2`.

Note the sign: Taylor's diffraction part is in phase with the Froude-Krylov force
and *increases* the surge force amplitude (so it lowers the surf-riding and
broaching threshold); it does not reproduce the reduction reported for small fishing
vessels in waves of ship length, which this long-wave theory cannot describe.
"""

from __future__ import annotations

import math


def taylor_diffraction_ratio(m_11: float, rho: float, volume: float) -> float:
    r"""Ratio :math:`r_D = X_D / X_{FK} = m_{11}/(\rho\nabla)` of Taylor (1928).

    Parameters
    ----------
    m_11 : float
        Added mass in the direction of the flow (surge), kg (>= 0).
    rho : float
        Water density, kg/m^3 (> 0).
    volume : float
        Displaced volume :math:`\nabla`, m^3 (> 0).

    Returns
    -------
    float
        :math:`r_D`; the wave surge force becomes :math:`(1 + r_D) X_{FK}`.
    """
    for name, val, lo in (("m_11", m_11, 0.0), ("rho", rho, None), ("volume", volume, None)):
        if not math.isfinite(val) or (val < 0.0 if lo is not None else val <= 0.0):
            raise ValueError(f"{name} must be finite and {'>= 0' if lo is not None else '> 0'}")
    return float(m_11 / (rho * volume))


def taylor_long_wave_surge_force(
    rho: float, volume: float, m_11: float, fluid_acceleration: float
) -> float:
    r"""Taylor's long-wave surge force :math:`(\rho\nabla + m_{11})\,\dot u` (N)."""
    taylor_diffraction_ratio(m_11, rho, volume)  # validates the arguments
    return float((rho * volume + m_11) * fluid_acceleration)


__all__ = ["taylor_diffraction_ratio", "taylor_long_wave_surge_force"]
