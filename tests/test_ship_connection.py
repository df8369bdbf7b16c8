"""The ship's critical Froude number as a heteroclinic connection, against brute force.

References
----------
* Umeda (1999), "Nonlinear dynamics of ship capsizing due to broaching in following
  and quartering seas", J. Mar. Sci. Technol. 4:16-26: the capsizing boundary is the
  ``Fn`` where the upslope branch of the crest saddle's unstable manifold reaches the
  neighbouring crest saddle (Figs. 10-15, 21, 23). The paper's 0.3247-0.3248 at
  ``chi_c = 10 deg`` is for measured coefficients; our vessel has estimated ones, so
  the references here are independent computations with the same model:
* bisection on the fate of the upslope branch by simulation (written in this file
  with :func:`continuation.dynamics.simulate.simulate`, and :func:`upslope_bisection`);
* at ``chi_c = 0`` the lateral motions decouple (``v = r = phi = p = delta = 0`` is
  invariant), so the critical ``Fn`` must be that of the uncoupled surge model
  (a 2-D system), found here by shooting with SciPy's DOP853.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from continuation.bvp.solve import check_convergence
from continuation.dynamics import SimEvent, simulate
from continuation.status import Status
from ship_models import purse_seiner_surge
from ship_models.analysis.critical_bisection import upslope_bisection
from ship_models.analysis.critical_bvp import check_critical_bvp, critical_fn_bvp
from ship_models.analysis.critical_curve import critical_curve
from ship_models.analysis.events import capsize_event
from ship_models.analysis.outcomes import ShipOutcome
from ship_models.analysis.upslope import UPSLOPE_SHIFT, upslope_branch

DEG = math.pi / 180


@pytest.fixture(scope="module")
def bvp10(model):
    return critical_fn_bvp(10 * DEG, model=model)


@pytest.fixture(scope="module")
def curve(model, bvp10):
    return critical_curve(model=model, start=bvp10)


# ------------------------------------------------------------------ independent references
def _upslope_passes(model, Fn: float, chi_c: float) -> bool:
    """True when the upslope branch passes the next crest (periodic motion).

    Written independently of ship_models.analysis (critical_bvp, upslope): own saddle and
    eigenvector, own events, CVODES through continuation.dynamics.simulate.
    """
    p = model.default_params().replace(Fn=Fn, chi_c=chi_c)
    pv = np.asarray(p.values)
    xs = model.find_equilibrium(p, "crest").z
    w, V = np.linalg.eig(model.jacobian(xs, pv))
    v = np.real(V[:, np.argmax(w.real)])
    v *= -np.sign(v[0]) / np.linalg.norm(v)  # xi_G decreasing: upslope
    beyond = SimEvent("beyond", lambda t, x: x[0] - (xs[0] - 1.4), terminal=True, direction=-1)
    back = SimEvent("back", lambda t, x: x[0] - (xs[0] - 0.7), terminal=True, direction=1)
    tr = simulate(
        model, xs + 1e-7 * v, p, (0.0, 500.0), events=[beyond, back, capsize_event(model)], dt=0.1
    )
    assert tr.terminal_event is not None, "fate undecided"
    return tr.terminal_event == "beyond"


def _bisect(model, chi_c: float, lo: float, hi: float, width: float) -> tuple[float, float]:
    assert _upslope_passes(model, lo, chi_c) and not _upslope_passes(model, hi, chi_c)
    while hi - lo > width:
        mid = 0.5 * (lo + hi)
        if _upslope_passes(model, mid, chi_c):
            lo = mid
        else:
            hi = mid
    return lo, hi


def _surge_critical_fn(width: float = 2e-7) -> float:
    """Shooting on the uncoupled surge model (2-D): the upslope separatrix of the crest
    saddle reaches the next crest saddle (Umeda 1999, surge-only heteroclinic)."""
    sm = purse_seiner_surge()

    def passes(Fn: float) -> bool:
        p = sm.default_params().replace(Fn=Fn)
        pv = np.asarray(p.values)
        fps = [fp for fp in sm.fixed_points(p) if fp.kind == "saddle"]
        xs = fps[0].x
        w, V = np.linalg.eig(sm.jacobian(xs, pv))
        v = np.real(V[:, np.argmax(w.real)])
        v *= -np.sign(v[0]) / np.linalg.norm(v)

        def beyond(t, x):
            return x[0] - (xs[0] - 1.4)

        def back(t, x):
            return x[0] - (xs[0] - 0.7)

        beyond.terminal, beyond.direction = True, -1
        back.terminal, back.direction = True, 1
        sol = solve_ivp(
            lambda t, x: sm.f(x, pv),
            (0.0, 800.0),
            xs + 1e-8 * v,
            method="DOP853",
            rtol=1e-11,
            atol=1e-12,
            events=[beyond, back],
        )
        assert sol.status == 1, "surge shooting undecided"
        return sol.t_events[0].size > 0

    lo, hi = 0.29, 0.31
    assert passes(lo) and not passes(hi)
    while hi - lo > width:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
    return 0.5 * (lo + hi)


# ------------------------------------------------------------------ one course
def test_bvp_agrees_with_bisection_at_10_deg(model, bvp10):
    """BVP vs brute force: the BVP's Fn lies in a 1e-4 fate bracket from simulations."""
    assert bvp10.success, bvp10.message
    lo, hi = _bisect(model, 10 * DEG, 0.300, 0.3032, 1e-4)
    assert lo <= bvp10.Fn <= hi
    assert abs(bvp10.Fn - 0.5 * (lo + hi)) < 1e-4


def test_bvp_agrees_with_fine_bisection_at_10_deg(model, bvp10):
    """To 1e-6 against upslope_bisection (bracket width 1e-6)."""
    b = upslope_bisection(10 * DEG, model=model, Fn_bracket=(0.3010, 0.3022), tol=1e-6)
    assert b.success, b.message
    assert b.bracket[1] - b.bracket[0] <= 1e-6
    assert abs(bvp10.Fn - b.Fn) < 1e-6


def test_bvp_inside_the_project_bisection_bracket(model, bvp10):
    """Against the project's bisection tool (ship_models.analysis.critical, Poincare fates)."""
    from ship_models.analysis.critical import critical_fn

    b = critical_fn(model, chi_c=10 * DEG, method="bisection", Fn_bracket=(0.29, 0.31), tol=1e-4)
    assert b.status is Status.SUCCESS, b.message
    lo, hi = b.bracket
    assert hi - lo <= 1e-4
    assert lo <= bvp10.Fn <= hi


def test_orbit_residual_and_end_points(model, bvp10):
    o = bvp10.orbit
    assert bvp10.residual_norm < 1e-10
    pv = np.asarray(o.params.values)
    # the ends are equilibria: the crest saddle and the same one a wavelength back
    assert np.max(np.abs(model.f(o.x_from, pv))) < 1e-9
    assert np.max(np.abs(model.f(o.x_to, pv))) < 1e-9
    shift = o.x_to - o.x_from
    assert shift[0] == pytest.approx(UPSLOPE_SHIFT, abs=1e-12)
    assert np.max(np.abs(shift[1:])) < 1e-12
    assert 0.5 < o.x_from[0] < 0.6  # near the crest (xi_G/lambda = 0.5)
    d0, d1 = bvp10.end_distances
    assert d0 < 1e-3 and d1 < 3e-2
    # the orbit travels one wavelength back (overtaken by the wave), never ahead of the crest
    xi = o.state("xi_G")
    assert xi[0] - xi[-1] == pytest.approx(1.0, abs=0.05)
    assert np.all(xi <= o.x_from[0] + 1e-3) and np.all(xi >= o.x_to[0] - 1e-3)


def test_mesh_and_truncation_convergence(bvp10):
    chk = check_convergence(bvp10.orbit)
    assert chk.ok
    assert chk.delta_mesh["Fn"] < 1e-6
    assert chk.delta_T["Fn"] < 1e-6


def test_check_of_a_solved_result_equals_check_true(model, bvp10):
    """check_critical_bvp(result) is the check that critical_fn_bvp(check=True) runs."""
    with_check = critical_fn_bvp(10 * DEG, model=model, check=True)
    assert with_check.Fn == bvp10.Fn  # the same deterministic solve
    chk = check_critical_bvp(bvp10)
    ref = with_check.convergence
    assert chk.delta_mesh["Fn"] == ref.delta_mesh["Fn"]
    assert chk.delta_T["Fn"] == ref.delta_T["Fn"]
    assert chk.ok == ref.ok
    with pytest.raises(ValueError, match="critical_fn_bvp"):
        check_critical_bvp(bvp10.orbit)


def test_bvp_independent_of_guess_fn(model, bvp10):
    """Guesses from manifolds on both sides of the switch give the same connection."""
    r = critical_fn_bvp(10 * DEG, model=model, Fn_guess=0.298)
    assert r.success
    assert abs(r.Fn - bvp10.Fn) < 1e-6


def test_guess_as_orbit_or_connection(model, bvp10):
    o = bvp10.orbit
    r1 = critical_fn_bvp(10 * DEG, model=model, guess=(o.t, o.x), Fn_guess=bvp10.Fn)
    r2 = critical_fn_bvp(10 * DEG, model=model, guess=bvp10)
    assert r1.success and r2.success
    assert abs(r1.Fn - bvp10.Fn) < 2e-7
    assert abs(r2.Fn - bvp10.Fn) < 1e-9  # same mesh and orbit: the same solution
    assert r1.orbit.x_to[0] - r1.orbit.x_from[0] == pytest.approx(UPSLOPE_SHIFT)


def test_simplified_newton_equals_full_newton(model, bvp10, monkeypatch):
    """The simplified-Newton solve and continuation.bvp.solve_connection's Newton agree."""
    import ship_models.analysis.critical_bvp as conn

    monkeypatch.setattr(conn, "_SIMPLIFIED_NEWTON", False)
    r = critical_fn_bvp(10 * DEG, model=model)
    assert r.success
    assert "Newton iterations" in r.message and "simplified" not in r.message
    assert abs(r.Fn - bvp10.Fn) < 1e-9


def test_unusable_guess_fn_falls_back_to_coarse_bisection(model, curve):
    """At chi_c = 0 and Fn = 0.45 the upslope branch never nears the shifted saddle."""
    r = critical_fn_bvp(0.0, model=model, Fn_guess=0.45)
    assert r.success
    assert abs(r.Fn_guess - r.Fn) < 5e-3  # the guess came from the coarse bisection
    assert abs(r.Fn - curve.Fn[0]) < 1e-6


# ------------------------------------------------------------------ the curve
def test_curve_complete(curve):
    assert curve.success, curve.message
    assert curve.chi_c.size == 31
    np.testing.assert_allclose(curve.chi_c_deg, np.arange(31.0), atol=1e-12)
    assert np.all(curve.converged)
    assert np.all(curve.residual_norm < 1e-8)
    # a valid codimension-one connection: the crest saddle keeps index 1 along the curve
    assert np.all(curve.n_unstable == 1)


def test_curve_at_10_deg_is_the_start(curve, bvp10):
    assert abs(curve.Fn[10] - bvp10.Fn) < 1e-9


@pytest.mark.parametrize("deg", [0, 20, 30])
def test_curve_against_one_shot_solves(model, curve, deg):
    r = critical_fn_bvp(deg * DEG, model=model)
    assert r.success
    assert abs(curve.Fn[deg] - r.Fn) < 1e-6


def test_curve_at_zero_course_is_the_surge_threshold(curve):
    """chi_c = 0: the lateral motions decouple; the surge model's shooting threshold."""
    assert abs(curve.Fn[0] - _surge_critical_fn()) < 1e-6


def test_curve_point_against_bisection(model, curve):
    b = upslope_bisection(25 * DEG, model=model, Fn_bracket=(0.303, 0.312), tol=2e-6)
    assert b.success, b.message
    assert abs(curve.Fn[25] - b.Fn) < 2e-6


def test_curve_from_a_start_outside_the_range(model, curve, bvp10):
    c = critical_curve(np.radians([12.0, 14.0, 16.0]), model=model, start=bvp10)
    assert c.success, c.message
    np.testing.assert_allclose(c.Fn, curve.Fn[[12, 14, 16]], atol=1e-6)


def test_curve_csv_and_json(curve, tmp_path):
    path = curve.to_csv(tmp_path / "c.csv")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    assert data.shape == (31, 4)
    np.testing.assert_allclose(data[:, 1], curve.Fn, atol=1e-10)
    js = curve.to_json()
    assert js["status"] == "SUCCESS" and len(js["Fn"]) == 31


# ------------------------------------------------------------------ fates, input, interrupts
def test_upslope_fates_on_both_sides(model):
    p = model.default_params().replace(chi_c=10 * DEG)
    assert upslope_branch(model, p.replace(Fn=0.300)).fate == ShipOutcome.PERIODIC
    assert upslope_branch(model, p.replace(Fn=0.303)).fate == ShipOutcome.CAPTURED


def test_bisection_reports_a_bad_bracket(model):
    b = upslope_bisection(10 * DEG, model=model, Fn_bracket=(0.303, 0.305), tol=1e-3)
    assert b.status is Status.NO_BRACKET
    assert "bracket" in b.message


def test_bisection_interrupt_keeps_bracket(model):
    calls = []

    def progress(Fn, fate):
        calls.append(Fn)
        if len(calls) == 3:
            raise KeyboardInterrupt

    b = upslope_bisection(
        10 * DEG, model=model, Fn_bracket=(0.300, 0.3032), tol=1e-6, progress=progress
    )
    assert b.status is Status.INTERRUPTED
    assert 0.300 <= b.bracket[0] < b.bracket[1] <= 0.3032


def test_curve_interrupt_returns_partial(model, bvp10):
    n = [0]

    def progress(pt):
        n[0] += 1
        if n[0] == 3:
            raise KeyboardInterrupt

    c = critical_curve(model=model, start=bvp10, progress=progress)
    assert c.status is Status.INTERRUPTED
    assert 0 < int(c.converged.sum()) < 31
    ok = c.converged
    assert np.all(np.isfinite(c.Fn[ok]))


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"chi_c": math.nan}, "chi_c"),
        ({"chi_c": 2.0}, "chi_c"),
        ({"chi_c": 0.1, "n_intervals": 1}, "n_intervals"),
        ({"chi_c": 0.1, "degree": 0}, "degree"),
        ({"chi_c": 0.1, "end_distance": -1.0}, "end_distance"),
        ({"chi_c": 0.1, "guess": "abc", "Fn_guess": 0.3}, "guess"),
    ],
)
def test_bad_input_bvp(model, kwargs, name):
    chi = kwargs.pop("chi_c")
    with pytest.raises(ValueError, match=name):
        critical_fn_bvp(chi, model=model, **kwargs)


def test_bad_input_curve_and_bisection(model):
    with pytest.raises(ValueError, match="chi_c_values"):
        critical_curve([], model=model)
    with pytest.raises(ValueError, match="chi_c_values"):
        critical_curve([0.0, 3.0], model=model)
    with pytest.raises(ValueError, match="bracket"):
        upslope_bisection(0.1, model=model, Fn_bracket=(0.31, 0.30))
    with pytest.raises(ValueError, match="tol"):
        upslope_bisection(0.1, model=model, tol=0.0)


# ------------------------------------------------------------------ command line
def test_cli_parse_courses():
    from broachkit_cli.commands.critical_curve import parse_courses

    np.testing.assert_allclose(parse_courses("0:30"), np.arange(31.0))
    np.testing.assert_allclose(parse_courses("0:30:10"), [0, 10, 20, 30])
    np.testing.assert_allclose(parse_courses("5,7.5"), [5, 7.5])
    for bad in ("0:abc", "30:0", "0:10:0", "", "0:90"):
        with pytest.raises(ValueError, match="--chi-c"):
            parse_courses(bad)


def test_cli_critical_curve_json(tmp_path, capsys, curve):
    import json

    from broachkit_cli.main import main

    rc = main(["critical-curve", "--chi-c", "8:12:2", "--json", "--out", str(tmp_path)])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "SUCCESS"
    assert out["chi_c_deg"] == [8.0, 10.0, 12.0]
    np.testing.assert_allclose(out["Fn"], curve.Fn[[8, 10, 12]], atol=1e-6)
    assert (tmp_path / "critical_curve.png").stat().st_size > 0
    assert (tmp_path / "critical_curve.csv").exists()
