r"""External forces of Umeda's (1999) surge-sway-yaw-roll model, written once with ``ops``.

:class:`ShipForces` holds every number the equations of motion need (SI units) and
evaluates the terms of Eqs. (4)-(11) with NumPy or CasADi operands, so that the
4-DOF model (:mod:`ship_models.umeda_4dof`) and the uncoupled surge model
(:mod:`ship_models.surge`) share one source of truth. It is built from a vessel file
by :func:`ship_models.estimation.build_forces`.

Rudder force (MMG form, linear in the angle of attack; Yasukawa, H. & Yoshimura, Y.
2015, "Introduction of MMG standard method for ship maneuvering predictions",
J. Mar. Sci. Technol. 20:37-52):

.. math::

    F_N &= \tfrac12\rho A_R f_\alpha\,\bigl(u_R^2\,\delta + \gamma_R u_R (v + l_R r)\bigr),\\
    Y_R &= -(1 + a_H) F_N,\quad N_R = -(x_R + a_H x_H) F_N,\quad
    K_R = (z_R + a_H z_H) F_N,\\
    u_R &= \varepsilon\sqrt{\eta\,\bigl((1-\kappa) u_a + \kappa Q\bigr)^2 + (1-\eta) u_a^2},
    \quad Q = \sqrt{u_a^2 + 8 K_T n^2 D_p^2/\pi},\ u_a = (1 - w_P) u,

(positive :math:`\delta` turns the bow to starboard; :math:`Q` is the fully developed
propeller-race speed of momentum theory, written without division by J so it stays
smooth at ``n -> 0``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from continuation.ops import NUMPY_OPS, Ops
from continuation.typing import FloatArray

from .contracts import WaveForceModel
from .hydro.propeller import revolutions, thrust
from .hydro.resistance import ResistanceFit

_EPS2 = 1e-12  # (m/s)^2 regularisation of square roots at u = n = 0


@dataclass(frozen=True)
class ShipForces:
    """All coefficients of the equations of motion (SI units, body axes at G).

    Attributes
    ----------
    rho, g, L, B, d_m : float
        Water density, gravity, length, breadth, mean draft.
    mass, m_x, m_y : float
        Ship mass and surge/sway added masses (kg).
    I_zz, J_zz, I_xx_J_xx : float
        Yaw inertia, yaw added inertia, roll inertia including added (kg m^2).
    Y_v1, Y_r1, N_v1, N_r1 : float
        Hull derivatives per unit surge speed: ``Y_v = Y_v1 u`` etc.
    Y_phi2, N_phi2, K_phi2 : float
        Heel derivatives per unit speed squared: ``Y_phi = Y_phi2 u^2`` etc.
    z_H : float
        Depth of the hull lateral force below G (m); hull ``K_v = -z_H Y_v``.
    K_p0, K_p1 : float
        Roll damping ``K_p(u) = K_p0 + K_p1 u`` (both <= 0, N m s).
    A_R, f_alpha, a_H, x_R, x_H, z_R, gamma_R, l_R, epsilon, kappa, eta : float
        Rudder model (see module doc); ``x_R, x_H`` from G, ``z_R`` below G.
    D_p, w_P, t_P : float
        Propeller diameter, wake and thrust-deduction fractions.
    kt : tuple of float
        ``(k0, k1, k2)`` of ``K_T(J) = k0 + k1 J + k2 J^2``.
    resistance : ResistanceFit
        Calm-water resistance curve.
    gz_coeffs : ndarray, shape (n,)
        ``GZ(phi) = sum_i gz_coeffs[i-1] sin(i phi)`` (m).
    waves : WaveForceModel
        The wave forces (:class:`~ship_models.contracts.WaveForceModel`; by default
        the Froude-Krylov strips :class:`~ship_models.hydro.waves.WaveStrips`).
    T_E, delta_max : float
        Steering-gear time constant (s) and rudder limit (rad).
    propeller : Propeller or None
        General open-water model (K_T curve, speed-dependent w_P, t_P,
        :class:`~ship_models.hydro.propeller.Propeller`); None: the quadratic ``kt``
        with constant ``w_P``, ``t_P`` (closed-form revolutions).
    validity : tuple of ValidityRange
        Ranges of the surge-balance estimates (:mod:`ship_models.validity`).
    """

    rho: float
    g: float
    L: float
    B: float
    d_m: float
    mass: float
    m_x: float
    m_y: float
    I_zz: float
    J_zz: float
    I_xx_J_xx: float
    Y_v1: float
    Y_r1: float
    N_v1: float
    N_r1: float
    Y_phi2: float
    N_phi2: float
    K_phi2: float
    z_H: float
    K_p0: float
    K_p1: float
    A_R: float
    f_alpha: float
    a_H: float
    x_R: float
    x_H: float
    z_R: float
    gamma_R: float
    l_R: float
    epsilon: float
    kappa: float
    eta: float
    D_p: float
    w_P: float
    t_P: float
    kt: tuple[float, float, float]
    resistance: ResistanceFit
    gz_coeffs: FloatArray
    waves: WaveForceModel
    T_E: float
    delta_max: float
    propeller: Any = None
    validity: tuple[Any, ...] = ()

    # ------------------------------------------------------------------ waves
    def wavelength(self, lambda_over_L: Any) -> Any:
        """Wavelength ``lambda`` (m)."""
        return lambda_over_L * self.L

    def celerity(self, lambda_over_L: Any, ops: Ops = NUMPY_OPS) -> Any:
        r"""Deep-water wave celerity :math:`c = \sqrt{g\lambda/2\pi}` (m/s)."""
        return ops.sqrt(self.g * lambda_over_L * self.L / (2.0 * ops.pi))

    def nominal_speed(self, Fn: Any) -> Any:
        """``u0 = Fn sqrt(g L)`` (m/s)."""
        return Fn * float(np.sqrt(self.g * self.L))

    # ------------------------------------------------------------------ surge
    def resistance_force(self, u: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Calm-water resistance ``R(u)`` (N)."""
        return self.resistance.evaluate(u, ops)

    def revolutions(self, Fn: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Commanded propeller revolution ``n(Fn)`` (1/s): ``T(u0; n) = R(u0)``."""
        u0 = self.nominal_speed(Fn)
        return self.revolutions_for(u0, self.resistance.evaluate(u0, ops), ops)

    def revolutions_for(self, u0: Any, R0: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Revolution ``n`` with ``T(u0; n) = R0`` (1/s)."""
        if self.propeller is not None:
            return self.propeller.revolutions(u0, R0, self.rho, ops)
        return revolutions(
            u0,
            R0,
            rho=self.rho,
            D_p=self.D_p,
            w_P=self.w_P,
            t_P=self.t_P,
            k=self.kt,
            ops=ops,
        )

    def thrust_force(self, u: Any, n: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Effective propeller thrust ``T(u; n)`` (N)."""
        if self.propeller is not None:
            return self.propeller.thrust(u, n, self.rho, ops)
        return thrust(u, n, rho=self.rho, D_p=self.D_p, w_P=self.w_P, t_P=self.t_P, k=self.kt)

    def surge_acceleration(self, u: Any, n: Any, X_w: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Eq. (5): ``(T(u; n) - R(u) + X_w) / (m + m_x)`` (m/s^2).

        Parameters
        ----------
        u, n : scalar
            Surge velocity (m/s) and propeller revolution (1/s).
        X_w : scalar
            Wave surge force (N): ``waves.forces(...)[0]`` (:attr:`waves`).
        ops : Ops
            NumPy or CasADi namespace.
        """
        return (self.thrust_force(u, n, ops) - self.resistance_force(u, ops) + X_w) / (
            self.mass + self.m_x
        )

    def check_validity(self, Fn: float, lambda_over_L: float, vessel: str = "") -> list[str]:
        """Check the speeds of an analysis at ``Fn`` against :attr:`validity`.

        The surge speeds visited run up to the wave celerity ``c``, and ``n(Fn)`` is
        set at ``u0 = Fn sqrt(g L)``: each range is evaluated at both (for ``"J"``
        ranges at the commanded revolution). Leaving a range is logged once
        (:func:`ship_models.validity.report`).

        Returns
        -------
        list of str
            The coefficients used outside their range at these parameters.
        """
        from .validity import report

        out: list[str] = []
        if not self.validity or not Fn > 0:
            return out
        sqrt_gL = float(np.sqrt(self.g * self.L))
        u0 = float(self.nominal_speed(Fn))
        c = float(self.celerity(lambda_over_L))
        n = None
        for rng in self.validity:
            for u, where in ((u0, f"the nominal speed (Fn {Fn:.4g})"),
                             (c, f"wave celerity (Fn {c / sqrt_gL:.4g})")):  # fmt: skip
                if rng.variable == "Fn":
                    val = u / sqrt_gL
                elif rng.variable == "u":
                    val = u
                else:
                    if n is None:
                        n = float(self.revolutions(Fn))
                    w = self.w_P if self.propeller is None else float(self.propeller.wake(u))
                    val = (1.0 - w) * u / (n * self.D_p)
                    where = f"{where}, n = {n:.4g} 1/s"
                if report(vessel, rng, val, where) and rng.coefficient not in out:
                    out.append(rng.coefficient)
        return out

    # ------------------------------------------------------------------ rudder
    def rudder_speed(self, u: Any, n: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Effective inflow speed at the rudder ``u_R`` (m/s)."""
        if self.propeller is not None:
            ua = (1.0 - self.propeller.wake(u, ops)) * u
            q = ua * ua + 8.0 / np.pi * self.propeller.loading(ua, n, ops)
        else:
            ua = (1.0 - self.w_P) * u
            D = self.D_p
            k0, k1, k2 = self.kt
            q = ua * ua + 8.0 / np.pi * (k0 * n * n * D * D + k1 * ua * n * D + k2 * ua * ua)
        Q = ops.sqrt(ops.fmax(q, 0.0) + _EPS2)
        inner = (1.0 - self.kappa) * ua + self.kappa * Q
        return self.epsilon * ops.sqrt(
            self.eta * inner * inner + (1.0 - self.eta) * ua * ua + _EPS2
        )

    def rudder_normal_force(
        self, u: Any, v: Any, r: Any, delta: Any, n: Any, ops: Ops = NUMPY_OPS
    ) -> Any:
        """Rudder normal force ``F_N`` (N), linear in the angle of attack."""
        uR = self.rudder_speed(u, n, ops)
        return (
            0.5
            * self.rho
            * self.A_R
            * self.f_alpha
            * (uR * uR * delta + self.gamma_R * uR * (v + self.l_R * r))
        )

    # ------------------------------------------------------------------ roll
    def gz(self, phi: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Righting arm ``GZ(phi)`` (m), odd sine series."""
        i = np.arange(1, self.gz_coeffs.size + 1, dtype=float)
        if ops.name == "casadi":
            return ca.dot(ca.DM(self.gz_coeffs), ca.sin(ca.DM(i) * phi))
        return np.sin(np.multiply.outer(phi, i)) @ self.gz_coeffs

    def roll_damping(self, u: Any) -> Any:
        """``K_p(u) = K_p0 + K_p1 u`` (N m s), negative."""
        return self.K_p0 + self.K_p1 * u

    @property
    def weight(self) -> float:
        """``m g`` (N)."""
        return self.mass * self.g

    def derivative_table(self, u: float) -> dict[str, float]:
        """Dimensional linear derivatives at surge speed ``u`` (for reports)."""
        return {
            "Y_v": self.Y_v1 * u,
            "Y_r": self.Y_r1 * u,
            "N_v": self.N_v1 * u,
            "N_r": self.N_r1 * u,
            "K_v": -self.z_H * self.Y_v1 * u,
            "K_r": -self.z_H * self.Y_r1 * u,
            "K_p": float(self.roll_damping(u)),
        }


__all__ = ["ShipForces"]
