"""Ship sweeps (ship_models.analysis.sweeps) on the generic sweep layer.

References: the surge-only threshold (shooting + Brent on the 2-D surge model) against
the 8-D heteroclinic connection by collocation at chi_c = 0, where the 4-DOF motion
stays in the surge plane; the connection continued in H/lambda against one-shot
solves and against bisection by simulation; sweep tables against direct calls.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from broachkit_cli.main import main
from continuation.status import Status
from ship_models.analysis import sweeps as S
from ship_models.analysis.sweeps import context as _ctx


@pytest.fixture(scope="module")
def ship():
    return _ctx._model("purse_seiner")


def test_surge_threshold_equals_the_connection_at_chi_c_0(ship):
    from ship_models.analysis.critical_bvp import critical_fn_bvp

    p = ship.default_params()
    st = S.surge_threshold(_ctx._surge("purse_seiner"), p["H_over_lambda"], p["lambda_over_L"])
    assert st.success, st.message
    bvp = critical_fn_bvp(0.0, model=ship)
    assert bvp.success
    # two independent methods on two models; both tolerances are far below 1e-6
    assert abs(st.Fn - bvp.Fn) < 1e-6
    fa, fb = st.Fn_range
    assert fa < st.Fn < fb


def test_surge_threshold_says_why_there_is_no_connection_in_gentle_waves():
    s = _ctx._surge("purse_seiner")
    st = S.surge_threshold(s, 0.02, 1.5)
    assert st.status is Status.NO_BRACKET and math.isnan(st.Fn)
    assert "saddle-node" in st.message
    fa, fb = st.Fn_range
    # surf-riding exists in a narrow band only, far above the paper's Fn = 0.3
    assert 0.35 < fa < fb < 0.6
    # the band narrows to the speed where thrust balances resistance at u = c
    ga, gb = S.surf_riding_range(s, 1e-4, 1.5)
    assert fa < ga < gb < fb and gb - ga < 0.01 * (fb - fa)


def test_run_task_rejects_an_unknown_task():
    with pytest.raises(ValueError, match="`task` must be one of"):
        S.run_task({"task": "nope"})


@pytest.mark.parametrize(
    "argv, flag",
    [
        (["sweep", "surface", "--h-over-lambda", "0.1:0.05:3"], "--h-over-lambda"),
        (["sweep", "surface", "--lambda-over-l", "a,b"], "--lambda-over-l"),
        (["sweep", "courses", "--chi-c", "0:90:10"], "--chi-c"),
        (["sweep", "boundary", "--initial", "speed=3"], "--initial"),
        (["sweep", "boundary", "--processes", "0"], "--processes"),
    ],
)
def test_cli_bad_input_is_one_line_and_nonzero(tmp_path, capsys, argv, flag):
    assert main([*argv, "--out", str(tmp_path / "o"), "--serial"] if "--processes" not in argv
                else [*argv, "--out", str(tmp_path / "o")]) == 2  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and flag in err[0]


@pytest.mark.slow
def test_critical_line_against_one_shot_solves_and_bisection(ship):
    from ship_models.analysis.critical_bisection import upslope_bisection as critical_fn_bisection
    from ship_models.analysis.critical_bvp import critical_fn_bvp

    chi = math.radians(10.0)
    line = S.critical_line(ship, chi, 1.5, [0.02, 0.08, 0.1])
    assert list(line.converged) == [False, True, True]
    assert "connection ends near" in line.reason and "saddle-node" in line.reason
    assert 0.02 < line.H_end < 0.08
    # physically: gentler waves need a higher speed to capture the ship
    assert line.Fn[1] > line.Fn[2]
    p = ship.default_params()
    for k in (1, 2):
        h = float(line.H_over_lambda[k])
        one = critical_fn_bvp(
            chi, model=ship, params=p.replace(H_over_lambda=h), Fn_guess=float(line.Fn[k])
        )
        assert one.success and abs(one.Fn - line.Fn[k]) < 1e-6
    # bisection by simulation on the fate of the upslope branch (a steep wave: at
    # H/lambda = 0.06 the two differ by 1.5e-3, see the notes of ship_models.analysis.sweeps)
    h = 0.08
    b = critical_fn_bisection(
        chi, model=ship, params=p.replace(H_over_lambda=h),
        Fn_bracket=(line.Fn[1] - 2e-3, line.Fn[1] + 2e-3), tol=1e-6,
    )  # fmt: skip
    assert b.success, b.message
    assert b.bracket[0] - 1e-6 <= line.Fn[1] <= b.bracket[1] + 1e-6


@pytest.mark.slow
def test_boundary_sweep_same_table_on_processes_and_in_process(tmp_path, ship):
    from ship_models.analysis.critical_bvp import critical_fn_bvp
    from ship_models.analysis.sudden_change import periodic_orbit, sudden_change_boundary

    opts = dict(positions=[0.5], map_offsets=(-0.004, 0.003), tol=1e-3)
    a = S.boundary_sweep("purse_seiner", 10.0, backend="serial", store=tmp_path / "a", **opts)
    b = S.boundary_sweep(
        "purse_seiner", 10.0, backend="processes", workers=2, store=tmp_path / "b", **opts
    )
    assert a.complete and b.complete
    assert a.boundaries.rows() == b.boundaries.rows()
    assert a.outcomes.rows() == b.outcomes.rows()
    assert [r.value["outcome"] for r in a.outcomes.records] == ["periodic", "capsize"]
    # the task is the library call: same bracket as a direct bisection
    chi = math.radians(10.0)
    fh = critical_fn_bvp(chi, model=ship).Fn
    orb = periodic_orbit(ship, ship.default_params().replace(Fn=0.1, chi_c=0.0), throw=True)
    d = sudden_change_boundary(ship, None, chi, 0.5, (fh - 0.004, fh + 0.003), 1e-3, orbit=orb)
    assert d.success and np.isclose(a.Fn[0], d.Fn, rtol=0, atol=1e-12)
    again = S.boundary_sweep("purse_seiner", 10.0, backend="serial", store=tmp_path / "a", **opts)
    assert again.boundaries.n_executed == 0 and again.outcomes.n_executed == 0


def test_vessel_files_are_named_by_absolute_path_for_remote_workers(tmp_path, monkeypatch):
    from ship_models.analysis.sweeps.context import _vessel_ref

    monkeypatch.chdir(tmp_path)
    assert _vessel_ref("my_ship.toml") == str(tmp_path / "my_ship.toml")
    assert _vessel_ref("purse_seiner") == "purse_seiner"
    with pytest.raises(ValueError, match="`vessel`"):
        _vessel_ref("")
    # the context is the file's content: same content, same hash
    assert S.vessel_context("purse_seiner") == S.vessel_context("purse_seiner")


def test_an_interrupted_surface_stops_before_its_checks(monkeypatch):
    from continuation.sweep import SweepResult

    calls = []

    def fake(fn, keys, **kw):
        calls.append(keys)
        return SweepResult((), tuple(keys), Status.INTERRUPTED, len(keys), 0, 0, "fake")

    from ship_models.analysis.sweeps import context

    monkeypatch.setattr(context, "run_sweep", fake)
    r = S.surface_sweep(H_over_lambda=[0.1], lambda_over_L=[1.5], check=2, backend="serial")
    assert len(calls) == 1 and r.check_sweep is None and r.checks == ()
    assert np.all(np.isnan(r.Fn)) and r.sweep.status is Status.INTERRUPTED
