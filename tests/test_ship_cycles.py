"""The ship overtaken by waves as a collocated rotation orbit (ship_models.analysis.cycles).

References: the return-map shooting solver (sudden_change.periodic_orbit, an independent
method: simulation + Newton on the Poincare map), the heteroclinic Fn of the connection
BVP (connection.critical_fn_bvp, computed at run time), the angle of vanishing stability,
and a closed-form fit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import CHI10

from continuation.bvp.collocation import CollocationMesh
from continuation.periodic.continuation import solve_orbit
from continuation.status import Status
from ship_models.analysis.critical_bvp import critical_fn_bvp
from ship_models.analysis.cycles import (
    compare_with_shooting,
    cycle_at,
    cycle_branch,
    fit_saddle_focus_limit,
    section_state,
    simulated_cycle,
)
from ship_models.analysis.events import capsize_angle
from ship_models.analysis.sudden_change import periodic_orbit


def _multiplier_change(coarse, fine) -> float:
    """Largest change of the sorted multiplier moduli from ``coarse`` to ``fine``."""
    from continuation.periodic import PeriodicOrbitProblem

    def moduli(orbit):
        prob = PeriodicOrbitProblem.from_orbit(orbit, "Fn")
        return np.sort(np.abs(prob.floquet(prob.reference, orbit.param("Fn")).multipliers))

    return float(np.max(np.abs(moduli(coarse) - moduli(fine))))


@pytest.fixture(scope="module")
def cycle01(model):
    return simulated_cycle(model, model.default_params().replace(Fn=0.1, chi_c=0.0))


def test_cycle_fn01_chi0_against_shooting(model, cycle01):
    """(Fn 0.1, chi_c 0): period to 1e-7 s, section state to 1e-7 (nondimensional).
    Multiplier moduli: within 1.1x the collocation's own error (the change on a doubled
    mesh, order 2m) + 1e-7, the shooting multipliers' accuracy (exact return-map
    Jacobian from the variational equations, about 1e-8 at map_rtol 1e-11)."""
    o = cycle01
    assert o.X[-1, 0] - o.X[0, 0] == pytest.approx(-1.0)  # one wave per period
    s = periodic_orbit(model, o.params)
    assert s.success and s.shift == -1
    c = compare_with_shooting(o, s)
    assert abs(c.dT) < 1e-7 and c.d_state < 1e-7, c
    fine = solve_orbit(o.on_mesh(CollocationMesh(2 * o.mesh.n_intervals, o.mesh.degree, 1.0)))
    mu_error = _multiplier_change(o, fine)
    assert c.d_multiplier <= 1.1 * mu_error + 1e-7, (c, mu_error)
    x, t = section_state(o, 0.0)
    assert x[0] == 0.0 and 0.0 <= t < o.T


@pytest.mark.slow
def test_cycle_fn03_chi45_by_continuation_against_shooting(model, cycle01):
    """(Fn 0.3, chi_c 45 deg), unreachable by simulation from the calm-water guess
    (it capsizes), by continuation in chi_c then Fn; against shooting started at its
    section state: state to 1e-6; its roll far inside the angle of vanishing stability.
    Multipliers and period are held to the collocation's own error. Multiplier moduli:
    within 1.1x their change on a doubled mesh + 1e-7 (shooting's accuracy). The
    period: the continued cycle's mesh (error_tol 1e-6 on the states) leaves a period
    error of about 3e-6 s of 19 s, which the same cycle on a doubled mesh shows (order
    2m = 8: the doubled mesh's own error is below 1/256 of it); the collocation period
    is within 1.1x that estimate + 1e-7 s of shooting, and the refined period within
    1e-7 s (shooting at map_rtol 1e-11 moves by 2e-8 s between its tolerances 1e-9 and 1e-12)."""
    o45 = cycle_at(cycle01, chi_c=math.radians(45.0), Fn=0.3)
    assert o45.param("Fn") == pytest.approx(0.3) and o45.param("chi_c") == pytest.approx(
        math.radians(45.0)
    )
    s = periodic_orbit(model, o45.params, x_guess=section_state(o45, 0.0)[0])
    assert s.success and s.attracting
    c = compare_with_shooting(o45, s)
    assert c.d_state < 1e-6, c
    fine = solve_orbit(o45.on_mesh(CollocationMesh(2 * o45.mesh.n_intervals, o45.mesh.degree, 1.0)))
    period_error = abs(o45.T - fine.T)
    mu_error = _multiplier_change(o45, fine)
    assert c.d_multiplier <= 1.1 * mu_error + 1e-7, (c, mu_error)
    assert abs(fine.T - s.period) < 1e-7, (fine.T, s.period)
    assert abs(c.dT) <= 1.1 * period_error + 1e-7, (c, period_error)
    assert np.max(np.abs(o45.X[:, model.state_index("phi")])) < 0.25 * capsize_angle(model)


@pytest.mark.slow
def test_fn_branch_period_blows_up_at_the_heteroclinic_fn(model):
    """chi_c = 10 deg from Fn 0.1: the period grows without bound; the limit fitted by
    T = a - b ln|Fn* - Fn| agrees with the connection BVP to 1e-4 (measured 4e-6), the
    saddle-focus fit too; the cycle loses stability before the end; its roll stays far
    inside the angle of vanishing stability."""
    fn_het = float(critical_fn_bvp(CHI10, model=model).Fn)
    o = simulated_cycle(model, model.default_params().replace(Fn=0.1, chi_c=CHI10))
    cb = cycle_branch(o, "Fn", p_max=0.4, period_max=60.0)
    assert cb.status == Status.PERIOD_UNBOUNDED, cb.message
    assert cb.T[-1] == pytest.approx(60.0) and cb.T[0] == pytest.approx(o.T)
    assert abs(cb.limit - fn_het) < 1e-4
    assert abs(cb.limit_saddle_focus - fn_het) < 1e-4
    assert abs(cb.p[-1] - fn_het) < 1e-5
    # stable at the start, unstable before the end (and before the period limit)
    assert cb.n_unstable[0] == 0 and cb.mu_max[0] < 1.0
    assert cb.lost_stability_at < fn_het and cb.n_unstable[-1] > 0
    assert np.max(cb.max_roll) < 0.25 * capsize_angle(model)
    js = cb.to_json()
    assert js["status"] == "PERIOD_UNBOUNDED" and len(js["rows"]["Fn"]) == len(cb.p)


def test_saddle_focus_fit_closed_form():
    """Rows generated from the law itself: p* recovered to rounding."""
    T = np.linspace(30.0, 60.0, 20)
    p = 0.3 + np.exp(-0.07 * (T - 60.0)) * (1e-5 * np.cos(0.8 * T) - 2e-5 * np.sin(0.8 * T))
    f = fit_saddle_focus_limit(p, T, 0.07, 0.8)
    assert f.p_star == pytest.approx(0.3, abs=1e-14) and f.residual < 1e-14
    with pytest.raises(ValueError, match="at least 4"):
        fit_saddle_focus_limit(p[:3], T[:3], 0.07, 0.8)


def test_bad_input(model, cycle01):
    with pytest.raises(ValueError, match="`free`"):
        cycle_branch(cycle01, "K_R")
    with pytest.raises(ValueError, match="`nope`"):
        cycle_at(cycle01, nope=1.0)
    with pytest.raises(ValueError, match="`t_settle`"):
        simulated_cycle(model, cycle01.params, t_settle=-1.0)
