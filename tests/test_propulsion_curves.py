"""Measured propulsion curves: splines, general propeller, vessel-file curves, validity."""

from __future__ import annotations

import logging

import casadi as ca
import numpy as np
import pytest

from continuation.ops import CASADI_OPS
from ship_models.hydro.curves import Polynomial1D, interpolating_spline
from ship_models.hydro.propeller import (
    Propeller,
    bseries_kt,
    bseries_kt_polynomial,
    bseries_zero_thrust_J,
    revolutions,
    thrust,
)
from ship_models.hydro.resistance import resistance_table
from ship_models.validity import reset_reports
from ship_models.vessel import VesselFileError, load_vessel, parse_vessel


def test_clamped_spline_reproduces_a_cubic_exactly() -> None:
    p = np.poly1d([0.3, -1.2, 0.5, 2.0])  # cubic: a clamped spline is exact
    x = np.array([0.0, 0.4, 1.1, 1.5, 2.6, 3.0])
    s = interpolating_spline(
        x, p(x), slope_start=float(p.deriv()(0.0)), slope_end=float(p.deriv()(3.0))
    )
    xx = np.linspace(0.0, 3.0, 301)
    np.testing.assert_allclose(s(xx), p(xx), atol=1e-12)
    np.testing.assert_allclose(s.derivative(xx), p.deriv()(xx), atol=1e-11)


def test_spline_fourth_order_and_c2() -> None:
    errs = []
    for n in (11, 21, 41):
        x = np.linspace(0.0, np.pi, n)
        s = interpolating_spline(x, np.sin(x), slope_start=1.0, slope_end=-1.0)
        xx = np.linspace(0.0, np.pi, 2001)
        errs.append(np.max(np.abs(s(xx) - np.sin(xx))))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders > 3.7), orders  # O(h^4) for a clamped cubic spline
    # C2: second differences of s' across a knot vanish with the step
    x = np.linspace(0.0, 1.0, 6)
    s = interpolating_spline(x, np.exp(x))
    k, h = x[2], 1e-6
    d2_left = (s.derivative(k) - s.derivative(k - h)) / h
    d2_right = (s.derivative(k + h) - s.derivative(k)) / h
    assert abs(d2_left - d2_right) < 1e-4


def test_spline_casadi_matches_numpy() -> None:
    x = np.array([0.0, 1.0, 2.5, 4.0])
    s = interpolating_spline(x, np.array([0.0, 1.0, 5.0, 3.0]))
    u = ca.SX.sym("u")
    f = ca.Function(
        "f", [u], [s.evaluate(u, CASADI_OPS), ca.jacobian(s.evaluate(u, CASADI_OPS), u)]
    )
    for xv in (0.3, 1.7, 3.9):
        val, der = f(xv)
        assert float(val) == pytest.approx(float(s(xv)), abs=1e-13)
        assert float(der) == pytest.approx(float(s.derivative(xv)), abs=1e-12)


def test_bad_spline_input() -> None:
    with pytest.raises(ValueError, match="strictly increasing"):
        interpolating_spline(np.array([0.0, 1.0, 1.0]), np.zeros(3))


def test_general_propeller_matches_closed_form_for_quadratic_kt() -> None:
    k = (0.34, -0.27, -0.136)
    prop = Propeller(2.6, Polynomial1D(np.array(k), (0.0, 0.9)), k, 0.25, 0.19)
    for u0, R0 in ((4.0, 2.0e4), (5.5, 4.5e4), (6.5, 9.0e4)):
        n_closed = revolutions(u0, R0, rho=1025.0, D_p=2.6, w_P=0.25, t_P=0.19, k=k)
        n_newton = prop.revolutions(u0, R0, 1025.0)
        assert n_newton == pytest.approx(n_closed, rel=1e-12)
        for u in (2.0, 6.0, 9.0):
            T_closed = thrust(u, n_closed, rho=1025.0, D_p=2.6, w_P=0.25, t_P=0.19, k=k)
            assert prop.thrust(u, n_closed, 1025.0) == pytest.approx(T_closed, rel=1e-12)


def test_bseries_polynomial_and_zero() -> None:
    c = bseries_kt_polynomial(1.0, 0.55, 4)
    J = np.linspace(0.0, 1.2, 13)
    np.testing.assert_allclose(np.polyval(c[::-1], J), bseries_kt(J, 1.0, 0.55, 4), atol=1e-14)
    J0 = bseries_zero_thrust_J(1.0, 0.55, 4)
    assert abs(float(bseries_kt(J0, 1.0, 0.55, 4))) < 1e-12
    prop = Propeller(2.6, Polynomial1D(np.array(c), (0.0, J0)), (c[0], c[1], c[2]), 0.25, 0.19)
    assert prop.revolution_residual(5.5, 4.5e4, 1025.0) < 1e-12


def _seiner_doc() -> dict:
    import tomllib

    from ship_models.vessel import DATA_DIR

    with open(DATA_DIR / "purse_seiner.toml", "rb") as fh:
        return tomllib.load(fh)


def test_resistance_table_in_vessel_file_reproduces_the_curve() -> None:
    from ship_models import Umeda4DOF

    base = Umeda4DOF("purse_seiner")
    u = np.linspace(0.5, 11.5, 45)
    R = base.forces.resistance_force(u)
    doc = _seiner_doc()
    doc["vessel"]["resistance_method"] = "table"
    doc["curves"] = {
        "resistance": {"x": list(u), "y": list(R / 1000.0), "x_unit": "m/s", "y_unit": "kN",
                       "source": "test: sampled from the Holtrop spline", "status": "measured"}
    }  # fmt: skip
    m = Umeda4DOF(parse_vessel(doc))
    # interpolant: exact at the data up to the conditioning of the truncated-power basis
    np.testing.assert_allclose(m.forces.resistance_force(u), R, rtol=0, atol=1e-11 * R.max())
    uu = np.linspace(1.0, 11.0, 200)
    np.testing.assert_allclose(
        m.forces.resistance_force(uu), base.forces.resistance_force(uu), rtol=2e-3
    )
    assert m.forces.resistance_force(0.0) == 0.0


def test_curve_errors_name_the_field() -> None:
    doc = _seiner_doc()
    bad = {"x": [1.0, 0.5, 2.0], "y": [1, 2, 3], "x_unit": "m/s", "y_unit": "kN"}
    doc["curves"] = {"resistance": bad | {"source": "s", "status": "measured"}}
    with pytest.raises(VesselFileError, match=r"curves\.resistance\.x"):
        parse_vessel(doc)
    doc = _seiner_doc()
    doc["vessel"]["resistance_method"] = "table"
    with pytest.raises(VesselFileError, match="curves.resistance"):
        parse_vessel(doc)
    doc = _seiner_doc()
    doc["vessel"]["propeller_method"] = "bogus"
    with pytest.raises(VesselFileError, match="propeller_method"):
        parse_vessel(doc)


def test_kt_curve_and_wake_curve_vessel() -> None:
    from ship_models import Umeda4DOF

    doc = _seiner_doc()
    doc["vessel"]["propeller_method"] = "curve"
    J = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    kt = [float(v) for v in bseries_kt(np.array(J), 1.0, 0.55, 4)]
    doc["curves"] = {
        "K_T": {"x": J, "y": kt, "x_unit": "-", "y_unit": "-", "source": "t", "status": "measured"},
        "w_P": {"x": [0.0, 5.0, 10.0], "y": [0.25, 0.24, 0.22], "x_unit": "m/s", "y_unit": "-",
                "source": "test", "status": "measured"},
    }  # fmt: skip
    m = Umeda4DOF(parse_vessel(doc))
    F = m.forces
    for Fn in (0.2, 0.3, 0.35):
        n = F.revolutions(Fn)
        u0 = F.nominal_speed(Fn)
        assert F.thrust_force(u0, n) == pytest.approx(F.resistance_force(u0), rel=1e-10)
    # the CasADi model traces and agrees with NumPy
    p = m.default_params()
    x = m.equilibrium_guess(p)
    res = m.find_equilibrium(p.replace(chi_c=0.0), guess=x)
    assert res.converged


def test_validity_warning_once(caplog: pytest.LogCaptureFixture) -> None:
    from ship_models import Umeda4DOF

    reset_reports()
    m = Umeda4DOF("purse_seiner")
    with caplog.at_level(logging.WARNING, logger="ship_models.validity"):
        m.check_params(m.default_params().replace(Fn=0.30))
        m.check_params(m.default_params().replace(Fn=0.31))
    msgs = [r.getMessage() for r in caplog.records]
    holtrop = [s for s in msgs if "Holtrop" in s]
    assert len(holtrop) == 1 and "Fn = 0.4886" in holtrop[0] and "0.38" in holtrop[0]
    assert sum("K_T" in s for s in msgs) == 1


def test_resistance_table_function() -> None:
    t = resistance_table(np.array([1.0, 2.0, 3.0]), np.array([1.0, 4.0, 9.0]))
    assert t(0.0) == 0.0 and t.u_max == 3.0
    np.testing.assert_allclose(t(np.array([1.0, 2.0, 3.0])), [1.0, 4.0, 9.0], rtol=1e-13)


def test_loaded_seiner_is_a_fishing_vessel() -> None:
    assert load_vessel("purse_seiner").meta["hull_type"] == "fishing_vessel"


def test_curves_round_trip_through_toml(tmp_path) -> None:
    from ship_models.vessel import dump_vessel

    doc = _seiner_doc()
    doc["vessel"]["propeller_method"] = "curve"
    doc["curves"] = {
        "K_T": {"coefficients": [0.34, -0.27, -0.14], "J_range": [0.0, 0.9],
                "source": "t", "status": "measured"},
        "w_P": {"x": [0.0, 5.0, 10.0], "y": [0.25, 0.24, 0.22], "x_unit": "kn", "y_unit": "-",
                "source": "t", "status": "measured"},
    }  # fmt: skip
    v = parse_vessel(doc)
    back = load_vessel(dump_vessel(v, tmp_path / "v.toml"))
    assert back.curves == v.curves and back.propeller_method == "curve"
    assert back.curves["w_P"].x[1] == pytest.approx(5.0 * 1852.0 / 3600.0, rel=1e-15)


@pytest.mark.parametrize("pd", [0.6, 0.8, 1.0, 1.2, 1.4])
def test_bseries_tail_is_c2_and_decreasing(pd: float) -> None:
    from ship_models.hydro.propeller import bseries_kt_curve

    kt = bseries_kt_curve(pd, 0.55, 4)
    J0 = kt.valid[1]
    J = np.linspace(0.0, J0, 50)
    np.testing.assert_allclose(kt(J), bseries_kt(J, pd, 0.55, 4), atol=1e-14)
    # C2 at J0: the tail is a truncated cubic (value, slope, curvature continuous)
    h = 1e-4
    d2 = [(kt(J0 + s + h) - 2 * kt(J0 + s) + kt(J0 + s - h)) / h**2 for s in (-2 * h, 2 * h)]
    assert abs(d2[1] - d2[0]) < 1e-2
    # strictly decreasing (a windmilling propeller brakes more) far beyond the range
    JJ = np.linspace(J0, 30.0, 3000)
    assert np.all(np.diff(kt(JJ)) < 0)
    assert np.all(kt.derivative(JJ) < 0)


def test_bseries_vessel_has_no_spurious_surf_riding_in_gentle_waves() -> None:
    """The extrapolated cubic used to give thrust at J >> J0 (surf-riding at Fn 0.019 in
    H/lambda = 0.02); with the C2 tail the gentle wave has no surge threshold, as with
    the quadratic fit."""
    import math

    from continuation.status import Status
    from ship_models.analysis.sweeps import surge as S
    from ship_models.surge import SurgeModel

    doc = _seiner_doc()
    doc["vessel"]["propeller_method"] = "bseries"
    st = S.surge_threshold(SurgeModel(parse_vessel(doc)), 0.02, 1.5)
    assert st.status is Status.NO_BRACKET and math.isnan(st.Fn)


def test_resistance_what_if_table_reproduces_the_default() -> None:
    """studies/resistance_beyond_range.py: at a = 0 its table is the default R(u) (the
    what-if numbers are differences to the default, not to a sampling error)."""
    from ship_models import Umeda4DOF
    from studies.resistance_beyond_range import raised_vessel

    base = Umeda4DOF("purse_seiner").forces
    sg = np.sqrt(base.g * base.L)
    u = np.linspace(0.2, 0.64 * sg, 400)
    R0 = base.resistance_force(u)
    m0 = Umeda4DOF(raised_vessel(0.0, 0.38, 0.45)).forces
    np.testing.assert_allclose(m0.resistance_force(u), R0, rtol=1e-5)
    m1 = Umeda4DOF(raised_vessel(0.5, 0.38, 0.45)).forces
    hi = u / sg >= 0.47  # two table spacings past the blend, whose curvature jumps at 0.45
    np.testing.assert_allclose(m1.resistance_force(u[hi]), 1.5 * R0[hi], rtol=1e-5)
    lo = u / sg <= 0.36  # the spline error decays geometrically away from 0.38
    np.testing.assert_allclose(m1.resistance_force(u[lo]), R0[lo], rtol=1e-5)
