"""The 4-DOF model of Umeda (1999) and its uncoupled surge reduction."""

from __future__ import annotations

import numpy as np
import pytest

from continuation.newton import newton
from continuation.settings import NewtonSettings
from continuation.system import System, check_jacobian
from ship_models.surge import SurgeModel
from ship_models.umeda_4dof import PARAM_NAMES, STATE_NAMES, Umeda4DOF


@pytest.fixture(scope="module")
def surge(model) -> SurgeModel:
    return SurgeModel(model.data)


def test_interface(model):
    assert isinstance(model, System)
    assert model.state_names == STATE_NAMES
    assert model.param_names[:4] == ("Fn", "chi_c", "H_over_lambda", "lambda_over_L")
    assert model.param_names == PARAM_NAMES
    p = model.default_params()
    assert p["Fn"] == 0.3248 and p["chi_c"] == pytest.approx(np.deg2rad(10.0))
    assert p["H_over_lambda"] == pytest.approx(1 / 9.2) and p["lambda_over_L"] == 1.5
    assert model.index("phi") == 5 and model.period[0] == 1.0
    x = model.random_state(3)
    f_np = np.asarray(model.rhs(x, p.values), dtype=float)
    np.testing.assert_allclose(model.f(x, p.values), f_np, rtol=1e-12, atol=1e-14)
    with pytest.raises(ValueError, match="where"):
        model.equilibrium_guess(p, where="middle")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jacobians_against_finite_differences(model, surge, seed):
    x = model.random_state(seed)
    p = model.default_params().values
    ex, ep = check_jacobian(model, x, p)
    assert ex <= 1.0 and ep <= 1.0
    xs = x[:2]
    ex, ep = check_jacobian(surge, xs, surge.default_params().values)
    assert ex <= 1.0 and ep <= 1.0


@pytest.mark.parametrize("seed", [0, 5, 11])
def test_port_starboard_symmetry(model, seed):
    """(v, chi, r, phi, p, delta, chi_c) -> -(...) maps the rhs to the flipped rhs."""
    x = model.random_state(seed)
    p = model.default_params().values.copy()
    p[1] = 0.23
    flip = np.array([1, 1, -1, -1, -1, -1, -1, -1], dtype=float)
    pf = p.copy()
    pf[1] = -p[1]
    f = model.f(x, p)
    g = model.f(flip * x, pf)
    np.testing.assert_allclose(g, flip * f, rtol=1e-12, atol=1e-12 * np.max(np.abs(f)))


def test_calm_water_straight_running_and_no_surf_riding(model, surge):
    p = model.default_params().replace(H_over_lambda=0.0)
    F = model.forces
    u0 = F.nominal_speed(p["Fn"])
    chi_c = p["chi_c"]
    x_eq = np.array([0.3, u0, 0.0, chi_c, 0.0, 0.0, 0.0, 0.0])
    f = model.f(x_eq, p.values)
    assert np.max(np.abs(f[1:])) < 1e-9  # steady straight running, T(u0; n) = R(u0)
    expected = (u0 * np.cos(chi_c) - model.celerity(p)) / (1.5 * F.L)
    assert f[0] == pytest.approx(expected, rel=1e-12)
    # Newton on the seven non-cyclic equations converges to it from a perturbed start
    rest = slice(1, 8)

    def G(z):
        return model.f(np.concatenate([[0.3], z]), p.values)[rest]

    def JG(z):
        return model.jacobian(np.concatenate([[0.3], z]), p.values)[rest, rest]

    z0 = x_eq[1:] + np.array([0.4, 0.1, 0.05, 0.01, 0.02, 0.0, 0.03])
    res = newton(G, JG, z0, NewtonSettings(tol=1e-9, max_iter=30))
    assert res.converged
    np.testing.assert_allclose(res.z, x_eq[1:], atol=1e-8)
    # no surf-riding: in calm water the surge force vanishes only at u0 < c
    ps = surge.default_params().replace(H_over_lambda=0.0)
    c = surge.celerity(ps)
    u = np.linspace(0.2 * c, 1.5 * c, 400)
    f2 = np.array([surge.f(np.array([0.0, ui]), ps.values)[1] for ui in u])
    sign_changes = np.nonzero(np.diff(np.sign(f2)))[0]
    assert sign_changes.size == 1
    assert abs(u[sign_changes[0]] - u0) < (u[1] - u[0])
    assert u0 < c


def test_surge_model_is_the_chi_c_zero_reduction(model, surge):
    p4 = model.default_params().replace(chi_c=0.0)
    ps = surge.default_params()
    rng = np.random.default_rng(7)
    for _ in range(5):
        xi, u = rng.uniform(0, 1), rng.uniform(3, 10)
        x = np.array([xi, u, 0, 0, 0, 0, 0, 0.0])
        f4 = model.f(x, p4.values)
        np.testing.assert_allclose(surge.f(np.array([xi, u]), ps.values), f4[:2], rtol=1e-12)
        assert np.max(np.abs(f4[2:])) < 1e-12  # lateral states stay zero


def test_surge_fixed_points_crest_saddle_trough_stable(surge):
    """Umeda (1999): at chi_c = 0 'usually two fixed points: an unstable one near the wave
    crest and a stable one near the wave trough' (found by regula falsi in the paper)."""
    p = surge.default_params()
    fps = surge.fixed_points(p)
    assert len(fps) == 2
    kinds = {fp.kind for fp in fps}
    assert kinds == {"saddle", "stable"}
    c = surge.celerity(p)
    for fp in fps:
        assert fp.newton.converged
        assert fp.x[1] == pytest.approx(c, rel=1e-12)
        assert np.max(np.abs(surge.f(fp.x, p.values))) < 1e-9
        dist_crest = abs(fp.x[0] - 0.5)
        if fp.kind == "saddle":
            assert dist_crest < 0.25
        else:
            assert dist_crest > 0.25


def test_4dof_fixed_points_at_chi_c_10deg_are_index_one_saddles(model):
    """Umeda (1999) Figs. 2-9 at Fn = 0.3248, chi_c = 10 deg: crest and trough fixed points are
    saddles with one real positive eigenvalue; at the crest chi > 0 and delta > 0, at the
    trough chi < 0 despite delta > 0."""
    p = model.default_params()
    crest = model.find_equilibrium(p, "crest")
    trough = model.find_equilibrium(p, "trough")
    for res in (crest, trough):
        assert res.converged
        ev = np.linalg.eigvals(model.jacobian(res.z, p.values))
        unstable = ev[ev.real > 0]
        assert unstable.size == 1 and abs(unstable[0].imag) < 1e-12
    xc, xt = crest.z, trough.z
    i = model.index
    assert abs(np.mod(xc[0], 1) - 0.5) < 0.25 and abs(np.mod(xt[0], 1) - 0.5) > 0.25
    assert xc[i("chi")] > 0 and xc[i("delta")] > 0
    assert xt[i("chi")] < 0 and xt[i("delta")] > 0


def test_rudder_saturation_is_smooth_and_bounded(model):
    F = model.forces
    p = model.default_params().values
    x = np.zeros(8)
    x[1] = 6.0
    x[3] = p[1] - 3.0  # huge heading error: command far beyond delta_max
    rate = model.f(x, p)[7]
    assert rate * F.T_E == pytest.approx(F.delta_max, rel=1e-6)
    lin = Umeda4DOF(model.data, saturation=False)
    x[3] = p[1] - 0.05  # small error: saturation is the identity to 1e-6
    assert model.f(x, p)[7] == pytest.approx(lin.f(x, p)[7], rel=1e-6)


def test_find_equilibrium_follows_the_crest_branch_to_large_courses(model):
    """At chi_c >= ~27 deg Newton from the zero-lateral-state guess landed on another
    equilibrium (heading ~43 deg at chi_c = 30 deg). find_equilibrium now continues the
    chi_c = 0 crest point to the course: the result is the crest point of
    find_fixed_point (independent: traced over 0..50 deg and polished), and past the
    branch's fold it fails with a message instead of returning another point."""
    from continuation.errors import ConvergenceError
    from ship_models.analysis.fixed_points import find_fixed_point

    for deg in (27.0, 30.0):
        p = model.default_params().replace(Fn=0.31, chi_c=np.radians(deg))
        res = model.find_equilibrium(p, "crest")
        assert res.converged
        ref = find_fixed_point(model, p, "crest")
        np.testing.assert_allclose(res.z, ref.x, atol=1e-9)
        assert np.degrees(res.z[model.index("chi")]) < deg  # heading between 0 and chi_c
    past = model.default_params().replace(Fn=0.31, chi_c=np.radians(50.0))
    res = model.find_equilibrium(past, "crest")
    assert not res.converged and "does not reach chi_c" in res.message
    with pytest.raises(ConvergenceError, match="does not reach"):
        model.find_equilibrium(past, "crest", throw=True)
