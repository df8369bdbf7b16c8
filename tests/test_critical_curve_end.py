"""The critical curve's first sheet, its fold in chi_c, its end and the boundary check.

References are independent computations: the connection solved with ``chi_c`` unknown
at fixed ``Fn`` (the fold in chi_c is the maximum of chi_c(Fn)), fresh single-course
solves from the simulated manifold, and Newton solves of the crest equilibrium either
side of its fold.
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np
import pytest

from continuation.bvp import connection_at, continue_connection, solve_connection
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status
from ship_models.analysis.boundary_check import boundary_refusal
from ship_models.analysis.critical_bvp import critical_fn_bvp
from ship_models.analysis.critical_curve import critical_curve
from ship_models.analysis.events import vanishing_angle

DEG = math.pi / 180.0
COURSES = np.array([0.0, 30.0, 38.0, 40.0, 45.0])


@pytest.fixture(scope="module")
def curve(model):
    return critical_curve(COURSES * DEG, model=model, keep_orbits=True)


def _chi_of_Fn(model, orbit, Fns):
    """chi_c (deg) of the connection solved with chi_c unknown at each fixed Fn."""
    out = []
    o = orbit
    for Fn in Fns:
        prob = o.problem.replace(free=("chi_c",), params=o.problem.params.replace(Fn=Fn))
        s = solve_connection(prob, o, method="broyden")
        assert s.success, s.message
        out.append(math.degrees(s.params["chi_c"]))
        o = s
    return np.array(out)


def test_curve_ends_at_its_fold(curve):
    assert curve.status is Status.SUCCESS, curve.message
    assert len(curve.folds) == 1
    chi_f, Fn_f = curve.folds[0]
    assert (curve.end_chi_c, curve.end_Fn) == (chi_f, Fn_f)
    assert curve.fold_error < 0.02 * DEG
    assert "ends at its fold" in curve.message
    assert list(curve.exists) == [True, True, True, False, False]
    assert np.all(curve.converged[:3]) and not np.any(curve.converged[3:])


def test_fold_against_chi_c_solved_at_fixed_Fn(model, curve):
    """Fold in chi_c = max of chi_c(Fn): a parabola through three fixed-Fn solves."""
    chi_f, Fn_f = curve.folds[0]
    h = 2e-3
    near = critical_fn_bvp(37.5 * DEG, model=model, Fn_guess=0.32)
    assert near.success, near.message
    chi = _chi_of_Fn(model, near.orbit, [Fn_f - h, Fn_f, Fn_f + h])
    a = 0.5 * (chi[2] + chi[0] - 2 * chi[1])
    b = 0.5 * (chi[2] - chi[0])
    assert a < 0  # a maximum: the curve turns back
    chi_max = chi[1] - b * b / (4 * a)
    Fn_max = Fn_f - h * b / (2 * a)
    assert abs(chi_max - math.degrees(chi_f)) < 0.02
    assert abs(Fn_max - Fn_f) < 5e-4
    # 40 deg lies beyond the first sheet: no course above the fold has a boundary
    assert chi_max < 40.0
    assert "folds back" in curve.reasons[3]


def test_crest_end_matches_the_equilibrium_fold(model, curve):
    """Newton on the crest equilibrium converges just below the end, not just above."""
    end = curve.crest_end_chi_c
    assert 43.0 * DEG < end < 45.0 * DEG
    p = model.default_params().replace(Fn=curve.end_Fn)
    assert model.find_equilibrium(p.replace(chi_c=end - 0.05 * DEG), "crest").converged
    assert not model.find_equilibrium(p.replace(chi_c=end + 0.05 * DEG), "crest").converged
    assert "crest saddle does not exist beyond" in curve.reasons[4]
    assert f"{math.degrees(end):.1f} deg" in curve.reasons[4]


def test_error_estimates_bound_fresh_solves(model, curve):
    """Every reported Fn against a fresh single-course solve from the simulated manifold."""
    for k in (1, 2):
        fresh = critical_fn_bvp(float(COURSES[k] * DEG), model=model, Fn_guess=curve.Fn[k])
        assert fresh.success, fresh.message
        assert abs(curve.Fn[k] - fresh.Fn) <= curve.error[k] + fresh.error + 1e-12


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks only on Linux")
@pytest.mark.usefixtures("single_threaded")
def test_forked_workers_give_the_same_curve(model, curve, monkeypatch):
    """Courses solved on a forked process and here: the same curve as all here, exactly.

    Each task of consecutive courses has its own Jacobian store, so its results depend
    on the task only, not on the process or the number of workers.
    """
    from continuation.sweep import forked

    children: list[int] = []
    init = forked.ForkedTasks.__init__

    def spy(self, *args, **kwargs):
        init(self, *args, **kwargs)
        children.append(self.n_children)

    monkeypatch.setattr(forked.ForkedTasks, "__init__", spy)
    courses = np.arange(0.0, 40.0, 2.0) * DEG  # 19 courses on the sheet: 3 tasks
    one = critical_curve(courses, model=model, start=curve.start, workers=1)
    n_one = len(children)
    two = critical_curve(courses, model=model, start=curve.start, workers=2, keep_orbits=True)
    assert max(children[:n_one]) == 0
    assert max(children[n_one:]) == 1, "the courses were not solved on a forked process"
    assert one.status is two.status is Status.SUCCESS, (one.message, two.message)
    for name in ("Fn", "error", "residual_norm", "converged", "exists"):
        assert np.array_equal(getattr(one, name), getattr(two, name), equal_nan=True), name
    assert one.reasons == two.reasons and one.folds == two.folds
    assert len(two.orbits) == int(two.converged.sum())


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks only on Linux")
@pytest.mark.usefixtures("single_threaded")
def test_an_error_in_the_courses_leaves_no_forked_process(model, curve, monkeypatch):
    import psutil

    from ship_models.analysis import critical_curve as cc

    parent = os.getpid()

    def broken(*args, **kwargs):
        if os.getpid() != parent:
            time.sleep(30.0)  # the forked process is still busy when this one fails
        raise ArithmeticError("a course failed")

    monkeypatch.setattr(cc, "_solve_task", broken)
    before = {p.pid for p in psutil.Process().children()}
    with pytest.raises(ArithmeticError, match="a course failed"):
        critical_curve(np.arange(0.0, 40.0, 2.0) * DEG, model=model, start=curve.start, workers=2)
    assert {p.pid for p in psutil.Process().children()} <= before


def test_boundary_refusal_roll_and_saddle(model, curve):
    o = curve.start.orbit
    p = o.problem.params.replace(Fn=float(o.params["Fn"]))
    assert boundary_refusal(model, o.x, o.x_from, p) == ""
    x = np.array(o.x)
    x[len(x) // 2, model.state_index("phi")] = -(vanishing_angle(model) + 0.1)
    assert "vanishing stability" in boundary_refusal(model, x, o.x_from, p)
    assert "crest saddle" in boundary_refusal(model, o.x, o.x_from + 1e-3, p)


@pytest.mark.slow
def test_capsized_connection_at_45_deg_is_refused(model, curve):
    """The branch continued past the fold to 45 deg carries a capsize: refused."""
    s = ContinuationSettings(
        ds=0.02, ds_max=0.1, p_min=-1e-3, p_max=45 * DEG, max_steps=200,
        newton=NewtonSettings(tol=1e-9, step_tol=1e-8, max_iter=8),
    )  # fmt: skip
    br = continue_connection(curve.start.orbit, "chi_c", s)
    assert br.status is Status.PARAM_BOUND and abs(br.p[-1] - 45 * DEG) < 1e-9
    r = critical_fn_bvp(45 * DEG, model=model, guess=connection_at(br, len(br.p) - 1))
    assert r.status is Status.REJECTED, r.message
    assert "vanishing stability" in r.message


def test_cli_critical_bvp_no_traceback(capsys):
    from broachkit_cli.main import main

    rc = main(["critical", "--chi-c", "45", "--method", "bvp", "--fn-guess", "0.6128"])
    out = capsys.readouterr()
    assert rc == 1
    assert "Traceback" not in out.out + out.err
    # a failure is one line on stderr (the front door's rule), naming the guess and the bracket
    assert out.err.count("\n") == 1
    # the search window is the surf-riding window of this wave within the resistance fit
    assert "0.6128" in out.err and "(0.1, 0.65)" in out.err


@pytest.mark.slow
def test_cli_critical_curve_end(capsys):
    """The heteroclinic line's end is a fact, not a failure (exit 0 without thresholds);
    with the capsizing threshold (default every 5 deg), 45 deg has none inside the
    window (the upslope branch already capsizes where the crest saddle first exists),
    which is a result not found: exit 1, said in the summary line and, with its
    reason, in the course's row."""
    from broachkit_cli.main import main

    rc = main(["critical-curve", "--chi-c", "0,45", "--threshold-step", "0"])
    out = capsys.readouterr()
    assert rc == 0
    assert "fold of the critical curve" in out.out
    assert "the crest saddle does not exist beyond chi_c" in out.out
    rc = main(["critical-curve", "--chi-c", "45"])
    out = capsys.readouterr()
    assert rc == 1
    assert "the crest saddle does not exist beyond chi_c" in out.out
    assert "not SUCCESS at chi_c = 45 deg (NO_BRACKET)" in out.out
    assert "NO_BRACKET: the upslope branch already capsizes at the lowest Fn" in out.out
