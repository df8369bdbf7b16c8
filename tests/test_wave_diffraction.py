"""G.I. Taylor's (1928) long-wave diffraction correction of the wave surge force.

References used as test values:

- Taylor, G.I. 1928, Proc. R. Soc. Lond. A 120:260-283: the force on a body in a
  long non-uniform stream is (rho V + m_11) DU/Dt; for a sphere m_11 = rho V / 2
  (Lamb, H. 1932, "Hydrodynamics", 6th ed., Sect. 92), so the ratio is exactly 1/2.
- Long-wave limit of the Froude-Krylov strip integral: X_FK -> rho V a omega^2
  (the undisturbed acceleration a omega^2 = g k a over the displaced volume).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ship_models import load_vessel, resolve_vessel
from ship_models.contracts import SeaState
from ship_models.hydro.diffraction import (
    taylor_diffraction_ratio,
    taylor_long_wave_surge_force,
)
from ship_models.vessel import DATA_DIR, VesselFileError

BASE = (DATA_DIR / "purse_seiner.toml").read_text()


def _write(tmp_path: Path, extra_meta: str = "", extra_hydro: str = "") -> Path:
    text = BASE.replace('name = "purse_seiner"', 'name = "ps_variant"\n' + extra_meta, 1)
    if extra_hydro:
        assert "[hydrodynamics]" in text
        text = text.replace("[hydrodynamics]\n", "[hydrodynamics]\n" + extra_hydro, 1)
    p = tmp_path / "ps_variant.toml"
    p.write_text(text)
    return p


def _amplitudes(strips, chi, lam_over_L, H_over_lambda=0.05):
    """Amplitudes of X_w, Y_w, N_w, K_w over xi_G (each is A sin(k xi_G + phase))."""
    sea = SeaState(H_over_lambda, lam_over_L)
    out = []
    for xi in (0.0, 0.25):
        out.append(np.array(strips.forces(xi, 5.0, chi, sea, lift=False)))
    return np.hypot(out[0], out[1])


@pytest.fixture(scope="module")
def fk():
    return resolve_vessel(load_vessel(DATA_DIR / "purse_seiner.toml"))


def test_sphere_ratio_is_one_half():
    rho, vol = 1025.0, 4.0 / 3.0 * math.pi * 0.5**3
    assert taylor_diffraction_ratio(0.5 * rho * vol, rho, vol) == pytest.approx(0.5, rel=1e-15)
    F = taylor_long_wave_surge_force(rho, vol, 0.5 * rho * vol, 2.0)
    assert F == pytest.approx(1.5 * rho * vol * 2.0, rel=1e-15)


@pytest.mark.parametrize("args", [(-1.0, 1025.0, 1.0), (1.0, 0.0, 1.0), (1.0, 1025.0, math.nan)])
def test_bad_arguments_raise(args):
    with pytest.raises(ValueError, match="must be finite"):
        taylor_diffraction_ratio(*args)


def test_froude_krylov_long_wave_limit_is_taylor_premise(fk):
    """X_FK / (rho V g k a) -> 1 as lambda/L -> infinity, at first order in k.

    The first-order error is the depth decay e^{k zeta} over the draft (about k d/2),
    so halving k halves the error and the Richardson extrapolation vanishes.
    """
    st = fk.forces.waves
    V = fk.hull.volume
    errs = []
    for lam_over_L in (20.0, 40.0, 80.0):
        lam = lam_over_L * st.L
        k = 2 * math.pi / lam
        a = 0.5 * 0.05 * lam
        X = _amplitudes(st, 0.0, lam_over_L)[0]
        errs.append(X / (st.rho * V * st.g * k * a) - 1.0)
    assert abs(errs[-1]) < 5e-3
    for e0, e1 in zip(errs[:-1], errs[1:], strict=True):
        assert 0.4 < e1 / e0 < 0.6  # first order
    assert abs(2.0 * errs[2] - errs[1]) < 0.2 * abs(errs[2])


def test_selected_model_scales_surge_force_by_taylor_ratio(tmp_path, fk):
    v = load_vessel(_write(tmp_path, 'wave_surge_model = "froude_krylov_taylor"'))
    assert v.wave_surge_model == "froude_krylov_taylor"
    tay = resolve_vessel(v)
    r_D = fk.forces.m_x / (fk.forces.rho * fk.hull.volume)
    c = tay.vessel.coefficients["hydrodynamics.wave_surge_diffraction"]
    assert c.status == "estimated" and "Taylor" in c.source
    assert c.value == pytest.approx(r_D, rel=1e-14)
    assert 0.0 < r_D < 0.5  # a ship's surge added mass is a small part of its mass
    for chi, lam in ((0.0, 1.5), (math.radians(10.0), 1.0), (math.radians(30.0), 3.0)):
        a_fk = _amplitudes(fk.forces.waves, chi, lam)
        a_t = _amplitudes(tay.forces.waves, chi, lam)
        assert a_t[0] / a_fk[0] == pytest.approx(1.0 + r_D, rel=1e-12)
        np.testing.assert_allclose(a_t[1:], a_fk[1:], rtol=1e-13)  # Y, N, K untouched


def test_given_ratio_and_scale_override(tmp_path, fk):
    hydro = (
        'wave_surge_diffraction = { value = 0.05, unit = "-", source = "test", '
        'status = "measured" }\n'
        'wave_surge_scale = { value = 0.9, unit = "-", source = "test", status = "measured" }\n'
    )
    tay = resolve_vessel(
        load_vessel(_write(tmp_path, 'wave_surge_model = "froude_krylov_taylor"', hydro))
    )
    a_fk = _amplitudes(fk.forces.waves, 0.0, 1.5)[0]
    a_t = _amplitudes(tay.forces.waves, 0.0, 1.5)[0]
    assert a_t / a_fk == pytest.approx(0.9 * 1.05, rel=1e-12)


def test_default_model_has_no_diffraction(fk):
    assert fk.vessel.wave_surge_model == "froude_krylov"
    assert "hydrodynamics.wave_surge_diffraction" not in fk.vessel.coefficients
    assert fk.forces.waves.surge_scale == 1.0


def test_unknown_model_is_refused(tmp_path):
    with pytest.raises(VesselFileError, match="wave_surge_model"):
        load_vessel(_write(tmp_path, 'wave_surge_model = "strip_diffraction"'))
