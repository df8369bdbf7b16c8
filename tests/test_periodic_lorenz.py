"""The Lorenz system's homoclinic explosion, reached by continuing cycles from a Hopf point.

sigma = 10, b = 8/3: the subcritical Hopf points of C+- at r_H = sigma (sigma + b + 3) /
(sigma - b - 1) = 470/19 shed unstable cycles that, continued down in r, end at the pair
of homoclinic orbits of the origin at r_hom = 13.9265574 (Doedel, Krauskopf & Osinga
2006, "Global bifurcations of the Lorenz manifold", Nonlinearity 19:2947-2972; Sparrow
1982, "The Lorenz Equations", 13.926). Not a problem the engine was written on: it checks
the period blow-up end (``PERIOD_UNBOUNDED``), the growing mesh of ``error_tol`` against a
fixed one, the restart at fixed period, the period limit's fit and its connection.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from continuation import ContinuationSettings, Status, System, continue_equilibria
from continuation.bvp import CollocationMesh, solve_connection
from continuation.periodic import continue_from_hopf, period_limit, problem_at

SIGMA, B = 10.0, 8.0 / 3.0
R_HOPF = SIGMA * (SIGMA + B + 3.0) / (SIGMA - B - 1.0)
R_HOM = 13.9265574  # published to 7 decimals


def _lorenz(x, p, ops):
    return ops.stack(
        [SIGMA * (x[1] - x[0]), p[0] * x[0] - x[1] - x[0] * x[2], x[0] * x[1] - B * x[2]]
    )


@pytest.fixture(scope="module")
def equilibria():
    s = System(_lorenz, ("x", "y", "z"), ("r",))
    r0 = 20.0
    c = math.sqrt(B * (r0 - 1.0))
    return continue_equilibria(s, [c, c, r0 - 1.0], {"r": r0}, "r", p_min=10.0, p_max=30.0,
                               ds=0.1, ds_max=0.5)  # fmt: skip


def _cycles(eq, **kw):
    st = ContinuationSettings(p_min=12.0, p_max=30.0, ds=0.05, ds_max=0.3, max_steps=400)
    return continue_from_hopf(eq, 0, st, mesh=CollocationMesh(60, 4, 1.0), **kw)


def test_hopf_point_of_the_lorenz_system(equilibria):
    hopf = [sp for sp in equilibria.special_points if sp.kind.value == "hopf"]
    assert len(hopf) == 1
    assert hopf[0].p == pytest.approx(R_HOPF, abs=1e-8)


@pytest.fixture(scope="module")
def adapted(equilibria):
    return _cycles(equilibria, period_max=40.0, error_tol=1e-6)


def test_cycles_from_the_hopf_point_end_at_the_homoclinic_explosion(adapted):
    br = adapted
    assert br.status == Status.PERIOD_UNBOUNDED, br.message
    # r converges like exp(-lambda_u T) (lambda_u ~ 11.8): within its discretisation
    # error of r_hom long before T = period_max, where the rows could no longer tell on
    # which side of r_hom they are; the branch ends there
    assert "no longer tells the side" in br.message
    assert br.records["T"][-1] < 40.0
    assert np.all(br.p > R_HOM - 5e-8)  # (r_hom is published to 7 decimals)
    assert br.p[-1] == pytest.approx(R_HOM, abs=5e-8)
    # the mesh grew where the period did
    n = [q.mesh.n_intervals for q in br.problem.problems]
    assert n[0] == 60 and max(n) > 100
    lim = period_limit(br)
    assert lim.p_star == pytest.approx(R_HOM, abs=1e-7)
    # the saddle is the origin; its unstable eigenvalue (-11 + sqrt(81 + 40 r)) / 2
    assert np.max(np.abs(lim.saddle)) < 1e-6
    assert lim.lambda_u == pytest.approx((-11 + math.sqrt(81 + 40 * R_HOM)) / 2, rel=1e-6)
    # an independent method: the homoclinic orbit solved from the last cycle
    res = solve_connection(lim.connection_problem(), (lim.t, lim.x))
    assert res.status == Status.SUCCESS, res.message
    assert res.value("r") == pytest.approx(R_HOM, abs=1e-7)
    assert res.value("r") == pytest.approx(lim.p_star, abs=1e-8)
    # every row's cycle solves its own mesh's equations (rows of coarser meshes padded)
    for k in (0, len(br) // 2, len(br) - 1):
        prob = problem_at(br, k)
        z = br.x[k][: prob.n_unknowns]
        assert np.max(np.abs(prob.residual(z, br.p[k])[:-1])) < 1e-8


def test_a_fixed_mesh_drifts_off_the_explosion_and_error_tol_does_not(equilibria, adapted):
    """60 intervals throughout (error_tol=None): the parameter moves away from r_hom by
    > 1e-7 as the period grows past 20 (its error estimate says so); with ``error_tol``
    every row is within the tolerance and none lies beyond r_hom."""
    fixed = _cycles(equilibria, period_max=22.0, adapt_every=10, error_tol=None)
    assert abs(fixed.p[-1] - R_HOM) > 1e-7
    assert fixed.records["error"][-1] > 1e-4
    T = adapted.records["T"]
    rows = np.flatnonzero(T > 8.0)
    assert rows.size >= 2
    assert np.max(np.abs(adapted.p[rows] - R_HOM)) < 5e-8
    assert np.max(adapted.records["error"]) <= 1.01e-6
    assert np.all(adapted.p > R_HOM - 5e-8)


def test_bad_error_tol(equilibria):
    with pytest.raises(ValueError, match="error_tol"):
        _cycles(equilibria, error_tol=-1.0)
    with pytest.raises(ValueError, match="max_intervals"):
        _cycles(equilibria, error_tol=1e-6, max_intervals=1)
