"""IMO 2008 IS Code checks: each formula in closed form (no printed worked example read)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ship_models.hydro.stability_criteria import (
    TABLE_S,
    TABLE_X1,
    general_criteria,
    roll_period,
    roll_to_windward,
    table,
    vessel_intact_stability,
    weather_criterion,
    weather_limit_area,
)

PHI = np.radians(np.arange(0.0, 90.5, 0.5))


def test_general_criteria_on_a_sine_curve() -> None:
    # GZ = a sin(2 phi): areas a/2 (1 - cos 2 phi), maximum at 45 deg, GM = 2a
    a = 0.4
    gz = a * np.sin(2 * PHI)
    crit = {c.name: c for c in general_criteria(PHI, gz, 2 * a)}
    d30, d40 = math.radians(30), math.radians(40)
    h2 = math.radians(0.5) ** 2  # trapezoid error of the sampled curve: O(h^2) GZ''
    assert crit["area_0_30"].value == pytest.approx(a / 2 * (1 - math.cos(2 * d30)), abs=h2)
    assert crit["area_0_40"].value == pytest.approx(a / 2 * (1 - math.cos(2 * d40)), abs=h2)
    assert crit["area_30_40"].value == pytest.approx(
        a / 2 * (math.cos(2 * d30) - math.cos(2 * d40)), abs=h2
    )
    assert crit["gz_at_30_or_more"].value == pytest.approx(a, abs=1e-12)
    assert crit["angle_of_max_gz"].value == pytest.approx(math.radians(45), abs=1e-4)
    assert crit["GM0"].required == 0.15


def test_fishing_vessel_gm0_is_035() -> None:
    gz = 0.3 * np.sin(2 * PHI)
    gen = {c.name: c for c in general_criteria(PHI, gz, 0.30)}
    fish = {c.name: c for c in general_criteria(PHI, gz, 0.30, vessel_class="fishing_vessel")}
    assert gen["GM0"].passed and not fish["GM0"].passed
    assert fish["GM0"].required == 0.35 and "Part B 2.1" in fish["GM0"].clause
    with pytest.raises(ValueError, match="vessel_class"):
        general_criteria(PHI, gz, 0.3, vessel_class="yacht")


def test_weather_criterion_linear_gz_closed_form() -> None:
    GM = 0.8
    gz = GM * PHI  # linear: phi_0 = lw1/GM, phi_c = lw2/GM, areas are triangles
    kw = dict(displacement_t=500.0, B=8.0, d=2.6, C_B=0.6, KG=3.0, GM=GM, L_wl=35.0)
    A, Z = 60.0, 2.0
    w = weather_criterion(PHI, gz, A_wind=A, Z_wind=Z, **kw)
    lw1 = 504.0 * A * Z / (1000.0 * 9.81 * 500.0)
    assert w.lw1 == pytest.approx(lw1, rel=1e-14) and w.lw2 == pytest.approx(1.5 * lw1, rel=1e-14)
    assert w.phi0 == pytest.approx(lw1 / GM, rel=1e-9)
    phi_c = 1.5 * lw1 / GM
    assert w.phi_c == pytest.approx(phi_c, rel=1e-9)
    lo = w.phi0 - w.phi1
    # a: lw2 above the line GM x from lo to phi_c; b: below it from phi_c to 50 deg
    assert w.area_a == pytest.approx(0.5 * GM * (phi_c - lo) ** 2, rel=1e-9)
    assert w.area_b == pytest.approx(0.5 * GM * (math.radians(50) - phi_c) ** 2, rel=1e-9)
    # phi_1 = 109 k X1 X2 sqrt(r s) deg with the tables interpolated
    T = 2 * (0.373 + 0.023 * 8.0 / 2.6 - 0.043 * 0.35) * 8.0 / math.sqrt(GM)
    assert w.T_roll == pytest.approx(T, rel=1e-14)
    X1 = np.interp(8.0 / 2.6, *TABLE_X1)
    r = 0.73 + 0.6 * (3.0 - 2.6) / 2.6
    s = np.interp(T, *TABLE_S)
    assert w.phi1 == pytest.approx(math.radians(109 * X1 * 0.95 * math.sqrt(r * s)), rel=1e-12)
    assert w.passed


def test_weather_limit_area_is_where_b_equals_a() -> None:
    GM = 0.5
    gz = GM * np.sin(2 * PHI) / 2
    kw = dict(displacement_t=400.0, B=7.6, d=2.65, C_B=0.6, KG=3.0, GM=GM, L_wl=34.5)
    A = weather_limit_area(PHI, gz, Z_wind=2.0, **kw)
    w = weather_criterion(PHI, gz, A_wind=A, Z_wind=2.0, **kw)
    assert min(w.area_b / w.area_a - 1.0, w.phi0_limit - w.phi0) == pytest.approx(0.0, abs=1e-4)
    assert not weather_criterion(PHI, gz, A_wind=1.2 * A, Z_wind=2.0, **kw).passed


def test_tables_and_period() -> None:
    assert table(TABLE_X1, 2.0) == 1.0 and table(TABLE_X1, 4.0) == 0.80  # constant beyond ends
    assert table(TABLE_S, 5.0) == 0.100 and table(TABLE_S, 25.0) == 0.035
    assert roll_period(7.6, 2.65, 34.5, 1.0) == pytest.approx(
        2 * (0.373 + 0.023 * 7.6 / 2.65 - 0.043 * 0.345) * 7.6, rel=1e-14
    )
    phi1, f = roll_to_windward(B=4.8, d=2.4, C_B=0.45, OG=0.0, T=6.0)  # X1 = 1, X2 = 0.75
    assert phi1 == pytest.approx(math.radians(109 * 1.0 * 0.75 * math.sqrt(0.73 * 0.1)), rel=1e-14)


def test_purse_seiner_checks() -> None:
    from ship_models.registry import get_vessel_data

    r = vessel_intact_stability(get_vessel_data("purse_seiner"))
    crit = {c.name: c for c in r["general"]}
    assert r["vessel_class"] == "fishing_vessel" and crit["GM0"].required == 0.35
    # the loading condition was fitted to the limit of the general criteria
    assert min(c.margin for c in r["general"]) > -1e-3
    assert r["weather"].passed and r["A_wind_limit"] > r["A_wind"]
