"""IMO surf-riding/broaching assessment (ship_models.assessment): formulas, weights, C.

References:
* torque-driven damped pendulum ``x'' + alpha x' + sin x = beta``: the heteroclinic
  (rotation) threshold beta_h = 0.597383 (alpha = 0.5) and 0.964327 (alpha = 1.0)
  (issue 26), computed here by the project's connection solver; Melnikov's 4 alpha / pi
  overshoots by 6.6 % and 32 %;
* Longuet-Higgins (1983) joint density: normalised to one; its wavelength-band mass in
  closed form; the midpoint-rule weights converge to it at second order;
* C and the operational limit on constructed cases with closed forms;
* the moments of the Bretschneider spectrum (T01/T02, nu).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.integrate as si

from continuation import System
from continuation.bvp import find_connection
from ship_models.assessment import criteria as L2
from ship_models.assessment.melnikov import (
    ThrustCoefficients,
    cos_half_moment,
    melnikov_revolutions,
    pendulum_melnikov,
    resistance_integral,
    resistance_integral_polynomial,
)
from ship_models.assessment.standard import ScatterTable, load_standard, read_scatter_table
from ship_models.assessment.wave_weights import (
    band_probability,
    bretschneider_period_ratio,
    lh83_density,
    spectral_width,
    wave_case_weights,
)


# ----------------------------------------------------------------- the pendulum
def _pendulum() -> System:
    def rhs(x, p, ops):
        return ops.stack([x[1], p[1] - p[0] * x[1] - ops.sin(x[0])])

    return System(rhs, ("x", "v"), ("alpha", "beta"), periodic={"x": 2 * np.pi})


@pytest.mark.parametrize(
    ("alpha", "beta_h", "overshoot"), [(0.5, 0.597383, 0.066), (1.0, 0.964327, 0.32)]
)
def test_pendulum_threshold_exact_and_melnikov(alpha, beta_h, overshoot):
    """The connection solver gives beta_h to the 6 digits quoted; Melnikov overshoots."""
    s = _pendulum()
    beta0 = min(pendulum_melnikov(alpha), 0.9)  # 4/pi > 1 has no equilibria at all
    saddle = [-np.pi - math.asin(beta0), 0.0]
    res = find_connection(s, s.params(alpha=alpha, beta=beta0), "beta", source=saddle,
                          shift={"x": 2 * np.pi}, branch=1)  # fmt: skip
    assert res.success, res.message
    # the quoted value has 6 decimals (rounding 5e-7) and the solve its own estimate
    assert res.error("beta") < 1e-7
    assert res.value("beta") == pytest.approx(beta_h, abs=5e-7 + res.error("beta"))
    assert pendulum_melnikov(alpha) / res.value("beta") - 1 == pytest.approx(overshoot, abs=0.005)


def test_melnikov_balance_is_the_pendulum_formula_for_linear_net_thrust():
    """T = n^2, R = R0 + alpha (u - c), f = k = m = 1: n^2 = R0 - 4 alpha / pi exactly."""
    alpha, R0, c = 0.37, 2.0, 5.0
    v0 = 2.0  # 2 sqrt(f / (k m))
    I_R = resistance_integral(lambda u: R0 + alpha * (u - c), c, v0)
    n = melnikov_revolutions(ThrustCoefficients(1.0, 0.0, 0.0), c, v0, I_R)
    assert float(n) ** 2 == pytest.approx(R0 - 4 * alpha / math.pi, rel=1e-13)


def test_polynomial_closed_form_equals_quadrature():
    """The circular's polynomial R: binomial closed form = Gauss-Legendre (exact for it)."""
    r = np.array([120.0, 35.0, -4.0, 0.9, -0.02])
    c, v0 = np.array([6.0, 9.5]), np.array([1.2, 3.1])
    poly = resistance_integral_polynomial(r, c, v0)
    quad = resistance_integral(lambda u: sum(rk * u ** (k + 1) for k, rk in enumerate(r)), c, v0)
    np.testing.assert_allclose(poly, quad, rtol=1e-12)


def test_cos_half_moments():
    expected = [2 * math.pi, 4.0, math.pi, 8 / 3, 3 * math.pi / 4, 32 / 15]
    for m, e in enumerate(expected):
        assert cos_half_moment(m) == pytest.approx(e, rel=1e-14)
        num = si.quad(lambda t, m=m: math.cos(t / 2) ** m, -math.pi, math.pi, epsabs=1e-13)[0]
        assert num == pytest.approx(e, rel=1e-12)


# -------------------------------------------------------------- wave weights
def test_spectrum_moments():
    """T01/T02 and nu of the omega^-5 exp(-B omega^-4) spectrum by quadrature of it."""
    B = 1.3

    def m(n):
        return si.quad(lambda w: w**n * w**-5 * math.exp(-B * w**-4), 0.0, np.inf, limit=400)[0]

    m0, m1, m2 = m(0), m(1), m(2)
    assert bretschneider_period_ratio() == pytest.approx(math.sqrt(m0 * m2) / m1, rel=1e-6)
    assert spectral_width() == pytest.approx(math.sqrt(m0 * m2 / m1**2 - 1), rel=1e-5)
    assert round(spectral_width(), 3) == 0.425  # the circular's rounded value


def test_lh83_density_integrates_to_one():
    nu = spectral_width()
    val = si.dblquad(lambda R, t: lh83_density(R, t, nu), 0.05, 60.0, 0.0, 8.0, epsabs=1e-10)[0]
    Tz, g = 1.0, 9.80665
    T01 = bretschneider_period_ratio() * Tz

    def lam(tau):  # local wavelength of the period tau T01
        return g * (tau * T01) ** 2 / (2 * math.pi)

    outside = band_probability(0.0, lam(0.05), Tz) + band_probability(lam(60.0), math.inf, Tz)
    # R > 8 holds less than exp(-64) of the mass
    assert val + outside == pytest.approx(1.0, abs=1e-7)
    assert band_probability(0.0, math.inf, 7.0) == pytest.approx(1.0, abs=1e-14)


def _band_grid(lam_lo: float, lam_hi: float, n_lam: int, n_s: int, s_max: float = 1.2):
    dl, ds = (lam_hi - lam_lo) / n_lam, s_max / n_s
    return lam_lo + dl * (np.arange(n_lam) + 0.5), ds * (np.arange(n_s) + 0.5), dl, ds


def test_weights_converge_to_the_band_probability_at_second_order():
    """sum w_ij over lambda/L in [1, 3] and all steepness -> the closed form, O(h^2)."""
    L, Hs, Tz = 80.0, 5.0, 8.5
    exact = band_probability(1.0 * L, 3.0 * L, Tz)
    errs = []
    for n in (40, 80, 160):
        lam, s, dl, ds = _band_grid(1.0, 3.0, n, 6 * n)
        errs.append(abs(wave_case_weights(lam, s, dl, ds, L, Hs, Tz).sum() - exact))
    assert errs[-1] < 1e-5 * exact
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.15)
    assert errs[1] / errs[2] == pytest.approx(4.0, rel=0.15)


def test_standard_grid_truncation_is_below_one_and_stated():
    st = load_standard()
    assert st.lambda_over_L.size == 80 and st.steepness.size == 100
    W = L2.sea_state_weights(st, 34.5, st.Hs_classes, st.Tz_classes)
    mass = W.sum(axis=(2, 3))
    assert np.all(mass > 0) and np.all(mass < 1)
    # the grid's band of wavelengths holds at most the closed-form band mass
    for a in range(3):
        for b, Tz in enumerate(st.Tz_classes[:3]):
            lam_lo = (st.lambda_over_L[0] - st.d_lambda_over_L / 2) * 34.5
            lam_hi = (st.lambda_over_L[-1] + st.d_lambda_over_L / 2) * 34.5
            assert mass[a, b] <= band_probability(lam_lo, lam_hi, Tz) * (1 + 1e-3)


# ------------------------------------------------------------------------ C
def _toy_standard(lam, s, dl, ds):
    st = load_standard()
    return dataclasses.replace(
        st, lambda_over_L=lam, steepness=s, d_lambda_over_L=dl, d_steepness=ds
    )


def test_C_on_a_constructed_case_with_a_closed_form():
    """All waves with lambda/L in [1.5, 2.5] surf-ride: C = sum W2 P_band(Hs, Tz)."""
    L = 60.0
    lam, s, dl, ds = _band_grid(1.5, 2.5, 120, 600)
    st = _toy_standard(lam, s, dl, ds)
    scatter = ScatterTable(np.array([3.0, 6.0]), np.array([7.0, 9.0]),
                           np.array([[1.0, 2.0], [3.0, 4.0]]), "constructed")  # fmt: skip
    W = L2.sea_state_weights(st, L, scatter.Hs, scatter.Tz)
    Fn_cr = np.full((lam.size, s.size), 0.25)
    res = L2.level2(0.3, Fn_cr, W, scatter.Hs, scatter.Tz, st, scatter)
    closed = sum(
        scatter.W2[a, b] * band_probability(1.5 * L, 2.5 * L, Tz)
        for a in range(2)
        for b, Tz in enumerate(scatter.Tz)
    )
    assert res.C == pytest.approx(closed, rel=2e-4)  # midpoint rule, O(h^2) (test above)
    assert res.C_upper == res.C and res.missing_cells == 0
    # below every threshold nothing surf-rides
    assert L2.level2(0.2, Fn_cr, W, scatter.Hs, scatter.Tz, st, scatter).C == 0.0


def test_missing_thresholds_bound_C_and_leave_the_verdict_open():
    lam, s, dl, ds = _band_grid(1.0, 3.0, 20, 40, s_max=0.15)
    st = _toy_standard(lam, s, dl, ds)
    sc = ScatterTable(np.array([5.0]), np.array([8.0]), np.array([[1.0]]), "one sea state")
    W = L2.sea_state_weights(st, 50.0, sc.Hs, sc.Tz)
    Fn_cr = np.full((lam.size, s.size), 0.5)
    Fn_cr[:, : s.size // 2] = np.nan
    r = L2.level2(0.3, Fn_cr, W, sc.Hs, sc.Tz, st, sc)
    assert r.C == 0.0 and r.C_upper == pytest.approx(W[0, 0][:, : s.size // 2].sum())
    assert r.missing_cells == lam.size * (s.size // 2)
    if r.C_upper > st.R_SR:
        assert r.vulnerable is None


def test_operational_limit_closed_form():
    Fn_cr = np.array([0.31, 0.28, 0.35, 0.30])
    a = np.array([0.002, 0.001, 0.004, 0.003])
    # sorted: 0.28 (0.001), 0.30 (0.004 cum), 0.31 (0.006 > 0.005) -> limit 0.31
    assert L2.operational_limit(Fn_cr, a, 0.005) == pytest.approx(0.31)
    assert L2.operational_limit(Fn_cr, a, 0.1) == math.inf
    with_missing = np.array([0.31, np.nan, 0.35, 0.30])
    assert L2.operational_limit(with_missing, a, 0.005) == pytest.approx(0.31)
    assert L2.operational_limit(with_missing, np.array([0, 0.006, 0, 0]), 0.005) == -math.inf


def test_level1():
    st = load_standard()
    assert not L2.level1(320.0, 0.5, st).vulnerable
    assert not L2.level1(34.5, 0.3, st).vulnerable
    r = L2.level1(34.5, 0.31, st)
    assert r.vulnerable and "200" in r.reason


# ------------------------------------------------------------------ inputs
def test_scatter_table_file(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("# source: constructed for the test\nHs\\Tz, 6.5, 7.5\n1.5, 10, 30\n2.5, 0, 60\n")
    sc = read_scatter_table(p)
    assert sc.source == "constructed for the test"
    np.testing.assert_allclose(sc.W2, [[0.1, 0.3], [0.0, 0.6]])
    for text, match in (
        ("Hs\\Tz, 6.5\n1.5, x\n", "not a number"),
        ("Hs\\Tz, 6.5, 7.5\n1.5, 1\n", "1 counts for 2"),
        ("Hs\\Tz, 6.5\n1.5, -1\n", ">= 0"),
        ("Hs\\Tz, 7.5, 6.5\n1.5, 1, 1\n", "increasing"),
        ("Hs\\Tz, 6.5\n1.5, 0\n", "all counts are zero"),
    ):
        p.write_text(text)
        with pytest.raises(ValueError, match=match):
            read_scatter_table(p)
    with pytest.raises(ValueError, match="does not exist"):
        read_scatter_table(tmp_path / "nope.csv")


def test_standard_file_sources_and_errors(tmp_path):
    st = load_standard()
    rows = st.table()
    assert all(r["source"] and r["status"] in ("given", "assumed") for r in rows)
    assert st.R_SR == 0.005 and st.L_min == 200.0 and st.Fn_max == 0.3
    bad = tmp_path / "bad.toml"
    bad.write_text("[level1]\nL_min = { value = 200.0, unit = 'm' }\n")
    with pytest.raises(ValueError, match="level1.L_min"):
        load_standard(bad)


# -------------------------------------------------------------- dC/dtheta
def test_contour_derivative_against_differences_of_the_continuous_C():
    """Fn_cr = 0.5 - 2 s + theta (1 + lambda/10): dC/dtheta by the contour formula equals
    central differences of C = sum_i dlam int_{s*(theta)} p_i(s) ds (quadrature)."""
    from ship_models.assessment.sensitivity import contour_derivative, scatter_density

    L, Fn = 50.0, 0.3
    lam = np.linspace(1.0, 2.9, 20)
    s = np.linspace(0.03, 0.15, 41)
    sc = ScatterTable(np.array([4.0, 6.0]), np.array([6.0, 8.0]),
                      np.array([[1.0, 2.0], [2.0, 1.0]]), "constructed")  # fmt: skip
    p = scatter_density(L, sc)

    def Fn_cr(theta):
        return 0.5 - 2 * s[None, :] + theta * (1 + lam[:, None] / 10)

    def C(theta):
        tot = 0.0
        for lm in lam:
            s_star = (0.5 + theta * (1 + lm / 10) - Fn) / 2
            lo = min(max(s_star, s[0]), s[-1])
            tot += 0.1 * si.quad(lambda x, lm=lm: float(p(lm, np.array([x]))[0]), lo, s[-1],
                                 epsabs=1e-13, epsrel=1e-12)[0]  # fmt: skip
        return tot

    dFn = np.broadcast_to(1 + lam[:, None] / 10, (lam.size, s.size))
    dC = contour_derivative(Fn, Fn_cr(0.0), dFn, lam, s, 0.1, p)
    h = 1e-4
    fd = (C(h) - C(-h)) / (2 * h)
    assert dC < 0  # raising every threshold lowers C
    assert dC == pytest.approx(fd, rel=1e-5)
