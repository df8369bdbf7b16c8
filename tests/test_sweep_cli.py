"""``broachkit sweep``: the same table from a LocalCluster and a scheduler; resume."""

from __future__ import annotations

import json

import pytest

from broachkit_cli.main import main

pytest.importorskip("distributed")


@pytest.mark.slow
def test_sweep_boundary_workers_and_scheduler_give_identical_tables(tmp_path):
    from distributed import LocalCluster

    common = ["sweep", "boundary", "--positions", "2", "--no-map", "--tol", "1e-3"]
    a, b = tmp_path / "a", tmp_path / "b"
    assert main([*common, "--workers", "2", "--out", str(a), "--no-progress"]) == 0
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        addr = cluster.scheduler_address
        assert main([*common, "--scheduler", addr, "--out", str(b), "--no-progress"]) == 0
    assert (a / "boundary.csv").read_text() == (b / "boundary.csv").read_text()
    for d in (a, b):
        assert (d / "boundary.png").stat().st_size > 0
        data = json.loads((d / "boundary.json").read_text())
        assert data["boundaries"]["n_failed"] == 0 and all(f is not None for f in data["Fn"])
    # run again: every task comes from its checkpoint
    assert main([*common, "--processes", "2", "--out", str(a), "--no-progress"]) == 0
    again = json.loads((a / "boundary.json").read_text())["boundaries"]
    assert again["n_executed"] == 0 and again["n_reused"] == 2
    assert (a / "boundary.csv").read_text() == (b / "boundary.csv").read_text()


def test_sweep_boundary_one_position_in_this_process(tmp_path):
    """The default command path (bisection tasks on the sweep layer) end to end, fast:
    one initial position, the Fig. 16 setup. Reference: the landing BVP of
    ``tests/test_capsize_boundary.py`` at xi_0 = 0 (Fn 0.3014739, an independent method)."""
    out = tmp_path / "one"
    argv = ["sweep", "boundary", "--positions", "1", "--no-map", "--tol", "1e-3", "--serial",
            "--out", str(out), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    data = json.loads((out / "boundary.json").read_text())
    assert data["boundaries"]["n_failed"] == 0
    (fn,) = data["Fn"]
    assert fn == pytest.approx(0.3014739, abs=1e-3)
    assert (out / "boundary.csv").stat().st_size > 0 and (out / "boundary.png").stat().st_size > 0
