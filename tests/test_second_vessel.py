"""A second vessel, the KVLCC2, from published sources independent of Umeda (1999).

References used as test values:

- Yasukawa, H. & Yoshimura, Y. (2015), "Introduction of MMG standard method for ship
  maneuvering predictions", J. Mar. Sci. Technol. 20:37-52 (YY2015): particulars,
  hydrodynamic derivatives, added masses, R0', K_T(J), w_P, t_P, rudder coefficients.
- Kim, W.J., Van, S.H. & Kim, D.H. (2001), "Measurement of flows around modern
  commercial ship models", Exp. Fluids 31:567-578: displacement volume 312 622 m^3,
  wetted surface 27 194 m^2.
- SIMMAN 2008 KVLCC2 conditions: GM = 5.71 m, KG = 18.6 m (so KM = 24.31 m).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize as so

from continuation.newton import newton
from continuation.settings import NewtonSettings
from continuation.system import check_jacobian
from ship_models import SurgeModel, Umeda4DOF, get_model, load_vessel, resolve_vessel
from ship_models.estimation import derivatives_about_g
from ship_models.vessel import VesselFileError, parse_vessel

RHO = 1025.0
L, B, D_M = 320.0, 58.0, 20.8
X_G = 0.0348 * L  # LCB 3.48 % L forward of midship (Kim et al. 2001); G above B
FN_SERVICE = 0.142  # 15.5 kn at L_pp = 320 m (YY2015)


@pytest.fixture(scope="module")
def model() -> Umeda4DOF:
    return get_model("kvlcc2")


@pytest.fixture(scope="module")
def data(model):
    return model.data


def _prime_at_g() -> dict[str, float]:
    """YY2015 derivatives about midship moved to G by hand (independent of the code)."""
    a = X_G / L
    Yv, Yr, Nv, Nr = -0.315, 0.083, -0.137, -0.049
    return {
        "Y_v": Yv,
        "Y_r": Yr - a * Yv,
        "N_v": Nv - a * Yv,
        "N_r": Nr - a * (Yr + Nv) + a * a * Yv,
    }


def test_file_loads_with_published_values_and_provenance():
    v = load_vessel("kvlcc2")
    assert v.get("particulars.L_pp") == 320.0 and v.get("particulars.B") == 58.0
    assert v.get("rudder.delta_max") == pytest.approx(np.deg2rad(35.0))
    for key in ("hydrodynamics.Y_v_prime", "hydrodynamics.N_r_prime", "propulsion.K_T0"):
        c = v.coefficient(key)
        assert c.status == "measured" and "Yasukawa & Yoshimura (2015)" in c.source
    for key, c in v.coefficients.items():
        assert c.status in ("given", "measured", "estimated", "assumed"), key
        assert c.source.strip(), key
    # the file gives only what is published or stated; the pipeline adds the rest
    d = resolve_vessel(v)
    added = set(d.vessel) - set(v)
    assert added and all(d.vessel.coefficient(k).status in ("estimated", "assumed") for k in added)
    for k in ("hydrodynamics.Y_v_prime", "hydrodynamics.m_x", "propulsion.w_P"):
        assert k not in added  # published (or given as a prime): not estimated


def test_hull_reproduces_published_displacement_surface_and_metacentre(data):
    """Parametric hull vs. Kim et al. (2001) and SIMMAN 2008 (independent hull data)."""
    assert data.hull.volume == pytest.approx(312_622.0, rel=2e-5)  # C_b L B d = nabla
    assert data.forces.mass == pytest.approx(RHO * 312_622.0, rel=2e-5)
    # wetted surface from the section girths of the generated hull (not the given S_f)
    assert data.info["wetted_surface_hull"] == pytest.approx(27_194.0, rel=0.02)
    # KM = KB + BM of the generated hull vs. SIMMAN KG + GM = 18.6 + 5.71 m
    assert data.info["KM"] == pytest.approx(18.6 + 5.71, rel=0.03)
    assert data.gz.slope0() == pytest.approx(5.71, rel=1e-12)


def test_published_coefficients_reach_the_equations_of_motion(data):
    """Dimensional forces = YY2015 primes x the MMG scales, moved from midship to G."""
    F = data.forces
    q = 0.5 * RHO * L * D_M  # rho/2 L d
    assert F.m_x == pytest.approx(0.022 * q * L, rel=1e-12)
    assert F.m_y == pytest.approx(0.223 * q * L, rel=1e-12)
    # J_zz about G = J_zz about midship + x_G^2 m_y (parallel axes)
    assert F.J_zz == pytest.approx(0.011 * q * L**3 + X_G**2 * 0.223 * q * L, rel=1e-12)
    assert F.I_zz == pytest.approx(F.mass * (0.25 * L) ** 2, rel=1e-12)
    pg = _prime_at_g()
    assert F.Y_v1 == pytest.approx(pg["Y_v"] * q, rel=1e-12)
    assert F.Y_r1 == pytest.approx(pg["Y_r"] * q * L, rel=1e-12)
    assert F.N_v1 == pytest.approx(pg["N_v"] * q * L, rel=1e-12)
    assert F.N_r1 == pytest.approx(pg["N_r"] * q * L * L, rel=1e-12)
    assert F.kt == (0.2931, -0.2753, -0.1385)
    assert (F.w_P, F.t_P, F.f_alpha) == (0.40, 0.220, 2.747)
    assert F.eta == pytest.approx(9.86 / 15.80, rel=1e-12)  # D_p / H_R
    assert F.x_R == pytest.approx(-0.5 * L - X_G) and F.x_H == pytest.approx(-0.464 * L - X_G)
    u = np.array([2.0, 7.95, 15.0, 22.3])
    np.testing.assert_allclose(F.resistance(u), 0.022 * q * u**2, rtol=1e-12)


def test_derivatives_about_g_is_a_change_of_reference_point():
    """Forces and moments are the same physics about O and about G (a' = (x_G - x_O)/L)."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        keys = ("Y_v_prime", "Y_r_prime", "N_v_prime", "N_r_prime")
        prime = dict(zip(keys, rng.normal(size=4), strict=True))
        a = rng.uniform(-0.1, 0.1)
        g = derivatives_about_g(prime, a)
        v_g, r = rng.normal(size=2)
        v_o = v_g - a * r  # lateral velocity at O (non-dimensional, r' = r L / U)
        Y_o = prime["Y_v_prime"] * v_o + prime["Y_r_prime"] * r
        N_o = prime["N_v_prime"] * v_o + prime["N_r_prime"] * r
        Y_g = g["Y_v_prime"] * v_g + g["Y_r_prime"] * r
        N_g = g["N_v_prime"] * v_g + g["N_r_prime"] * r
        assert Y_g == pytest.approx(Y_o, rel=1e-12, abs=1e-14)
        assert N_g == pytest.approx(N_o - a * Y_o, rel=1e-12, abs=1e-14)
    assert derivatives_about_g(prime, 0.0) == prime


def test_schema_refuses_conflicting_added_mass_forms():
    v = load_vessel("kvlcc2")
    doc = v.to_dict()
    doc["hydrodynamics"]["m_x"] = {"value": 1.0e6, "unit": "kg", "source": "x", "status": "given"}
    with pytest.raises(VesselFileError, match=r"hydrodynamics\.m_x"):
        parse_vessel(doc)
    # consistent values are accepted
    doc["hydrodynamics"]["m_x"]["value"] = 0.022 * 0.5 * RHO * L**2 * D_M
    assert parse_vessel(doc).get("hydrodynamics.m_x") == pytest.approx(24_014_848.0)
    # R0' makes the Holtrop fit range unnecessary; without R0' it is required again
    del doc["resistance"]["R0_prime"]
    with pytest.raises(VesselFileError, match=r"resistance\.Fn_max_fit.*R0_prime"):
        parse_vessel(doc)


def test_revolutions_balance_the_mmg_resistance(model):
    """n(Fn) from the closed form = root of (1 - t_P) rho n^2 D^4 K_T(J) = R0' rho/2 L d u^2."""
    u0 = FN_SERVICE * np.sqrt(9.80665 * L)
    R0 = 0.022 * 0.5 * RHO * L * D_M * u0**2

    def balance(n):
        J = u0 * (1 - 0.40) / (n * 9.86)
        kt = 0.2931 - 0.2753 * J - 0.1385 * J**2
        return (1 - 0.220) * RHO * n**2 * 9.86**4 * kt - R0

    n_ref = so.brentq(balance, 0.5, 5.0, xtol=1e-14)
    p = model.default_params().replace(Fn=FN_SERVICE)
    assert model.revolutions(p) == pytest.approx(n_ref, rel=1e-10)


@pytest.mark.parametrize("seed", [0, 1])
def test_jacobians_and_symmetry(model, seed):
    x = model.random_state(seed)
    p = model.default_params().replace(Fn=FN_SERVICE).values
    assert max(check_jacobian(model, x, p)) <= 1.0
    flip = np.array([1, 1, -1, -1, -1, -1, -1, -1], dtype=float)
    pf = p.copy()
    pf[1] = -p[1]
    f = model.f(x, p)
    np.testing.assert_allclose(
        model.f(flip * x, pf), flip * f, rtol=1e-12, atol=1e-12 * np.max(abs(f))
    )


def test_calm_water_straight_running_at_service_speed(model):
    p = model.default_params().replace(Fn=FN_SERVICE, H_over_lambda=0.0, chi_c=0.0)
    u0 = model.forces.nominal_speed(FN_SERVICE)
    x_eq = np.array([0.3, u0, 0, 0, 0, 0, 0, 0.0])
    f = model.f(x_eq, p.values)
    assert np.max(np.abs(f[1:])) < 1e-9
    assert f[0] == pytest.approx((u0 - model.celerity(p)) / L, rel=1e-12)

    def G(z):
        return model.f(np.concatenate([[0.3], z]), p.values)[1:]

    def JG(z):
        return model.jacobian(np.concatenate([[0.3], z]), p.values)[1:, 1:]

    z0 = x_eq[1:] + np.array([1.0, 0.2, 0.05, 0.002, 0.01, 0.0, 0.02])
    res = newton(G, JG, z0, NewtonSettings(tol=1e-9, max_iter=40))
    assert res.converged
    np.testing.assert_allclose(res.z, x_eq[1:], atol=1e-7)


def test_course_stability_matrix_matches_mmg_closed_form(model):
    """Rudder fixed (K_R = 0), calm water: the sway-yaw block of the Jacobian equals the
    linear MMG matrix assembled by hand from the published coefficients (YY2015 rudder
    inflow formula, derivatives moved to G), and its eigenvalues are eigenvalues of the
    full 8x8 Jacobian (the block is decoupled: heel derivatives are zero)."""
    p = model.default_params().replace(Fn=FN_SERVICE, H_over_lambda=0.0, chi_c=0.0, K_R=0.0)
    u0 = FN_SERVICE * np.sqrt(9.80665 * L)
    n = model.revolutions(p)
    x = np.array([0.3, u0, 0, 0, 0, 0, 0, 0.0])
    Jm = model.jacobian(x, p.values)

    q = 0.5 * RHO * L * D_M * u0
    pg = _prime_at_g()
    mass = RHO * 0.8098 * L * B * D_M
    m_x, m_y = 0.022 * q / u0 * L, 0.223 * q / u0 * L
    Izz = mass * (0.25 * L) ** 2
    Jzz = 0.011 * 0.5 * RHO * L**4 * D_M + X_G**2 * m_y
    # rudder inflow (YY2015): u_R = eps u (1 - w_P) sqrt(eta (1 + kappa (sqrt(1 + 8 K_T / pi J^2)
    # - 1))^2 + 1 - eta), eta = D_p / H_R
    J = u0 * 0.6 / (n * 9.86)
    kt = 0.2931 - 0.2753 * J - 0.1385 * J**2
    eta = 9.86 / 15.80
    u_R = (
        1.09
        * u0
        * 0.6
        * np.sqrt(eta * (1 + 0.5 * (np.sqrt(1 + 8 * kt / (np.pi * J**2)) - 1)) ** 2 + 1 - eta)
    )
    dFN_dv = 0.5 * RHO * 112.5 * 2.747 * 0.5175 * u_R  # d F_N / d v
    dFN_dr = dFN_dv * (-0.710 * L)  # l_R
    x_R, x_H = -0.5 * L - X_G, -0.464 * L - X_G
    kY, kN = -(1 + 0.312), -(x_R + 0.312 * x_H)
    A = np.array(
        [
            [
                (pg["Y_v"] * q + kY * dFN_dv) / (mass + m_y),
                (pg["Y_r"] * q * L - (mass + m_x) * u0 + kY * dFN_dr) / (mass + m_y),
            ],
            [
                (pg["N_v"] * q * L + kN * dFN_dv) / (Izz + Jzz),
                (pg["N_r"] * q * L**2 + kN * dFN_dr) / (Izz + Jzz),
            ],
        ]
    )
    i = [model.index("v"), model.index("r")]
    np.testing.assert_allclose(Jm[np.ix_(i, i)], A, rtol=1e-9)
    ev_full = np.linalg.eigvals(Jm)
    for lam in np.linalg.eigvals(A):
        assert np.min(np.abs(ev_full - lam)) < 1e-9 * max(1.0, abs(lam))


def test_surf_riding_equilibria_at_service_speed(model):
    """In the file's wave (H/lambda = 1/30, lambda = L) the surge model at Fn = 0.142 has
    the two fixed points of Grim's surf-riding picture: a saddle near the crest and a
    stable point near the trough; the 4-DOF model at chi_c = 0 has the same points with
    the lateral states zero; at chi_c = +-10 deg the crest equilibria are mirror images."""
    surge = SurgeModel(model.data)
    ps = surge.default_params().replace(Fn=FN_SERVICE)
    assert ps["H_over_lambda"] == pytest.approx(1 / 30) and ps["lambda_over_L"] == 1.0
    fps = surge.fixed_points(ps)
    assert sorted(fp.kind for fp in fps) == ["saddle", "stable"]
    c = surge.celerity(ps)
    assert c == pytest.approx(np.sqrt(9.80665 * L / (2 * np.pi)), rel=1e-12)
    p4 = model.default_params().replace(Fn=FN_SERVICE, chi_c=0.0)
    for fp in fps:
        assert fp.x[1] == pytest.approx(c, rel=1e-12)
        near_crest = abs(fp.x[0] - 0.5) < 0.25
        assert near_crest == (fp.kind == "saddle")
        x = np.zeros(8)
        x[:2] = fp.x
        assert np.max(np.abs(model.f(x, p4.values))) < 1e-9
    p = model.default_params().replace(Fn=FN_SERVICE, chi_c=np.deg2rad(10.0))
    res = model.find_equilibrium(p, "crest")
    assert res.converged and np.max(np.abs(model.f(res.z, p.values))) < 1e-9
    assert abs(np.mod(res.z[0], 1.0) - 0.5) < 0.25
    flip = np.array([1, 1, -1, -1, -1, -1, -1, -1], dtype=float)
    pm = p.replace(chi_c=-np.deg2rad(10.0))
    mirror = model.find_equilibrium(pm, "crest", guess=flip * res.z + 1e-3)
    assert mirror.converged
    np.testing.assert_allclose(model.difference(mirror.z, flip * res.z), 0.0, atol=1e-8)
    # index-1 saddle near the crest, as for the purse seiner (Umeda 1999, Fig. 6)
    ev = np.linalg.eigvals(model.jacobian(res.z, p.values))
    assert np.sum(ev.real > 0) == 1
