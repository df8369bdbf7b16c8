"""Every ``broachkit sweep`` kind end to end on a small case, in this process.

Each run must end with its one-line summary, write its CSV/JSON/PNG, and report
``SUCCESS`` only when every task finished and every check agreed (issue 28: the
surface's check stage once crashed in every task and the command still said SUCCESS).
"""

from __future__ import annotations

import functools
import json

import pytest

from broachkit_cli.main import main

#: The paper's wave (Umeda 1999): H/lambda = 1/9.2 (0.1087), lambda/L = 1.5.
PAPER_H = "0.1087"


def _run(capsys, argv):
    rc = main([*argv, "--serial", "--no-progress"])
    lines = capsys.readouterr().out.strip().splitlines()
    return rc, lines


@pytest.mark.parametrize(
    ("kind", "extra"),
    [
        # (the plain boundary also runs in the default suite in tests/test_sweep_cli.py)
        pytest.param("boundary", ["--chi-c", "10", "--positions", "1", "--no-map", "--tol",
                                  "1e-3"], marks=pytest.mark.slow),
        pytest.param("boundary", ["--chi-c", "10", "--positions", "1", "--no-map", "--tol",
                                  "1e-3", "--method", "bvp"], marks=pytest.mark.slow),
        ("courses", ["--chi-c", "10", "--tol", "1e-3"]),
        ("surface", ["--chi-c", "10", "--h-over-lambda", PAPER_H, "--lambda-over-l", "1.5",
                     "--check", "1", "--thresholds", "1"]),
    ],
    ids=["boundary", "boundary-bvp", "courses", "surface"],
)  # fmt: skip
def test_every_sweep_kind_runs_end_to_end(tmp_path, capsys, kind, extra):
    out = tmp_path / kind
    rc, lines = _run(capsys, ["sweep", kind, *extra, "--out", str(out)])
    assert rc == 0, lines
    assert len(lines) == 1 and lines[0].startswith(f"sweep {kind}: SUCCESS: ")
    data = json.loads((out / f"{kind}.json").read_text())
    assert data["status"] == "SUCCESS"
    for suffix in ("csv", "png"):
        assert (out / f"{kind}.{suffix}").stat().st_size > 0
    if kind == "surface":
        (check,) = data["checks_by_bisection"]
        # the connection's Fn lies inside the independent bisection's bracket
        assert check["status"] == "SUCCESS" and check["agrees"] is True
        assert check["Fn_lower"] - 1e-5 <= data["Fn"][0][0] <= check["Fn_upper"] + 1e-5
        # the paper's wave: the connection at 10 deg (README: 0.30161168, error 2.5e-8)
        assert data["Fn"][0][0] == pytest.approx(0.30161168, abs=1e-5)
        # the capsizing threshold there: the surface is the threshold (mechanism heteroclinic)
        (th,) = data["capsizing_thresholds"]
        assert th["status"] == "SUCCESS" and th["is_heteroclinic"] is True
        assert abs(th["Fn"] - data["Fn"][0][0]) <= th["error"] + 1e-3
    # run again: every task from its checkpoint, the same status
    rc2, lines2 = _run(capsys, ["sweep", kind, *extra, "--out", str(out)])
    assert rc2 == 0 and "from checkpoints" in lines2[0]
    assert json.loads((out / f"{kind}.json").read_text())["Fn"] == data["Fn"]


def test_a_sweep_whose_checks_fail_does_not_report_success(tmp_path, capsys, monkeypatch):
    """The surface with an agreement tolerance no check can meet: CHECK_FAILED, exit 1."""
    import ship_models.analysis.sweeps as sweeps

    strict = functools.partial(sweeps.surface_sweep, agree_tol=-1.0)
    monkeypatch.setattr(sweeps, "surface_sweep", strict)
    out = tmp_path / "s"
    argv = ["sweep", "surface", "--chi-c", "10", "--h-over-lambda", PAPER_H,
            "--lambda-over-l", "1.5", "--check", "1", "--out", str(out)]  # fmt: skip
    rc, lines = _run(capsys, argv)
    assert rc == 1
    assert lines[-1].startswith("sweep surface: CHECK_FAILED: ") and "0 of 1 checks" in lines[-1]
    assert json.loads((out / "surface.json").read_text())["status"] == "CHECK_FAILED"


def test_a_sweep_whose_tasks_fail_does_not_report_success(tmp_path, capsys, monkeypatch):
    """Every task raising (as the check stage did with a stale keyword): FAILED, exit 1."""
    import ship_models.analysis.sweeps.tasks as tasks

    def broken(key):
        raise TypeError("upslope_bisection() got an unexpected keyword argument 'bracket'")

    monkeypatch.setitem(tasks._TASKS, "bisect", broken)
    out = tmp_path / "s"
    argv = ["sweep", "surface", "--chi-c", "10", "--h-over-lambda", PAPER_H,
            "--lambda-over-l", "1.5", "--check", "1", "--out", str(out)]  # fmt: skip
    rc, lines = _run(capsys, argv)
    assert rc == 1 and lines[-1].startswith("sweep surface: FAILED: ")
    assert json.loads((out / "surface.json").read_text())["status"] == "FAILED"
