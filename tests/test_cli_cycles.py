"""``broachkit cycles``: options, bad input (fast) and one real branch (slow).

The real run is checked against independent references: the period blow-up Fn fitted
from the cycle branch against the connecting-orbit solver's critical Fn (the two
methods meet at the heteroclinic bifurcation, Umeda 1999), the files against the
printed JSON, and the roll physically against the angle of vanishing stability.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from broachkit_cli.main import _load_commands, build_parser, main


def _parse(*argv: str):
    return build_parser(_load_commands()).parse_args(["cycles", *argv])


def test_cycles_is_registered_with_its_defaults() -> None:
    args = _parse()
    assert args.command == "cycles"
    assert args.vary == "fn"
    assert args.Fn == pytest.approx(0.1)
    assert args.chi_c == pytest.approx(10.0)
    assert args.out is None and not args.json and not args.compare


def test_cycles_parses_paper_names() -> None:
    args = _parse("--chi-c", "20", "--fn", "0.2", "--vary", "chi-c", "--chi-c-max", "40",
                  "--period-max", "45", "--json", "--out", "x")  # fmt: skip
    assert (args.chi_c, args.Fn, args.vary, args.chi_c_max, args.period_max) == (
        20.0, 0.2, "chi-c", 40.0, 45.0,
    )  # fmt: skip
    assert args.json and str(args.out) == "x"


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--fn", "-0.1"], "--fn"),
        (["--fn", "nan"], "--fn"),
        (["--fn", "0.3", "--fn-max", "0.2"], "--fn-max"),
        (["--chi-c", "95"], "--chi-c"),
        (["--period-max", "0"], "--period-max"),
        (["--max-steps", "0"], "--max-steps"),
        (["--vary", "chi-c", "--compare"], "--compare"),
        (["--vary", "chi-c", "--chi-c", "70", "--chi-c-max", "60"], "--chi-c-min/--chi-c-max"),
        (["--vary", "chi-c", "--chi-c-max", "100"], "--chi-c-max"),
        (["--fn", "5"], "--fn"),  # beyond the vessel's resistance fit
        (["--vessel", "no_such_ship"], "--vessel"),
        (["--h-over-lambda", "0.5"], "--h-over-lambda"),
    ],
)
def test_cycles_bad_input_is_one_line_naming_the_option(
    argv: list[str], option: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["cycles", *argv]) == 2
    err = capsys.readouterr().err
    assert option in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_cycles_out_is_checked_before_computing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from broachkit_cli.commands import cycles

    def never(*a, **k):  # pragma: no cover - must not be reached
        raise AssertionError("computed before checking --out")

    monkeypatch.setattr(cycles, "compute", never)
    f = tmp_path / "a_file"
    f.write_text("")
    assert main(["cycles", "--out", str(f)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and err.count("\n") == 1


def test_cycles_unknown_vary_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["cycles", "--vary", "H"])
    assert exc.value.code == 2
    assert "--vary" in capsys.readouterr().err


@pytest.mark.slow
def test_cycles_fn_branch_ends_at_the_heteroclinic_fn(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "cyc"
    code = main(["cycles", "--chi-c", "10", "--compare", "--json", "--out", str(out)])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0, doc
    assert doc["status"] == "PERIOD_UNBOUNDED"
    assert doc["T_last"] >= 0.99 * 60.0  # the default --period-max
    # two independent methods: the period blow-up of the cycle branch and the
    # connecting-orbit BVP meet at the heteroclinic Fn (measured 4e-6 apart)
    assert doc["Fn_bvp_status"] == "SUCCESS"
    assert abs(doc["Fn_limit_fit"] - doc["Fn_bvp"]) < 1e-4
    assert abs(doc["Fn_limit_saddle_focus"] - doc["Fn_bvp"]) < 1e-4
    assert doc["Fn_first"] == pytest.approx(0.1, abs=1e-12)
    assert doc["Fn_last"] < doc["Fn_limit_fit"] + 1e-4
    # physics: a cycle never rolls past the angle of vanishing stability
    assert 0.0 < doc["max_roll_deg"] < doc["vanishing_angle_deg"]
    assert doc["rolls_past_vanishing_angle"] is False
    lost = doc["Fn_lost_stability"]
    assert lost is None or doc["Fn_first"] < lost <= doc["Fn_last"]
    # the files: complete, and the same numbers as printed
    on_disk = json.loads((out / "cycles_fn.json").read_text())
    assert on_disk["Fn_limit_fit"] == doc["Fn_limit_fit"]
    lines = [ln for ln in (out / "cycles_fn.csv").read_text().splitlines() if ln[:1] != "#"]
    rows = list(csv.DictReader(lines))
    assert len(rows) == doc["rows"]
    T = np.array([float(r["T"]) for r in rows])
    assert math.isclose(T[-1], doc["T_last"], rel_tol=1e-12)
    assert np.all(T > 0)
    assert (out / "cycles_fn.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(out.glob(".*tmp*"))


def _fake_result(max_roll_deg: float, vanishing_deg: float = 63.3):
    """A (doc, branch) pair shaped like compute()'s, without computing (for the writers)."""
    from types import SimpleNamespace

    p = np.linspace(0.1, 0.3, 5)
    cb = SimpleNamespace(p=p, T=np.linspace(7.0, 60.0, 5),
                         max_roll=np.radians(np.linspace(3.0, max_roll_deg, 5)),
                         max_heading=np.full(5, 0.1), mu_max=np.linspace(0.9, 2.0, 5),
                         mu_lead=np.linspace(0.9, 2.0, 5) + 0j,
                         n_unstable=np.array([0, 0, 0, 1, 1]))  # fmt: skip
    doc = {"vessel": "purse_seiner", "vary": "Fn", "Fn": 0.1, "chi_c_deg": 10.0,
           "status": "PERIOD_UNBOUNDED", "message": "m", "rows": 5, "Fn_first": 0.1,
           "Fn_last": 0.3, "T_last": 60.0, "Fn_limit_fit": 0.301, "Fn_limit_saddle_focus": 0.301,
           "Fn_lost_stability": float(p[3]), "max_roll_deg": max_roll_deg,
           "vanishing_angle_deg": vanishing_deg,
           "rolls_past_vanishing_angle": max_roll_deg >= vanishing_deg}  # fmt: skip
    return doc, cb


@pytest.mark.parametrize(("roll", "code"), [(10.0, 0), (70.0, 1)])
def test_cycles_files_and_capsize_verdict(
    roll: float, code: int, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    from broachkit_cli.commands import cycles

    monkeypatch.setattr(cycles, "compute", lambda *a: _fake_result(roll))
    assert main(["cycles", "--out", str(tmp_path)]) == code
    text = capsys.readouterr().out
    assert ("ROLLS PAST" in text) == (roll > 63.3)
    assert "Fn* = 0.301" in text and "stability lost at Fn = 0.25" in text
    lines = [ln for ln in (tmp_path / "cycles_fn.csv").read_text().splitlines() if ln[:1] != "#"]
    rows = list(csv.DictReader(lines))
    assert [float(r["max_roll_deg"]) for r in rows][-1] == pytest.approx(roll)
    assert json.loads((tmp_path / "cycles_fn.json").read_text())["branch"]["T"][-1] == 60.0
    assert (tmp_path / "cycles_fn.png").stat().st_size > 1000
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "cycles_fn.csv", "cycles_fn.json", "cycles_fn.png",
    ]  # fmt: skip


def test_cycles_text_without_blow_up_or_instability(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from broachkit_cli.commands import cycles

    doc, cb = _fake_result(10.0)
    doc.update(status="PARAM_BOUND", Fn_limit_fit=math.nan, Fn_limit_saddle_focus=math.nan,
               Fn_lost_stability=math.nan)  # fmt: skip
    monkeypatch.setattr(cycles, "compute", lambda *a: (doc, cb))
    assert main(["cycles"]) == 0
    text = capsys.readouterr().out
    assert "no period blow-up: the branch ended by PARAM_BOUND" in text
    assert "stable throughout" in text and "nan" not in text
