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
from ship_models import purse_seiner


@pytest.fixture(scope="module")
def model():
    return purse_seiner()


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
