"""The vessel and wave-force contracts: a toy vessel with its own wave-force model.

The toy vessel is the purse seiner with a wave-force model of its own class, which
scales the Froude-Krylov surge force by KAPPA. The same physics reaches the model by an
independent path: the vessel file's ``hydrodynamics.wave_surge_scale = KAPPA`` on the
default strips. Fixed points, the critical Fn and its sensitivity of the toy model must
equal those of that reference (and differ from the unscaled ship): so every analysis,
the rebuilds of sensitivity included, sees the plugged-in forces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from continuation.ops import NUMPY_OPS, Ops
from ship_models import get_model, register_model
from ship_models.analysis.critical_bvp import critical_fn_bvp
from ship_models.analysis.fixed_points import find_fixed_point
from ship_models.analysis.sensitivity import critical_fn_sensitivity, model_at
from ship_models.contracts import (
    SeaState,
    VesselModel,
    WaveForceModel,
    WaveInputs,
    wave_model_name,
)
from ship_models.estimation import build_vessel_model
from ship_models.hydro.waves import WaveStrips, strip_waves
from ship_models.registry import unregister_model
from ship_models.umeda_4dof import Umeda4DOF
from ship_models.vessel import load_vessel

KAPPA = 0.8
CHI = math.radians(10.0)
KEYS = ("propulsion.w_P", "factor.Y_w")


@dataclass(frozen=True)
class ScaledSurgeWaves:
    """A wave-force model of another class: strips with the surge force times kappa."""

    inner: WaveStrips
    kappa: float

    @property
    def name(self) -> str:
        return "toy_scaled_surge"

    def forces(
        self,
        xi_over_lambda: Any,
        u: Any,
        chi: Any,
        sea: SeaState,
        ops: Ops = NUMPY_OPS,
        *,
        lift: bool = True,
    ) -> tuple[Any, Any, Any, Any]:
        X, Y, N, K = self.inner.forces(xi_over_lambda, u, chi, sea, ops, lift=lift)
        return self.kappa * X, Y, N, K


def toy_waves(inputs: WaveInputs) -> ScaledSurgeWaves:
    """Builder of the toy wave-force model."""
    return ScaledSurgeWaves(strip_waves(inputs), KAPPA)


@pytest.fixture(scope="module")
def toy():
    register_model(
        "toy_scaled_surge_vessel",
        lambda **options: Umeda4DOF("purse_seiner", waves=toy_waves, **options),
        description="purse seiner with a toy wave-force model",
    )
    try:
        yield get_model("toy_scaled_surge_vessel")
    finally:
        unregister_model("toy_scaled_surge_vessel")


@pytest.fixture(scope="module")
def reference():
    v = load_vessel("purse_seiner").with_overrides({"hydrodynamics.wave_surge_scale": KAPPA})
    return Umeda4DOF(build_vessel_model(v))


@pytest.fixture(scope="module")
def plain():
    return get_model("purse_seiner")


@pytest.fixture(scope="module")
def connections(toy, reference, plain):
    out = {k: critical_fn_bvp(CHI, model=m) for k, m in
           (("toy", toy), ("reference", reference), ("plain", plain))}  # fmt: skip
    assert all(c.success for c in out.values()), {k: c.message for k, c in out.items()}
    return out


def test_models_conform_to_the_protocols(toy, plain):
    for m in (toy, plain):
        assert isinstance(m, VesselModel)
        assert isinstance(m.forces.waves, WaveForceModel)
    assert wave_model_name(toy) == "toy_scaled_surge"
    assert wave_model_name(plain) == "froude_krylov_strips"
    assert toy.data.wave_builder is toy_waves


def test_toy_forces_equal_the_reference_forces(toy, reference):
    args = (0.37, 8.0, 0.3, SeaState(1 / 9.2, 1.5))
    np.testing.assert_allclose(
        toy.forces.waves.forces(*args), reference.forces.waves.forces(*args), rtol=1e-13
    )


def test_fixed_points_see_the_toy_forces(toy, reference, plain):
    p = plain.default_params()
    fp = {k: find_fixed_point(m, p, "crest") for k, m in
          (("toy", toy), ("reference", reference), ("plain", plain))}  # fmt: skip
    np.testing.assert_allclose(fp["toy"].x, fp["reference"].x, atol=1e-9)
    assert abs(fp["toy"].x[0] - fp["plain"].x[0]) > 1e-3


def test_critical_fn_sees_the_toy_forces(connections):
    c = connections
    # same physics by two code paths: equal within the connections' error estimates
    # (the adaptive meshes may differ in the last bits)
    tol = max(c["toy"].error, c["reference"].error)
    assert abs(c["toy"].Fn - c["reference"].Fn) <= tol
    assert abs(c["toy"].Fn - c["plain"].Fn) > 1e-3


def test_rebuilds_keep_the_wave_force_model(toy):
    raw = load_vessel("purse_seiner")
    m = model_at(raw, {"propulsion.w_P": 0.2}, {"factor.Y_w": 1.1}, model=toy)
    assert wave_model_name(m) == "toy_scaled_surge"
    assert isinstance(m, Umeda4DOF) and m.options == toy.options
    assert toy.rebuild(raw).data.wave_builder is toy_waves


def test_sensitivity_sees_the_toy_forces(toy, reference, plain, connections):
    raw = load_vessel("purse_seiner")
    ref_raw = raw.with_overrides({"hydrodynamics.wave_surge_scale": KAPPA})
    c = connections
    s_toy = critical_fn_sensitivity(CHI, vessel=raw, keys=KEYS, connection=c["toy"], model=toy)
    s_ref = critical_fn_sensitivity(
        CHI, vessel=ref_raw, keys=KEYS, connection=c["reference"], model=reference
    )
    s_plain = critical_fn_sensitivity(
        CHI, vessel=raw, keys=KEYS, connection=c["plain"], model=plain
    )
    for k in KEYS:
        d_toy, d_ref = s_toy.entry(k).dFn_dtheta, s_ref.entry(k).dFn_dtheta
        # same finite-difference steps on the same physics: equal up to rounding of the
        # residual differences (relative step 1e-4, residuals ~1e-12 -> ~1e-7 relative)
        assert d_toy == pytest.approx(d_ref, rel=1e-5, abs=1e-9), k
        assert abs(d_toy - s_plain.entry(k).dFn_dtheta) > 1e-3 * abs(d_toy), k
