"""Sensitivity of the critical Fn: adjoint derivatives against re-solved connections."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from ship_models.analysis.critical_bvp import critical_fn_bvp
from ship_models.analysis.sensitivity import (
    FACTORS,
    critical_fn_sensitivity,
    model_at,
    resolve_at,
    tornado_figure,
    uncertainty_band,
)
from ship_models.estimation import build_vessel_model
from ship_models.umeda_4dof import Umeda4DOF
from ship_models.vessel import load_vessel

pytestmark = pytest.mark.slow  # each re-solve rebuilds the ship model (several seconds)

CHI = math.radians(10.0)
#: one of each kind: assumed file value, given value (estimates follow), estimated value,
#: factor on an intermediate quantity, system parameter (exact derivative)
KEYS = (
    "hydrodynamics.wave_surge_scale",
    "particulars.B",
    "propulsion.w_P",
    "factor.R_surf",
    "autopilot.K_R",
)


@pytest.fixture(scope="module")
def vessel():
    return load_vessel("purse_seiner")


@pytest.fixture(scope="module")
def resolved(vessel):
    return build_vessel_model(vessel).vessel


@pytest.fixture(scope="module")
def sens(vessel):
    model = Umeda4DOF(build_vessel_model(vessel))
    conn = critical_fn_bvp(CHI, model=model)
    assert conn.success
    return critical_fn_sensitivity(CHI, vessel=vessel, keys=KEYS, connection=conn, model=model)


def _fd(sens, vessel, resolved, key, rel=1e-3, same=True):
    """Central difference of re-solved critical Fn."""
    conn = sens.connection
    e = sens.entry(key)
    h = rel * abs(e.value)
    out = []
    for th in (e.value + h, e.value - h):
        if key in FACTORS:
            m = model_at(vessel, {}, {key: th}, resolved=resolved)
            out.append(resolve_at(conn, m, same_discretisation=same))
        elif key == "autopilot.K_R":
            out.append(resolve_at(conn, conn.orbit.problem.system, same_discretisation=same,
                                  params={"K_R": th}))  # fmt: skip
        else:
            m = model_at(vessel, {key: th}, resolved=resolved)
            out.append(resolve_at(conn, m, same_discretisation=same))
    return (out[0] - out[1]) / (2 * h)


@pytest.mark.parametrize("key", KEYS)
def test_adjoint_sensitivity_matches_resolved_connections(sens, vessel, resolved, key):
    """dFn*/dtheta (one adjoint solve) = central difference of re-solved Fn* to 1e-4."""
    e = sens.entry(key)
    fd = _fd(sens, vessel, resolved, key)
    assert e.dFn_dtheta == pytest.approx(fd, rel=1e-4)
    assert e.method == ("exact" if key == "autopilot.K_R" else "central")


def test_adjoint_sensitivity_matches_independent_full_resolves(sens, vessel, resolved):
    """Against full critical_fn_bvp re-solves (own padding, rebased problem): 1e-3."""
    key = "hydrodynamics.wave_surge_scale"
    fd = _fd(sens, vessel, resolved, key, rel=1e-2, same=False)
    assert sens.entry(key).dFn_dtheta == pytest.approx(fd, rel=1e-3)


def test_entries_sorted_json_and_physics(sens, tmp_path):
    els = [abs(e.elasticity) for e in sens.entries if e.elasticity is not None]
    assert els == sorted(els, reverse=True)
    d = json.loads(json.dumps(sens.to_json()))
    assert d["Fn"] == pytest.approx(sens.Fn) and len(d["entries"]) == len(KEYS)
    # a weaker wave surge force raises the threshold (more speed is needed to surf-ride);
    # more resistance near the wave celerity (n held) also raises it
    assert sens.entry("hydrodynamics.wave_surge_scale").dFn_dtheta < 0
    assert sens.entry("factor.R_surf").dFn_dtheta > 0
    assert sens.entry("factor.R_surf").quantity > 0  # R(c) in N
    p = tornado_figure(sens, tmp_path / "t.png")
    assert p.stat().st_size > 1000


def test_linear_band_against_sampled_connections(sens, vessel):
    """Linear propagation vs. re-solved samples, on three coefficients with uncertainties.

    The re-solved Fn of each sampled coefficient set must agree with the linear
    prediction to second order: for sigma scaled by 0.3, the remainder is below 5 % of
    the linear change (and the sampled spread within the expected scatter).
    """
    keep = ("hydrodynamics.wave_surge_scale", "propulsion.w_P", "factor.R_surf")
    unc = {k: u for k, u in vessel.uncertainties.items() if k in keep}
    v3 = dataclasses.replace(vessel, uncertainties=unc)
    band = uncertainty_band(sens, v3, n_samples=5, seed=3, scale=0.3)
    assert [k for k, _ in band.contributions] == [
        "hydrodynamics.wave_surge_scale", "propulsion.w_P",
    ]  # fmt: skip
    expect = math.hypot(*(v for _, v in band.contributions))
    assert band.sigma_linear == pytest.approx(expect, rel=1e-12)
    assert band.samples.size == 5 and band.failed == 0
    dlin = band.sample_linear - sens.Fn
    remainder = band.samples - band.sample_linear
    assert np.max(np.abs(remainder)) <= 0.05 * np.max(np.abs(dlin))


def test_wave_steepness_elasticity_is_the_sum_of_the_wave_force_factors(vessel, sens):
    """Every wave force is linear in H (celerity depends on lambda only), so the exact
    CasADi elasticity in H/lambda equals the sum of the rebuilt-model elasticities of
    the four wave-force amplitudes (X_w via wave_surge_scale, Y_w, N_w, K_w)."""
    keys = ("waves.H_over_lambda", "factor.Y_w", "factor.N_w", "factor.K_w")
    s2 = critical_fn_sensitivity(CHI, vessel=vessel, keys=keys, connection=sens.connection,
                                 model=sens.connection.orbit.problem.system)  # fmt: skip
    assert s2.entry("waves.H_over_lambda").method == "exact"
    total = sens.entry("hydrodynamics.wave_surge_scale").elasticity + sum(
        s2.entry(k).elasticity for k in keys[1:]
    )
    assert s2.entry("waves.H_over_lambda").elasticity == pytest.approx(total, rel=1e-5)
