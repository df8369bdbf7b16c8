"""Issue 27 items 2-3: --out checked before computing; messages in the user's units."""

from __future__ import annotations

import re
import time

import pytest

from broachkit_cli.main import main

#: Commands with an --out, and the arguments of a short run of each.
OUT_COMMANDS = [
    ["calibrate", "--target", "fn_crit=0.32475"],
    ["sensitivity"],
    ["critical-curve", "--chi-c", "0:1"],
    ["cycles", "--chi-c", "10"],
    ["periodic", "--fn", "0.3", "--chi-c", "45"],
    ["periodic-branch", "--chi-c", "10", "--fn", "0.1:0.35"],
    ["manifold", "--fn", "0.30155", "--chi-c", "10"],
    ["demo"],
    ["reproduce", "--only", "demo"],
    ["sweep", "surface"],
]


@pytest.mark.parametrize("argv", OUT_COMMANDS, ids=[a[0] + "-" + a[-1] for a in OUT_COMMANDS])
def test_an_unwritable_out_is_refused_before_anything_is_computed(tmp_path, capsys, argv):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    t0 = time.perf_counter()
    assert main([*argv, "--out", str(blocker / "sub")]) == 2
    err = capsys.readouterr().err.strip()
    assert time.perf_counter() - t0 < 5.0  # nothing was computed
    assert len(err.splitlines()) == 1 and "--out" in err
    assert not re.search(r"\b[A-Z][a-zA-Z]*Error\b", err)


def test_calibrate_out_may_be_a_folder_and_the_short_coefficient_name_is_accepted():
    from ship_models.analysis.calibration import coefficient_key
    from ship_models.estimation import build_vessel_model
    from ship_models.vessel import load_vessel

    resolved = build_vessel_model(load_vessel("purse_seiner")).vessel
    assert coefficient_key("wave_surge_scale", resolved) == "hydrodynamics.wave_surge_scale"
    full = "hydrodynamics.wave_surge_scale"
    assert coefficient_key(full, resolved) == full
    assert coefficient_key("no_such_thing", resolved) == "no_such_thing"


def test_calibrate_out_folder_gives_the_default_file_name(tmp_path):
    from broachkit_cli.options import prepare_out_file

    assert prepare_out_file(tmp_path, "v_calibrated.toml") == tmp_path / "v_calibrated.toml"
    assert prepare_out_file(tmp_path / "x.toml", "v.toml") == tmp_path / "x.toml"


@pytest.mark.parametrize(
    "argv",
    [
        ["critical", "--chi-c", "42", "--method", "bisection"],
        ["critical", "--chi-c", "10", "--h-over-lambda", "0.02"],
    ],
)
def test_messages_show_parameters_in_degrees_without_reprs(capsys, argv):
    rc = main(argv)
    text = capsys.readouterr()
    msg = text.err + text.out
    assert "np.float64" not in msg and "{'" not in msg
    assert not re.search(r"chi_c'?:? ?=? ?0\.\d{4,}", msg)  # no course in radians
    if rc == 2:
        assert f"chi_c = {argv[2]} deg" in msg
