"""Explicit calibration: the target is reproduced and survives the written vessel file."""

from __future__ import annotations

import math

import pytest

from ship_models.analysis.calibration import calibrate
from ship_models.analysis.critical_bvp import critical_fn_bvp
from ship_models.estimation import build_vessel_model
from ship_models.umeda_4dof import Umeda4DOF
from ship_models.vessel import load_vessel

pytestmark = pytest.mark.slow

CHI = math.radians(10.0)
TARGET = 0.32475


@pytest.fixture(scope="module")
def cal():
    return calibrate("hydrodynamics.wave_surge_scale", TARGET, CHI, target_source="test target")


def test_calibration_reproduces_its_target(cal):
    assert cal.success, cal.message
    assert abs(cal.Fn_check - TARGET) <= 1e-6
    assert cal.value_before == 1.0 and 0.0 < cal.value < 1.0  # a weaker surge force
    assert cal.Fn_before < TARGET


def test_calibrated_file_round_trips_and_reproduces_the_target(cal, tmp_path):
    p = cal.write(tmp_path / "calibrated.toml")
    v = load_vessel(p)
    c = v.coefficient("hydrodynamics.wave_surge_scale")
    assert c.value == cal.value and c.status == "calibrated"
    assert "test target" in c.source and f"{TARGET:.8g}" in c.source
    assert "replaces 1" in c.source  # the value it replaced is kept in the provenance
    assert "calibrat" in v.meta["calibration"]
    assert "hydrodynamics.wave_surge_scale" not in v.uncertainties
    # every other number is unchanged
    base = load_vessel("purse_seiner")
    for k, b in base.coefficients.items():
        assert v.coefficients[k] == b, k
    conn = critical_fn_bvp(CHI, model=Umeda4DOF(build_vessel_model(v)), Fn_guess=TARGET)
    assert conn.success and abs(conn.Fn - TARGET) <= 1e-6


def test_calibration_refuses_bad_requests():
    with pytest.raises(ValueError, match="target_Fn"):
        calibrate("hydrodynamics.wave_surge_scale", -0.3)
    with pytest.raises(ValueError, match="coefficient"):
        calibrate("hydrodynamics.no_such", 0.3)
    with pytest.raises(ValueError, match="parameter"):
        calibrate("autopilot.K_R", 0.3)
