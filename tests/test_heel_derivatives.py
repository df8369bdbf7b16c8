"""The analogy estimate of the heel derivatives (ship_models.hydro.heel)."""

from __future__ import annotations

import math

import pytest

from ship_models import Umeda4DOF
from ship_models.hydro.heel import (
    SON_NOMOTO,
    SON_NOMOTO_HULL,
    son_nomoto_heel_derivatives,
    son_nomoto_ratios,
)
from ship_models.vessel import VesselFileError, load_vessel, parse_vessel

# Son & Nomoto's container ship SR 108: L = 175 m, d = 8.5 m
L_SN, D_SN = 175.0, 8.5


def test_applied_to_its_own_hull_it_returns_the_measured_derivatives() -> None:
    """Round trip through the normalisations: Son & Nomoto's primes (rho/2 L^2 U^2 for
    forces, rho/2 L^3 U^2 for moments) converted to this project's (rho/2 L d U^2,
    rho/2 L^2 d U^2, rho/2 L d^2 U^2) and back must give the measured heel derivatives;
    K_v = -z_H Y_v fixes the height z_H of the reference hull's drift force."""
    sn = SON_NOMOTO
    Yv = sn["Y_v"] * L_SN / D_SN  # rho/2 L^2 U -> rho/2 L d U
    Nv = sn["N_v"] * L_SN / D_SN  # rho/2 L^3 U -> rho/2 L^2 d U
    z_H_over_L = -sn["K_v"] / sn["Y_v"]  # K_v = -z_H Y_v, both per rho/2 L^3 U
    est = son_nomoto_heel_derivatives(
        Yv,
        Nv,
        z_H_over_L * L_SN / D_SN,
        L_over_B=SON_NOMOTO_HULL["L/B"],
        B_over_d=SON_NOMOTO_HULL["B/d"],
        C_b=SON_NOMOTO_HULL["C_b"],
    )
    assert est.Y_phi_prime == pytest.approx(sn["Y_phi"] * L_SN / D_SN, rel=1e-12)
    assert est.N_phi_prime == pytest.approx(sn["N_phi"] * L_SN / D_SN, rel=1e-12)
    assert est.K_phi_prime == pytest.approx(sn["K_phi"] * (L_SN / D_SN) ** 2, rel=1e-12)
    assert est.outside == ()


def test_ratios_and_signs() -> None:
    aY, aN, aK = son_nomoto_ratios()
    assert aY == pytest.approx(0.000063 / 0.0116, rel=1e-12)
    assert aN == pytest.approx(0.0001424 / 0.0038545, rel=1e-12)
    assert aK == pytest.approx(-0.000021 / 0.0003026, rel=1e-12)
    # heel to starboard acts like a drift to starboard: Y_phi, N_phi of the signs of Y_v, N_v
    est = son_nomoto_heel_derivatives(-0.46, -0.14, 0.3, L_over_B=4.5, B_over_d=2.9, C_b=0.6)
    assert est.Y_phi_prime < 0 and est.N_phi_prime < 0
    assert est.K_phi_prime == pytest.approx(-aK * 0.3 * -0.46, rel=1e-12)
    assert est.outside == ("L/B 4.5 (SR 108: 6.89)",)


def test_rejects_a_destabilising_drift_force() -> None:
    with pytest.raises(ValueError, match="Y_v_prime"):
        son_nomoto_heel_derivatives(0.1, -0.1, 0.3, L_over_B=6.9, B_over_d=3.0, C_b=0.56)


def _with_method(method: str):  # type: ignore[no-untyped-def]
    d = load_vessel("purse_seiner").to_dict()
    d["vessel"]["heel_derivatives_method"] = method
    return parse_vessel(d)


def test_the_vessel_option_feeds_the_equations() -> None:
    """The drift derivatives the ratios multiply are the equations' own, about G
    (``Y_v1``, ``N_v1`` of the forces; the file's N_v' refers to midship)."""
    m = Umeda4DOF(_with_method("son_nomoto_ratio"))
    v, F = m.vessel, m.forces
    q = 0.5 * F.rho * F.L * F.d_m
    aY, aN, _ = son_nomoto_ratios()
    for name, ref in (("Y_phi_prime", aY * F.Y_v1 / q), ("N_phi_prime", aN * F.N_v1 / (q * F.L))):
        c = v.coefficient(f"hydrodynamics.{name}")
        assert c.status == "estimated"
        assert "Son & Nomoto (1981)" in c.source and "L/B 4.54" in c.source
        assert c.value == pytest.approx(ref, rel=1e-12)
    assert F.Y_phi2 == pytest.approx(aY * F.Y_v1, rel=1e-12)
    assert F.N_phi2 == pytest.approx(aN * F.N_v1, rel=1e-12)
    assert math.isfinite(F.K_phi2) and F.K_phi2 < 0.0  # an added restoring moment
    # the default vessel keeps them at zero, as assumed
    d = Umeda4DOF("purse_seiner")
    assert d.forces.Y_phi2 == d.forces.N_phi2 == d.forces.K_phi2 == 0.0
    assert d.vessel.coefficient("hydrodynamics.N_phi_prime").status == "assumed"


def test_leaving_the_reference_hull_form_is_logged_once(caplog) -> None:  # type: ignore[no-untyped-def]
    from ship_models.estimation import build_vessel_model
    from ship_models.validity import reset_reports

    reset_reports()
    v = _with_method("son_nomoto_ratio")
    with caplog.at_level("WARNING", logger="ship_models.validity"):
        build_vessel_model(v)
        build_vessel_model(v)
    hits = [r.getMessage() for r in caplog.records if "Son & Nomoto" in r.getMessage()]
    assert len(hits) == 1
    assert "L/B = 4.539" in hits[0] and "valid 5.167..8.612" in hits[0]


def test_unknown_method_is_refused_by_name() -> None:
    with pytest.raises(VesselFileError, match="heel_derivatives_method"):
        _with_method("hirano")


@pytest.mark.slow
def test_heel_estimate_study_quick_path() -> None:
    """studies/heel_estimate.py --quick: the estimate moves the crest fold at the paper's
    Fn by about a degree but leaves the 10 deg threshold within its error estimate."""
    from studies.heel_estimate import evaluate

    zero = evaluate("none", quick=True)[0]
    est = evaluate("son_nomoto_ratio", quick=True)[0]
    assert est["N_phi_prime"] < 0.0 == zero["N_phi_prime"]
    assert 0.3 < zero["crest_fold_deg"] - est["crest_fold_deg"] < 3.0
    assert zero["mechanism"] == est["mechanism"] == "heteroclinic"
    assert abs(est["Fn_threshold"] - zero["Fn_threshold"]) <= est["error"] + zero["error"]
