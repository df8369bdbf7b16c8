"""``broachkit critical --method bvp|both``: the collocation answer agrees with bisection.

Issue 5 asks that the boundary-value critical Fn at chi_c = 10 deg agree with the
bisection on manifold fates (an independent, brute-force method) to 1e-4 in Fn.
"""

from __future__ import annotations

import json

import pytest

from broachkit_cli.main import main


def test_critical_both_methods_agree(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["critical", "--chi-c", "10", "--method", "both", "--tol", "1e-5", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["status"] == "SUCCESS"
    lo, hi = out["bracket"]
    assert hi - lo <= 1e-5
    assert out["bisection"]["fate_lo"] != out["bisection"]["fate_hi"]
    # the connecting orbit lies in the bisection bracket (to the bracket's own width)
    assert lo - 1e-5 <= out["Fn"] <= hi + 1e-5
    assert abs(out["difference"]) < 1e-4
    assert out["bvp"]["residual_norm"] < 1e-8
    # mesh and truncation-time refinement move the answer by less than 1e-6
    assert abs(out["bvp"]["delta_Fn_mesh"]) < 1e-6
    assert abs(out["bvp"]["delta_Fn_T"]) < 1e-6


def test_critical_bvp_rejects_bad_guess(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["critical", "--chi-c", "10", "--method", "bvp", "--fn-guess", "-1"])
    assert code == 2
    assert "--fn-guess" in capsys.readouterr().err
