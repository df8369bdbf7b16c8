"""Issue 28 item 4: nonsense vessel files get a one-line refusal naming the field.

``broachkit vessels validate`` and every model built from a file (``--vessel FILE``)
refuse a 50 MB file, a 0.3 s natural roll period, a 1 deg rudder limit, a tiny rudder
and an autopilot gain K_R = 0; the packaged vessels pass.
"""

from __future__ import annotations

import re

import pytest

from broachkit_cli.main import main
from ship_models.validation import imo_roll_period, plausibility_problems, rudder_area_minimum
from ship_models.vessel import DATA_DIR, load_vessel

BASE = (DATA_DIR / "purse_seiner.toml").read_text()


def _edit(text: str, key: str, value: str) -> str:
    new, n = re.subn(rf"^{key} = \{{ value = [^,]+,", f"{key} = {{ value = {value},", text,
                     flags=re.M)  # fmt: skip
    assert n == 1, key
    return new


CASES = {
    "roll_period": ("T_phi", "0.3", "loading.T_phi"),
    "rudder_limit": ("delta_max", "1.0", "rudder.delta_max"),
    "tiny_rudder": ("A_R", "0.01", "rudder.A_R"),
    "no_gain": ("K_R", "0.0", "autopilot.K_R"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_implausible_files_are_refused_in_one_line(tmp_path, capsys, case):
    key, value, field = CASES[case]
    f = tmp_path / f"{case}.toml"
    f.write_text(_edit(BASE, key, value))
    assert main(["vessels", "validate", str(f)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"`{field}`" in err and "invalid" in err
    # and a model is never built from it: one line, exit 2
    assert main(["fixed-points", "--vessel", str(f), "--fn", "0.3", "--chi-c", "10"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"`{field}`" in err


def test_a_huge_file_is_refused_before_it_is_read(tmp_path, capsys):
    f = tmp_path / "huge.toml"
    with f.open("wb") as fh:
        fh.truncate(50_000_000)
    assert main(["vessels", "validate", str(f)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "50.0 MB is too large" in err
    assert main(["critical", "--vessel", str(f), "--chi-c", "10"]) == 2
    assert "too large" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["purse_seiner", "kvlcc2"])
def test_the_packaged_vessels_are_plausible(name):
    assert plausibility_problems(load_vessel(name).coefficients) == []


def test_the_reference_formulas():
    # IMO IS Code 2008 A 2.3.4 for the purse seiner (B 7.6, d 2.65, L 34.5, GM 1.0):
    # C = 0.373 + 0.023 * 7.6/2.65 - 0.043 * 0.345 = 0.42413..., T = 2 C B / 1
    C = 0.373 + 0.023 * 7.6 / 2.65 - 0.043 * 0.345
    assert imo_roll_period(7.6, 2.65, 34.5, 1.0) == pytest.approx(2 * C * 7.6, rel=1e-14)
    assert rudder_area_minimum(100.0, 5.0, 20.0) == pytest.approx(5.0 * 2.0, rel=1e-14)
