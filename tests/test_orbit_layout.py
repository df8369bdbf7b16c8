"""One collocation core for connections, landings and periodic orbits.

The three problems place the orbit's unknowns and its collocation and continuity rows
by one layout (``continuation.bvp.layout.OrbitLayout``), condense the same stage blocks
and estimate the local error with one monitor (``continuation.bvp.collocation.LocalError``).
The collocation and continuity rows of all three are filled by one compiled kernel
(``continuation.bvp._collocation_jit``, checked against finite differences in
``test_collocation_kernel``) with each problem's scaling; the stage values come from the
landing's CasADi graph and from the cycle's mapped point function: on the same orbit
values they must give the same rows. References: the equations themselves (the
collocation row of a cycle is ``T`` times a connection's, module doc of ``layout``), and
for the local error the closed-form derivatives of ``sin(2 pi tau)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from continuation.bvp.collocation import CollocationMesh, LocalError
from continuation.bvp.landing import LandingProblem
from continuation.bvp.layout import OrbitLayout
from continuation.periodic.problem import PeriodicOrbitProblem, error_estimate
from continuation.system import System


def _rhs(x, p, ops):
    # a saddle at (p, 0) (for the landing) with a nonlinear coupling in both rows
    return ops.stack([x[0] - p[0] + x[1] ** 2, -x[1] + 0.3 * ops.sin(x[0])])


@pytest.fixture(scope="module")
def system():
    return System(_rhs, ("u", "y"), ("p",))


def _problems(system, N=7, m=3, T=2.5):
    mesh = CollocationMesh(N, m, T)
    n = system.n_states
    lay = OrbitLayout(n, N, m)
    rng = np.random.default_rng(5)
    X = rng.standard_normal((lay.n_points, n))  # any orbit values: the rows are compared
    land = LandingProblem(system, {"p": 0.3}, "p", start=[0.1, 1.0], saddle=[0.3, 0.0],
                          mesh=mesh)  # fmt: skip
    z_land = land.pack(X)
    ref = np.concatenate([np.cos(np.arange(n * lay.n_points)), [T]])
    cyc = PeriodicOrbitProblem(system, system.params(p=0.3), "p", mesh.with_T(1.0), (0, 0), ref)
    z_cyc = np.concatenate([X.ravel(), [T]])
    return lay, land, z_land, cyc, z_cyc, T


def test_landing_and_cycle_share_rows_and_unknowns(system):
    # the same X through the landing and the cycle (their stage values from two CasADi
    # functions, their rows by the one kernel with their two scalings): the
    # collocation rows differ by the factor T only (1/(h T) D X - f against
    # 1/h D X - T f), the continuity rows are the same, in the same places, and so are
    # the Jacobian's entries in the orbit's unknowns
    lay, land, z_land, cyc, z_cyc, T = _problems(system)
    G_l = land.residual(z_land)
    G_c = cyc.residual(z_cyc, 0.3)
    a, b = lay.continuity_row, lay.boundary_row
    scale = np.max(np.abs(G_c[:b]))
    np.testing.assert_allclose(T * G_l[:a], G_c[:a], rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(G_l[a:b], G_c[a:b], rtol=0, atol=1e-13 * scale)
    J_l = land.jacobian(z_land).toarray()[:b, : lay.n_orbit_unknowns]
    J_c = cyc.jacobian(z_cyc, 0.3).toarray()[:b, : lay.n_orbit_unknowns]
    J_l[:a] *= T
    np.testing.assert_allclose(J_l, J_c, rtol=0, atol=1e-13 * np.max(np.abs(J_c)))


def test_one_condensation_for_all_three(system):
    # the landing (a connection layout with a start point) and the cycle hand the same
    # stage blocks to the condenser; they are the layout's
    lay, land, _, cyc, _, _ = _problems(system)
    rows, cols = lay.stage_blocks()
    for cond in (land.functions.condenser, cyc.layout.condenser):
        assert np.array_equal(cond.rows_s, rows)
        assert np.array_equal(cond.cols_s, cols)
    assert land.layout.orbit == cyc.layout.orbit == lay


@pytest.mark.parametrize("periodic", [False, True])
def test_local_error_derivative_converges_to_the_closed_form(periodic):
    # x(tau) = sin(2 pi tau): x^(m+1) is known; the estimate from differences of the
    # m-th derivatives of neighbouring intervals converges at least at first order in h
    # (one-sided ends: first order there; interior and wrapped differences: second)
    m = 3
    errs = []
    for N in (20, 40, 80):
        mesh = CollocationMesh(N, m, 1.0)
        X = np.sin(2 * math.pi * mesh.tau)[:, None]
        d = LocalError(mesh, periodic=periodic).derivative(X)[:, 0]
        mids = 0.5 * (mesh.nodes[:-1] + mesh.nodes[1:])
        exact = (2 * math.pi) ** (m + 1) * np.sin(2 * math.pi * mids + (m + 1) * math.pi / 2)
        errs.append(np.max(np.abs(d - exact)) / (2 * math.pi) ** (m + 1))
    assert errs[1] <= 0.55 * errs[0] and errs[2] <= 0.55 * errs[1]
    # error bound of a one-sided difference: the quotient sits h/2 off the midpoint
    # and the m-th derivative of the interpolant is x^(m) somewhere in its interval,
    # so |error| <= (h/2 + h) |x^(m+2)|, relative to |x^(m+1)|: 1.5 h 2 pi
    assert errs[-1] <= 1.5 * (1 / 80) * 2 * math.pi


def test_cycle_error_estimate_is_the_local_error_and_tracks_the_true_error():
    # the cycle's estimate is LocalError(periodic=True); for the interpolant of
    # sin(2 pi tau) (the Gauss points' polynomial on each interval) the true error
    # between the points is C_m h^(m+1) |x^(m+1)| to leading order, so estimate and
    # true error agree to a factor of a few and fall as h^(m+1)
    m = 3
    ratios, ests = [], []
    for N in (10, 20):
        mesh = CollocationMesh(N, m, 1.0)
        X = np.sin(2 * math.pi * mesh.tau)[:, None]
        est = error_estimate(mesh, X)
        assert est == LocalError(mesh, periodic=True)(X)
        tt = np.linspace(0.0, 1.0, 4001)
        true = np.max(np.abs(mesh.interpolate(X, tt)[:, 0] - np.sin(2 * math.pi * tt)))
        ratios.append(est / true)
        ests.append(est)
    assert all(0.2 < r < 5.0 for r in ratios)
    assert ests[0] / ests[1] == pytest.approx(2 ** (m + 1), rel=0.1)


def test_equidistribution_uses_the_local_error_monitor():
    # the adaptive mesh of every orbit: nodes equidistribute |x^(m+1)|^(1/(m+1)) of
    # LocalError (plus a 5 % floor): for x = tanh(20 (tau - 1/2)) the intervals shrink
    # where the front is
    mesh = CollocationMesh(30, 4, 1.0)
    X = np.tanh(20 * (mesh.tau - 0.5))[:, None]
    new = mesh.equidistributed(X)
    h = np.diff(new.nodes)
    mid = 0.5 * (new.nodes[:-1] + new.nodes[1:])
    assert np.max(h[np.abs(mid - 0.5) < 0.1]) < 0.5 * np.min(h[np.abs(mid - 0.5) > 0.35])


def test_landing_result_is_the_connection_result_with_its_start(tmp_path):
    # one result class body for both kinds; the landing records its start condition
    # (x_from = x_0(s), s, start_name) and survives save/load; closed form of the
    # truncated landing u' = u - p + y^2, y' = -y from (s, c): p(T) = s + c^2 (1 - e^{-3T}) / 3
    from continuation.bvp import ConnectionAccuracy, ConnectionResult, OrbitResult
    from continuation.bvp.landing_solve import solve_landing
    from continuation.bvp.result import LandingResult

    sys2 = System(lambda x, p, ops: ops.stack([x[0] - p[0] + x[1] ** 2, -x[1]]), ("u", "y"),
                  ("p",))  # fmt: skip
    T, s, c = 3.0, 0.1, 1.0
    prob = LandingProblem(sys2, {"p": 0.3}, "p", start=lambda v: [v, c], saddle=[0.3, 0.0],
                          T=T, s=s, start_name="s")  # fmt: skip
    res = solve_landing(prob, (np.linspace(0, T, 50), np.zeros((50, 2))),
                        accuracy=ConnectionAccuracy(estimate=False))  # fmt: skip
    assert res.success
    assert isinstance(res, LandingResult) and isinstance(res, OrbitResult)
    assert not isinstance(res, ConnectionResult)
    p_T = s + c**2 * (1 - math.exp(-3 * T)) / 3
    # collocation error O(h^{2m}) on 40 intervals of degree 4: far below 1e-9
    assert res.value("p") == pytest.approx(p_T, abs=1e-9)
    np.testing.assert_array_equal(res.x_from, [s, c])
    np.testing.assert_allclose(res.x[0], res.x_from, atol=1e-10)
    np.testing.assert_allclose(res.x_eq, [res.value("p"), 0.0], atol=1e-10)
    assert res.end_distance == pytest.approx(np.linalg.norm(res.x[-1] - res.x_eq))
    np.testing.assert_allclose(res.state("y"), c * np.exp(-res.t), atol=1e-8)
    path = res.save(tmp_path / "landing")
    back = LandingResult.load(path)
    assert isinstance(back, LandingResult) and back.s == s and back.start_name == "s"
    np.testing.assert_array_equal(back.x, res.x)
    assert OrbitResult.load(path).s == s
    with pytest.raises(ValueError, match="does not hold a ConnectionResult"):
        ConnectionResult.load(path)


def test_integral_phase_condition_closed_form(system):
    # the phase row (phase_reference, shared by connections and cycles) against the
    # closed form: reference x^(tau) = (sin 2 pi tau, cos 2 pi tau), orbit shifted by
    # delta: int <x^(tau + delta) - x^(tau), x^'(tau)> dtau = 2 pi sin(2 pi delta);
    # Gauss quadrature and the derivative of the degree-4 polynomial on 30 intervals are
    # exact to O(h^4) = 1e-6 relative at most
    from continuation.bvp.layout import phase_reference

    mesh = CollocationMesh(30, 4, 1.0)
    tau = mesh.tau
    ref_X = np.column_stack([np.sin(2 * math.pi * tau), np.cos(2 * math.pi * tau)])
    ref, dref = phase_reference(mesh, ref_X)
    assert ref.shape == dref.shape == (mesh.n_intervals * mesh.degree, 2)
    cyc = PeriodicOrbitProblem(system, system.params(p=0.3), "p", mesh, (0, 0),
                               np.concatenate([ref_X.ravel(), [1.0]]))  # fmt: skip
    for delta in (0.01, 0.1, 0.3):
        X = np.column_stack([np.sin(2 * math.pi * (tau + delta)),
                             np.cos(2 * math.pi * (tau + delta))])  # fmt: skip
        g = cyc.residual(np.concatenate([X.ravel(), [1.0]]), 0.3)[-1]
        exact = 2 * math.pi * math.sin(2 * math.pi * delta)
        assert g == pytest.approx(exact, rel=1e-6)


def test_both_kinds_print_with_their_estimates():
    # the kinds keep OrbitResult's repr (value +- error, status, mesh), not a dataclass one
    from continuation.bvp.result import ConnectionResult, LandingResult, OrbitResult

    assert ConnectionResult.__repr__ is OrbitResult.__repr__
    assert LandingResult.__repr__ is OrbitResult.__repr__
