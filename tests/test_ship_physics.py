"""Physics of the vessel model checked against closed forms and independent methods."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize as so

from ship_models.contracts import SeaState
from ship_models.estimation import resolve_vessel
from ship_models.hydro.added_mass import lewis_sway_added_mass
from ship_models.hydro.hull import box_hull
from ship_models.hydro.hydrostatics import gz_curve, heeled_equilibrium, section_polygons
from ship_models.hydro.resistance import ittc57_cf
from ship_models.hydro.waves import WaveStrips
from ship_models.umeda_4dof import Umeda4DOF
from ship_models.vessel import load_vessel

#: The purse seiner's wave (H/lambda = 1/9.2, lambda/L = 1.5) for the force checks.
SEA = SeaState(1 / 9.2, 1.5)

RHO, G = 1025.0, 9.80665


@pytest.fixture(scope="module")
def data():
    return resolve_vessel(load_vessel("purse_seiner"))


def _box_strips(L=40.0, B=8.0, d=3.0, zeta_G=-0.8):
    hull = box_hull(L, B, d, D=6.0, n_stations=24)
    strips = WaveStrips.from_hull(
        hull,
        x_G=0.0,
        zeta_G=zeta_G,
        m22=np.zeros(hull.n_stations),
        z_H=1.0,
        rho=RHO,
        g=G,
        n_depth=16,
    )
    return hull, strips


def test_froude_krylov_surge_on_barge_closed_form():
    r"""Rectangular barge, heading chi, linear deep-water wave eta = -a cos(k xi).

    X_FK = -int_V dp/dx dV with p = -rho g a e^{k zeta} cos k xi gives
    X = -rho g a (1 - e^{-kd}) B sinc(k B sin(chi)/2) * 2 sin(k L cos(chi)/2)/k * sin(k xi_G)
    (Gauss's theorem on the calm-water hull; e.g. Newman 1977, Marine Hydrodynamics,
    Sect. 6.18, for the Froude-Krylov force). At chi = 0 this is
    -rho g a B (1 - e^{-kd}) (2/k) sin(kL/2) sin(k xi_G).
    """
    L, B, d = 40.0, 8.0, 3.0
    _, strips = _box_strips(L, B, d)
    Hl, lL = 1 / 12, 1.3
    lam = lL * L
    k, a = 2 * np.pi / lam, 0.5 * Hl * lam
    for chi in (0.0, np.deg2rad(30.0)):
        s, c = np.sin(chi), np.cos(chi)
        sinc = np.sinc(k * B * s / 2 / np.pi)
        amp = RHO * G * a * (1 - np.exp(-k * d)) * B * sinc * 2 * np.sin(k * L * c / 2) / k
        for xi in (0.1, 0.25, 0.4, 0.77):
            X, Y, N, K = strips.forces(xi, 5.0, chi, SeaState(Hl, lL), lift=False)
            X_exact = -amp * np.sin(2 * np.pi * xi)
            assert X == pytest.approx(X_exact, rel=1e-10)
            if chi:
                assert Y == pytest.approx(-np.tan(chi) * X_exact, rel=1e-10)


def _surface_integral_box(L, B, d, zeta_G, xi_over_lambda, chi, Hl, lL, n=48):
    """Brute-force -int p n dS over the wetted faces of a box (Gauss-Legendre on each face)."""
    lam = lL * L
    k, a = 2 * np.pi / lam, 0.5 * Hl * lam
    s, c = np.sin(chi), np.cos(chi)
    t, w = np.polynomial.legendre.leggauss(n)

    def nodes(lo, hi):
        return 0.5 * (lo + hi) + 0.5 * (hi - lo) * t, 0.5 * (hi - lo) * w

    def pressure(x, y, zeta):
        return -RHO * G * a * np.exp(k * zeta) * np.cos(k * (xi_over_lambda * lam + x * c - y * s))

    F = np.zeros(3)
    M = np.zeros(3)

    def add(pts, normal, dS):
        nonlocal F, M
        x, y, zeta = pts
        p = pressure(x, y, zeta)
        f = -p[..., None] * np.asarray(normal) * dS[..., None]  # body axes x, y, z(down)
        r = np.stack([x, y, zeta_G - zeta], axis=-1)
        F = F + f.reshape(-1, 3).sum(0)
        M = M + np.cross(r, f).reshape(-1, 3).sum(0)

    xs, wx = nodes(-L / 2, L / 2)
    ys, wy = nodes(-B / 2, B / 2)
    zs, wzz = nodes(-d, 0.0)
    X_, Y_ = np.meshgrid(xs, ys, indexing="ij")
    add((X_, Y_, np.full_like(X_, -d)), (0, 0, 1), np.outer(wx, wy))  # bottom, normal down
    X_, Z_ = np.meshgrid(xs, zs, indexing="ij")
    for sign in (1, -1):
        add((X_, np.full_like(X_, sign * B / 2), Z_), (0, sign, 0), np.outer(wx, wzz))
    Y_, Z_ = np.meshgrid(ys, zs, indexing="ij")
    for sign in (1, -1):
        add((np.full_like(Y_, sign * L / 2), Y_, Z_), (sign, 0, 0), np.outer(wy, wzz))
    return F, M


@pytest.mark.parametrize("chi_deg", [0.0, 25.0, 60.0])
def test_froude_krylov_all_components_against_surface_pressure_integration(chi_deg):
    """Strip formulas (Gauss's theorem + waterplane term) vs direct hull-surface integration."""
    L, B, d, zeta_G = 40.0, 8.0, 3.0, -0.8
    _, strips = _box_strips(L, B, d, zeta_G)
    chi = np.deg2rad(chi_deg)
    for xi in (0.13, 0.5, 0.81):
        X, Y, N, K = strips.forces(xi, 5.0, chi, SeaState(1 / 12, 1.3), lift=False)
        F, M = _surface_integral_box(L, B, d, zeta_G, xi, chi, 1 / 12, 1.3)
        scale_f = np.max(np.abs(F)) + 1.0
        scale_m = np.max(np.abs(M)) + 1.0
        assert X == pytest.approx(F[0], abs=1e-9 * scale_f)
        assert Y == pytest.approx(F[1], abs=1e-9 * scale_f)
        assert K == pytest.approx(M[0], abs=1e-9 * scale_m)
        assert N == pytest.approx(M[2], abs=1e-9 * scale_m)


def test_wave_forces_have_zero_mean_over_a_wavelength(data):
    strips = data.forces.waves
    xi = np.arange(64) / 64
    for chi in (0.0, 0.2, -0.5, 1.0):
        vals = np.array([strips.forces(s, 8.5, chi, SEA) for s in xi])
        amp = np.max(np.abs(vals), axis=0) + 1.0
        assert np.all(np.abs(vals.mean(axis=0)) < 1e-12 * amp)


def test_strip_quadrature_converges(data):
    """X_w of the purse seiner with 40 strips agrees with 160 strips (Gauss-Legendre)."""
    v = data.vessel.with_overrides({"hull.n_stations": 160, "hull.n_depth": 24})
    fine = resolve_vessel(v).forces.waves
    coarse = data.forces.waves
    for chi in (0.0, 0.3):
        for xi in (0.2, 0.45, 0.7):
            a = np.array(coarse.forces(xi, 8.0, chi, SEA))
            b = np.array(fine.forces(xi, 8.0, chi, SEA))
            scale = np.max(np.abs(b))
            assert np.max(np.abs(a - b)) < 2e-3 * scale


def test_parametric_hull_matches_particulars(data):
    """Displacement and l.c.b. exactly; wetted surface within 5 % of Table 1's S_f = 324 m^2."""
    hull, v = data.hull, data.vessel
    L, B = v.get("L_pp"), v.get("particulars.B")
    d_m = 0.5 * (v.get("d_f") + v.get("d_a"))
    assert hull.volume == pytest.approx(v.get("C_b") * L * B * d_m, rel=1e-9)
    assert hull.lcb == pytest.approx(-v.get("lcb_aft"), abs=1e-9 * L)
    assert hull.wetted_surface() == pytest.approx(324.0, rel=0.05)


def test_gz_slope_equals_gm_and_gz_is_odd(data):
    gz = data.gz
    hull = data.hull
    poly = section_polygons(hull)
    V0 = gz.volume
    xB = hull.lcb
    phi = np.deg2rad(0.25)
    st = heeled_equilibrium(hull, poly, phi, V0, xB)
    slope = (st.y_B * np.cos(phi) + (st.zeta_B - gz.zeta_G) * np.sin(phi)) / phi
    assert slope == pytest.approx(1.0, rel=0.01)  # GM = 1.0 m, Umeda (1999) Table 1
    assert gz.slope0() == pytest.approx(1.0, rel=1e-12)
    for deg in (15.0, 40.0, 100.0):
        p = np.deg2rad(deg)
        a = heeled_equilibrium(hull, poly, p, V0, xB)
        b = heeled_equilibrium(hull, poly, -p, V0, xB)
        gza = a.y_B * np.cos(p) + (a.zeta_B - gz.zeta_G) * np.sin(p)
        gzb = b.y_B * np.cos(-p) + (b.zeta_B - gz.zeta_G) * np.sin(-p)
        assert gzb == pytest.approx(-gza, abs=1e-9)
    phis = np.linspace(-np.pi, np.pi, 73)
    np.testing.assert_allclose(gz(-phis), -gz(phis), atol=1e-14)
    assert gz.fit_error < 0.005  # the smooth fit follows the hydrostatic curve within 5 mm
    assert 0.0 < gz.vanishing_angle < np.pi


def test_gz_of_wall_sided_box_matches_scribanti_formula():
    """Wall-sided formula GZ = sin(phi) (GM + BM tan^2(phi) / 2) (exact for a box before
    deck immersion or bilge emergence; e.g. Rawson & Tupper, Basic Ship Theory, Ch. 4)."""
    L, B, d, D = 40.0, 8.0, 3.0, 8.0
    hull = box_hull(L, B, d, D, n_stations=8)
    GM = 0.5
    gz = gz_curve(hull, GM, heel_step=np.deg2rad(5.0), n_terms=12)
    BM = B**2 / (12 * d)
    for deg in (5.0, 10.0, 20.0, 30.0):
        k = int(round(deg / 5.0))
        p = np.deg2rad(deg)
        expected = np.sin(p) * (GM + 0.5 * BM * np.tan(p) ** 2)
        assert gz.gz[k] == pytest.approx(expected, rel=2e-4)


def test_lewis_added_mass_closed_forms():
    """Half-ellipse (a3 = 0) and flat plate: sway added mass rho pi d^2 / 2 (Lewis 1929)."""
    d = np.array([2.0, 3.0])
    for b in (0.5, 1.0, 4.0):
        m = lewis_sway_added_mass(RHO, np.full(2, b), d, np.full(2, np.pi / 4))
        np.testing.assert_allclose(m, 0.5 * RHO * np.pi * d**2, rtol=1e-12)
    m = lewis_sway_added_mass(RHO, np.zeros(2), d, np.full(2, 0.7))
    np.testing.assert_allclose(m, 0.5 * RHO * np.pi * d**2, rtol=1e-12)


def test_ittc57_and_resistance_fit(data):
    assert float(ittc57_cf(1e9)) == pytest.approx(0.075 / 49.0, rel=1e-14)
    assert data.info["resistance_fit_error"] < 0.01
    hh, v = data.holtrop, data.vessel
    u = np.linspace(2.0, 10.0, 17)
    exact = hh.total_resistance(
        u,
        rho=v.get("rho"),
        g=v.get("g"),
        nu=v.get("nu"),
        form_factor=v.get("resistance.form_factor"),
        C_A=v.get("resistance.C_A"),
    )
    np.testing.assert_allclose(data.forces.resistance(u), exact, rtol=0.01)


def test_revolutions_closed_form_against_root_finder(data):
    F = data.forces
    for Fn in (0.15, 0.3248, 0.42):
        u0 = F.nominal_speed(Fn)
        R0 = float(F.resistance_force(u0))
        n_bracket = so.brentq(
            lambda n, u0=u0, R0=R0: F.thrust_force(u0, n) - R0, 0.5, 20.0, xtol=1e-14
        )
        assert float(F.revolutions(Fn)) == pytest.approx(n_bracket, rel=1e-10)


def test_linear_roll_period_reproduces_t_phi(data):
    """Roll eigenvalues of the model Jacobian at zero speed: |lambda| = 2 pi / T_phi."""
    m = Umeda4DOF(data)
    p = m.default_params().replace(Fn=0.0, H_over_lambda=0.0).values
    x = np.zeros(8)
    J = m.jacobian(x, p)
    ev = np.linalg.eigvals(J[5:7, 5:7])
    full = np.linalg.eigvals(J)
    # the roll pair is also a pair of eigenvalues of the full 8x8 Jacobian
    for e in ev:
        assert np.min(np.abs(full - e)) < 1e-10
    omega_n = abs(ev[0])
    assert 2 * np.pi / omega_n == pytest.approx(7.4, rel=1e-6)  # Umeda (1999) Table 1


def test_loading_condition_marginally_meets_is_code(data):
    """Umeda (1999): the loading condition 'marginally complies with the IS Code'. The
    estimated watertight topside extension makes the smallest IS-criterion margin ~ 0."""
    from ship_models.hydro.hydrostatics import gz_curve, is_code_criteria, is_code_margin

    assert abs(data.info["is_code_margin"]) < 0.01
    assert data.vessel.coefficient("stability.topside_height").status == "estimated"
    crit = is_code_criteria(data.gz)
    assert crit["angle_of_max_gz"][0] == pytest.approx(np.deg2rad(25.0), abs=np.deg2rad(0.5))
    bare = gz_curve(data.hull, 1.0, heel_step=np.deg2rad(2.0), n_terms=8)
    assert is_code_margin(bare) < 0  # the bare hull (freeboard 0.27-0.57 m) does not comply
    assert bare.vanishing_angle < data.gz.vanishing_angle


def test_wave_lift_vanishes_without_speed_or_heading_and_is_linear_in_u(data):
    """Slender-body lift ~ u * (lateral orbital velocity ~ sin chi): zero at u = 0 and at
    chi = 0, linear in u, and never a surge force."""
    w = data.forces.waves
    for xi in (0.1, 0.6):
        with_l = np.array(w.forces(xi, 0.0, 0.4, SEA, lift=True))
        without = np.array(w.forces(xi, 0.0, 0.4, SEA, lift=False))
        np.testing.assert_allclose(with_l, without, rtol=0, atol=0)
        d1 = np.array(w.forces(xi, 4.0, 0.4, SEA)) - without
        d2 = np.array(w.forces(xi, 8.0, 0.4, SEA)) - without
        np.testing.assert_allclose(d2, 2 * d1, rtol=1e-12, atol=1e-6)
        assert d1[0] == 0.0
        assert abs(d1[3] + w.z_H * d1[1]) < 1e-9 * abs(d1[1])  # K_L = -z_H Y_L
        zero_heading = np.array(w.forces(xi, 8.0, 0.0, SEA))
        assert np.all(np.abs(zero_heading[1:]) < 1e-9)
