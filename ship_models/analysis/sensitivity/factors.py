"""Factors on intermediate quantities of the force model, and the key classes.

See :mod:`ship_models.analysis.sensitivity` for what each factor scales.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from continuation.ops import NUMPY_OPS, Ops

from ...contracts import WaveForceModel
from ...estimation import VesselModelData
from ...forces import ShipForces

#: Factors on intermediate quantities of the force model (name -> description).
FACTORS: dict[str, str] = {
    "factor.R_surf": "resistance R(u) in the surge equation (n(Fn) held)",
    "factor.T_surf": "thrust T(u; n) in the surge equation (n held)",
    "factor.R_nominal": "R(u0) in the calm-water balance that sets n(Fn)",
    "factor.Y_w": "amplitude of the wave sway force Y_w",
    "factor.N_w": "amplitude of the wave yaw moment N_w",
    "factor.K_w": "amplitude of the wave roll moment K_w",
}

#: Vessel keys that are parameters of the dynamical system (exact CasADi derivative).
SYSTEM_PARAMS: dict[str, str] = {
    "waves.H_over_lambda": "H_over_lambda",
    "waves.lambda_over_L": "lambda_over_L",
    "autopilot.K_R": "K_R",
    "autopilot.T_D": "T_D",
}

#: Coefficients that set the numerical discretisation of the estimation, not the ship.
#: Their derivatives are reported (kind ``"numerical"``) but measure the local response
#: of a least-squares fit, not a convergence error: e.g. halving
#: ``resistance.knot_spacing_Fn`` moves Fn* by -5.5e-5 (R-fit error 0.56 % -> 0.24 %),
#: not by the +3.8e-3 its derivative would extrapolate.
NUMERICAL_KEYS = frozenset(
    {
        "resistance.Fn_max_fit",
        "resistance.knot_spacing_Fn",
        "propulsion.J_max_fit",
        "stability.heel_step",
    }
)

_KT = ("propulsion.K_T0", "propulsion.K_T1", "propulsion.K_T2")


@dataclass(frozen=True)
class _FactoredWaves:
    """A wave-force model with factors on the lateral force amplitudes."""

    inner: WaveForceModel
    f_Y: float = 1.0
    f_N: float = 1.0
    f_K: float = 1.0

    @property
    def name(self) -> str:
        return self.inner.name

    def forces(self, *args: Any, **kwargs: Any) -> tuple[Any, Any, Any, Any]:
        X, Y, N, K = self.inner.forces(*args, **kwargs)
        return X, self.f_Y * Y, self.f_N * N, self.f_K * K


@dataclass(frozen=True)
class _FactoredForces(ShipForces):
    """Ship forces with factors on R and T in the surge equation and on R(u0) in n(Fn)."""

    f_R_surf: float = 1.0
    f_T_surf: float = 1.0
    f_R_nominal: float = 1.0

    def resistance_force(self, u: Any, ops: Ops = NUMPY_OPS) -> Any:
        return self.f_R_surf * super().resistance_force(u, ops)

    def thrust_force(self, u: Any, n: Any, ops: Ops = NUMPY_OPS) -> Any:
        return self.f_T_surf * super().thrust_force(u, n, ops)

    def revolutions(self, Fn: Any, ops: Ops = NUMPY_OPS) -> Any:
        u0 = self.nominal_speed(Fn)
        return self.revolutions_for(u0, self.f_R_nominal * self.resistance.evaluate(u0, ops), ops)


def _with_factors(data: VesselModelData, factors: Mapping[str, float]) -> VesselModelData:
    unknown = sorted(set(factors) - set(FACTORS))
    if unknown:
        raise ValueError(f"`factors`: unknown factor(s) {unknown}; known are {list(FACTORS)}")
    if all(float(v) == 1.0 for v in factors.values()):
        return data
    F = data.forces
    waves = _FactoredWaves(
        F.waves,
        f_Y=float(factors.get("factor.Y_w", 1.0)),
        f_N=float(factors.get("factor.N_w", 1.0)),
        f_K=float(factors.get("factor.K_w", 1.0)),
    )
    kw = {f.name: getattr(F, f.name) for f in dataclasses.fields(ShipForces)}
    kw["waves"] = waves
    forces = _FactoredForces(
        **kw,
        f_R_surf=float(factors.get("factor.R_surf", 1.0)),
        f_T_surf=float(factors.get("factor.T_surf", 1.0)),
        f_R_nominal=float(factors.get("factor.R_nominal", 1.0)),
    )
    return dataclasses.replace(data, forces=forces)
