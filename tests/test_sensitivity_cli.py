"""``broachkit sensitivity`` and ``broachkit calibrate`` through ``broachkit_cli.main.main``."""

from __future__ import annotations

import json

import pytest

from broachkit_cli.main import main


@pytest.mark.slow
def test_sensitivity_json_and_files(capsys, tmp_path):
    keys = "hydrodynamics.wave_surge_scale,factor.R_surf"
    assert (
        main(["sensitivity", "--chi-c", "10", "--keys", keys, "--json", "--out", str(tmp_path)])
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    s = doc["sensitivity"]
    assert s["chi_c_deg"] == pytest.approx(10.0) and 0.25 < s["Fn"] < 0.40
    assert {e["key"] for e in s["entries"]} == set(keys.split(","))
    assert "band" not in doc  # a subset of keys gives no band
    assert (tmp_path / "tornado.png").stat().st_size > 1000
    assert json.loads((tmp_path / "sensitivity.json").read_text())["sensitivity"]["Fn"] == s["Fn"]
