"""``broachkit periodic`` and ``broachkit periodic-branch`` (issue 12's commands)."""

from __future__ import annotations

import json
import math

import pytest

from broachkit_cli.main import main


def _run(capsys, *argv):
    rc = main(list(argv))
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def test_periodic_cycle_agrees_with_the_shooting_solver(capsys, tmp_path):
    rc, out, _ = _run(capsys, "periodic", "--fn", "0.1", "--chi-c", "0", "--shooting",
                      "--json", "--out", str(tmp_path))  # fmt: skip
    assert rc == 0
    doc = json.loads(out)
    assert doc["status"] == "SUCCESS" and doc["stable"]
    # collocation against the return-map shooting solver (independent method)
    assert doc["shooting"]["status"] == "SUCCESS"
    assert abs(doc["shooting"]["dT"]) < 1e-6
    assert doc["T"] == pytest.approx(doc["shooting"]["T"], abs=1e-6)
    assert doc["waves_per_period"] == pytest.approx(1.0, abs=1e-12)
    # in following seas (chi_c = 0) the lateral motions are not excited
    assert doc["max_roll_deg"] < 1e-6
    assert len(doc["multipliers"]) == 7
    assert max(m["abs"] for m in doc["multipliers"]) < 1.0
    assert doc["trivial_multiplier_error"] < 1e-6
    for name in ("periodic.csv", "periodic.json", "periodic.png"):
        assert (tmp_path / name).stat().st_size > 0


def test_periodic_branch_over_a_short_fn_range(capsys):
    """0.1 -> 0.2 at 10 deg: the whole range is covered by stable cycles whose period
    grows with Fn (the ship is overtaken more slowly), without the blow-up of 0.3016."""
    rc, out, _ = _run(capsys, "periodic-branch", "--chi-c", "10", "--fn", "0.1:0.2", "--json")
    assert rc == 0
    doc = json.loads(out)
    assert doc["status"] == "PARAM_BOUND"
    assert doc["Fn_last"] == pytest.approx(0.2, abs=1e-10)
    for key in ("Fn_limit_fit", "Fn_lost_stability"):
        assert doc[key] is None or math.isnan(doc[key])
