"""Command line: ``broachkit fixed-points``, ``manifold``, ``critical`` (JSON output).

The numbers printed are checked against the library calls they wrap (independent
Newton solves for the fixed points), and bad options give exit code 2 with the
option named.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from broachkit_cli.main import main
from continuation.equilibria import solve_equilibrium
from ship_models.analysis.critical import critical_fn
from ship_models.analysis.eigen import paper_scales
from ship_models.analysis.events import vanishing_angle


def _json(capsys, argv):
    code = main(argv)
    out = capsys.readouterr().out
    return code, json.loads(out)


def test_fixed_points_json(capsys, model):
    code, res = _json(capsys, ["fixed-points", "--fn", "0.3248", "--chi-c", "10", "--json"])
    assert code == 0
    assert res["chi_c_deg"] == 10.0
    assert res["params"]["chi_c"] == pytest.approx(math.radians(10.0), rel=1e-15)
    labels = [fp["label"] for fp in res["fixed_points"]]
    assert labels[0] == "crest" and "trough" in labels
    p = model.default_params().replace(Fn=0.3248, chi_c=math.radians(10.0))
    for fp in res["fixed_points"]:
        x = np.array([fp["state"][n] for n in model.state_names])
        # an independent Newton solve from a perturbed start lands on the printed point
        ref = solve_equilibrium(model, x * 1.001 + 1e-4, p)
        assert np.max(np.abs(model.difference(ref.z, x))) < 1e-8
        assert fp["state_deg"]["phi"] == pytest.approx(math.degrees(x[5]))
        lam = np.array([complex(*z) for z in fp["eigenvalues"]])
        assert fp["saddle_index"] == int(np.sum(lam.real > 1e-10))
        lam_ref = np.linalg.eigvals(model.jacobian(x, p.values))
        assert np.sort(lam_ref.real) == pytest.approx(np.sort(lam.real), abs=1e-9)
        nd = np.array([complex(*z) for z in fp["eigenvalues_nondim"]])
        assert nd == pytest.approx(lam * res["time_scale_L_over_c"], rel=1e-12)
    crest = res["fixed_points"][0]
    assert crest["saddle_index"] == 1
    v = crest["unstable_eigenvector_nondim"]
    assert v["xi_G"] > 0 and max(abs(c) for c in v.values()) == pytest.approx(1.0)
    assert crest["dominant_motions"] == ["surge"]


def test_fixed_points_text_and_bad_options(capsys):
    assert main(["fixed-points", "--chi-c", "-10"]) == 0
    out = capsys.readouterr().out
    assert "crest" in out and "trough" in out and "saddle index 1" in out
    assert main(["fixed-points", "--chi-c", "95"]) == 2
    assert "--chi-c" in capsys.readouterr().err
    assert main(["fixed-points", "--fn", "-0.1"]) == 2
    assert "--fn" in capsys.readouterr().err
    assert main(["fixed-points", "--h-over-lambda", "0"]) == 2
    assert "--h-over-lambda" in capsys.readouterr().err


def test_manifold_json(capsys, tmp_path, model):
    code, res = _json(
        capsys,
        ["manifold", "--fn", "0.3248", "--chi-c", "10", "--json", "--out", str(tmp_path)],
    )
    assert code == 0
    assert res["saddle"]["label"] == "crest" and res["saddle"]["saddle_index"] == 1
    br = res["branches"]
    assert br["downslope"]["fate"]["kind"] == "capsize"
    assert br["upslope"]["fate"]["kind"] == "capsize"
    assert br["downslope"]["sign"] == 1.0 and br["upslope"]["sign"] == -1.0
    # the start points sit eps (nondimensional) from the printed saddle
    x_s = np.array([res["saddle"]["state"][n] for n in model.state_names])
    p = model.default_params()
    scales, _ = paper_scales(model, p, x_s)
    for b in br.values():
        d = (np.array(b["x0"]) - x_s) / scales
        assert np.max(np.abs(d)) == pytest.approx(res["eps"], rel=1e-9)
    # the capsized end state is beyond the capsize angle
    phi_end = abs(br["downslope"]["x_end"][5])
    assert phi_end == pytest.approx(vanishing_angle(model), abs=1e-6)
    for name in ("downslope", "upslope"):
        csv = tmp_path / f"manifold_{name}.csv"
        assert csv.exists() and csv.read_text().startswith("t,xi_G")


def test_critical_json_matches_library(capsys, model):
    argv = ["critical", "--chi-c", "10", "--fn-min", "0.30", "--fn-max", "0.305"]
    code, res = _json(capsys, [*argv, "--tol", "1e-3", "--method", "bisection", "--json"])
    assert code == 0
    assert res["method"] == "bisection" and res["status"] == "SUCCESS"
    lo, hi = res["bracket"]
    assert 0 < hi - lo <= 1e-3
    assert (res["fate_lo"], res["fate_hi"]) == ("periodic", "capsize")
    ref = critical_fn(
        model, chi_c=math.radians(10.0), method="bisection", Fn_bracket=(0.30, 0.305), tol=1e-3
    )
    assert (lo, hi) == ref.bracket
    assert res["Fn"] == ref.Fn
    with pytest.raises(SystemExit):
        main(["critical", "--method", "shooting"])
    capsys.readouterr()
    assert main(["critical", "--fn-min", "0.4", "--fn-max", "0.3"]) == 2
    assert "--fn-min" in capsys.readouterr().err


def test_reproduce_runs_and_skips_finished_steps(capsys, tmp_path):
    code = main(["reproduce", "--out", str(tmp_path), "--only", "fig06_09", "--json"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["steps"] == ["fig06_09"] and "fig06_09" in summary["seconds"]
    step = tmp_path / "fig06_09"
    for name in ("fig06_eigenvalues_crest.png", "fig09_eigenvector_trough.png", "summary.json"):
        assert (step / name).exists()
    data = json.loads((step / "summary.json").read_text())
    assert data["points"]["crest"]["saddle_index"] == 1
    mtime = (step / "summary.json").stat().st_mtime_ns
    assert main(["reproduce", "--out", str(tmp_path), "--only", "fig06_09", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["seconds"] == {}  # skipped
    assert (step / "summary.json").stat().st_mtime_ns == mtime
    assert main(["reproduce", "--out", str(tmp_path), "--only", "nonsense"]) == 2
    assert "--only" in capsys.readouterr().err
