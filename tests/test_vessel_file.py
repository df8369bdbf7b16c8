"""Vessel data files: loading, validation with field names, overrides, estimates."""

from __future__ import annotations

import copy
import json
import math
import tomllib
from pathlib import Path

import pytest

from ship_models.vessel import (
    DATA_DIR,
    Coefficient,
    VesselFileError,
    available_vessels,
    load_vessel,
    parse_vessel,
)

PACKAGED = DATA_DIR / "purse_seiner.toml"


@pytest.fixture(scope="module")
def doc() -> dict:
    with PACKAGED.open("rb") as fh:
        return tomllib.load(fh)


def _mutated(doc: dict, section: str, key: str, **changes: object) -> dict:
    d = copy.deepcopy(doc)
    d[section][key].update(changes)
    return d


def test_packaged_vessel_loads_with_given_table_1_values():
    v = load_vessel("purse_seiner")
    assert "purse_seiner" in available_vessels()
    # Umeda (1999) Table 1
    assert v.get("particulars.L_pp") == 34.5
    assert v.get("loading.GM") == 1.0
    assert v.get("T_phi") == 7.4
    assert v.get("waves.H_over_lambda") == pytest.approx(1 / 9.2, rel=1e-15)
    assert v.coefficient("loading.GM").status == "given"
    # angles given in degrees come back in radians
    assert v.get("rudder.delta_max") == pytest.approx(math.radians(35.0))
    for key, c in v.coefficients.items():
        assert c.status in ("given", "measured", "estimated", "assumed"), key
        assert c.source.strip(), key


def test_to_dict_is_json_and_round_trips(doc):
    v = load_vessel(PACKAGED)
    d = v.to_dict()
    s = json.dumps(d)
    back = parse_vessel(json.loads(s))
    assert back.coefficients == v.coefficients


def test_with_overrides_value_and_coefficient():
    v = load_vessel("purse_seiner")
    v2 = v.with_overrides({"loading.GM": 1.2})
    assert v2.get("loading.GM") == 1.2
    assert v2.coefficient("loading.GM").status == "measured"
    assert v.get("loading.GM") == 1.0  # immutable original
    c = Coefficient(0.3, "-", "captive model test, report X", "measured")
    v3 = v.with_overrides({"hydrodynamics.Y_v_prime": c})
    assert v3.coefficient("hydrodynamics.Y_v_prime") == c
    with pytest.raises(VesselFileError, match="loading.GMX"):
        v.with_overrides({"loading.GMX": 1.0})
    with pytest.raises(VesselFileError, match="loading.GM"):
        v.with_overrides({"loading.GM": -1.0})


@pytest.mark.parametrize(
    ("section", "key", "changes", "field"),
    [
        ("loading", "GM", {"value": 0.0}, "loading.GM"),
        ("loading", "GM", {"value": -0.3}, "loading.GM"),
        ("particulars", "B", {"value": -7.6}, "particulars.B"),
        ("particulars", "L_pp", {"value": 0.0}, "particulars.L_pp"),
        ("particulars", "d_a", {"value": -1.0}, "particulars.d_a"),
        ("waves", "H_over_lambda", {"value": 1 / 6.5}, "waves.H_over_lambda"),
        ("loading", "T_phi", {"value": float("nan")}, "loading.T_phi"),
        ("loading", "GM", {"status": "guessed"}, "loading.GM.status"),
        ("loading", "GM", {"unit": "ft"}, "loading.GM"),
        ("loading", "GM", {"extra": 1}, "loading.GM"),
        ("rudder", "delta_max", {"value": 120.0}, "rudder.delta_max"),
    ],
)
def test_bad_values_name_the_field(doc, section, key, changes, field):
    with pytest.raises(VesselFileError, match=field.replace(".", r"\.")):
        parse_vessel(_mutated(doc, section, key, **changes))


def test_negative_mass_refused(doc):
    d = copy.deepcopy(doc)
    d["loading"]["mass"] = {"value": -4.2e5, "unit": "kg", "source": "x", "status": "given"}
    with pytest.raises(VesselFileError, match=r"loading\.mass"):
        parse_vessel(d)
    # a mass inconsistent with rho C_b L B d_m is refused as well
    d["loading"]["mass"]["value"] = 2.0e5
    with pytest.raises(VesselFileError, match=r"loading\.mass"):
        parse_vessel(d)
    d["loading"]["mass"]["value"] = 425.2
    d["loading"]["mass"]["unit"] = "t"
    assert parse_vessel(d).get("loading.mass") == pytest.approx(425200.0)


def test_missing_field_and_missing_keys(doc):
    d = copy.deepcopy(doc)
    del d["loading"]["GM"]
    with pytest.raises(VesselFileError, match=r"missing required field `loading\.GM`"):
        parse_vessel(d)
    d = copy.deepcopy(doc)
    del d["loading"]["T_phi"]["source"]
    with pytest.raises(VesselFileError, match=r"loading\.T_phi.*source"):
        parse_vessel(d)
    d = copy.deepcopy(doc)
    d["loading"]["T_phi"] = 7.4  # bare number, not a table
    with pytest.raises(VesselFileError, match=r"loading\.T_phi"):
        parse_vessel(d)


def test_unknown_key_and_section(doc):
    d = copy.deepcopy(doc)
    d["loading"]["G_M"] = copy.deepcopy(d["loading"]["GM"])
    with pytest.raises(VesselFileError, match=r"loading\.G_M"):
        parse_vessel(d)
    d = copy.deepcopy(doc)
    d["loadings"] = {}
    with pytest.raises(VesselFileError, match="loadings"):
        parse_vessel(d)


def test_inconsistent_drafts_refused(doc):
    with pytest.raises(VesselFileError, match=r"particulars\.d_m"):
        parse_vessel(_mutated(doc, "particulars", "d_m", value=2.9))
    with pytest.raises(VesselFileError, match=r"particulars\.d_a"):
        parse_vessel(_mutated(doc, "particulars", "d_a", value=3.2))


def test_bad_file_on_disk(tmp_path: Path):
    text = PACKAGED.read_text()
    bad = tmp_path / "steep.toml"
    bad.write_text(text.replace("value = 0.10869565217391304", "value = 0.2"))
    with pytest.raises(VesselFileError, match=r"waves\.H_over_lambda"):
        load_vessel(bad)
    with pytest.raises(ValueError, match="packaged vessels"):
        load_vessel("no_such_vessel")
    broken = tmp_path / "broken.toml"
    broken.write_text("[loading\nGM = 1")
    with pytest.raises(VesselFileError, match="TOML"):
        load_vessel(broken)


def test_estimates_are_recorded_and_overrides_reach_the_model():
    from ship_models.estimation import resolve_vessel

    v = load_vessel("purse_seiner")
    d = resolve_vessel(v)
    for key in (
        "hydrodynamics.m_x",
        "hydrodynamics.Y_v_prime",
        "propulsion.w_P",
        "propulsion.K_T0",
        "resistance.form_factor",
    ):
        c = d.vessel.coefficient(key)
        assert c.status == "estimated" and c.source, key
        assert key not in v  # the file itself does not give it
    m_x = 0.1 * d.forces.mass
    d2 = resolve_vessel(v.with_overrides({"hydrodynamics.m_x": m_x}))
    assert d2.forces.m_x == pytest.approx(m_x)
    assert d2.vessel.coefficient("hydrodynamics.m_x").source == "user override"
    assert d2.forces.m_y == pytest.approx(d.forces.m_y)  # the rest is unchanged
