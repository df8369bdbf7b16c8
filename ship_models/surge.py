r"""Uncoupled surge model: the chi_c = 0 reduction of Umeda's (1999) model.

With the autopilot course along the waves (chi_c = 0), lateral motions vanish
(v = chi = r = phi = p = delta = 0 is invariant) and Eqs. (4)-(5) reduce to

.. math::

    \dot\xi_G/\lambda = (u - c)/\lambda, \qquad
    \dot u = \{T(u; n) - R(u) + X_w(\xi_G/\lambda)\}/(m + m_x),

a pendulum-like system on the cylinder :math:`\xi_G/\lambda \in [0, 1)` (Grim 1951,
Makov 1969, Umeda & Kohyama 1990). It shares the force functions of
:class:`~ship_models.umeda_4dof.Umeda4DOF` (same :class:`~ship_models.forces.ShipForces`).

Fixed points have ``u = c`` and :math:`X_w(\xi) = R(c) - T(c; n)`; a linear
:math:`X_w` has two per wavelength when the right-hand side is smaller than its
amplitude: a saddle near the crest and a stable point near the trough.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.optimize as so

from continuation.newton import NewtonResult, newton
from continuation.ops import Ops
from continuation.params import Params
from continuation.settings import NewtonSettings
from continuation.typing import FloatArray

from .contracts import SeaState, WaveForceBuilder
from .estimation import VesselModelData
from .paper import PAPER_FN
from .umeda_4dof import VesselSystem
from .vessel import VesselData

SURGE_STATE_NAMES = ("xi_G", "u")
SURGE_PARAM_NAMES = ("Fn", "H_over_lambda", "lambda_over_L")


@dataclass(frozen=True)
class SurgeFixedPoint:
    """A fixed point of the surge model.

    Attributes
    ----------
    x : ndarray, shape (2,)
        ``(xi_G/lambda, u)``.
    eigenvalues : ndarray, shape (2,)
        Of the Jacobian.
    kind : str
        ``"saddle"``, ``"stable"`` or ``"unstable"``.
    newton : NewtonResult
        The verifying Newton solve started from the bracketing root.
    """

    x: FloatArray
    eigenvalues: FloatArray
    kind: str
    newton: NewtonResult


class SurgeModel(VesselSystem):
    """Uncoupled surge model (states ``xi_G``, ``u``) as a :class:`continuation.System`.

    Parameters
    ----------
    vessel : VesselData, str, Path or VesselModelData
        As for :class:`~ship_models.umeda_4dof.Umeda4DOF`; pass ``model.data`` to share
        an already resolved vessel.
    waves : WaveForceBuilder, optional
        Builds the wave-force model (default: Froude-Krylov strips).

    Parameters of the system: ``(Fn, H_over_lambda, lambda_over_L)``.
    """

    def __init__(
        self,
        vessel: VesselData | str | Path | VesselModelData = "purse_seiner",
        *,
        waves: WaveForceBuilder | None = None,
    ) -> None:
        super().__init__(
            vessel,
            waves,
            state_names=SURGE_STATE_NAMES,
            param_names=SURGE_PARAM_NAMES,
            defaults={
                "Fn": PAPER_FN,
                "H_over_lambda": "waves.H_over_lambda",
                "lambda_over_L": "waves.lambda_over_L",
            },
            label="surge",
        )

    def _rhs(self, x: Any, p: Any, ops: Ops) -> Any:
        F = self.forces
        xi, u = x[0], x[1]
        Fn, Hl, lL = p[0], p[1], p[2]
        n = F.revolutions(Fn, ops)
        f1 = (u - F.celerity(lL, ops)) / F.wavelength(lL)
        X_w = F.waves.forces(xi, u, 0.0, SeaState(Hl, lL), ops, lift=False)[0]
        f2 = F.surge_acceleration(u, n, X_w, ops)
        return ops.stack([f1, f2])

    def surge_force(
        self, xi: FloatArray | float, u: float, params: Params | FloatArray
    ) -> FloatArray:
        """``T(u; n) - R(u) + X_w(xi)`` (N) at the given xi values, shape like ``xi``."""
        pv = self.check_params(params)
        F = self.forces
        n = F.revolutions(pv[0])
        xi = np.asarray(xi, dtype=float)
        sea = SeaState(pv[1], pv[2])
        X = np.vectorize(lambda s: F.waves.forces(s, u, 0.0, sea, lift=False)[0])(xi)
        return F.thrust_force(u, n) - F.resistance_force(u) + X

    def fixed_points(
        self,
        params: Params | FloatArray,
        *,
        n_grid: int = 400,
        settings: NewtonSettings | None = None,
    ) -> list[SurgeFixedPoint]:
        """All fixed points in one wavelength: brentq on the surge acceleration at u = c
        (zero where the surge force ``T - R + X_w`` is), then Newton.

        Returns
        -------
        list of SurgeFixedPoint
            Sorted by ``xi_G``; empty if surf-riding is impossible for ``params``.
        """
        pv = self.check_params(params)
        c = self.celerity(pv)
        grid = np.linspace(0.0, 1.0, n_grid + 1)
        # du/dt at u = c: the surge force over the (positive) surge mass, so the same
        # sign changes and roots; evaluated by the CasADi trace, all grid points at once
        f_fun = self.casadi_functions()["f"]
        on_grid = f_fun.map(n_grid + 1)
        f = np.asarray(on_grid(np.vstack([grid, np.full_like(grid, c)]), pv))[1]
        out: list[SurgeFixedPoint] = []
        s = settings or NewtonSettings(tol=1e-10, max_iter=30)

        def acc(t: float) -> float:
            return float(f_fun(np.array([t, c]), pv)[1])

        for i in range(n_grid):
            if f[i] == 0.0 or f[i] * f[i + 1] < 0:
                xi0 = so.brentq(acc, grid[i], grid[i + 1], xtol=1e-14)
                res = newton(
                    lambda z: self.f(z, pv), lambda z: self.jacobian(z, pv), np.array([xi0, c]), s
                )
                ev = np.linalg.eigvals(self.jacobian(res.z, pv))
                re = np.real(ev)
                if np.all(re < 0):
                    kind = "stable"
                elif np.all(re > 0):
                    kind = "unstable"
                else:
                    kind = "saddle"
                z = res.z.copy()
                z[0] = np.mod(z[0], 1.0)
                out.append(SurgeFixedPoint(z, ev, kind, res))
        return sorted(out, key=lambda fp: fp.x[0])


__all__ = ["SURGE_PARAM_NAMES", "SURGE_STATE_NAMES", "SurgeFixedPoint", "SurgeModel"]
