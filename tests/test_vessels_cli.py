"""``broachkit vessels list|show|validate`` through ``broachkit_cli.main.main``."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from broachkit_cli.main import main
from ship_models import get_vessel_data, list_models, load_vessel
from ship_models.vessel import DATA_DIR, STATUSES

README = Path(__file__).resolve().parents[1] / "ship_models" / "README.md"


def test_list(capsys):
    assert main(["vessels", "list"]) == 0
    out = capsys.readouterr().out
    for name in ("purse_seiner", "purse_seiner_surge", "kvlcc2", "kvlcc2_surge"):
        assert re.search(rf"^{name}\s", out, re.M), name
    assert main(["vessels", "list", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == list_models()
    seiner = next(r for r in rows if r["name"] == "purse_seiner")
    assert seiner["kind"] == "4dof" and seiner["origin"] == "built-in"
    assert seiner["target"].endswith("purse_seiner.toml")
    assert main(["vessels"]) == 0  # no action: list
    assert "purse_seiner" in capsys.readouterr().out


def test_show_json_has_every_coefficient_with_provenance(capsys):
    assert main(["vessels", "show", "purse_seiner", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    resolved = get_vessel_data("purse_seiner").vessel
    coeffs = doc["coefficients"]
    assert set(coeffs) == set(resolved.coefficients)
    for key, c in coeffs.items():
        assert set(c) == {"value", "unit", "source", "status"}, key
        assert c["status"] in STATUSES and c["source"].strip(), key
        assert c["value"] == resolved.coefficient(key).value
    # Umeda (1999) Table 1 values are 'given'; the pipeline's fill-ins say how
    assert coeffs["particulars.L_pp"] == {
        "value": 34.5,
        "unit": "m",
        "source": "Umeda (1999) Table 1",
        "status": "given",
    }
    assert coeffs["hydrodynamics.Y_v_prime"]["status"] == "estimated"
    assert "Inoue" in coeffs["hydrodynamics.Y_v_prime"]["source"]
    assert sum(doc["status_counts"].values()) == len(coeffs)
    assert doc["derived"]["KG"] == pytest.approx(get_vessel_data("purse_seiner").info["KG"])
    assert doc["name"] == "purse_seiner" and doc["file"].endswith("purse_seiner.toml")


def test_show_text_and_file_path(capsys, tmp_path: Path):
    assert main(["vessels", "show", "kvlcc2"]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if "hydrodynamics.Y_v_prime" in x)
    assert "-0.315" in line and "measured" in line and "Yasukawa & Yoshimura (2015)" in line
    assert "[particulars]" in out and re.search(r"\d+ coefficients: \d+ given", out)
    f = tmp_path / "mine.toml"
    shutil.copy(DATA_DIR / "kvlcc2.toml", f)
    assert main(["vessels", "show", str(f), "--no-estimate", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["coefficients"]) == set(load_vessel(f).coefficients)  # file values only
    assert doc["derived"] == {}
    assert main(["vessels", "show", "purse_seiner", "--no-estimate"]) == 0
    assert "estimated" not in capsys.readouterr().out.split("coefficients:")[0]


def test_show_unknown_name_lists_the_available(capsys):
    assert main(["vessels", "show", "titanic"]) == 2
    err = capsys.readouterr().err
    assert "unknown model 'titanic'" in err and "purse_seiner" in err


def test_validate_good_files(capsys):
    for f in (DATA_DIR / "purse_seiner.toml", DATA_DIR / "kvlcc2.toml"):
        assert main(["vessels", "validate", str(f)]) == 0
        out = capsys.readouterr().out
        assert f"{f}: valid" in out
        assert re.search(r"\d+ more filled by the estimation pipeline", out)
    assert main(["vessels", "validate", "--schema-only", str(DATA_DIR / "kvlcc2.toml")]) == 0
    assert ": valid" in capsys.readouterr().out


EXTRA_KEY = 'G_M = { value = 1, unit = "m", source = "x", status = "given" }\n'


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ('GM = { value = 1.0,', "GM = { value = -1.0,", "loading.GM"),
        ('status = "given" }\nT_phi', 'status = "guessed" }\nT_phi', "loading.GM.status"),
        ("[loading]\n", "[loading]\n" + EXTRA_KEY, "loading.G_M"),
        ("value = 0.10869565217391304", "value = 0.2", "waves.H_over_lambda"),
        ('B = { value = 7.6, unit = "m"', 'B = { value = 7.6, unit = "ft"', "particulars.B"),
    ],
)  # fmt: skip
def test_validate_bad_file_names_the_field(capsys, tmp_path: Path, old, new, field):
    text = (DATA_DIR / "purse_seiner.toml").read_text()
    assert old in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(old, new, 1))
    assert main(["vessels", "validate", str(bad)]) == 1
    cap = capsys.readouterr()
    assert "invalid" in cap.err and f"`{field}" in cap.err
    assert ": valid" not in cap.out


def test_validate_missing_field_broken_toml_and_missing_file(capsys, tmp_path: Path):
    text = (DATA_DIR / "purse_seiner.toml").read_text()
    f = tmp_path / "no_gm.toml"
    f.write_text("\n".join(x for x in text.splitlines() if not x.startswith("GM =")))
    assert main(["vessels", "validate", str(f)]) == 1
    assert "missing required field `loading.GM`" in capsys.readouterr().err
    f.write_text("[loading\nGM = 1")
    assert main(["vessels", "validate", str(f)]) == 1
    assert "TOML" in capsys.readouterr().err
    assert main(["vessels", "validate", str(tmp_path / "nothing.toml")]) == 1
    assert "no vessel file" in capsys.readouterr().err


def test_validate_reports_estimation_failure(capsys, tmp_path: Path):
    """A file that passes the schema but whose particulars no parametric hull can match."""
    text = (DATA_DIR / "kvlcc2.toml").read_text()
    f = tmp_path / "k.toml"
    f.write_text(text.replace("C_wp = { value = 0.90,", "C_wp = { value = 0.80,"))
    assert main(["vessels", "validate", "--schema-only", str(f)]) == 0
    capsys.readouterr()
    assert main(["vessels", "validate", str(f)]) == 1
    err = capsys.readouterr().err
    assert "estimation pipeline failed" in err and "hull.C_wp" in err


def test_readme_example_file_is_valid(capsys, tmp_path: Path):
    """The annotated minimal file of ship_models/README.md validates, including estimation."""
    text = README.read_text()
    blocks = re.findall(r"```toml\n(.*?)```", text, re.S)
    example = next(b for b in blocks if "[particulars]" in b)
    f = tmp_path / "my_trawler.toml"
    f.write_text(example)
    assert main(["vessels", "validate", str(f)]) == 0
    out = capsys.readouterr().out
    assert "valid: vessel 'my_trawler'" in out
    # the README shows this very line as the expected output
    shown = out.strip().split(": valid: ", 1)[1]
    assert shown in text
