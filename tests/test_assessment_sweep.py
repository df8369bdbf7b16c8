"""The exact Level 2 grid on the sweep engine against the in-process continuation.

The sweep (:func:`ship_models.assessment.exact_sweep.exact_threshold_sweep`) runs
blocks of wavelengths as independent tasks, each continued from its own start; the
in-process path (:func:`ship_models.assessment.exact.exact_threshold_grid`) continues
across the whole grid from one start. The two start each column from a different
neighbour, so they agree cell by cell within the sum of their error estimates (an
independent check of those estimates), not to rounding. The same tasks give the same
table on every backend: in this process, and on a Dask ``LocalCluster`` through
``broachkit assess --workers 1`` (a Dask ``LocalCluster`` of one worker process, as
``tests/test_sweep.py`` does with two; one task here).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from broachkit_cli.main import main
from ship_models.assessment import load_standard
from ship_models.assessment.exact import exact_threshold_grid
from ship_models.assessment.exact_sweep import exact_threshold_sweep
from ship_models.surge import SurgeModel
from ship_models.vessel import DATA_DIR

LAM = np.array([1.5, 1.525, 1.55, 1.575])
STEEP = 0.03 + 0.012 * np.arange(10)


@pytest.fixture(scope="module")
def direct():
    return exact_threshold_grid(SurgeModel("purse_seiner"), LAM, STEEP)


@pytest.fixture(scope="module")
def swept():
    """Two tasks of two wavelengths, run in this process."""
    return exact_threshold_sweep(
        "purse_seiner", LAM, STEEP, columns_per_task=2, backend="serial", progress=False
    )


def test_sweep_path_equals_the_direct_path_within_the_error_estimates(direct, swept):
    assert direct.complete and swept.complete, (direct.column_status, swept.column_status)
    assert swept.engine.startswith("sweep (serial, 2 tasks")
    assert all(st.startswith("ok") for st in swept.column_status)
    diff = np.abs(swept.Fn_cr - direct.Fn_cr)
    assert np.all(diff <= swept.error + direct.error), np.max(diff / (swept.error + direct.error))
    # a real check: the estimates are small (the connection solver's rtol is 1e-6)
    assert np.max(swept.error) < 5e-5 and np.max(direct.error) < 5e-5
    # the block starting at 1.525 continues to 1.5 as the direct path (start 1.55)
    # reaches 1.5 through 1.525: same cells, different paths, hence not bit-equal
    assert swept.steps > 0 and np.max(diff) > 0


def test_sweep_rejects_bad_blocks_and_grids():
    with pytest.raises(ValueError, match="columns_per_task"):
        exact_threshold_sweep("purse_seiner", LAM, STEEP, columns_per_task=0, backend="serial")
    with pytest.raises(ValueError, match="steepness"):
        exact_threshold_sweep("purse_seiner", LAM, STEEP[::-1], backend="serial")
    with pytest.raises(ValueError, match="vessel"):
        exact_threshold_sweep("no_such_ship", LAM, STEEP, backend="serial")


def _small_standard(path):
    """The shipped criterion file with the grid cut to LAM x STEEP."""
    text = (DATA_DIR / "imo" / "surf_riding_level2.toml").read_text()
    doc = tomllib.loads(text)
    new = {
        "lambda_over_L_first": float(LAM[0]), "lambda_over_L_step": 0.025,
        "lambda_over_L_count": 4, "steepness_first": float(STEEP[0]),
        "steepness_step": 0.012, "steepness_count": 10,
    }  # fmt: skip
    lines = []
    for line in text.splitlines():
        key = line.split("=", 1)[0].strip()
        if key in new:
            entry = doc["level2"][key]
            line = (
                f'{key} = {{ value = {new[key]!r}, unit = "{entry["unit"]}", '
                f'source = "test grid", status = "assumed" }}'
            )
        lines.append(line)
    path.write_text("\n".join(lines) + "\n")
    st = load_standard(path)
    assert np.allclose(st.lambda_over_L, LAM) and np.allclose(st.steepness, STEEP)
    return path


def _assess(argv):
    """``broachkit assess ARGV`` in a child process (a Dask client leaves threads behind
    in the process that ran it, which the forking tests refuse): exit code, stdout."""
    root = str(Path(__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([root, os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run(
        [sys.executable, "-m", "broachkit_cli.main", "assess", *argv],
        capture_output=True, text=True, env=env, timeout=600,
    )  # fmt: skip
    return proc.returncode, proc.stdout, proc.stderr


def test_cli_assess_runs_the_exact_grid_on_a_dask_cluster(tmp_path, swept):
    pytest.importorskip("distributed")
    std = _small_standard(tmp_path / "small.toml")
    out = tmp_path / "out"
    argv = ["--fn-service", "0.33", "--standard", str(std), "--workers", "1",
            "--out", str(out), "--json"]  # fmt: skip
    code, stdout, stderr = _assess(argv)
    assert code == 0, stderr
    doc = json.loads(stdout)
    assert doc["exact_grid"]["engine"].startswith("sweep (dask, 1 task of")
    assert doc["exact_grid"]["complete"]
    with np.load(out / "assessment_grids.npz") as z:
        Fn, err = z["Fn_cr_exact"], z["Fn_cr_exact_error"]
    # one task of the 4 wavelengths here (two of two in `swept`): within the estimates
    assert np.all(np.abs(Fn - swept.Fn_cr) <= err + swept.error)
    # the checkpoint of the one task is kept: a rerun takes it without running anything
    code, stdout, stderr = _assess(argv)
    assert code == 0, stderr
    again = json.loads(stdout)
    with np.load(out / "assessment_grids.npz") as z:
        assert np.array_equal(z["Fn_cr_exact"], Fn)
    assert again["level2"]["exact"]["C_sea_state_max"] == doc["level2"]["exact"]["C_sea_state_max"]


def test_error_estimate_covers_the_fixed_mesh_at_the_column_ends():
    """The rows of a column are solved on the mesh adapted at its middle steepness; at
    the ends that mesh's error (5.4e-6 in Fn at the steepest wave of this column)
    exceeded the old estimate (collocation at the start plus spline, about 1e-6).
    Against cold adapted solves, no slack."""
    lam = 2.875
    from ship_models.assessment.exact import surf_riding_connection

    st = load_standard()
    surge = SurgeModel("purse_seiner")
    g = exact_threshold_grid(surge, np.array([lam]), st.steepness)
    assert g.complete and g.column_status[0] == "ok"
    for j in (0, st.steepness.size - 1):
        cold = surf_riding_connection(surge, float(st.steepness[j]), lam)
        assert cold.success
        err = abs(g.Fn_cr[0, j] - cold.value("Fn"))
        assert err <= g.error[0, j] + cold.error("Fn"), (j, err, g.error[0, j])


def test_cli_assess_bad_worker_count_is_one_line(capsys):
    assert main(["assess", "--fn-service", "0.33", "--no-exact", "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert "--workers" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
