"""Vessel files: the [uncertainties] section, status `calibrated`, wave_surge_model, TOML writer."""

from __future__ import annotations

import copy
import math
import tomllib

import pytest

from ship_models.contracts import SeaState
from ship_models.estimation import build_vessel_model
from ship_models.vessel import (
    DATA_DIR,
    STATUSES,
    Coefficient,
    VesselFileError,
    dump_vessel,
    load_vessel,
    parse_vessel,
    vessel_to_toml,
)


@pytest.fixture(scope="module")
def doc() -> dict:
    with (DATA_DIR / "purse_seiner.toml").open("rb") as fh:
        return tomllib.load(fh)


def test_default_vessel_uncertainties_are_stated_and_sourced():
    v = load_vessel("purse_seiner")
    assert len(v.uncertainties) >= 20
    for key, u in v.uncertainties.items():
        assert u.source.strip(), key
        # none is presented as a published accuracy: every one is an explicit assumption
        # or a type B estimate derived in this project (GUM 4.3.7), which says how
        assert u.source.startswith(("assumed:", "type B (GUM")), key
        assert v.coefficients.get(key, Coefficient(0, "-", "x", "estimated")).status != "given"
    resolved = build_vessel_model(v).vessel
    # relative uncertainty: fraction of the (estimated) value, in its unit
    m_x = resolved.coefficient("hydrodynamics.m_x").value
    assert resolved.sigma("hydrodynamics.m_x") == pytest.approx(0.30 * m_x, rel=1e-14)
    assert resolved.sigma("propulsion.w_P") == pytest.approx(0.05, rel=1e-14)
    assert resolved.sigma("particulars.B") is None


@pytest.mark.parametrize(
    ("entry", "match"),
    [
        (
            {"value": -0.1, "type": "relative", "source": "x"},
            r"uncertainties\.hydrodynamics\.m_x\.value",
        ),
        (
            {"value": 0.1, "type": "gaussian", "source": "x"},
            r"uncertainties\.hydrodynamics\.m_x\.type",
        ),
        (
            {"value": 0.1, "type": "relative", "source": " "},
            r"uncertainties\.hydrodynamics\.m_x\.source",
        ),
        ({"value": 0.1, "type": "absolute", "source": "x"}, r"needs a `unit`"),
        ({"value": 0.1, "type": "absolute", "unit": "m", "source": "x"}, r"unit 'm' not accepted"),
        ({"value": 0.1, "type": "relative", "source": "x", "sd": 1}, r"unknown key"),
    ],
)
def test_bad_uncertainties_are_refused_naming_the_field(doc, entry, match):
    d = copy.deepcopy(doc)
    d["uncertainties"]["hydrodynamics.m_x"] = entry
    with pytest.raises(VesselFileError, match=match):
        parse_vessel(d)


def test_uncertainty_of_an_unknown_coefficient_is_refused(doc):
    d = copy.deepcopy(doc)
    d["uncertainties"]["hydrodynamics.m_z"] = {"value": 0.1, "type": "relative", "source": "x"}
    with pytest.raises(VesselFileError, match=r"uncertainties\.hydrodynamics\.m_z"):
        parse_vessel(d)


def test_calibrated_status_and_wave_surge_model(doc):
    assert "calibrated" in STATUSES
    d = copy.deepcopy(doc)
    d["hydrodynamics"]["wave_surge_scale"] = {
        "value": 0.8, "unit": "-", "source": "calibrated to a target", "status": "calibrated",
    }  # fmt: skip
    v = parse_vessel(d)
    assert v.get("hydrodynamics.wave_surge_scale") == 0.8
    assert v.wave_surge_model == "froude_krylov"
    d["hydrodynamics"]["wave_surge_scale"]["value"] = 0.0
    with pytest.raises(VesselFileError, match=r"hydrodynamics\.wave_surge_scale"):
        parse_vessel(d)
    d = copy.deepcopy(doc)
    d["vessel"]["wave_surge_model"] = "potential_flow_3d"
    with pytest.raises(VesselFileError, match=r"vessel\.wave_surge_model"):
        parse_vessel(d)


def test_wave_surge_scale_scales_the_surge_force_only():
    v = load_vessel("purse_seiner")
    base = build_vessel_model(v)
    half = build_vessel_model(v.with_overrides({"hydrodynamics.wave_surge_scale": 0.5}))
    assert base.vessel.coefficient("hydrodynamics.wave_surge_scale").status == "assumed"
    args = (0.3, 9.0, math.radians(10.0), SeaState(1 / 9.2, 1.5))
    X0, Y0, N0, K0 = base.forces.waves.forces(*args)
    X1, Y1, N1, K1 = half.forces.waves.forces(*args)
    assert X1 == pytest.approx(0.5 * X0, rel=1e-13)
    assert (Y1, N1, K1) == pytest.approx((Y0, N0, K0), rel=1e-13)


def test_toml_writer_round_trips(tmp_path):
    v = load_vessel("purse_seiner")
    v2 = v.with_overrides(
        {"hydrodynamics.wave_surge_scale": Coefficient(0.7534162333607475, "-",
                                                       'calibrated "x" \\ y', "calibrated")}
    )  # fmt: skip
    p = dump_vessel(v2, tmp_path / "c.toml", header="line one\nline two")
    back = load_vessel(p)
    assert back.coefficients == v2.coefficients
    assert back.uncertainties == v2.uncertainties
    assert back.meta == v2.meta and back.name == v2.name
    assert vessel_to_toml(back) == vessel_to_toml(v2)
