"""The exact surf-riding threshold against independent checks, Melnikov's against it,
the whole assessment path (two vessels) and the ``broachkit assess`` command.

Independent references:
* the fate of the simulated unstable manifold (shooting) changes sign across the
  connection's Fn (and across the saddle-node Fn in gentle waves);
* a cold solve at a cell equals the value continued across the grid (within the
  continuation's error estimate);
* the surge model's connection at the paper's wave equals the 4-DOF model's critical
  Fn at chi_c = 0 (lateral motions vanish there), see README (0.30077).
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from broachkit_cli.main import main
from ship_models.assessment import assess, load_standard
from ship_models.assessment.exact import (
    SN_MARGIN,
    exact_threshold_grid,
    manifold_fate,
    saddle_node_fn,
    surf_riding_connection,
)
from ship_models.assessment.melnikov import melnikov_grid
from ship_models.assessment.standard import ScatterTable
from ship_models.surge import SurgeModel


@pytest.fixture(scope="module")
def surge() -> SurgeModel:
    return SurgeModel("purse_seiner")


@pytest.fixture(scope="module")
def columns(surge):
    """Three columns of the standard grid: 1.5 (plain), 2.0 (ends in a saddle-node loop)."""
    st = load_standard()
    lam = np.array([1.5, 2.0, 2.9])
    return lam, st.steepness, exact_threshold_grid(surge, lam, st.steepness)


def test_connection_against_shooting_and_the_4dof_model(surge):
    r = surf_riding_connection(surge, 1 / 9.2, 1.5)
    assert r.success and r.error("Fn") < 1e-6
    Fn = r.value("Fn")
    d = 1e-5 + r.error("Fn")
    assert manifold_fate(surge, 1 / 9.2, 1.5, Fn - d) == -1  # overtaken
    assert manifold_fate(surge, 1 / 9.2, 1.5, Fn + d) == 1  # captured
    # Umeda4DOF at chi_c = 0 by collocation (README table: 0.30077)
    assert Fn == pytest.approx(0.30077, abs=1e-5)


def test_grid_columns_against_cold_solves(surge, columns):
    lam, s, g = columns
    assert g.complete, g.column_status
    assert g.column_status[1].startswith("ok; saddle-node")
    assert np.nanmax(g.error) < 1e-4
    for i, j in ((0, 0), (0, 77), (1, 60), (2, 99)):
        cold = surf_riding_connection(surge, float(s[j]), float(lam[i]))
        assert cold.success
        tol = g.error[i, j] + cold.error("Fn") + 1e-7
        assert g.Fn_cr[i, j] == pytest.approx(cold.value("Fn"), abs=tol)


def test_saddle_node_part_against_shooting(surge, columns):
    """Below the saddle-node loop the threshold is where the equilibria are born."""
    lam, s, g = columns
    sn = saddle_node_fn(surge.forces, lam[1:2], s[:1])[0, 0]
    assert g.Fn_cr[1, 0] == pytest.approx(sn, abs=1e-12)
    assert SN_MARGIN <= g.error[1, 0] < 2 * SN_MARGIN
    assert manifold_fate(surge, float(s[0]), 2.0, sn - 1e-4) == -1
    assert manifold_fate(surge, float(s[0]), 2.0, sn + 1e-4) == 1


def test_melnikov_against_exact_over_the_columns(surge, columns):
    """Melnikov's closed form lies below the exact threshold for this hull; as a
    perturbation of the undamped separatrix it improves as the wave force grows against
    the net thrust: the error falls with the steepness along every column (about 12 %
    in long gentle waves, 1-2 % in the steepest)."""
    lam, s, g = columns
    m = melnikov_grid(surge.forces, lam, s)
    rel = np.abs(m.Fn_cr / g.Fn_cr - 1)
    assert np.all(m.Fn_cr < g.Fn_cr)
    assert np.max(rel) < 0.13
    mid = s.size // 2
    assert np.all(rel[:, -1] < rel[:, mid]) and np.all(rel[:, mid] < rel[:, 0])
    assert np.max(rel[:, -1]) < 0.025


def test_kvlcc2_whole_path():
    """L >= 200 m: Level 1 passes; Level 2 computed anyway (three wave lengths)."""
    st = load_standard()
    st = dataclasses.replace(st, lambda_over_L=np.array([1.0, 2.0, 2.975]))
    sc = ScatterTable(np.array([4.5, 8.5]), np.array([8.5, 11.5]),
                      np.array([[5.0, 1.0], [1.0, 2.0]]), "constructed")  # fmt: skip
    a = assess("kvlcc2", 0.142, scatter=sc, standard=st)
    doc = a.to_json()
    assert doc["level1"]["verdict"] == "not vulnerable" and "320" in doc["level1"]["reason"]
    # thresholds of the VLCC lie far above its service speed: nothing surf-rides
    assert np.nanmin(a.exact.Fn_cr) > 0.2 and np.nanmin(a.melnikov.Fn_cr) > 0.2
    assert doc["level2"]["melnikov"]["C"] == 0.0 and doc["level2"]["exact"]["C"] == 0.0
    assert doc["level2"]["exact"]["verdict"] == "not vulnerable"
    assert doc["threshold_comparison"]["max_rel_difference"] < 0.01


def test_cli_assess(tmp_path, capsys):
    sc = tmp_path / "scatter.csv"
    sc.write_text("# source: constructed\nHs\\Tz, 5.5, 6.5\n3.5, 10, 20\n5.5, 5, 10\n")
    out = tmp_path / "out"
    code = main(["assess", "--fn-service", "0.36", "--no-exact", "--scatter", str(sc),
                 "--out", str(out), "--json"])  # fmt: skip
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["level1"]["vulnerable"] is True
    mel = doc["level2"]["melnikov"]
    assert mel["C"] > 0
    assert mel["verdict"] == ("vulnerable" if mel["C"] > 0.005 else "not vulnerable")
    # the operational limit lies below the service Fn exactly when C exceeds R_SR
    assert (mel["Fn_limit"] < 0.36) == (mel["C"] > 0.005)
    assert doc["scatter_table"]["source"] == "constructed"
    for name in ("c_per_sea_state.png", "threshold.png", "assessment.json"):
        assert (out / name).stat().st_size > 0
    assert json.loads((out / "assessment.json").read_text())["Fn_service"] == 0.36


@pytest.mark.parametrize(
    ("argv", "word"),
    [
        (["--fn-service", "-0.1"], "--fn-service"),
        (["--fn-service", "0.3", "--scatter", "/nonexistent.csv"], "--scatter"),
        (["--fn-service", "0.3", "--vessel", "no_such_ship"], "--vessel"),
    ],
)
def test_cli_assess_bad_input(argv, word, capsys):
    assert main(["assess", "--no-exact", *argv]) == 2
    err = capsys.readouterr().err
    assert word in err and "Traceback" not in err


def test_broaching_at_chi_zero_is_the_surf_riding_threshold_and_weights_are_kept():
    """At chi_c = 0 the 4-DOF capsizing threshold (through the one adapter) is the surge
    model's connection (lateral motions vanish); the coarse re-binning keeps every weight."""
    from ship_models.assessment.broaching import broaching_level2
    from ship_models.assessment.criteria import sea_state_weights
    from ship_models.umeda_4dof import Umeda4DOF

    st = load_standard()
    m4 = Umeda4DOF("purse_seiner")
    W = sea_state_weights(st, 34.5, np.array([4.5]), np.array([6.5]))
    surge = SurgeModel(m4.data)
    ref = surf_riding_connection(surge, 0.1, 1.5)
    sc = ScatterTable(np.array([4.5]), np.array([6.5]), np.array([[1.0]]), "one sea state")
    b = broaching_level2(m4, 0.33, [0.0], [1.5], [0.1], W, st, sc,
                         Fn_guess=np.array([[ref.value("Fn")]]))  # fmt: skip
    assert b.status[0][0][0] == "SUCCESS"
    assert b.Fn_cap[0, 0, 0] == pytest.approx(ref.value("Fn"), abs=1e-6)
    # one coarse case carries the whole grid's weight
    assert b.C[0] == pytest.approx(W.sum() if 0.33 > ref.value("Fn") else 0.0, rel=1e-12)


def test_cli_assess_broaching_json_from_a_vessel_file(tmp_path, capsys):
    from ship_models.vessel import DATA_DIR

    sc = tmp_path / "scatter.csv"
    sc.write_text("Hs\\Tz, 8.5\n6.5, 1\n")
    argv = ["assess", "--vessel", str(DATA_DIR / "kvlcc2.toml"), "--fn-service", "0.142",
            "--no-exact", "--scatter", str(sc), "--broaching", "--chi-c", "0",
            "--broaching-lambda", "1.5", "--broaching-steepness", "0.1", "--json"]  # fmt: skip
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    b = doc["broaching"]
    assert b["status"] == [[["SUCCESS"]]] and b["C"] == [0.0]
    assert b["Fn_cap"][0][0][0] > 0.142  # the VLCC at its service speed does not broach


@pytest.mark.slow
def test_whole_grid_exact_threshold(surge):
    """The 80 x 100 grid by continuation: every case, within its error estimates, and
    against cold solves at cases spread over the grid."""
    st = load_standard()
    g = exact_threshold_grid(surge, st.lambda_over_L, st.steepness)
    assert g.complete, [s for s in g.column_status if not s.startswith("ok")]
    assert np.nanmax(g.error) < 2e-4
    rng = np.random.default_rng(7)
    for i, j in zip(rng.integers(0, 80, 6), rng.integers(0, 100, 6), strict=True):
        if g.column_status[i].startswith("ok; saddle-node") and st.steepness[j] < 0.032:
            continue  # the fold's closed form there (test_saddle_node_part_against_shooting)
        cold = surf_riding_connection(surge, float(st.steepness[j]), float(st.lambda_over_L[i]))
        assert cold.success
        tol = g.error[i, j] + cold.error("Fn") + 1e-7
        assert g.Fn_cr[i, j] == pytest.approx(cold.value("Fn"), abs=tol)


def test_criterion_sensitivity_signs_and_uncertainty_scaling():
    """A larger wave force raises C, a larger surge added mass lowers it (Melnikov's
    v0 = 2 sqrt(f / (k (m + m_x)))); dC per sigma uses the vessel file's uncertainty."""
    from ship_models.assessment.sensitivity import criterion_sensitivity

    st = load_standard()
    sc = ScatterTable(np.array([3.5, 5.5]), np.array([5.5, 6.5]),
                      np.array([[10.0, 20.0], [5.0, 10.0]]), "constructed")  # fmt: skip
    keys = ["hydrodynamics.wave_surge_scale", "hydrodynamics.m_x"]
    rows = {r.key: r for r in criterion_sensitivity("purse_seiner", 0.35, st, sc, keys=keys)}
    ws, mx = rows[keys[0]], rows[keys[1]]
    assert ws.dC_dtheta > 0 and mx.dC_dtheta < 0
    from ship_models.vessel import load_vessel

    rel = load_vessel("purse_seiner").uncertainties[keys[0]].value  # relative, in the file
    assert ws.sigma == pytest.approx(rel * ws.value)
    assert ws.dC_sigma == pytest.approx(ws.sigma * ws.dC_dtheta)


def test_exact_grid_keeps_finished_columns_on_ctrl_c(surge, monkeypatch):
    """The engine turns Ctrl-C into Status.INTERRUPTED; the grid stops there and returns
    the columns finished before (here the first), the rest NaN and marked."""
    import ship_models.assessment.exact as ex

    real = ex.continue_connection
    calls = {"n": 0}

    def interrupted_after_one(*args, **kw):
        calls["n"] += 1
        br = real(*args, **kw)
        if calls["n"] > 1:
            return dataclasses.replace(br, status=ex.Status.INTERRUPTED)
        return br

    monkeypatch.setattr(ex, "continue_connection", interrupted_after_one)
    st = load_standard()
    g = ex.exact_threshold_grid(surge, np.array([1.5, 1.525, 1.55]), st.steepness)
    assert g.column_status[1].startswith("ok")  # the start column (the middle one)
    assert [s for i, s in enumerate(g.column_status) if i != 1] == ["interrupted"] * 2
    assert np.isfinite(g.Fn_cr[1]).all() and np.isnan(g.Fn_cr[[0, 2]]).all()
